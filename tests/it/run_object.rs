//! One calibration run ([`naocalib::run::Run`]): `batch --json` prints every run as the
//! result JSON `solve --json` prints for the same dataset (one serde type, the same keys
//! and values), and a run's provenance says whether a calibration was solved or imported.

use std::path::Path;

use naocalib::batch::BatchJson;
use naocalib::calibration::Origin;
use naocalib::dataset::Dataset;
use naocalib::report::ResultJson;
use naocalib::run::{self, RunOptions};
use serde_json::Value;

use crate::util::{naocalib, stderr};

/// `naocalib simulate` of a small dataset with realistic effects (compliance, play) into
/// `dir`.
fn simulate(dir: &Path, seed: u64) {
    let out = naocalib()
        .args(["simulate", "--stances", "8", "--heads", "2"])
        .args(["--effects", "realistic", "--seed", &seed.to_string()])
        .arg(dir)
        .output()
        .expect("ran");
    assert!(out.status.success(), "simulate failed: {}", stderr(&out));
}

/// `naocalib ARGS` must succeed (exit 0 or 3, a result either way); its stdout as JSON.
fn json(args: &[&str], paths: &[&Path]) -> Value {
    let out = naocalib().args(args).args(paths).output().expect("ran");
    assert!(
        matches!(out.status.code(), Some(0 | 3)),
        "{args:?}: {:?} {}",
        out.status,
        stderr(&out)
    );
    serde_json::from_slice(&out.stdout).expect("JSON")
}

/// Two one-sigmas equal to within the last bits (a covariance is not bit-reproducible
/// from one process to the next).
fn close(a: Option<f64>, b: Option<f64>) -> bool {
    match (a, b) {
        (Some(a), Some(b)) => a == b || (a - b).abs() <= 1e-9 * a.abs().max(b.abs()),
        (a, b) => a == b,
    }
}

#[test]
fn batch_json_runs_are_solve_json_results() {
    let tmp = tempfile::tempdir().unwrap();
    let robot = tmp.path().join("nao");
    let datasets = [robot.join("a"), robot.join("b")];
    for (seed, d) in (61..).zip(&datasets) {
        simulate(d, seed);
    }
    // Compliance and play freed: the runs have standing leg offsets.
    let options = ["--free", "compliance,play", "--solver", "lm"];
    let out = tmp.path().join("out");
    let batch = json(
        &[
            &["batch", "--json", "--no-progress"][..],
            &options,
            &["--out"],
        ]
        .concat(),
        &[&out, &robot],
    );
    // The batch's JSON is one type: its runs read as the result JSON of `solve --json`.
    let batch: BatchJson = serde_json::from_value(batch).expect("a batch JSON");
    assert_eq!(batch.runs.len(), 2);
    // Its run files (`--out`) are the same results.
    for (run, name) in batch.runs.iter().zip(["a.json", "b.json"]) {
        let text = std::fs::read_to_string(out.join(name)).unwrap();
        let file: ResultJson = serde_json::from_str(&text).expect("a result JSON");
        assert_eq!(&file, run, "{name}");
    }
    for (run, dir) in batch.runs.iter().zip(&datasets) {
        let solve = json(&[&["solve", "--json"][..], &options].concat(), &[dir]);
        let keys = |v: &Value| v.as_object().unwrap().keys().cloned().collect::<Vec<_>>();
        let run_value = serde_json::to_value(run).unwrap();
        // Every key solve prints, the batch's run has (and no other).
        assert_eq!(keys(&run_value), keys(&solve), "{}", dir.display());
        let solve: ResultJson = serde_json::from_value(solve).expect("a result JSON");
        assert_eq!(run.dataset, Some(dir.display().to_string()));
        assert_eq!(run.dataset, solve.dataset);
        assert_eq!(run.angles, solve.angles);
        assert!(run.angles.is_some(), "the dataset's joint-angle source");
        assert_eq!(run.corrected_by, solve.corrected_by);
        assert_eq!(run.rms_px, solve.rms_px);
        assert_eq!(run.iterations, solve.iterations);
        assert_eq!(run.outliers, solve.outliers);
        assert_eq!(run.misfit.detected, solve.misfit.detected);
        assert_eq!(
            run.parameters.0.keys().collect::<Vec<_>>(),
            solve.parameters.0.keys().collect::<Vec<_>>()
        );
        for (name, p) in &run.parameters.0 {
            let s = &solve.parameters.0[name];
            assert_eq!(p.value, s.value, "{name}");
            assert_eq!((p.fixed, p.unit.as_deref()), (s.fixed, s.unit.as_deref()));
            assert!(close(p.std, s.std), "{name}: {:?} vs {:?}", p.std, s.std);
        }
        // The standing leg offsets, with the lying torques they rest on.
        let (Some(a), Some(b)) = (&run.standing, &solve.standing) else {
            panic!(
                "standing offsets missing: {:?} / {:?}",
                run.standing, solve.standing
            )
        };
        assert_eq!(a.keys().collect::<Vec<_>>(), b.keys().collect::<Vec<_>>());
        assert!(!a.is_empty());
        for (name, entry) in a {
            let (
                naocalib::calibration::StandingIn::Table(x),
                naocalib::calibration::StandingIn::Table(y),
            ) = (entry, &b[name])
            else {
                panic!("{name}: not a table")
            };
            assert_eq!(x.value, y.value, "{name}");
            assert_eq!(x.tau_lying_max, y.tau_lying_max, "{name}");
            assert!(x.tau_lying_max.is_some_and(|t| t > 0.0), "{name}: {x:?}");
            assert!(close(x.std, y.std), "{name}: {:?} vs {:?}", x.std, y.std);
        }
    }
}

#[test]
fn provenance_says_solved_or_imported() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("nao/run1");
    simulate(&dir, 71);
    let dataset = Dataset::load(&dir).unwrap();
    let options = RunOptions {
        solver: "lm".into(),
        ..RunOptions::default()
    };
    let first = run::calibrate(&dataset, &options).unwrap();
    assert_eq!(first.provenance.origin, Origin::Solved);
    assert_eq!(first.provenance.dataset, dir);
    assert_eq!(first.provenance.version, env!("CARGO_PKG_VERSION"));
    assert_eq!(first.calibration.origin, Origin::Solved);
    assert!(first.start_from.is_none() && first.changes.is_none());

    // Its result JSON, read back, is a solved calibration.
    let result = tmp.path().join("result.json");
    let text = serde_json::to_string_pretty(&ResultJson::from_run(&first).to_value()).unwrap();
    std::fs::write(&result, text).unwrap();
    let solved = naocalib::export::read_start_from(&result).unwrap();
    assert_eq!(solved.origin, Origin::Solved);
    assert!(!solved.is_import());

    // The robot's files written from it and imported again: an imported calibration, also
    // once written to its TOML and read back.
    let files = tmp.path().join("robot");
    let out = naocalib()
        .arg("export")
        .arg(&result)
        .arg("--dir")
        .arg(&files)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let imported = tmp.path().join("imported.toml");
    let out = naocalib()
        .arg("import")
        .args([
            files.join("cameraCalibration.cfg"),
            files.join("jointCalibration.cfg"),
        ])
        .arg("--out")
        .arg(&imported)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let previous = naocalib::export::read_start_from(&imported).unwrap();
    assert_eq!(previous.origin, Origin::Imported);
    assert!(previous.is_import());

    // A run started from it records it, with its origin, and the change since it.
    let options = RunOptions {
        start_from: Some(previous),
        ..options
    };
    let second = run::calibrate(&dataset, &options).unwrap();
    assert_eq!(second.provenance.origin, Origin::Solved);
    let start = second
        .start_from
        .as_ref()
        .expect("the calibration it started from");
    assert_eq!(start.origin, Origin::Imported);
    let changes = second.changes.as_ref().expect("the change since it");
    let knee = changes
        .iter()
        .find(|c| c.param == naocalib::model::Param::LKneePitch)
        .expect("a leg offset estimated");
    // The robot's files held the first run's offsets (rounded): the change is small.
    assert!(knee.change.abs() < 0.01, "{knee:?}");
    let json = ResultJson::from_run(&second);
    assert!(
        json.changes
            .as_ref()
            .is_some_and(|c| c.contains_key("LKneePitch"))
    );
}

/// `solve --export DIR --force` never writes over the calibration it starts from.
#[test]
fn solve_files_never_replace_the_start_calibration() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("nao/run1");
    simulate(&dir, 72);
    let out = tmp.path().join("out");
    let first = naocalib()
        .args(["solve", "--solver", "lm", "--export"])
        .arg(&out)
        .arg(&dir)
        .output()
        .unwrap();
    assert!(first.status.success(), "{}", stderr(&first));
    let start = out.join("calibration.toml");
    let before = std::fs::read(&start).unwrap();
    let again = naocalib()
        .args(["solve", "--solver", "lm", "--force", "--export"])
        .arg(&out)
        .arg("--start-from")
        .arg(&start)
        .arg(&dir)
        .output()
        .unwrap();
    crate::util::assert_clean_failure(&again, &["calibration.toml"]);
    assert_eq!(std::fs::read(&start).unwrap(), before);
}
