//! End to end through the `naocalib` binary: simulate → solve, and bad input that must end
//! with a clear message (file, line, field) and exit code 1 — never a panic or an abort.

use crate::util::{assert_clean_failure, naocalib, simulate_small, stderr};
use std::path::{Path, PathBuf};
use std::process::Output;

use serde_json::Value;

fn solve(dir: &Path, extra: &[&str]) -> Output {
    naocalib()
        .arg("solve")
        .arg(dir)
        .args(extra)
        .output()
        .expect("ran")
}

fn small_dataset() -> (tempfile::TempDir, PathBuf) {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = tmp.path().join("ds");
    simulate_small(&dir, 7);
    (tmp, dir)
}

fn edit(path: &Path, f: impl FnOnce(&str) -> String) {
    let text = std::fs::read_to_string(path).expect("read");
    std::fs::write(path, f(&text)).expect("write");
}

/// Replaces field `column` of data line `line` (1-based, header = 1) of a CSV file.
fn set_field(path: &Path, line: usize, column: &str, value: &str) {
    edit(path, |text| {
        let mut lines: Vec<String> = text.lines().map(String::from).collect();
        let col = lines[0]
            .split(',')
            .position(|c| c == column)
            .expect("column");
        let mut fields: Vec<String> = lines[line - 1].split(',').map(String::from).collect();
        fields[col] = value.to_string();
        lines[line - 1] = fields.join(",");
        lines.join("\n") + "\n"
    });
}

#[test]
fn simulate_then_solve_recovers_truth_json() {
    let (_tmp, dir) = small_dataset();
    let out = solve(&dir, &["--json"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let json: Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    assert_eq!(json["solver"], naocalib::solve::backend_names()[0]);
    assert_eq!(json["converged"], true);
    assert!(json["iterations"].as_u64().unwrap() > 0);
    let rms = json["rms_px"].as_array().unwrap();
    assert!(rms.iter().all(|r| r.as_f64().unwrap() < 0.2), "rms {rms:?}");
    let params = json["parameters"].as_object().unwrap();
    for name in [
        "CamYaw",
        "LHipPitch",
        "RAnkleRoll",
        "LBoardTransX",
        "RBoardRotZ",
    ] {
        let p = &params[name];
        let err = p["value"].as_f64().unwrap() - p["truth"].as_f64().unwrap();
        let std = p["std"].as_f64().unwrap();
        assert!(std > 0.0, "{name}: std {std}");
        assert!(
            err.abs() < 5.0 * std + 1e-9,
            "{name}: error {err} vs std {std}"
        );
    }
    assert_eq!(params["HeadYaw"]["fixed"], true);
    assert_eq!(params["HeadYaw"]["std"], 0.0);
}

#[test]
fn fix_holds_parameters_at_zero() {
    let (_tmp, dir) = small_dataset();
    let out = solve(&dir, &["--json", "--fix", "CamYaw,LBoardRotZ"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let json: Value = serde_json::from_slice(&out.stdout).unwrap();
    for name in ["CamYaw", "LBoardRotZ"] {
        assert_eq!(json["parameters"][name]["value"], 0.0);
        assert_eq!(json["parameters"][name]["fixed"], true);
    }
}

#[test]
fn table_output_names_every_parameter() {
    let (_tmp, dir) = small_dataset();
    let out = solve(&dir, &[]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8_lossy(&out.stdout);
    for name in ["CamYaw", "RBoardTransY", "rms x", "iterations", "truth"] {
        assert!(text.contains(name), "table lacks {name}: {text}");
    }
    assert!(!text.contains("NaN"), "{text}");
}

#[test]
fn unknown_fix_name_is_an_error() {
    let (_tmp, dir) = small_dataset();
    assert_clean_failure(&solve(&dir, &["--fix", "CamYawn"]), &["CamYawn", "--fix"]);
}

#[test]
fn missing_column() {
    let (_tmp, dir) = small_dataset();
    let path = dir.join("captures.csv");
    edit(&path, |t| t.replacen("LKneePitch", "LKnee", 1));
    assert_clean_failure(&solve(&dir, &[]), &["captures.csv", "LKneePitch"]);
}

#[test]
fn nan_joint_angle() {
    let (_tmp, dir) = small_dataset();
    set_field(&dir.join("captures.csv"), 3, "LHipRoll", "NaN");
    assert_clean_failure(&solve(&dir, &[]), &["captures.csv", "line 3", "LHipRoll"]);
}

#[test]
fn infinite_pixel() {
    let (_tmp, dir) = small_dataset();
    set_field(&dir.join("corners.csv"), 5, "u", "inf");
    assert_clean_failure(&solve(&dir, &[]), &["corners.csv", "line 5", "u"]);
}

#[test]
fn duplicate_capture_id() {
    let (_tmp, dir) = small_dataset();
    set_field(&dir.join("captures.csv"), 4, "capture", "0");
    assert_clean_failure(&solve(&dir, &[]), &["captures.csv", "line 4", "capture"]);
}

#[test]
fn corner_of_unknown_capture() {
    let (_tmp, dir) = small_dataset();
    set_field(&dir.join("corners.csv"), 2, "capture", "999");
    assert_clean_failure(
        &solve(&dir, &[]),
        &["corners.csv", "line 2", "capture", "999"],
    );
}

#[test]
fn vertex_outside_board() {
    let (_tmp, dir) = small_dataset();
    set_field(&dir.join("corners.csv"), 6, "col", "6");
    assert_clean_failure(&solve(&dir, &[]), &["corners.csv", "line 6", "col"]);
}

#[test]
fn unknown_board_value() {
    let (_tmp, dir) = small_dataset();
    set_field(&dir.join("captures.csv"), 2, "board", "middle");
    assert_clean_failure(
        &solve(&dir, &[]),
        &["captures.csv", "line 2", "board", "middle"],
    );
}

#[test]
fn empty_captures_file() {
    let (_tmp, dir) = small_dataset();
    std::fs::write(dir.join("captures.csv"), "").unwrap();
    assert_clean_failure(&solve(&dir, &[]), &["captures.csv", "empty"]);
}

#[test]
fn empty_dataset_toml() {
    let (_tmp, dir) = small_dataset();
    std::fs::write(dir.join("dataset.toml"), "").unwrap();
    assert_clean_failure(&solve(&dir, &[]), &["dataset.toml", "camera"]);
}

#[test]
fn missing_dataset_directory() {
    let tmp = tempfile::tempdir().unwrap();
    assert_clean_failure(&solve(&tmp.path().join("nope"), &[]), &["nope"]);
}

#[test]
fn too_few_corners() {
    let (_tmp, dir) = small_dataset();
    edit(&dir.join("corners.csv"), |t| {
        t.lines().take(9).collect::<Vec<_>>().join("\n") + "\n"
    });
    assert_clean_failure(&solve(&dir, &[]), &["corners.csv", "too few corners"]);
}

#[test]
fn point_behind_camera() {
    let (_tmp, dir) = small_dataset();
    set_field(&dir.join("captures.csv"), 2, "HeadYaw", "3.1");
    assert_clean_failure(
        &solve(&dir, &[]),
        &["captures.csv", "line 2", "behind the camera"],
    );
}

#[test]
fn simulate_refuses_to_overwrite() {
    let (_tmp, dir) = small_dataset();
    let before = std::fs::read(dir.join("corners.csv")).unwrap();
    let out = naocalib()
        .args(["simulate", "--seed", "9"])
        .arg(&dir)
        .output()
        .unwrap();
    assert_clean_failure(&out, &["--force"]);
    assert_eq!(before, std::fs::read(dir.join("corners.csv")).unwrap());
}

#[test]
fn rank_deficient_dataset_exits_cleanly_with_named_diagnostics() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("one");
    let out = naocalib()
        .args(["simulate", "--stances", "1", "--heads", "1"])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let out = solve(&dir, &[]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("NOT determined") && text.contains("--fix"),
        "{text}"
    );
    assert!(!text.contains("NaN"), "{text}");
    let out = solve(&dir, &["--json"]);
    let json: Value = serde_json::from_slice(&out.stdout).expect("JSON");
    let id = &json["identifiability"];
    assert!(id["rank"].as_u64().unwrap() < id["free"].as_u64().unwrap());
    assert!(!id["suggest_fix"].as_array().unwrap().is_empty());
    assert!(!String::from_utf8_lossy(&out.stdout).contains("NaN"));
}

#[test]
fn noise_options_and_checks() {
    let (_tmp, dir) = small_dataset();
    let out = solve(&dir, &["--json", "--bootstrap", "5", "--px-noise", "0.1"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let json: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!((json["noise"]["px"].as_f64().unwrap() - 0.1).abs() < 1e-12);
    let cam = &json["parameters"]["CamYaw"];
    assert!(cam["std_sandwich"].as_f64().unwrap() > 0.0);
    assert!(cam["std_bootstrap"].as_f64().unwrap() > 0.0);
    let out = solve(&dir, &["--json", "--loss", "huber:2"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert_clean_failure(&solve(&dir, &["--loss", "tukey"]), &["tukey"]);
    assert_clean_failure(&solve(&dir, &["--px-noise=-1"]), &["--px-noise"]);
}
