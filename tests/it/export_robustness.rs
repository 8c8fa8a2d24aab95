//! The report side of robustness: plots of non-finite residuals end; exports carry
//! `converged` and refuse a result that is not a calibration; undetermined parameters are
//! written as not determined (never `0 ± 0`); a null σ in the result JSON is accepted.

use std::path::Path;
use std::sync::mpsc;
use std::time::Duration;

use naocalib::export::{self, Calibration, ExportError, Format, WriteOptions, read_calibration};
use naocalib::model::{FixedSet, Model, Param, Side};
use naocalib::report::plot;
use naocalib::sim::{SimOptions, simulate};
use naocalib::solve::{Problem, Solution, UncertaintyOptions, backend, calibrate};

use crate::util::{naocalib, simulate_small, solve, stderr};

fn small_solution(seed: u64) -> (naocalib::dataset::Dataset, Solution) {
    let options = SimOptions {
        seed,
        stances: 6,
        heads: 2,
        ..SimOptions::default()
    };
    let dataset = simulate(&Model::default(), &options).unwrap();
    let problem = Problem::from_dataset(&dataset, FixedSet::default()).unwrap();
    let solution = solve(&problem, backend("lm", false).unwrap().as_ref()).unwrap();
    (dataset, solution)
}

#[test]
fn plots_of_non_finite_residuals_end() {
    let (dataset, mut solution) = small_solution(11);
    let bad = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 1e300, -1e308];
    for (k, r) in solution.residuals.iter_mut().enumerate().take(40) {
        r.solved = [bad[k % bad.len()], 1.0];
        r.initial = [2.0, bad[(k + 1) % bad.len()]];
    }
    solution.rms_px = [f64::NAN, f64::INFINITY];
    let sides = plot::capture_sides(&dataset);
    let dir = tempfile::tempdir().unwrap();
    let (tx, rx) = mpsc::channel();
    let path = dir.path().to_path_buf();
    std::thread::spawn(move || {
        let files = plot::solution_plots(
            &solution,
            Some(&sides),
            &path,
            "bad",
            &WriteOptions::default(),
        );
        let svg = plot::residual_scatter_svg(&solution, Some(&sides));
        let _ = tx.send((files.map(|f| f.len()), svg.is_ok()));
    });
    let (files, svg) = rx
        .recv_timeout(Duration::from_secs(120))
        .expect("plotting non-finite residuals must end");
    assert_eq!(files.unwrap(), 4);
    assert!(svg);
    let text = std::fs::read_to_string(dir.path().join("bad_residuals.svg")).unwrap();
    assert!(
        text.contains("non-finite left out"),
        "says what it left out"
    );
}

#[test]
fn exports_carry_converged_and_refuse_what_is_not_a_calibration() {
    let (_, mut solution) = small_solution(12);
    let good = Calibration::from_solution(&solution, None);
    assert!(good.problems().is_empty(), "{:?}", good.problems());
    let dir = tempfile::tempdir().unwrap();
    let opts = WriteOptions::default();
    let path = dir.path().join("good.toml");
    export::export(&good, &export::own::Toml, &path, &opts).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains("converged = true"), "{text}");
    assert_eq!(read_calibration(&path).unwrap().converged, Some(true));

    solution.summary.converged = false;
    let bad = Calibration::from_solution(&solution, None);
    assert_eq!(bad.problems(), vec!["the solver did not converge"]);
    // naocalib's own files are written, and say so.
    let path = dir.path().join("bad.json");
    export::export(&bad, &export::own::Json, &path, &opts).unwrap();
    let back = read_calibration(&path).unwrap();
    assert_eq!(back.converged, Some(false));
    assert!(!back.problems().is_empty());
    // Files robots load are refused, one by one and all together, and nothing is written.
    for (format, target) in export::every_file(&bad, &dir.path().join("robot")) {
        let result = export::export(&bad, format, &target, &opts);
        if format.robot() {
            let e = result.unwrap_err();
            assert!(matches!(e, ExportError::NotACalibration { .. }), "{e}");
            assert!(e.to_string().contains("did not converge"), "{e}");
            assert!(!target.exists());
        } else {
            result.unwrap();
        }
    }
    let all = dir.path().join("all");
    assert!(export::export_all(&bad, &all, &opts).is_err());
    assert!(!all.exists());
    // Rendered anyway, a team file starts with the marker.
    let text = export::bhuman::Camera.write(&bad);
    assert!(text.starts_with("// NOT A CALIBRATION"), "{text}");

    // Residuals far beyond any plausible noise, and non-finite values, are no calibration.
    let mut implausible = good.clone();
    implausible.rms_px = Some([40.0, 3.0]);
    assert!(implausible.problems()[0].contains("plausible"));
    let mut nan = good.clone();
    nan.parameters[0].value = f64::NAN;
    assert!(nan.problems()[0].contains("CamYaw"));
}

#[test]
fn undetermined_parameters_are_not_written_as_zero_plus_minus_zero() {
    let dataset = simulate(
        &Model::default(),
        &SimOptions {
            stances: 6,
            heads: 2,
            ..Default::default()
        },
    )
    .unwrap();
    let mut problem = Problem::from_dataset(&dataset, FixedSet::default()).unwrap();
    let left: Vec<u64> = dataset
        .captures
        .iter()
        .filter(|c| c.side == Side::Left)
        .map(|c| c.id)
        .collect();
    problem.captures.retain(|c| left.contains(&c.capture));
    let lm = backend("lm", false).unwrap();
    let s = calibrate(&problem, lm.as_ref(), &UncertaintyOptions::default()).unwrap();
    assert!(!s.is_determined(Param::RKneePitch));
    let cal = Calibration::from_solution(&s, None);
    let knee = cal.get(Param::RKneePitch).unwrap();
    assert_eq!(knee.std, None);
    assert!(!knee.is_determined());
    assert!(cal.get(Param::LKneePitch).unwrap().std.is_some());

    let toml = cal.to_toml();
    let block = toml
        .split("[parameters.RKneePitch]")
        .nth(1)
        .unwrap()
        .split("[parameters.")
        .next()
        .unwrap();
    assert!(block.contains("undetermined = true"), "{block}");
    assert!(!block.contains("std"), "no sigma for it: {block}");
    assert!(toml.contains("NOT determined by the data"));
    assert_eq!(
        Calibration::from_toml(&toml, Path::new("x.toml")).unwrap(),
        cal
    );
    let joints = export::bhuman::Joints.write(&cal);
    let line = joints.lines().find(|l| l.contains("rKneePitch")).unwrap();
    assert!(line.contains("NOT determined"), "{line}");

    // The result JSON of solve (a null σ) converts.
    let json = naocalib::report::json(&s, None);
    assert!(json["parameters"]["RKneePitch"]["std"].is_null());
    assert_eq!(json["parameters"]["RKneePitch"]["undetermined"], true);
    let back = Calibration::from_json(&json.to_string(), Path::new("result.json")).unwrap();
    assert_eq!(back.get(Param::RKneePitch).unwrap().std, None);
    assert_eq!(back.parameters, cal.parameters);
}

#[test]
fn export_command_reads_null_sigma_and_marks_when_asked() {
    let tmp = tempfile::tempdir().unwrap();
    let ds = tmp.path().join("ds");
    simulate_small(&ds, 13);
    let out = naocalib()
        .args(["solve", "--json", "--solver", "lm"])
        .arg(&ds)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let mut json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    // A null sigma (a parameter the data do not determine) is accepted.
    json["parameters"]["RAnkleRoll"]["std"] = serde_json::Value::Null;
    let result = tmp.path().join("result.json");
    std::fs::write(&result, json.to_string()).unwrap();
    let cfg = tmp.path().join("jointCalibration.cfg");
    let out = naocalib()
        .arg("export")
        .arg(&result)
        .arg("--out")
        .arg(&cfg)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let text = std::fs::read_to_string(&cfg).unwrap();
    assert!(text.contains("NOT determined"), "{text}");

    // Not converged: refused with exit 1 and a reason, written only when asked, marked.
    json["converged"] = serde_json::Value::Bool(false);
    std::fs::write(&result, json.to_string()).unwrap();
    let hulks = tmp.path().join("head.json");
    let out = naocalib()
        .arg("export")
        .arg(&result)
        .args(["--format", "hulks-head", "--out"])
        .arg(&hulks)
        .output()
        .unwrap();
    crate::util::assert_clean_failure(&out, &["not a calibration", "did not converge"]);
    assert!(!hulks.exists());
    let out = naocalib()
        .arg("export")
        .arg(&result)
        .args(["--allow-unconverged", "--format", "hulks-head", "--out"])
        .arg(&hulks)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(stderr(&out).contains("warning"));
    let text = std::fs::read_to_string(&hulks).unwrap();
    assert!(text.contains("naocalib_not_a_calibration"), "{text}");
}
