//! Inputs a hostile user can give: one test per cause of an abort, a hang, a wrong success
//! or an unclear message, each through the `naocalib` command. Every failure must be exit 1
//! with a message naming the file (and line and field) or flag, and leave files untouched.

use std::path::Path;
use std::time::Duration;

use crate::util::{assert_clean_failure, naocalib, run, simulate_small, stderr};

/// Replaces the first occurrence of `from` in the file at `path` by `to`.
fn edit(path: &Path, from: &str, to: &str) {
    let text = std::fs::read_to_string(path).unwrap();
    assert!(text.contains(from), "{} lacks {from:?}", path.display());
    std::fs::write(path, text.replacen(from, to, 1)).unwrap();
}

/// A small simulated dataset in `tmp/d`.
fn dataset(tmp: &Path) -> std::path::PathBuf {
    let dir = tmp.join("d");
    simulate_small(&dir, 3);
    dir
}

#[test]
fn simulate_with_huge_counts_fails_cleanly_and_writes_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let out_dir = tmp.path().join("out");
    for (stances, heads) in [
        ("100000000000", "3"),
        ("18446744073709551615", "2"),
        ("0", "3"),
    ] {
        let out = naocalib()
            .args(["simulate", "--stances", stances, "--heads", heads])
            .arg(&out_dir)
            .timeout(Duration::from_secs(60))
            .output()
            .unwrap();
        assert_clean_failure(&out, &["--stances", "--heads"]);
        assert!(!out_dir.exists(), "nothing written");
    }
    let out = naocalib()
        .args(["simulate", "--stances", "50001", "--heads", "1"])
        .arg(&out_dir)
        .output()
        .unwrap();
    assert_clean_failure(&out, &["= 100002 captures", "at most 100000"]);
}

#[cfg(unix)]
#[test]
fn a_fifo_or_device_in_place_of_a_dataset_file_does_not_hang() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = dataset(tmp.path());
    let captures = dir.join("captures.csv");
    std::fs::remove_file(&captures).unwrap();
    let made = std::process::Command::new("mkfifo")
        .arg(&captures)
        .status()
        .unwrap();
    assert!(made.success());
    let out = naocalib()
        .args(["solve", "--solver", "lm"])
        .arg(&dir)
        .timeout(Duration::from_secs(60))
        .output()
        .unwrap();
    assert_clean_failure(&out, &["captures.csv", "FIFO", "expected a regular file"]);

    // A device as the truth to simulate with: /dev/zero would be read forever.
    let out = naocalib()
        .args(["simulate", "--truth", "/dev/zero"])
        .arg(tmp.path().join("s"))
        .timeout(Duration::from_secs(60))
        .output()
        .unwrap();
    assert_clean_failure(&out, &["/dev/zero", "device"]);
}

#[test]
fn a_corner_far_outside_the_image_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = dataset(tmp.path());
    let corners = dir.join("corners.csv");
    let text = std::fs::read_to_string(&corners).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let mut fields: Vec<&str> = lines[1].split(',').collect();
    fields[3] = "1e20";
    lines[1] = fields.join(",");
    std::fs::write(&corners, lines.join("\n")).unwrap();
    let out = run(&["solve", "--solver", "lm"], &dir);
    assert_clean_failure(
        &out,
        &[
            "corners.csv line 2, field u",
            "100000000000000000000 px is outside -640 … 1280 px",
        ],
    );
}

#[test]
fn absurd_link_and_focal_lengths_are_refused() {
    let cases = [
        (
            "thigh_mm = 100.0",
            "thigh_mm = -100.0",
            "field robot.thigh_mm",
        ),
        ("tibia_mm = 102.9", "tibia_mm = 0", "field robot.tibia_mm"),
        ("fx = 562.5", "fx = 1e9", "field camera.fx"),
        ("fy = 562.5", "fy = 3", "field camera.fy"),
        ("cx = 324.0", "cx = 5000", "field camera.cx"),
        ("width = 640", "width = 100000", "field camera.width"),
    ];
    let tmp = tempfile::tempdir().unwrap();
    let dir = dataset(tmp.path());
    let toml = dir.join("dataset.toml");
    let good = std::fs::read(&toml).unwrap();
    for (from, to, field) in cases {
        std::fs::write(&toml, &good).unwrap();
        edit(&toml, from, to);
        let out = run(&["solve", "--solver", "lm"], &dir);
        assert_clean_failure(&out, &["dataset.toml line", field, "must be", " … "]);
    }
}

#[test]
fn a_board_smaller_than_3x3_squares_is_refused_when_read() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = dataset(tmp.path());
    edit(&dir.join("dataset.toml"), "squares_y = 5", "squares_y = 2");
    let out = run(&["solve", "--solver", "lm"], &dir);
    assert_clean_failure(
        &out,
        &[
            "dataset.toml line 15, field board.squares_y",
            "3 … 64 squares",
        ],
    );
}

#[test]
fn a_symlinked_dataset_counts_once_in_batch() {
    let tmp = tempfile::tempdir().unwrap();
    let parent = tmp.path().join("robot");
    let dir = parent.join("a");
    simulate_small(&dir, 5);
    #[cfg(unix)]
    std::os::unix::fs::symlink(&dir, parent.join("b")).unwrap();
    #[cfg(not(unix))]
    return;
    let runs = |args: &[&Path]| {
        let out = naocalib()
            .args(["batch", "--json", "--solver", "lm", "--no-progress"])
            .args(args)
            .output()
            .unwrap();
        assert!(out.status.success(), "{}", stderr(&out));
        let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        json["runs"].as_array().unwrap().len()
    };
    assert_eq!(runs(&[&dir, &parent.join("b")]), 1, "named twice");
    assert_eq!(runs(&[&parent]), 1, "found twice in the parent");
    assert_eq!(runs(&[&dir, &parent.join("./a/../a")]), 1, "spelled twice");
}

#[test]
fn messages_blame_the_right_thing_and_print_the_os_error_once() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = dataset(tmp.path());
    // A file given as the dataset: the file is not a directory, not "dataset.toml missing".
    let out = run(&["solve"], dir.join("dataset.toml"));
    assert_clean_failure(&out, &["dataset.toml: is not a directory"]);
    assert!(
        !stderr(&out).contains("dataset.toml/dataset.toml"),
        "{}",
        stderr(&out)
    );

    // A directory where captures.csv should be.
    std::fs::rename(dir.join("captures.csv"), tmp.path().join("c.csv")).unwrap();
    std::fs::create_dir(dir.join("captures.csv")).unwrap();
    let out = run(&["solve"], &dir);
    assert_clean_failure(&out, &["captures.csv: cannot read: it is a directory"]);

    // Simulating into a path whose parent is a file: the OS error once.
    let out = naocalib()
        .arg("simulate")
        .arg(dir.join("dataset.toml/out"))
        .output()
        .unwrap();
    let err = stderr(&out);
    assert_clean_failure(&out, &["dataset.toml/out", "a file is in the way"]);
    assert!(err.matches("os error").count() <= 1, "{err}");

    // Simulating into an existing file.
    let out = naocalib()
        .arg("simulate")
        .arg(dir.join("dataset.toml"))
        .output()
        .unwrap();
    assert_clean_failure(&out, &["dataset.toml: exists and is not a directory"]);
}

#[test]
fn a_refused_simulate_leaves_the_dataset_untouched() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = dataset(tmp.path());
    let before: Vec<Vec<u8>> = ["dataset.toml", "captures.csv", "corners.csv", "truth.toml"]
        .iter()
        .map(|f| std::fs::read(dir.join(f)).unwrap())
        .collect();
    let out = naocalib()
        .args(["simulate", "--seed", "9"])
        .arg(&dir)
        .output()
        .unwrap();
    assert_clean_failure(&out, &["already exists", "--force"]);
    let out = naocalib()
        .args(["simulate", "--force", "--px-noise", "nan"])
        .arg(&dir)
        .output()
        .unwrap();
    assert_clean_failure(&out, &["--px-noise"]);
    for (f, b) in ["dataset.toml", "captures.csv", "corners.csv", "truth.toml"]
        .iter()
        .zip(&before)
    {
        assert_eq!(&std::fs::read(dir.join(f)).unwrap(), b, "{f} changed");
    }
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .filter(|n| n.to_string_lossy().starts_with(".naocalib-"))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left: {leftovers:?}");
}

#[cfg(feature = "detect")]
#[test]
fn an_overlay_never_replaces_an_input_image() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("d");
    let out = naocalib()
        .args(["simulate", "--stances", "1", "--heads", "1", "--images"])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    // The first image is named as its overlay would be.
    std::fs::rename(
        dir.join("images/0000.png"),
        dir.join("images/capture_0000.png"),
    )
    .unwrap();
    edit(
        &dir.join("captures.csv"),
        "images/0000.png",
        "images/capture_0000.png",
    );
    let image = std::fs::read(dir.join("images/capture_0000.png")).unwrap();
    let out = naocalib()
        .args(["detect", "--force", "--jobs", "1", "--overlay"])
        .arg(dir.join("images"))
        .arg(&dir)
        .output()
        .unwrap();
    let err = stderr(&out);
    assert!(!err.contains("panicked"), "{err}");
    assert!(
        err.contains("capture_0000.png: is an input file; refusing to overwrite it"),
        "{err}"
    );
    assert_eq!(
        std::fs::read(dir.join("images/capture_0000.png")).unwrap(),
        image,
        "the input image is untouched"
    );
    // The outputs are checked before any image is read: nothing else is written either.
    assert!(
        !dir.join("images/capture_0001.png").exists(),
        "no overlay written once one is refused"
    );
    assert_ne!(out.status.code(), Some(0));
}
