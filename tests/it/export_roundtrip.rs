//! Exports round-trip: reading an exported file back gives the same values; the B-Human
//! files carry the right numbers; outputs never replace inputs or existing files.

use std::path::Path;

use crate::util::solve;
use assert_cmd::Command;
use naocalib::export::{
    self, Calibration, ExportError, Format, WriteOptions, bhuman, read_calibration,
};
use naocalib::model::{CameraId, FixedSet, Model, Param};
use naocalib::sim::{SimOptions, simulate};
use naocalib::solve::{Problem, Solution, backend};

fn solution() -> Solution {
    let options = SimOptions {
        seed: 3,
        stances: 6,
        heads: 2,
        ..SimOptions::default()
    };
    let dataset = simulate(&Model::default(), &options).unwrap();
    let problem = Problem::from_dataset(&dataset, FixedSet::default()).unwrap();
    solve(&problem, backend("lm", false).unwrap().as_ref()).unwrap()
}

#[test]
fn toml_and_json_round_trip() {
    let s = solution();
    let cal = Calibration::from_solution(&s, Some(Path::new("data/x")));
    let dir = tempfile::tempdir().unwrap();
    let toml_path = dir.path().join("calibration.toml");
    export::export(
        &cal,
        &export::own::Toml,
        &toml_path,
        &WriteOptions::default(),
    )
    .unwrap();
    let back = read_calibration(&toml_path).unwrap();
    assert_eq!(back, cal, "TOML reads back bit for bit");
    let text = std::fs::read_to_string(&toml_path).unwrap();
    assert!(text.contains("true angle = logged angle + alpha") && text.contains("store -alpha"));
    assert!(text.contains("unit = \"deg\"") && text.contains("unit = \"mm\""));
    assert!(text.contains("converged = true"));

    let json_path = dir.path().join("calibration.json");
    export::export(
        &cal,
        &export::own::Json,
        &json_path,
        &WriteOptions::default(),
    )
    .unwrap();
    let back = read_calibration(&json_path).unwrap();
    assert_eq!(back.solver, cal.solver);
    assert_eq!(back.dataset, cal.dataset);
    for (a, b) in back.parameters.iter().zip(&cal.parameters) {
        assert_eq!((a.param, a.fixed), (b.param, b.fixed));
        assert_eq!(a.value, b.value, "{}", a.param);
        assert_eq!(a.std, b.std, "{}", a.param);
    }
    // Values are the solution's, in report units; held parameters are marked.
    assert_eq!(cal.value(Param::CamPitch), s.report_value(Param::CamPitch));
    assert!(cal.get(Param::HeadYaw).unwrap().fixed);
}

#[test]
fn bhuman_files_carry_the_offsets() {
    let s = solution();
    let cal = Calibration::from_solution(&s, None);
    let camera = bhuman::Camera.write(&cal);
    let [x, y, z] = bhuman::Camera::stored(&camera, Path::new("-"), CameraId::Lower)
        .unwrap()
        .unwrap();
    let close = |a: f64, b: f64| (a - b).abs() <= 5.1e-5;
    assert!(close(x, s.report_value(Param::CamRoll)), "{camera}");
    assert!(close(y, s.report_value(Param::CamPitch)), "{camera}");
    assert!(close(z, s.report_value(Param::CamYaw)), "{camera}");
    assert!(camera.contains("cameraRotationCorrections = {\n  upper = {x = 0deg;"));
    assert!(camera.contains("\n  lower = {x = "));

    let joints = bhuman::Joints.write(&cal);
    let offsets = bhuman::Joints::stored(&joints, Path::new("-")).unwrap();
    assert_eq!(offsets.len(), 27);
    let get = |n: &str| offsets.iter().find(|(k, _)| k == n).unwrap().1;
    assert!(close(get("lKneePitch"), -s.report_value(Param::LKneePitch)));
    assert!(close(get("rAnkleRoll"), -s.report_value(Param::RAnkleRoll)));
    assert_eq!(get("lShoulderPitch"), 0.0);
    assert_eq!(get("waistYaw"), 0.0);
    assert!(joints.contains("store -alpha"));
}

#[test]
fn refuses_inputs_and_existing_files() {
    let cal = Calibration::from_solution(&solution(), None);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("calibration.toml");
    let opts = WriteOptions::default();
    export::export(&cal, &export::own::Toml, &path, &opts).unwrap();
    let e = export::export(&cal, &export::own::Toml, &path, &opts).unwrap_err();
    assert!(
        matches!(
            e,
            ExportError::Write(naocalib::output::WriteError::Exists { .. })
        ),
        "{e}"
    );
    let input = WriteOptions {
        force: true,
        inputs: vec![path.clone()],
    };
    let e = export::export(&cal, &export::own::Json, &path, &input).unwrap_err();
    assert!(
        matches!(
            e,
            ExportError::Write(naocalib::output::WriteError::Input { .. })
        ),
        "{e}"
    );
    // export_all checks every path before writing any.
    let all = dir.path().join("all");
    std::fs::create_dir_all(&all).unwrap();
    std::fs::write(all.join("jointCalibration.cfg"), "keep").unwrap();
    assert!(export::export_all(&cal, &all, &opts).is_err());
    assert!(!all.join("calibration.toml").exists());
    assert_eq!(
        std::fs::read_to_string(all.join("jointCalibration.cfg")).unwrap(),
        "keep"
    );
    // A malformed file is a clear error.
    std::fs::write(
        dir.path().join("bad.toml"),
        "format = \"naocalib-calibration\"\nversion = 1\n",
    )
    .unwrap();
    let e = read_calibration(&dir.path().join("bad.toml")).unwrap_err();
    assert!(e.to_string().contains("parameters"), "{e}");
    // Unknown keys are refused, naming the line.
    let text = Calibration::from_solution(&solution(), None)
        .to_toml()
        .replace("version = 1", "version = 1\ncolour = \"red\"");
    std::fs::write(dir.path().join("extra.toml"), text).unwrap();
    let e = read_calibration(&dir.path().join("extra.toml")).unwrap_err();
    assert!(
        e.to_string().contains("line ") && e.to_string().contains("colour"),
        "{e}"
    );
}

#[test]
fn cli_solve_export_and_export_command() {
    let tmp = tempfile::tempdir().unwrap();
    let ds = tmp.path().join("ds");
    let options = SimOptions {
        seed: 4,
        stances: 6,
        heads: 2,
        ..SimOptions::default()
    };
    simulate(&Model::default(), &options)
        .unwrap()
        .write(&ds, false)
        .unwrap();
    let exports = tmp.path().join("exports");
    let out = Command::cargo_bin("naocalib")
        .unwrap()
        .args(["solve", "--json", "--export"])
        .arg(&exports)
        .arg(&ds)
        .output()
        .unwrap();
    assert!(out.status.success(), "{out:?}");
    let result_path = tmp.path().join("result.json");
    std::fs::write(&result_path, &out.stdout).unwrap();
    let from_solve = read_calibration(&exports.join("calibration.toml")).unwrap();
    // The result JSON of `solve --json` converts to the same calibration.
    let from_result = read_calibration(&result_path).unwrap();
    for (a, b) in from_result.parameters.iter().zip(&from_solve.parameters) {
        assert_eq!(a.value, b.value, "{}", a.param);
    }
    // Every file, but that of the intrinsics, which the calibration does not carry.
    for format in export::FORMATS {
        let name = format.file();
        assert_eq!(exports.join(name).is_file(), !format.intrinsics(), "{name}");
    }
    // `export` refuses to overwrite its input, and writes by file name.
    let out = Command::cargo_bin("naocalib")
        .unwrap()
        .args(["export", "--force", "--out"])
        .arg(&result_path)
        .arg(&result_path)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("input file"));
    let cfg = tmp.path().join("lower_cameraCalibration.cfg");
    let out = Command::cargo_bin("naocalib")
        .unwrap()
        .arg("export")
        .arg(&result_path)
        .arg("--out")
        .arg(&cfg)
        .output()
        .unwrap();
    assert!(out.status.success(), "{out:?}");
    assert!(
        std::fs::read_to_string(&cfg)
            .unwrap()
            .contains("cameraRotationCorrections = {")
    );
    // --export into the dataset directory never touches the dataset's files.
    let out = Command::cargo_bin("naocalib")
        .unwrap()
        .args(["solve", "--force", "--export"])
        .arg(&ds)
        .arg(&ds)
        .output()
        .unwrap();
    assert!(out.status.success(), "{out:?}");
    assert!(naocalib::dataset::Dataset::load(&ds).is_ok());
}
