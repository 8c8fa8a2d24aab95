//! From images to a calibration: `naocalib solve --detect` on rendered datasets (the truth
//! recovered, corners.csv never written, the other options still working, unusable images
//! named), `simulate --images` refusing an existing dataset before it writes any image, and
//! detection falling back to the whole image when the logged joints put the board elsewhere.

use crate::util::{assert_clean_failure, naocalib, run, stderr};
use std::path::{Path, PathBuf};
use std::process::Output;

use naocalib::dataset::{Dataset, read_truth};
use naocalib::detect::{self, DetectOptions, Outcome};
use naocalib::model::{Joint, Model, Param, Unit};
use naocalib::sim::render::{ImageOutput, RenderOptions};
use naocalib::sim::{SimOptions, simulate};
use serde_json::Value;

/// `simulate --images` with `stances` stances × 2 head postures per leg into `dir`
/// (default rendering: blur σ 0.8 px, grey noise σ 2), no joint noise.
fn rendered(dir: &Path, stances: usize) {
    let out = naocalib()
        .args(["simulate", "--images", "--heads", "2", "--seed", "7"])
        .args(["--stances", &stances.to_string()])
        .arg(dir)
        .output()
        .expect("ran");
    assert!(out.status.success(), "simulate: {}", stderr(&out));
}

fn json(out: &Output) -> Value {
    assert!(
        out.status.success(),
        "exit {:?}: {}",
        out.status,
        stderr(out)
    );
    serde_json::from_slice(&out.stdout).expect("JSON on stdout")
}

/// Every file under `dir`, relative, sorted, with its bytes.
fn snapshot(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut files = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else {
                let bytes = std::fs::read(&path).unwrap();
                files.push((path.strip_prefix(dir).unwrap().to_path_buf(), bytes));
            }
        }
    }
    files.sort();
    files
}

#[test]
fn solve_detect_recovers_the_truth_without_writing_corners_csv() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("ds");
    rendered(&dir, 6);
    // simulate --images leaves a corners.csv without vertices; --detect needs none at all.
    std::fs::remove_file(dir.join("corners.csv")).unwrap();
    let before = snapshot(&dir);

    let out = run(&["solve", "--detect", "--json"], &dir);
    let result = json(&out);
    let err = stderr(&out);
    assert!(
        err.contains("24 images: 24 found, 0 not found, 0 rejected, 0 unreadable"),
        "{err}"
    );
    assert!(err.contains("576 vertices detected"), "{err}");
    assert_eq!(result["converged"], true);
    assert!(!dir.join("corners.csv").exists(), "corners.csv was created");
    assert_eq!(snapshot(&dir), before, "the dataset was changed");

    let truth = read_truth(&dir.join("truth.toml")).unwrap();
    for p in Param::ALL.iter().take(21) {
        let entry = &result["parameters"][p.name()];
        let (value, std) = (
            entry["value"].as_f64().unwrap(),
            entry["std"].as_f64().unwrap(),
        );
        let error = value - truth.report_value(*p);
        // Detection is accurate to a few hundredths of a pixel and there is no joint noise.
        let tol = match p.unit() {
            Unit::Deg => 0.05,
            _ => 0.25,
        };
        assert!(
            error.abs() < tol && error.abs() < 5.0 * std,
            "{}: error {error:.4} (σ {std:.4})",
            p.name()
        );
    }

    // The same as detect, then solve from the corners.csv it writes.
    let out = run(&["detect"], &dir);
    assert!(out.status.success(), "{}", stderr(&out));
    let from_file = json(&run(&["solve", "--json"], &dir));
    for p in Param::ALL.iter().take(21) {
        let a = result["parameters"][p.name()]["value"].as_f64().unwrap();
        let b = from_file["parameters"][p.name()]["value"].as_f64().unwrap();
        assert!((a - b).abs() < 1e-6, "{}: {a} vs {b}", p.name());
    }
}

#[test]
fn solve_detect_ignores_corners_csv_and_keeps_the_other_options() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("ds");
    rendered(&dir, 4);
    // A corners.csv that would not even load is neither read nor touched.
    std::fs::write(dir.join("corners.csv"), "capture,row,col,u,v\n99,0,0,1,2\n").unwrap();
    let before = snapshot(&dir);
    // One image is missing: it is reported, the rest are solved with.
    let missing = dir.join("images/0003.png");
    let image = std::fs::read(&missing).unwrap();
    std::fs::remove_file(&missing).unwrap();
    let plots = tmp.path().join("plots");
    let export = tmp.path().join("export");
    let out = naocalib()
        .args([
            "solve",
            "--detect",
            "--json",
            "--fix",
            "LBoardRotZ",
            "--solver",
            "lm",
        ])
        .arg("--plots")
        .arg(&plots)
        .arg("--export")
        .arg(&export)
        .arg(&dir)
        .output()
        .unwrap();
    let result = json(&out);
    let err = stderr(&out);
    assert!(
        err.contains("capture 3 (images/0003.png): error:") && err.contains("no such file"),
        "{err}"
    );
    assert!(
        err.contains("15 found, 0 not found, 0 rejected, 1 unreadable"),
        "{err}"
    );
    assert_eq!(result["solver"], "lm");
    assert_eq!(result["parameters"]["LBoardRotZ"]["fixed"], true);
    assert_eq!(result["parameters"]["LBoardRotZ"]["std"], 0.0);
    assert!(export.join("calibration.toml").exists());
    assert!(std::fs::read_dir(&plots).unwrap().count() > 0);
    std::fs::write(&missing, image).unwrap();
    assert_eq!(snapshot(&dir), before, "the dataset was changed");

    // Without --detect the broken corners.csv is what is solved with, and refused.
    let out = run(&["solve"], &dir);
    assert_clean_failure(&out, &["corners.csv line 2", "capture 99"]);
    // Option mistakes are reported before detection runs.
    let out = run(&["solve", "--detect", "--fix", "Nope"], &dir);
    assert_clean_failure(&out, &["--fix"]);
    assert!(!stderr(&out).contains("found"), "{}", stderr(&out));
}

#[test]
fn solve_detect_without_usable_images_fails_with_the_reason() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("ds");
    rendered(&dir, 2);
    let solve = || run(&["solve", "--detect"], &dir);
    // Every image missing.
    let images = dir.join("images");
    let kept = tmp.path().join("kept");
    std::fs::rename(&images, &kept).unwrap();
    assert_clean_failure(
        &solve(),
        &[
            "no board found in any of its 8 images",
            "0 found, 0 not found, 0 rejected, 8 unreadable",
            "images/0000.png: no such file",
        ],
    );
    // Every image unreadable.
    std::fs::create_dir(&images).unwrap();
    for k in 0..8 {
        std::fs::write(images.join(format!("{k:04}.png")), b"not an image").unwrap();
    }
    assert_clean_failure(
        &solve(),
        &[
            "no board found in any of its 8 images",
            "not a readable image",
        ],
    );
    // Images without a board.
    for k in 0..8 {
        let blank = naocalib::sim::render::GreyImage {
            width: 640,
            height: 480,
            pixels: vec![128; 640 * 480],
        };
        blank
            .write_png(&images.join(format!("{k:04}.png")))
            .unwrap();
    }
    assert_clean_failure(
        &solve(),
        &[
            "no board found in any of its 8 images",
            "0 found, 8 not found",
        ],
    );
    assert!(!dir.join("corners.csv").exists() || Dataset::load(&dir).unwrap().corners.is_empty());

    // A dataset whose captures name no images at all.
    let plain = tmp.path().join("plain");
    let out = run(&["simulate", "--stances", "2", "--heads", "1"], &plain);
    assert!(out.status.success(), "{}", stderr(&out));
    let out = run(&["solve", "--detect"], &plain);
    assert_clean_failure(&out, &["no capture in captures.csv names an image"]);
}

#[test]
fn simulate_images_refuses_an_existing_dataset_before_writing_any_image() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("ds");
    let out = run(&["simulate", "--stances", "2", "--heads", "1"], &dir);
    assert!(out.status.success(), "{}", stderr(&out));
    let before = snapshot(&dir);
    let out = run(
        &["simulate", "--images", "--stances", "2", "--heads", "1"],
        &dir,
    );
    assert_clean_failure(&out, &["already exists; use --force"]);
    assert!(!dir.join("images").exists(), "images were written");
    assert_eq!(snapshot(&dir), before);

    // Only truth.toml left: still refused, still no image.
    for name in ["dataset.toml", "captures.csv", "corners.csv"] {
        std::fs::remove_file(dir.join(name)).unwrap();
    }
    let out = run(
        &["simulate", "--images", "--stances", "2", "--heads", "1"],
        &dir,
    );
    assert_clean_failure(&out, &["truth.toml: already exists"]);
    assert!(!dir.join("images").exists(), "images were written");

    // The truth.toml read with --truth is never the one --force would replace.
    let out = naocalib()
        .args(["simulate", "--images", "--force", "--truth"])
        .arg(dir.join("truth.toml"))
        .arg(&dir)
        .output()
        .unwrap();
    assert_clean_failure(&out, &["is the truth.toml this would write"]);
    assert!(!dir.join("images").exists(), "images were written");

    // With --force the dataset is replaced, images and all.
    let out = run(
        &[
            "simulate",
            "--images",
            "--force",
            "--stances",
            "2",
            "--heads",
            "1",
        ],
        &dir,
    );
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(std::fs::read_dir(dir.join("images")).unwrap().count(), 4);
    let dataset = Dataset::load(&dir).unwrap();
    assert!(dataset.captures.iter().all(|c| c.image.is_some()));
}

/// With the logged HeadYaw off by more and more, the board leaves the region where the
/// model predicts it: detection then searches the whole image, and the model-based
/// assignment still gives every vertex its (row, col) — until the board is too far from
/// the prediction, when the image is rejected with the reason. Never a wrong assignment.
#[test]
fn detection_falls_back_to_the_whole_image() {
    let tmp = tempfile::tempdir().unwrap();
    let model = Model::default();
    let options = SimOptions {
        seed: 3,
        stances: 2,
        heads: 1,
        px_noise: 0.0,
        joint_noise: 0.0,
        images: Some(ImageOutput {
            dir: tmp.path().to_path_buf(),
            options: RenderOptions::default(),
            force: false,
        }),
        ..SimOptions::default()
    };
    let mut dataset = simulate(&model, &options).unwrap();
    dataset.dir = tmp.path().to_path_buf();
    let truth = dataset.corners_by_capture();

    let (mut fallback, mut too_far) = (0, 0);
    for capture in &dataset.captures {
        for step in 0..=16 {
            let offset = 0.04 * step as f64;
            let mut logged = capture.clone();
            let yaw = logged.joints.get(Joint::HeadYaw);
            logged.joints.set(Joint::HeadYaw, yaw + offset);
            let r = detect::detect_capture(&dataset, &logged, &DetectOptions::default());
            match &r.outcome {
                Outcome::Found {
                    corners,
                    whole_image,
                    ..
                } => {
                    assert_eq!(corners.len(), 24, "{r}");
                    for c in corners {
                        let t = truth[&capture.id]
                            .iter()
                            .find(|t| t.vertex == c.vertex)
                            .unwrap();
                        let e = (c.pixel[0] - t.pixel[0]).hypot(c.pixel[1] - t.pixel[1]);
                        assert!(
                            e < 0.5,
                            "offset {offset}: {r}: {:?} is {e} px off",
                            c.vertex
                        );
                    }
                    if *whole_image {
                        fallback += 1;
                        assert!(
                            r.to_string()
                                .contains("not where predicted; found in the whole image"),
                            "{r}"
                        );
                    }
                }
                // Every reason to reject is a disagreement with the model's prediction.
                Outcome::Rejected { reason } if offset > 0.0 && reason.contains("model") => {
                    if reason.contains("from where the model predicts") {
                        too_far += 1;
                    }
                }
                _ => panic!("offset {offset}: {r}"),
            }
        }
    }
    assert!(
        fallback > 0,
        "no offset made detection search the whole image"
    );
    assert!(too_far > 0, "no offset was large enough to be rejected");
}
