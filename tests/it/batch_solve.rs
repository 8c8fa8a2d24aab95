//! Batch solving over simulated datasets, some deliberately broken: every good one is
//! solved exactly as `solve` does, every broken one is reported with its reason, the
//! summary statistics are right, drift flags a real change, and `--out` writes safely.

use std::path::{Path, PathBuf};

use assert_cmd::Command;
use naocalib::batch::{self, BatchOptions, DriftOptions, Grouping, drift};
use naocalib::dataset::Dataset;
use naocalib::export::{ExportError, WriteOptions};
use naocalib::model::{FixedSet, Model, PARAMETER_COUNT, Param};
use naocalib::sim::{SimOptions, simulate};
use naocalib::solve::{self, Problem, UncertaintyOptions};
use serde_json::Value;

fn small(seed: u64, truth: Option<[f64; PARAMETER_COUNT]>) -> Dataset {
    let options = SimOptions {
        seed,
        stances: 6,
        heads: 2,
        truth,
        ..SimOptions::default()
    };
    simulate(&Model::default(), &options).expect("simulated")
}

/// `robot/run1..run3` (one truth), and three broken datasets in `robot/`.
fn fixture(root: &Path) -> (PathBuf, Vec<PathBuf>) {
    let robot = root.join("robot");
    let first = small(1, None);
    let truth = first.truth.as_ref().unwrap().values;
    let mut good = Vec::new();
    for (k, ds) in [first, small(2, Some(truth)), small(3, Some(truth))]
        .into_iter()
        .enumerate()
    {
        let dir = robot.join(format!("run{}", k + 1));
        ds.write(&dir, false).expect("written");
        good.push(dir);
    }
    // No captures.csv.
    let dir = robot.join("x_no_captures");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::copy(good[0].join("dataset.toml"), dir.join("dataset.toml")).unwrap();
    // A corrupt number in corners.csv.
    let dir = robot.join("x_bad_number");
    small(4, Some(truth)).write(&dir, false).unwrap();
    let corners = std::fs::read_to_string(dir.join("corners.csv")).unwrap();
    let mut lines: Vec<String> = corners.lines().map(String::from).collect();
    lines[3] = lines[3].replacen(|c: char| c.is_ascii_digit(), "x", 1);
    std::fs::write(dir.join("corners.csv"), lines.join("\n") + "\n").unwrap();
    // Too few corners to calibrate.
    let dir = robot.join("x_few_corners");
    let mut ds = small(5, Some(truth));
    ds.corners.truncate(5);
    ds.write(&dir, false).unwrap();
    (robot, good)
}

fn same(a: f64, b: f64) -> bool {
    a == b || (a.is_nan() && b.is_nan())
}

/// The reported std is not bit-reproducible from one `solve` to the next (the covariance
/// differs in the last bits between two runs of the same solve), so it is compared to
/// within 1e-9 relative; values, RMS and iterations must be identical.
fn close(a: f64, b: f64) -> bool {
    same(a, b) || (a - b).abs() <= 1e-9 * a.abs().max(b.abs())
}

#[test]
fn batch_solves_like_solve_reports_failures_and_summarises() {
    let tmp = tempfile::tempdir().unwrap();
    let (robot, good) = fixture(tmp.path());
    let options = BatchOptions::default();
    let result = batch::run(std::slice::from_ref(&robot), &options, &|_| {});

    // Every good dataset, exactly as solve does.
    let got: Vec<&Path> = result.runs.iter().map(|r| r.dataset()).collect();
    assert_eq!(got, good.iter().map(PathBuf::as_path).collect::<Vec<_>>());
    for run in &result.runs {
        let dataset = Dataset::load(run.dataset()).unwrap();
        let problem = Problem::from_dataset(&dataset, FixedSet::default()).unwrap();
        let backend = solve::backend(&options.run.solver, false).unwrap();
        let direct =
            solve::calibrate(&problem, backend.as_ref(), &UncertaintyOptions::default()).unwrap();
        for i in 0..PARAMETER_COUNT {
            assert!(same(run.solution.values[i], direct.values[i]), "value {i}");
            assert!(close(run.solution.std[i], direct.std[i]), "std {i}");
        }
        assert_eq!(run.solution.rms_px, direct.rms_px);
        assert_eq!(run.solution.summary.iterations, direct.summary.iterations);
    }

    // Every broken one, with its reason.
    let reasons: Vec<(String, String)> = result
        .failures
        .iter()
        .map(|f| {
            (
                f.dataset
                    .file_name()
                    .unwrap()
                    .to_string_lossy()
                    .into_owned(),
                f.error.to_string(),
            )
        })
        .collect();
    assert_eq!(reasons.len(), 3, "{reasons:?}");
    let reason = |name: &str| &reasons.iter().find(|(n, _)| n == name).unwrap().1;
    assert!(reason("x_no_captures").contains("captures.csv: no such file"));
    let bad = reason("x_bad_number");
    assert!(bad.contains("corners.csv line 4"), "{bad}");
    assert!(reason("x_few_corners").contains("too few corners"));

    // Summary statistics against a direct computation.
    let summary = result.summary();
    assert_eq!(summary.runs, 3);
    for p in [Param::CamYaw, Param::LKneePitch, Param::RBoardTransY] {
        let v: Vec<f64> = result
            .runs
            .iter()
            .map(|r| r.solution.report_value(p))
            .collect();
        let s: Vec<f64> = result
            .runs
            .iter()
            .map(|r| r.solution.report_std(p))
            .collect();
        let mean = (v[0] + v[1] + v[2]) / 3.0;
        let std =
            (((v[0] - mean).powi(2) + (v[1] - mean).powi(2) + (v[2] - mean).powi(2)) / 2.0).sqrt();
        let st = summary.get(p).unwrap();
        assert_eq!(st.n, 3);
        assert!((st.mean - mean).abs() < 1e-12, "{p}");
        assert!((st.std - std).abs() < 1e-12, "{p}");
        assert!(
            (st.mean_sigma - (s[0] + s[1] + s[2]) / 3.0).abs() < 1e-12,
            "{p}"
        );
    }
    // Held parameters are not summarised as estimates.
    assert!(summary.get(Param::HeadYaw).is_none());

    // Reports: the table lists the runs and the failures; the JSON too.
    let table = result.table(&DriftOptions::default());
    assert!(table.contains("mean ± std"), "{table}");
    assert!(table.contains("FAILED"), "{table}");
    assert!(table.contains("drift"), "{table}");
    let json = result.json(&DriftOptions::default());
    assert_eq!(json["runs"].as_array().unwrap().len(), 3);
    assert_eq!(json["summary"]["failed"], 3);
    assert_eq!(
        json["summary"]["drift"]["pairs"].as_array().unwrap().len(),
        2
    );
}

#[test]
fn drift_flags_a_changed_joint() {
    let a = small(11, None);
    let mut truth = a.truth.as_ref().unwrap().values;
    let b_same = small(12, Some(truth));
    truth[Param::LKneePitch.index()] += 1.0f64.to_radians();
    let b_changed = small(13, Some(truth));
    let mut datasets = vec![a, b_same, b_changed];
    for (k, d) in datasets.iter_mut().enumerate() {
        d.dir = format!("nao/run{k}").into();
    }
    let options = BatchOptions {
        drift: DriftOptions {
            mode: batch::DriftMode::First,
            ..DriftOptions::default()
        },
        ..BatchOptions::default()
    };
    let result = batch::solve_datasets(&datasets, &options, &|_| {});
    assert_eq!(result.runs.len(), 3);
    let pairs = result.drift(&options.drift);
    assert_eq!(pairs.len(), 2);
    assert_eq!((pairs[1].from, pairs[1].to), (0, 2));
    let flagged: Vec<Param> = pairs[1].flagged().map(|d| d.param).collect();
    assert!(flagged.contains(&Param::LKneePitch), "{flagged:?}");
    let knee = pairs[1]
        .params
        .iter()
        .find(|d| d.param == Param::LKneePitch)
        .unwrap();
    assert!((knee.delta - 1.0).abs() < 0.3, "{knee:?}");
    // z is Δ over the combined sigma.
    let (s0, s2) = (&result.runs[0].solution, &result.runs[2].solution);
    let sigma = s0
        .report_std(Param::LKneePitch)
        .hypot(s2.report_std(Param::LKneePitch));
    assert!((knee.z.unwrap() - knee.delta / sigma).abs() < 1e-12);
    // A run against itself: nothing changed; held parameters have no z.
    for d in drift(s0, s0, 3.0) {
        assert!(!d.flagged);
        assert_eq!(d.delta, 0.0);
    }
    // Different parents are different robots: no pairs across them.
    let mut split = datasets.clone();
    split[2].dir = "other/run".into();
    let r = batch::solve_datasets(&split, &options, &|_| {});
    assert_eq!(r.drift(&options.drift).len(), 1);
    let all = DriftOptions {
        grouping: Grouping::All,
        ..options.drift
    };
    assert_eq!(r.drift(&all).len(), 2);
}

#[test]
fn out_writes_atomically_and_never_over_inputs() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("robot/run1");
    small(21, None).write(&dir, false).unwrap();
    let mut options = BatchOptions::default();
    options.run.solver = "lm".into();
    let result = batch::run(std::slice::from_ref(&dir), &options, &|_| {});
    assert_eq!(result.runs.len(), 1);
    let out = tmp.path().join("out");
    let files = result
        .write(&out, &options.drift, &WriteOptions::default())
        .unwrap();
    assert_eq!(files.runs, [out.join("run1.json")]);
    let run: Value =
        serde_json::from_str(&std::fs::read_to_string(&files.runs[0]).unwrap()).unwrap();
    assert_eq!(run["dataset"], dir.display().to_string());
    assert!(run["parameters"]["CamYaw"]["std"].as_f64().unwrap() > 0.0);
    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(&files.summary).unwrap()).unwrap();
    assert_eq!(summary["runs"], 1);
    // Again: refused without force, allowed with it.
    let e = result
        .write(&out, &options.drift, &WriteOptions::default())
        .unwrap_err();
    assert!(
        matches!(
            e,
            ExportError::Write(naocalib::output::WriteError::Exists { .. })
        ),
        "{e}"
    );
    let force = WriteOptions {
        force: true,
        ..WriteOptions::default()
    };
    result.write(&out, &options.drift, &force).unwrap();
    // Writing into the dataset's own directory cannot touch its files, even with force.
    let e = naocalib::output::write_atomic(
        &dir.join("corners.csv"),
        b"x",
        &WriteOptions::protecting_dataset(&dir, true),
    )
    .unwrap_err();
    assert!(
        matches!(e, naocalib::output::WriteError::Input { .. }),
        "{e}"
    );
    assert!(Dataset::load(&dir).is_ok());
    let names: Vec<_> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(
        names.iter().all(|n| !n.starts_with(".naocalib-")),
        "{names:?}"
    );
}

#[test]
fn cli_batch_matches_cli_solve_and_exits_non_zero_on_failure() {
    let tmp = tempfile::tempdir().unwrap();
    let good = tmp.path().join("nao/a");
    small(31, None).write(&good, false).unwrap();
    let broken = tmp.path().join("nao/b");
    std::fs::create_dir_all(&broken).unwrap();
    std::fs::write(broken.join("dataset.toml"), "[camera]\n").unwrap();
    let out = Command::cargo_bin("naocalib")
        .unwrap()
        .args(["batch", "--json"])
        .arg(tmp.path().join("nao"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2), "{out:?}");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("dataset.toml"), "{stderr}");
    let batch: Value = serde_json::from_slice(&out.stdout).unwrap();
    let solve = Command::cargo_bin("naocalib")
        .unwrap()
        .args(["solve", "--json"])
        .arg(&good)
        .output()
        .unwrap();
    assert!(solve.status.success());
    let solve: Value = serde_json::from_slice(&solve.stdout).unwrap();
    let run = &batch["runs"][0];
    assert_eq!(run["dataset"], solve["dataset"]);
    let (bp, sp) = (
        run["parameters"].as_object().unwrap(),
        solve["parameters"].as_object().unwrap(),
    );
    assert_eq!(bp.keys().collect::<Vec<_>>(), sp.keys().collect::<Vec<_>>());
    for (name, b) in bp {
        let s = &sp[name];
        assert_eq!(b["value"], s["value"], "{name}");
        assert_eq!(b["unit"], s["unit"], "{name}");
        assert_eq!(b["fixed"], s["fixed"], "{name}");
        let (x, y) = (b["std"].as_f64().unwrap(), s["std"].as_f64().unwrap());
        assert!(close(x, y), "{name}: std {x} vs {y}");
    }
    assert_eq!(run["rms_px"], solve["rms_px"]);
    assert_eq!(run["iterations"], solve["iterations"]);
    assert_eq!(
        batch["summary"]["failures"][0]["dataset"],
        broken.display().to_string()
    );
    // The human table, with the good run only: exit 0.
    let out = Command::cargo_bin("naocalib")
        .unwrap()
        .arg("batch")
        .arg(&good)
        .output()
        .unwrap();
    assert!(out.status.success(), "{out:?}");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("CamYaw") && text.contains("rms x"), "{text}");
}

/// `batch --loss huber --bootstrap N` runs each dataset as `solve` with the same options:
/// the same values, the same outliers, a bootstrap std for every free parameter.
#[test]
fn cli_batch_loss_and_bootstrap_match_cli_solve() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("nao/a");
    let mut ds = small(41, None);
    // Three gross outliers, 25 px off.
    for k in [5, 60, 150] {
        ds.corners[k].pixel[0] += 25.0;
    }
    ds.write(&dir, false).unwrap();
    let run = |args: &[&str]| -> Value {
        let out = Command::cargo_bin("naocalib")
            .unwrap()
            .args(args)
            .args(["--json", "--loss", "huber", "--bootstrap", "4"])
            .arg(if args[0] == "batch" {
                tmp.path().join("nao")
            } else {
                dir.clone()
            })
            .output()
            .unwrap();
        assert!(out.status.success(), "{out:?}");
        serde_json::from_slice(&out.stdout).unwrap()
    };
    let batch = run(&["batch", "--no-progress"]);
    let solve = run(&["solve"]);
    let b = &batch["runs"][0];
    assert_eq!(
        b["outliers"].as_array().unwrap().len(),
        3,
        "{}",
        b["outliers"]
    );
    assert_eq!(b["outliers"], solve["outliers"]);
    for (name, p) in b["parameters"].as_object().unwrap() {
        let s = &solve["parameters"][name];
        assert_eq!(p["value"], s["value"], "{name}");
        if p.get("fixed").is_none() {
            let (x, y) = (
                p["std_bootstrap"].as_f64().unwrap(),
                s["std_bootstrap"].as_f64().unwrap(),
            );
            assert!(x > 0.0 && close(x, y), "{name}: bootstrap std {x} vs {y}");
        }
    }
}
