//! Outputs a careless user, a full device or a kill can spoil: one test per class
//! of failure, each through the `naocalib` command. No output replaces an input; no panic,
//! standard output included; multi-file outputs are all or nothing and leave no temporary
//! file; no robot file from a result that is no plausible calibration; absurd flags refused;
//! errors said once and clearly.

use std::path::{Path, PathBuf};
use std::process::Stdio;
use std::time::Duration;

use crate::util::{assert_clean_failure, naocalib, run, simulate_small, stderr};

/// The `naocalib` binary as a plain command (to spawn, kill and redirect it).
fn plain() -> std::process::Command {
    std::process::Command::new(assert_cmd::cargo::cargo_bin("naocalib"))
}

/// A small simulated dataset in `tmp/d`.
fn dataset(tmp: &Path) -> PathBuf {
    let dir = tmp.join("d");
    simulate_small(&dir, 5);
    dir
}

/// The names in `dir`, sorted (empty when it does not exist).
fn names(dir: &Path) -> Vec<String> {
    let mut out: Vec<String> = std::fs::read_dir(dir)
        .map(|d| {
            d.map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default();
    out.sort();
    out
}

/// The names of naocalib's temporary files and stages anywhere under `dir`.
fn temporaries(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(dir).into_iter().flatten().flatten() {
        let path = entry.path();
        if entry
            .file_name()
            .to_string_lossy()
            .starts_with(".naocalib-")
        {
            out.push(path.clone());
        }
        if path.is_dir() {
            out.extend(temporaries(&path));
        }
    }
    out
}

/// Every file of `dir` with its bytes.
fn snapshot(dir: &Path) -> Vec<(String, Vec<u8>)> {
    names(dir)
        .into_iter()
        .filter(|n| dir.join(n).is_file())
        .map(|n| {
            let bytes = std::fs::read(dir.join(&n)).unwrap();
            (n, bytes)
        })
        .collect()
}

/// `naocalib solve --json` of `dir` (lm) into `path`: a result JSON for `export`.
fn result_json(dir: &Path, path: &Path) -> serde_json::Value {
    let out = run(&["solve", "--solver", "lm", "--plain-std", "--json"], dir);
    assert!(out.status.success(), "{}", stderr(&out));
    std::fs::write(path, &out.stdout).unwrap();
    serde_json::from_slice(&out.stdout).unwrap()
}

#[test]
fn no_output_replaces_an_input() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = dataset(tmp.path());
    let before = snapshot(&dir);
    // batch --report onto the dataset's captures.csv, even with --force.
    let out = batch_forced("--report", &dir.join("captures.csv"), &dir);
    assert_clean_failure(&out, &["captures.csv", "is an input file"]);
    // … and --out into a dataset file's place.
    let out = batch_forced("--out", &dir.join("corners.csv"), &dir);
    assert_clean_failure(&out, &["corners.csv"]);
    // plan over its own --camera file.
    let out = naocalib()
        .args([
            "plan",
            "--captures",
            "4",
            "--pool",
            "2",
            "--force",
            "--camera",
        ])
        .arg(dir.join("dataset.toml"))
        .arg(dir.join("dataset.toml"))
        .output()
        .unwrap();
    assert_clean_failure(&out, &["dataset.toml", "is an input file"]);
    // simulate over its --stance-file.
    let plan = tmp.path().join("plan.csv");
    std::fs::copy(dir.join("captures.csv"), &plan).unwrap();
    let out = naocalib()
        .args(["simulate", "--force", "--stance-file"])
        .arg(dir.join("captures.csv"))
        .arg(&dir)
        .output()
        .unwrap();
    assert_clean_failure(&out, &["captures.csv", "is an input file"]);
    assert_eq!(snapshot(&dir), before, "the dataset is untouched");
}

#[test]
fn a_degenerate_problem_is_an_error_not_a_panic() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = dataset(tmp.path());
    // The only free parameter is one the data do not determine (rank 0).
    let out = run(
        &[
            "solve",
            "--solver",
            "lm",
            "--fix",
            "paper",
            "--free",
            "LKneePitchPlay",
        ],
        &dir,
    );
    let err = stderr(&out);
    assert!(!err.contains("panicked"), "{err}");
    // A result (exit 0, or 3 when it is no calibration) or a clean error (exit 1).
    assert!(
        matches!(out.status.code(), Some(0 | 1 | 3)),
        "{:?}: {err}",
        out.status
    );
    if out.status.code() == Some(1) {
        assert!(err.contains("naocalib: error:"), "{err}");
    }
}

#[cfg(unix)]
#[test]
fn a_closed_or_full_standard_output_does_not_panic() {
    let tmp = tempfile::tempdir().unwrap();
    // simulate … | true: the reader is gone before anything is printed.
    let out_dir = tmp.path().join("s");
    let mut child = plain()
        .args(["simulate", "--stances", "6", "--heads", "2"])
        .arg(&out_dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let err = stderr(&out);
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(
        out.status.code(),
        Some(0),
        "a closed pipe ends quietly: {err}"
    );
    assert!(err.is_empty(), "quietly: {err}");
    assert_eq!(
        names(&out_dir),
        ["captures.csv", "corners.csv", "dataset.toml", "truth.toml"]
    );

    // export … >/dev/full: the files are written, the full device is an error.
    let json = tmp.path().join("r.json");
    result_json(&out_dir, &json);
    let full = std::fs::OpenOptions::new()
        .write(true)
        .open("/dev/full")
        .unwrap();
    let out = plain()
        .arg("export")
        .arg(&json)
        .arg("--out")
        .arg(tmp.path().join("c.toml"))
        .stdout(Stdio::from(full))
        .output()
        .unwrap();
    assert_clean_failure(&out, &["standard output", "No space left on device"]);
    assert_eq!(
        stderr(&out).matches("os error").count(),
        1,
        "{}",
        stderr(&out)
    );
    assert!(tmp.path().join("c.toml").is_file());
}

#[test]
fn a_refused_plot_set_writes_no_plot() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = dataset(tmp.path());
    let plots = tmp.path().join("plots");
    std::fs::create_dir(&plots).unwrap();
    // A later plot of the set is already there: none of the others may appear.
    std::fs::write(plots.join("solve_captures.svg"), b"mine").unwrap();
    let out = naocalib()
        .args(["solve", "--solver", "lm", "--plain-std", "--plots"])
        .arg(&plots)
        .arg(&dir)
        .output()
        .unwrap();
    assert_clean_failure(&out, &["solve_captures.svg", "already exists"]);
    assert_eq!(names(&plots), ["solve_captures.svg"]);
    assert_eq!(
        std::fs::read(plots.join("solve_captures.svg")).unwrap(),
        b"mine"
    );
    assert!(
        temporaries(tmp.path()).is_empty(),
        "{:?}",
        temporaries(tmp.path())
    );
}

#[test]
fn export_dir_with_a_file_in_the_way_writes_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = dataset(tmp.path());
    let json = tmp.path().join("r.json");
    result_json(&dir, &json);
    let target = tmp.path().join("export");
    std::fs::create_dir(&target).unwrap();
    std::fs::write(target.join("hulks"), b"a file").unwrap();
    let out = naocalib()
        .arg("export")
        .arg(&json)
        .arg("--dir")
        .arg(&target)
        .output()
        .unwrap();
    assert_clean_failure(&out, &["hulks", "a file is in the way"]);
    assert_eq!(names(&target), ["hulks"]);
    // solve --export as well.
    let out = naocalib()
        .args(["solve", "--solver", "lm", "--plain-std", "--export"])
        .arg(&target)
        .arg(&dir)
        .output()
        .unwrap();
    assert_clean_failure(&out, &["hulks", "a file is in the way"]);
    assert_eq!(names(&target), ["hulks"]);
    assert!(temporaries(tmp.path()).is_empty());
}

#[cfg(unix)]
#[test]
fn a_killed_batch_leaves_all_or_nothing_and_no_temporary_survives() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("data");
    for k in 0..3 {
        simulate_small(&data.join(format!("r{k}")), 20 + k);
    }
    let out_dir = tmp.path().join("out");
    let complete = ["r0.json", "r1.json", "r2.json", "summary.json"];
    let mut outcomes = Vec::new();
    for delay_ms in [0u64, 40, 120, 250, 400, 700] {
        let mut child = plain()
            .args(["batch", "--solver", "lm", "--no-progress", "--threads", "1"])
            .arg("--out")
            .arg(&out_dir)
            .arg("--force")
            .arg(&data)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        std::thread::sleep(Duration::from_millis(delay_ms));
        let _ = child.kill();
        let _ = child.wait();
        let found = names(&out_dir);
        assert!(
            found.is_empty() || found == complete,
            "after a kill at {delay_ms} ms: {found:?}"
        );
        outcomes.push(found.len());
    }
    // The next run (with --force where a whole set was published) succeeds and removes
    // what the killed ones left.
    let out = batch_forced("--out", &out_dir, &data);
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(names(&out_dir), complete);
    assert!(
        temporaries(tmp.path()).is_empty(),
        "left: {:?} (outcomes {outcomes:?})",
        temporaries(tmp.path())
    );
}

#[cfg(unix)]
#[test]
fn a_stale_temporary_of_a_dead_process_is_removed_and_a_live_ones_kept() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = dataset(tmp.path());
    let export = tmp.path().join("e");
    std::fs::create_dir(&export).unwrap();
    // A pid that does not run (above Linux's largest), and this test's own (alive).
    let dead = export.join(".naocalib-4194999-abc.toml");
    let dead_stage = tmp.path().join(".naocalib-4194999-stage-x");
    let live = export.join(format!(".naocalib-{}-abc.toml", std::process::id()));
    std::fs::write(&dead, b"half").unwrap();
    std::fs::create_dir(&dead_stage).unwrap();
    std::fs::write(dead_stage.join("r.json"), b"half").unwrap();
    std::fs::write(&live, b"being written").unwrap();
    let out = naocalib()
        .args([
            "solve",
            "--solver",
            "lm",
            "--plain-std",
            "--force",
            "--export",
        ])
        .arg(&export)
        .arg(&dir)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        !dead.exists() && !dead_stage.exists(),
        "stale temporaries removed"
    );
    assert!(live.exists(), "a running process's temporary is kept");
    assert!(export.join("cameraCalibration.cfg").is_file());
}

/// Writes `json` to `tmp/name` and runs `naocalib export` of it into every format.
fn export_all(tmp: &Path, name: &str, json: &serde_json::Value) -> std::process::Output {
    let path = tmp.join(name);
    std::fs::write(&path, serde_json::to_string_pretty(json).unwrap()).unwrap();
    naocalib()
        .arg("export")
        .arg(&path)
        .arg("--dir")
        .arg(tmp.join(format!("{name}.out")))
        .output()
        .unwrap()
}

#[test]
fn garbage_never_becomes_a_robot_file() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = dataset(tmp.path());
    let good = result_json(&dir, &tmp.path().join("good.json"));
    let out = export_all(tmp.path(), "good", &good);
    assert!(out.status.success(), "{}", stderr(&out));

    let set = |key: &str, value: serde_json::Value| {
        let mut j = good.clone();
        j["parameters"][key]["value"] = value;
        j
    };
    let cases: Vec<(&str, serde_json::Value, &str)> = vec![
        ("pitch", set("CamPitch", 1e300.into()), "CamPitch"),
        ("knee", set("LKneePitch", 720.0.into()), "LKneePitch"),
        ("fx", set("Fx", (-600.0).into()), "Fx"),
        ("thigh", set("LThigh", (-150.0).into()), "LThigh"),
        (
            "play",
            set("RKneePitchPlay", (-0.2).into()),
            "RKneePitchPlay",
        ),
        (
            "compliance",
            set("LHipRollCompliance", (-0.1).into()),
            "LHipRollCompliance",
        ),
        (
            "missing",
            {
                let mut j = good.clone();
                j.as_object_mut().unwrap().remove("converged");
                j
            },
            "converged",
        ),
        (
            "rms",
            {
                let mut j = good.clone();
                j["rms_px"] = serde_json::json!([-0.5, 0.4]);
                j
            },
            "rms_px",
        ),
    ];
    for (name, json, needle) in cases {
        let out = export_all(tmp.path(), name, &json);
        assert_clean_failure(&out, &[needle]);
        assert!(
            !tmp.path().join(format!("{name}.out")).exists(),
            "{name}: nothing written"
        );
    }
    // A parameter given twice: serde would keep the last silently.
    let text = serde_json::to_string_pretty(&good).unwrap();
    let twice = text.replacen(
        "\"CamYaw\": {",
        "\"CamYaw\": {\"value\": 0.1},\n    \"CamYaw\": {",
        1,
    );
    assert_ne!(twice, text);
    let path = tmp.path().join("twice.json");
    std::fs::write(&path, twice).unwrap();
    let out = naocalib()
        .arg("export")
        .arg(&path)
        .arg("--out")
        .arg(tmp.path().join("twice.cfg"))
        .args(["--format", "bhuman-camera"])
        .output()
        .unwrap();
    assert_clean_failure(&out, &["CamYaw", "twice"]);
    // A JSON array where a string belongs says so.
    let mut array = good.clone();
    array["solver"] = serde_json::json!(["lm"]);
    let out = export_all(tmp.path(), "array", &array);
    assert_clean_failure(&out, &["array", "expected a string"]);
}

#[test]
fn auto_model_on_one_pixel_corners_writes_no_robot_file() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = dataset(tmp.path());
    // Every vertex seen at the same pixel.
    let text = std::fs::read_to_string(dir.join("corners.csv")).unwrap();
    let mut lines = text.lines();
    let mut one = format!("{}\n", lines.next().unwrap());
    for line in lines {
        let fields: Vec<&str> = line.split(',').collect();
        one.push_str(&format!(
            "{},{},{},320.5,240.5\n",
            fields[0], fields[1], fields[2]
        ));
    }
    std::fs::write(dir.join("corners.csv"), one).unwrap();
    let export = tmp.path().join("export");
    let out = naocalib()
        .args(["solve", "--solver", "lm", "--model", "auto", "--export"])
        .arg(&export)
        .arg(&dir)
        .timeout(Duration::from_secs(120))
        .output()
        .unwrap();
    let err = stderr(&out);
    assert!(!err.contains("panicked"), "{err}");
    assert_ne!(out.status.code(), Some(0), "no calibration: {err}");
    for robot in [
        "cameraCalibration.cfg",
        "jointCalibration.cfg",
        "hulks",
        "naoth",
    ] {
        assert!(!export.join(robot).exists(), "{robot} written: {err}");
    }
}

#[test]
fn absurd_flags_are_refused_with_their_range() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = dataset(tmp.path());
    for (flag, value) in [
        ("--joint-noise-deg", "1e5"),
        ("--joint-noise-deg", "1e300"),
        ("--px-noise", "1e-300"),
        ("--px-noise", "0"),
    ] {
        let out = run(&["solve", "--solver", "lm", flag, value], &dir);
        assert_clean_failure(&out, &[flag]);
    }
    let out = naocalib()
        .args(["plan", "--px-noise", "1e-300"])
        .arg(tmp.path().join("p.csv"))
        .output()
        .unwrap();
    assert_clean_failure(&out, &["--px-noise", "0.001"]);
    assert!(!tmp.path().join("p.csv").exists());
    for (free, fix) in [
        ("LKneePitch", "LKneePitch"),
        ("play", "play"),
        ("Fx", "intrinsics"),
    ] {
        let out = run(
            &["solve", "--solver", "lm", "--free", free, "--fix", fix],
            &dir,
        );
        assert_clean_failure(&out, &["--free", "--fix"]);
    }
    // Freeing a family but holding one of its members stays allowed.
    let out = run(
        &[
            "solve",
            "--solver",
            "lm",
            "--plain-std",
            "--free",
            "head",
            "--fix",
            "HeadYaw",
        ],
        &dir,
    );
    assert!(out.status.code() != Some(1), "{}", stderr(&out));
    let out = run(&["solve", "--solver", "lm", "--bootstrap", "10001"], &dir);
    assert_clean_failure(&out, &["--bootstrap"]);
}

#[cfg(feature = "detect")]
#[test]
fn detect_refuses_a_pattern_opencv_cannot_find() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = dataset(tmp.path());
    let out = run(&["detect", "--pattern", "2x2"], &dir);
    assert_clean_failure(&out, &["2x2", "3x3"]);
}

#[test]
fn errors_are_said_once_and_clearly() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = dataset(tmp.path());
    // A directory given as the result to export: refused before it is opened, said once.
    let out = naocalib()
        .arg("export")
        .arg(&dir)
        .arg("--out")
        .arg(tmp.path().join("c.toml"))
        .output()
        .unwrap();
    let err = stderr(&out);
    assert_clean_failure(&out, &["is a directory"]);
    assert_eq!(err.matches("is a directory").count(), 1, "{err}");
    // A file where a directory must be made.
    let out = naocalib()
        .args(["solve", "--solver", "lm", "--plain-std", "--plots"])
        .arg(dir.join("dataset.toml").join("plots"))
        .arg(&dir)
        .output()
        .unwrap();
    assert_clean_failure(&out, &["dataset.toml", "a file is in the way"]);
}

/// `naocalib batch --solver lm --no-progress --force FLAG TARGET DATA`: its output.
fn batch_forced(flag: &str, target: &Path, data: &Path) -> std::process::Output {
    naocalib()
        .args(["batch", "--solver", "lm", "--no-progress", "--force", flag])
        .arg(target)
        .arg(data)
        .output()
        .unwrap()
}

/// Every output into a symbolic link that points to nothing — the directory to write into,
/// or a directory on the way to a file — is refused before anything is written, naming
/// the link and where it points; nothing is made through it.
#[cfg(unix)]
#[test]
fn a_dangling_symbolic_link_on_the_way_is_named_and_nothing_is_made_through_it() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = dataset(tmp.path());
    let json = tmp.path().join("r.json");
    result_json(&dir, &json);
    let images = tmp.path().join("images");
    let out = naocalib()
        .args(["simulate", "--images", "--stances", "1", "--heads", "1"])
        .arg(&images)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let solve = ["solve", "--solver", "lm", "--plain-std"];
    // (arguments before the output, whether the output is below the link, arguments after).
    let mut cases: Vec<(Vec<&str>, &str, Vec<&Path>)> = vec![
        (vec!["sandal"], "", vec![]),
        (
            vec!["simulate", "--stances", "1", "--heads", "1"],
            "",
            vec![],
        ),
        ([&solve[..], &["--plots"]].concat(), "", vec![&dir]),
        ([&solve[..], &["--export"]].concat(), "", vec![&dir]),
        ([&solve[..], &["--report"]].concat(), "r.html", vec![&dir]),
        (
            [&solve[..], &["--report"]].concat(),
            "sub/r.html",
            vec![&dir],
        ),
        (
            vec!["batch", "--solver", "lm", "--no-progress", "--out"],
            "",
            vec![&dir],
        ),
        (vec!["export", json.to_str().unwrap(), "--dir"], "", vec![]),
        (
            vec!["export", json.to_str().unwrap(), "--out"],
            "c.toml",
            vec![],
        ),
    ];
    if cfg!(feature = "detect") {
        cases.push((vec!["detect", "--overlay"], "", vec![&images]));
    }
    for (k, (before, below, after)) in cases.into_iter().enumerate() {
        let link = tmp.path().join(format!("link-{k}"));
        let gone = tmp.path().join(format!("gone-{k}"));
        std::os::unix::fs::symlink(&gone, &link).unwrap();
        let output = if below.is_empty() {
            link.clone()
        } else {
            link.join(below)
        };
        let out = naocalib()
            .args(&before)
            .arg(&output)
            .args(&after)
            .output()
            .unwrap();
        // The link named, and where it points.
        let link_named = link.display().to_string();
        let said = format!(
            "is a symbolic link to {}, which does not exist",
            gone.display()
        );
        assert_clean_failure(&out, &[link_named.as_str(), said.as_str()]);
        assert!(!gone.exists(), "{before:?}: made through the link");
        let err = stderr(&out);
        assert_eq!(
            err.matches("does not exist").count(),
            1,
            "{before:?}: {err}"
        );
    }
    assert!(temporaries(tmp.path()).is_empty());
}

/// A write that fails part-way (here: the file-size limit, as a full disk would) names the
/// output the user asked for — never the staging directory a set of files is written into
/// first — and leaves neither the output nor a temporary: for every writer of a set
/// (a dataset, its images, plots, exports, batch results, sandals) and of single files.
#[cfg(unix)]
#[test]
fn a_failed_write_names_the_output_never_a_staging_path() {
    use std::os::unix::process::CommandExt as _;
    let tmp = tempfile::tempdir().unwrap();
    let dir = dataset(tmp.path());
    let json = tmp.path().join("r.json");
    result_json(&dir, &json);
    let out_dir = tmp.path().join("out");
    std::fs::create_dir(&out_dir).unwrap();
    let d = dir.to_str().unwrap();
    let j = json.to_str().unwrap();
    let solve = ["solve", "--solver", "lm", "--plain-std"];
    // (arguments before the output, the output's name, arguments after).
    let cases: Vec<(Vec<&str>, &str, Vec<&str>)> = vec![
        (
            vec!["simulate", "--stances", "2", "--heads", "1"],
            "sim",
            vec![],
        ),
        (
            vec!["simulate", "--images", "--stances", "1", "--heads", "1"],
            "img",
            vec![],
        ),
        ([&solve[..], &["--plots"]].concat(), "plots", vec![d]),
        ([&solve[..], &["--export"]].concat(), "export", vec![d]),
        ([&solve[..], &["--report"]].concat(), "report.html", vec![d]),
        (
            vec!["batch", "--solver", "lm", "--no-progress", "--out"],
            "batch",
            vec![d],
        ),
        (
            vec!["batch", "--solver", "lm", "--no-progress", "--plots"],
            "bplots",
            vec![d],
        ),
        (vec!["sandal"], "sandal", vec![]),
        (vec!["export", j, "--dir"], "teams", vec![]),
    ];
    for (before, name, after) in cases {
        let output = out_dir.join(name);
        let mut command = plain();
        command.args(&before).arg(&output).args(&after);
        // SAFETY: only async-signal-safe calls between fork and exec.
        unsafe {
            command.pre_exec(|| {
                // Writing past 1 KiB fails (EFBIG) instead of killing the process.
                libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
                let limit = libc::rlimit {
                    rlim_cur: 1024,
                    rlim_max: 1024,
                };
                libc::setrlimit(libc::RLIMIT_FSIZE, &limit);
                Ok(())
            });
        }
        let out = command.output().unwrap();
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(1), "{before:?}: {err}");
        assert!(err.contains("File too large"), "{before:?}: {err}");
        assert!(
            err.contains(&format!("{}/", output.display()))
                || err.contains(&format!("{}:", output.display())),
            "{before:?}: the output is not named: {err}"
        );
        assert!(
            !err.contains(".naocalib-"),
            "{before:?}: a staging path: {err}"
        );
        assert!(!output.exists(), "{before:?}: part of the output is left");
    }
    assert!(temporaries(tmp.path()).is_empty());
}

/// `export RESULT --update FILE` where RESULT has the name a backup of FILE would take
/// (`FILE.bak`, or `FILE.bak.2` beside an older `FILE.bak`): the backup takes the next
/// free name, and the result, an input, is never replaced.
#[test]
fn an_update_never_gives_its_backup_the_results_name() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = dataset(tmp.path());
    let team = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/teams/bhuman/cameraCalibration.cfg");
    for older in [false, true] {
        let work = tmp.path().join(format!("older-{older}"));
        std::fs::create_dir(&work).unwrap();
        let file = work.join("cameraCalibration.cfg");
        std::fs::copy(&team, &file).unwrap();
        let robot = std::fs::read(&file).unwrap();
        let result = if older {
            std::fs::write(work.join("cameraCalibration.cfg.bak"), b"an older backup").unwrap();
            work.join("cameraCalibration.cfg.bak.2")
        } else {
            work.join("cameraCalibration.cfg.bak")
        };
        let json = result_json(&dir, &result);
        let out = naocalib()
            .arg("export")
            .arg(&result)
            .arg("--update")
            .arg(&file)
            .output()
            .unwrap();
        assert!(out.status.success(), "{}", stderr(&out));
        let kept = work.join(if older {
            "cameraCalibration.cfg.bak.3"
        } else {
            "cameraCalibration.cfg.bak.2"
        });
        assert_eq!(
            std::fs::read(&kept).unwrap(),
            robot,
            "the robot's file kept"
        );
        let still: serde_json::Value =
            serde_json::from_slice(&std::fs::read(&result).unwrap()).unwrap();
        assert_eq!(still, json, "the result is untouched");
        if older {
            assert_eq!(
                std::fs::read(work.join("cameraCalibration.cfg.bak")).unwrap(),
                b"an older backup"
            );
        }
    }
}
