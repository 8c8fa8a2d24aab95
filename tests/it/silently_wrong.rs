//! Nothing silently wrong: a column that resembles a known one is refused by every reader
//! of captures (solve, capture's plan) before anything is read further or moved; a plan
//! names exactly the parameters its design leaves undetermined; every reader of a
//! calibration to start from (`solve --start-from`, `detect --start-from`, `plan
//! --around`) applies one plausibility rule, and a robot's team file (any format) or a
//! file that is no calibration is pointed to `naocalib import`.

use std::path::{Path, PathBuf};

use naocalib::export::{Entry, Posture};
use naocalib::model::Param;

use crate::capture::{Bench, plan_file};
use crate::util::{assert_clean_failure, naocalib, sample, stderr};

/// `text` (a CSV) with a column `name` holding `value` in every row added at the end.
fn with_column(text: &str, name: &str, value: &str) -> String {
    let mut out = String::new();
    for (k, line) in text.lines().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        out.push_str(line);
        out.push(',');
        out.push_str(if k == 0 { name } else { value });
        out.push('\n');
    }
    out
}

/// A near miss of the `camera` column (any case, a letter off) is refused with the
/// column and the known one named: by solve on a dataset, and by capture on a plan before
/// the robot is even reached (no LoLA runs here) and before any file is written.
#[test]
fn a_near_miss_of_a_known_column_is_refused_before_anything_moves() {
    for name in ["Camera", "CAMERA", "camra", "cameras"] {
        // A dataset.
        let dir = tempfile::tempdir().unwrap();
        let ds = dir.path().join("ds");
        std::fs::create_dir(&ds).unwrap();
        for file in ["dataset.toml", "corners.csv"] {
            std::fs::copy(sample().join(file), ds.join(file)).unwrap();
        }
        let captures = std::fs::read_to_string(sample().join("captures.csv")).unwrap();
        std::fs::write(
            ds.join("captures.csv"),
            with_column(&captures, name, "lower"),
        )
        .unwrap();
        let out = naocalib().arg("solve").arg(&ds).output().unwrap();
        let field = format!("captures.csv line 1, field {name}");
        assert_clean_failure(&out, &[field.as_str(), "did you mean 'camera'"]);

        // A plan given to capture.
        let b = Bench::new();
        let plan = b.path("plan.csv");
        plan_file(&plan, 2, 3);
        let text = std::fs::read_to_string(&plan).unwrap();
        std::fs::write(&plan, with_column(&text, name, "upper")).unwrap();
        let out = b
            .capture(&plan, "ds", "no-robot.sock", &b.fixed_camera(), &[])
            .output()
            .unwrap();
        let field = format!("plan.csv line 1, field {name}");
        assert_clean_failure(&out, &[field.as_str(), "did you mean 'camera'"]);
        assert!(!b.path("ds").exists(), "{name}: a dataset was begun");
    }
}

/// Runs `naocalib plan` for `config` with `args`; its stdout.
fn plan_report(config: &Path, out: &Path, args: &[&str]) -> String {
    let run = naocalib()
        .arg("plan")
        .arg(out)
        .arg("--camera")
        .arg(config)
        .args(["--pool", "30", "--force"])
        .args(args)
        .output()
        .unwrap();
    assert!(run.status.success(), "{args:?}: {}", stderr(&run));
    String::from_utf8(run.stdout).unwrap()
}

/// The parameters a plan's table shows as undetermined (its first σ column), and what its
/// "plan:" line says: whether every parameter is determined, and the ones it names.
fn undetermined_in(report: &str) -> (Vec<String>, bool, Vec<String>) {
    let table: Vec<String> = report
        .lines()
        .filter(|l| l.split_whitespace().nth(2) == Some("undet."))
        .map(|l| l.split_whitespace().next().unwrap().to_string())
        .collect();
    let line = report.lines().find(|l| l.starts_with("plan: ")).unwrap();
    let all = line.contains("every free parameter determined");
    let named = line
        .split("free parameters undetermined: ")
        .nth(1)
        .map(|list| list.split(", ").map(str::to_string).collect())
        .unwrap_or_default();
    (table, all, named)
}

/// A plan says exactly which parameters its design leaves undetermined, whatever the
/// cause: too few captures (two, with both cameras), or a camera without captures (the
/// lower camera of `--cameras upper`, named among them); "every free parameter determined"
/// only when none.
#[test]
fn a_plan_names_exactly_the_parameters_its_design_leaves_undetermined() {
    let dir = tempfile::tempdir().unwrap();
    let config = dir.path().join("dataset.toml");
    let mut text = std::fs::read_to_string(sample().join("dataset.toml")).unwrap();
    text.push_str(
        "\n[upper_camera]\nwidth = 640\nheight = 480\nfx = 562.5\nfy = 562.5\ncx = 320.0\n\
         cy = 240.0\n",
    );
    std::fs::write(&config, text).unwrap();
    let out = dir.path().join("plan.csv");
    for (args, expected) in [
        (&["--captures", "2"][..], None),
        (
            &["--captures", "4", "--cameras", "upper"][..],
            Some(["CamYaw", "CamPitch", "CamRoll"]),
        ),
    ] {
        let report = plan_report(&config, &out, args);
        let (table, all, named) = undetermined_in(&report);
        assert!(!table.is_empty(), "{args:?}: {report}");
        assert!(!all, "{args:?}: said every parameter determined\n{report}");
        assert_eq!(named, table, "{args:?}: {report}");
        if let Some(expected) = expected {
            for p in expected {
                assert!(
                    named.iter().any(|n| n == p),
                    "{args:?}: {p} not named: {report}"
                );
            }
        }
    }
}

/// A calibration with every value 0 but `param` at `value` (report units).
fn calibration_with(dir: &Path, param: Param, value: f64) -> PathBuf {
    let cal = crate::util::converged_calibration(Posture::Lying, |p| Entry {
        param: p,
        value: if p == param { value } else { 0.0 },
        std: Some(0.05),
        fixed: false,
    });
    let path = dir.join(format!("{}-{value}.toml", param.name()));
    std::fs::write(&path, cal.to_toml()).unwrap();
    path
}

/// One plausibility rule for every reader of a calibration to start from: a value beyond
/// its physical bound (any parameter, either sign) is refused by `solve --start-from` and
/// `plan --around` alike, with the same words; a team's robot file given to `plan --around`
/// is pointed to `naocalib import`.
#[test]
fn every_reader_of_a_start_calibration_applies_one_plausibility_rule() {
    let dir = tempfile::tempdir().unwrap();
    let config = dir.path().join("dataset.toml");
    let mut text = std::fs::read_to_string(sample().join("dataset.toml")).unwrap();
    text.push_str(
        "\n[upper_camera]\nwidth = 640\nheight = 480\nfx = 562.5\nfy = 562.5\ncx = 320.0\n\
         cy = 240.0\n",
    );
    std::fs::write(&config, text).unwrap();
    for (param, value) in [
        (Param::UpperCamPitch, 45.0),
        (Param::CamYaw, -31.0),
        (Param::LKneePitch, 40.0),
    ] {
        let cal = calibration_with(dir.path(), param, value);
        let needle = format!("{} = {value}", param.name());
        let solve = naocalib()
            .arg("solve")
            .arg(sample())
            .arg("--start-from")
            .arg(&cal)
            .output()
            .unwrap();
        assert_clean_failure(
            &solve,
            &[needle.as_str(), "not a calibration to start from"],
        );
        let plan = naocalib()
            .arg("plan")
            .arg(dir.path().join("p.csv"))
            .arg("--camera")
            .arg(&config)
            .arg("--around")
            .arg(&cal)
            .output()
            .unwrap();
        assert_clean_failure(&plan, &[needle.as_str(), "not a calibration to start from"]);
        assert!(!dir.path().join("p.csv").exists());
    }
    let team = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/teams/bhuman/cameraCalibration.cfg");
    let plan = naocalib()
        .arg("plan")
        .arg(dir.path().join("p.csv"))
        .arg("--camera")
        .arg(&config)
        .arg("--around")
        .arg(&team)
        .output()
        .unwrap();
    assert_clean_failure(&plan, &["cameraCalibration.cfg", "naocalib import"]);
}

/// Every robot's file naocalib knows (every team format of the registry, as `solve
/// --export` writes it), and a file that is no calibration at all, given as the
/// calibration to start from — `solve --start-from`, `detect --start-from`, `plan
/// --around` — is refused at once, naming the file and pointing to `naocalib import`,
/// never with only a parser's "expected value at line 1 column 1".
#[test]
fn every_reader_of_a_start_calibration_points_a_robots_file_to_import() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("d");
    let out = naocalib()
        .args([
            "simulate",
            "--stances",
            "6",
            "--heads",
            "2",
            "--upper-stances",
            "2",
        ])
        .arg(&data)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let export = dir.path().join("export");
    let out = naocalib()
        .args([
            "solve",
            "--solver",
            "lm",
            "--plain-std",
            "--free",
            "intrinsics",
        ])
        .arg("--export")
        .arg(&export)
        .arg(&data)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let garbage = dir.path().join("notes.cfg");
    std::fs::write(&garbage, "robot 23 is calibrated, see the log\n").unwrap();
    let mut files: Vec<(String, PathBuf)> = naocalib::export::FORMATS
        .iter()
        .filter(|f| f.robot())
        .map(|f| (f.name().to_string(), export.join(f.file())))
        .collect();
    files.push(("no calibration".into(), garbage));
    for (format, file) in files {
        assert!(file.exists(), "{format}: {} not written", file.display());
        let name = file.file_name().unwrap().to_str().unwrap().to_string();
        let solve = naocalib()
            .args(["solve", "--start-from"])
            .arg(&file)
            .arg(&data)
            .output()
            .unwrap();
        let plan = naocalib()
            .args(["plan", "--captures", "4", "--around"])
            .arg(&file)
            .arg(dir.path().join("p.csv"))
            .output()
            .unwrap();
        let mut outs = vec![("solve", solve), ("plan", plan)];
        if cfg!(feature = "detect") {
            let detect = naocalib()
                .args(["detect", "--force", "--start-from"])
                .arg(&file)
                .arg(&data)
                .output()
                .unwrap();
            outs.push(("detect", detect));
        }
        for (reader, out) in outs {
            let err = stderr(&out);
            assert_eq!(out.status.code(), Some(1), "{format}, {reader}: {err}");
            for needle in [name.as_str(), "naocalib import"] {
                assert!(err.contains(needle), "{format}, {reader}: {needle}: {err}");
            }
        }
        assert!(!dir.path().join("p.csv").exists());
    }
}

/// A parameter a run did not determine (the lower camera of an upper-camera-only run, the
/// upper camera of a lower-camera-only run) takes no part in the batch's statistics or
/// drift: each camera's mean is the one run's that saw it, and no drift is reported for
/// either camera between the two runs; the run's column reads `undet.`, not a value.
#[test]
fn batch_statistics_and_drift_leave_out_what_a_run_did_not_determine() {
    let dir = tempfile::tempdir().unwrap();
    let (lower, mixed, upper) = (
        dir.path().join("lo"),
        dir.path().join("mix"),
        dir.path().join("up"),
    );
    for (out, args) in [
        (&lower, &["--seed", "3", "--stances", "12"][..]),
        (
            &mixed,
            &["--seed", "4", "--stances", "4", "--upper-stances", "12"][..],
        ),
    ] {
        let run = naocalib()
            .arg("simulate")
            .arg(out)
            .args(args)
            .output()
            .unwrap();
        assert!(run.status.success(), "{}", stderr(&run));
    }
    // The upper camera's captures of the mixed dataset alone.
    std::fs::create_dir(&upper).unwrap();
    std::fs::copy(mixed.join("dataset.toml"), upper.join("dataset.toml")).unwrap();
    let captures = std::fs::read_to_string(mixed.join("captures.csv")).unwrap();
    let header = captures.lines().next().unwrap();
    let camera = header.split(',').position(|c| c == "camera").unwrap();
    let kept: Vec<&str> = captures
        .lines()
        .skip(1)
        .filter(|l| l.split(',').nth(camera) == Some("upper"))
        .collect();
    let ids: Vec<&str> = kept.iter().map(|l| l.split(',').next().unwrap()).collect();
    std::fs::write(
        upper.join("captures.csv"),
        format!("{header}\n{}\n", kept.join("\n")),
    )
    .unwrap();
    let corners = std::fs::read_to_string(mixed.join("corners.csv")).unwrap();
    let corners: Vec<&str> = corners
        .lines()
        .enumerate()
        .filter(|(k, l)| *k == 0 || ids.contains(&l.split(',').next().unwrap()))
        .map(|(_, l)| l)
        .collect();
    std::fs::write(upper.join("corners.csv"), corners.join("\n") + "\n").unwrap();

    let batch = |json: bool| {
        let mut c = naocalib();
        c.arg("batch").arg(&lower).arg(&upper).args([
            "--robots",
            "all",
            "--drift",
            "first",
            "--no-progress",
        ]);
        if json {
            c.arg("--json");
        }
        let run = c.output().unwrap();
        assert!(run.status.success(), "{}", stderr(&run));
        String::from_utf8(run.stdout).unwrap()
    };
    let json: serde_json::Value = serde_json::from_str(&batch(true)).unwrap();
    let stats = &json["summary"]["parameters"];
    for name in [
        "CamYaw",
        "CamPitch",
        "CamRoll",
        "UpperCamYaw",
        "UpperCamPitch",
        "UpperCamRoll",
    ] {
        assert_eq!(stats[name]["n"], 1, "{name}: {}", stats[name]);
        assert!(stats[name]["std"].is_null(), "{name}: {}", stats[name]);
    }
    let pairs = json["summary"]["drift"]["pairs"].as_array().unwrap();
    assert_eq!(pairs.len(), 1);
    let drifted = pairs[0]["parameters"].as_object().unwrap();
    assert!(!drifted.is_empty());
    for name in drifted.keys() {
        assert!(!name.contains("Cam"), "{name} drifts: {}", drifted[name]);
    }
    let text = batch(false);
    let row = text.lines().find(|l| l.starts_with("CamYaw ")).unwrap();
    assert_eq!(row.split_whitespace().nth(3), Some("undet."), "{row}");
}

/// A plan search that cannot succeed ends with an error that says why, within its budget
/// of draws (no time asserted): an upper camera whose box of offsets no capture survives
/// (±3°), and a robot whose upper camera sits at the edge of the plausible (−30°).
#[test]
fn a_plan_search_that_cannot_succeed_ends_with_why() {
    let dir = tempfile::tempdir().unwrap();
    let config = dir.path().join("dataset.toml");
    let mut text = std::fs::read_to_string(sample().join("dataset.toml")).unwrap();
    text.push_str(
        "\n[upper_camera]\nwidth = 640\nheight = 480\nfx = 562.5\nfy = 562.5\ncx = 320.0\n\
         cy = 240.0\n",
    );
    std::fs::write(&config, text).unwrap();
    let around = calibration_with(dir.path(), Param::UpperCamPitch, -30.0);
    for args in [
        vec!["--upper-offset-deg".to_string(), "3".to_string()],
        vec!["--around".to_string(), around.display().to_string()],
    ] {
        let out = naocalib()
            .arg("plan")
            .arg(dir.path().join("p.csv"))
            .arg("--camera")
            .arg(&config)
            .args(["--captures", "8", "--pool", "20"])
            .args(&args)
            .output()
            .unwrap();
        assert_clean_failure(&out, &["feasible upper-camera captures", "draws"]);
        assert!(!dir.path().join("p.csv").exists(), "{args:?}");
    }
}
