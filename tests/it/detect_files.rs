//! `naocalib detect` through the binary: OpenCV's own sample images with `--pattern 9x6
//! --no-model` (compared with OpenCV's `findChessboardCorners` + `cornerSubPix`), bad image
//! files that must each give a clear per-image error, and the corners.csv rules.

use crate::util::{naocalib, stderr};
use std::path::{Path, PathBuf};

use naocalib::dataset::Dataset;
use naocalib::detect::cv;
use naocalib::sim::render::GreyImage;

const SAMPLES: [&str; 6] = [
    "left01.jpg",
    "left02.jpg",
    "left03.jpg",
    "left04.jpg",
    "left06.jpg",
    "left12.jpg",
];

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/opencv")
}

/// A dataset of the sample images: a 640 × 480 camera, a 10 × 7 board (9 × 6 inner
/// vertices), zero joint angles.
fn sample_dataset(dir: &Path) {
    std::fs::create_dir_all(dir.join("images")).unwrap();
    std::fs::write(
        dir.join("dataset.toml"),
        "[camera]\nwidth = 640\nheight = 480\nfx = 536.0\nfy = 536.0\ncx = 342.0\ncy = 235.0\n\n\
         [board]\nsquares_x = 10\nsquares_y = 7\nsquare_mm = 25.0\n",
    )
    .unwrap();
    let mut csv = String::from("capture,board,image");
    let joints = [
        "HeadYaw",
        "HeadPitch",
        "LHipYawPitch",
        "LHipRoll",
        "LHipPitch",
        "LKneePitch",
        "LAnklePitch",
        "LAnkleRoll",
        "RHipYawPitch",
        "RHipRoll",
        "RHipPitch",
        "RKneePitch",
        "RAnklePitch",
        "RAnkleRoll",
    ];
    for j in joints {
        csv += ",";
        csv += j;
    }
    csv += "\n";
    for (k, name) in SAMPLES.iter().enumerate() {
        std::fs::copy(fixtures().join(name), dir.join("images").join(name)).unwrap();
        csv += &format!("{k},left,images/{name}{}\n", ",0".repeat(joints.len()));
    }
    std::fs::write(dir.join("captures.csv"), csv).unwrap();
}

/// OpenCV's tutorial recipe (default flags, 30 iterations or 0.001), with one window for
/// the whole image of `half` pixels each side of the corner. (The tutorial's fixed 11 makes
/// a 23-pixel window, larger than the squares in the far part of left02.jpg, where it then
/// goes astray by several pixels; so does 0.3 of the median square.)
fn opencv_reference(path: &Path, half: i32) -> Vec<[f64; 2]> {
    let grey = naocalib::detect::read_grey(path).unwrap();
    let mut corners = cv::find_chessboard(&grey, None, 9, 6, cv::Search::Exhaustive)
        .unwrap()
        .unwrap_or_else(|| panic!("OpenCV finds the board in {}", path.display()));
    cv::corner_sub_pix(&grey, &mut corners, half, 30, 0.001).unwrap();
    corners.iter().map(|p| [p[0] as f64, p[1] as f64]).collect()
}

#[test]
fn opencv_samples_agree_with_opencv() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("samples");
    sample_dataset(&dir);
    let out = naocalib()
        .args(["detect", "--pattern", "9x6", "--no-model"])
        .arg(&dir)
        .output()
        .unwrap();
    let err = stderr(&out);
    assert!(out.status.success(), "{err}");
    assert!(err.contains("6 found, 0 not found"), "{err}");
    let dataset = Dataset::load(&dir).unwrap();
    assert_eq!(dataset.corners.len(), 6 * 54);
    let mut worst = 0.0f64;
    let mut sum2 = 0.0;
    for (k, name) in SAMPLES.iter().enumerate() {
        // One window for all corners that fits the smallest square: 0.3 of it (naocalib
        // sizes the window per corner).
        let ours: Vec<_> = dataset.corners_of(k as u64).map(|c| c.pixel).collect();
        let mut spacing: Vec<f64> = ours
            .windows(2)
            .enumerate()
            .filter(|(i, _)| (i + 1) % 9 != 0)
            .map(|(_, w)| ((w[0][0] - w[1][0]).powi(2) + (w[0][1] - w[1][1]).powi(2)).sqrt())
            .collect();
        spacing.sort_by(f64::total_cmp);
        let half = (0.3 * spacing[0]).round() as i32;
        let reference = opencv_reference(&dir.join("images").join(name), half);
        let mut w = 0.0f64;
        for c in dataset.corners_of(k as u64) {
            let r = reference[(c.vertex.row * 9 + c.vertex.col) as usize];
            w = w.max(((c.pixel[0] - r[0]).powi(2) + (c.pixel[1] - r[1]).powi(2)).sqrt());
        }
        eprintln!("{name}: window ±{half} px, worst difference {w:.3} px");
        for c in dataset.corners_of(k as u64) {
            let r = reference[(c.vertex.row * 9 + c.vertex.col) as usize];
            let d = ((c.pixel[0] - r[0]).powi(2) + (c.pixel[1] - r[1]).powi(2)).sqrt();
            worst = worst.max(d);
            sum2 += d * d;
        }
    }
    let rms = (sum2 / (6.0 * 54.0)).sqrt();
    eprintln!("against OpenCV's recipe: rms {rms:.3} px, worst {worst:.3} px");
    assert!(rms < 0.05 && worst < 0.2, "rms {rms}, worst {worst}");
}

/// A small rendered dataset: 8 captures with images.
fn rendered(dir: &Path) {
    let out = naocalib()
        .args([
            "simulate",
            "--images",
            "--stances",
            "4",
            "--heads",
            "1",
            "--seed",
            "5",
        ])
        .arg(dir)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
}

#[test]
fn bad_image_files_give_per_image_errors() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("ds");
    rendered(&dir);
    let img = |k: u32| dir.join(format!("images/{k:04}.png"));
    // 0: truncated PNG, 1: empty, 2: missing, 3: wrong size, 4: not an image,
    // 5: a symbolic link out of the dataset, 6: corrupt JPEG; 7 stays good.
    let png = std::fs::read(img(0)).unwrap();
    std::fs::write(img(0), &png[..png.len() / 3]).unwrap();
    std::fs::write(img(1), b"").unwrap();
    std::fs::remove_file(img(2)).unwrap();
    let small = GreyImage {
        width: 320,
        height: 240,
        pixels: vec![128; 320 * 240],
    };
    small.write_png(&img(3)).unwrap();
    std::fs::write(img(4), "capture,row\n1,2\n").unwrap();
    let outside = tmp.path().join("outside.png");
    std::fs::copy(img(5), &outside).unwrap();
    std::fs::remove_file(img(5)).unwrap();
    #[cfg(unix)]
    std::os::unix::fs::symlink(&outside, img(5)).unwrap();
    std::fs::write(img(6), b"\xff\xd8\xff\xe0garbage").unwrap();

    let out = naocalib().arg("detect").arg(&dir).output().unwrap();
    let err = stderr(&out);
    assert!(out.status.success(), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    for needle in [
        "capture 0 (images/0000.png): error:",
        "0000.png: not a readable image",
        "capture 1 (images/0001.png): error:",
        "0001.png: the file is empty",
        "0002.png: no such file",
        "0003.png: the image is 320×240 pixels, but the lower camera that took it (its \
         capture's camera column) is 640×480 in [camera] of dataset.toml",
        "0004.png: not a readable image: not a PNG, JPEG",
        "0006.png: not a readable image",
        "capture 7 (images/0007.png): found 24 vertices",
        "1 found, 0 not found, 0 rejected, 7 unreadable",
    ] {
        assert!(err.contains(needle), "stderr lacks '{needle}':\n{err}");
    }
    #[cfg(unix)]
    assert!(
        err.contains("0005.png: the image path leaves the dataset directory"),
        "{err}"
    );
    let dataset = Dataset::load(&dir).unwrap();
    assert_eq!(dataset.corners.len(), 24);
    assert!(dataset.corners.iter().all(|c| c.capture == 7));
}

#[test]
fn corners_csv_is_replaced_only_with_force() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("ds");
    rendered(&dir);
    // simulate --images leaves corners.csv without vertices: detect may fill it.
    let out = naocalib().arg("detect").arg(&dir).output().unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(stderr(&out).contains("8 found"), "{}", stderr(&out));
    let before = std::fs::read(dir.join("corners.csv")).unwrap();
    let out = naocalib().arg("detect").arg(&dir).output().unwrap();
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(stderr(&out).contains("use --force"), "{}", stderr(&out));
    assert_eq!(std::fs::read(dir.join("corners.csv")).unwrap(), before);
    let overlays = tmp.path().join("overlays");
    let solved = tmp.path().join("solved.json");
    std::fs::write(
        &solved,
        r#"{"parameters": {"CamPitch": {"value": 1.5, "std": 0.1, "unit": "deg"}}}"#,
    )
    .unwrap();
    let out = naocalib()
        .args(["detect", "--force", "--jobs", "1", "--overlay"])
        .arg(&overlays)
        .arg("--after")
        .arg(&solved)
        .arg(&dir)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(std::fs::read(dir.join("corners.csv")).unwrap(), before);
    let overlay = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(overlays.join("capture_0000.png")).unwrap(),
    ))
    .read_info()
    .unwrap();
    let info = overlay.info();
    assert_eq!((info.width, info.height), (640, 480));
    assert_eq!(info.color_type, png::ColorType::Rgb);
    // A path with '..' is refused when the dataset is read, naming the line and field.
    let captures = std::fs::read_to_string(dir.join("captures.csv")).unwrap();
    std::fs::write(
        dir.join("captures.csv"),
        captures.replacen("images/0000.png", "../0000.png", 1),
    )
    .unwrap();
    let out = naocalib()
        .args(["detect", "--force"])
        .arg(&dir)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert!(
        stderr(&out).contains("captures.csv line 2, field image"),
        "{}",
        stderr(&out)
    );
}

#[test]
fn rejected_and_not_found_are_reported() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("ds");
    rendered(&dir);
    // Capture 0 claims the other foot: the model predicts that board far from the one seen.
    let captures = std::fs::read_to_string(dir.join("captures.csv")).unwrap();
    let mut lines: Vec<String> = captures.lines().map(str::to_string).collect();
    lines[1] = if lines[1].contains(",left,") {
        lines[1].replacen(",left,", ",right,", 1)
    } else {
        lines[1].replacen(",right,", ",left,", 1)
    };
    std::fs::write(dir.join("captures.csv"), lines.join("\n") + "\n").unwrap();
    // Capture 1 shows no board at all.
    let blank = GreyImage {
        width: 640,
        height: 480,
        pixels: (0..640 * 480).map(|k| (k % 7 * 20 + 60) as u8).collect(),
    };
    blank.write_png(&dir.join("images/0001.png")).unwrap();
    let out = naocalib().arg("detect").arg(&dir).output().unwrap();
    let err = stderr(&out);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("capture 0 (images/0000.png): rejected: "),
        "{err}"
    );
    assert!(
        err.contains("capture 1 (images/0001.png): not found"),
        "{err}"
    );
    assert!(err.contains("6 found, 1 not found, 1 rejected"), "{err}");
}

/// A picture of the wrong size names the size of the camera that took it and that
/// camera's table in dataset.toml (`[camera]` or `[upper_camera]`), whichever it is.
#[test]
fn a_wrong_sized_picture_names_the_table_of_the_camera_that_took_it() {
    let tmp = tempfile::tempdir().unwrap();
    let base = tmp.path().join("base");
    let out = naocalib()
        .args(["simulate", "--images", "--stances", "1", "--heads", "1"])
        .args(["--upper-stances", "1", "--seed", "2"])
        .arg("--board")
        .arg(crate::util::paper_board())
        .arg(&base)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let text = std::fs::read_to_string(base.join("dataset.toml")).unwrap();
    for (table, camera, other) in [
        ("[upper_camera]", "upper", "lower"),
        ("[camera]", "lower", "upper"),
    ] {
        let dir = tmp.path().join(camera);
        std::fs::create_dir_all(dir.join("images")).unwrap();
        for name in ["captures.csv", "corners.csv"] {
            std::fs::copy(base.join(name), dir.join(name)).unwrap();
        }
        for e in std::fs::read_dir(base.join("images")).unwrap() {
            let e = e.unwrap();
            std::fs::copy(e.path(), dir.join("images").join(e.file_name())).unwrap();
        }
        // That camera's table says 1280 × 960; its pictures are 640 × 480.
        let at = text.find(&format!("{table}\n")).unwrap();
        let (head, tail) = text.split_at(at);
        let end = tail.find("\n\n").unwrap();
        let changed = tail[..end]
            .replace("width = 640", "width = 1280")
            .replace("height = 480", "height = 960");
        std::fs::write(
            dir.join("dataset.toml"),
            format!("{head}{changed}{}", &tail[end..]),
        )
        .unwrap();
        let out = naocalib().arg("detect").arg(&dir).output().unwrap();
        let err = stderr(&out);
        let said = format!(
            "the image is 640×480 pixels, but the {camera} camera that took it (its capture's \
             camera column) is 1280×960 in {table} of dataset.toml"
        );
        let captures = naocalib::dataset::read_captures(&dir.join("captures.csv")).unwrap();
        for c in &captures {
            let line = err
                .lines()
                .find(|l| l.starts_with(&format!("capture {} ", c.id)))
                .unwrap_or_else(|| panic!("{err}"));
            if c.camera.name() == camera {
                assert!(line.contains(&said), "{line}");
            } else {
                assert!(line.contains("found 24 vertices"), "{other}: {line}");
            }
        }
    }
}
