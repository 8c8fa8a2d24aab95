//! Both cameras in one session: the upper camera's chain, its parameters recovered from
//! noise-free data by every backend, honest uncertainties on robots as the teams' files show
//! them, datasets with a `camera` column and `[upper_camera]` read and written, and a clear
//! error for an upper capture without the upper camera's intrinsics.

use naocalib::dataset::Dataset;
use naocalib::model::{CameraId, Family, FixedSet, JointAngles, Model, PARAMETER_COUNT, Param};
use naocalib::sim::{SimOptions, simulate};
use naocalib::solve::{Problem, UncertaintyOptions, backend, calibrate};

use crate::util::{assert_clean_failure, naocalib, run, stderr};

/// 12 lower-camera and `upper` upper-camera stances per leg, two head postures each.
fn both_cameras(seed: u64, upper: usize, px: f64, joint_deg: f64) -> SimOptions {
    SimOptions {
        seed,
        stances: 12,
        heads: 2,
        upper_stances: upper,
        px_noise: px,
        joint_noise: joint_deg.to_radians(),
        ..SimOptions::default()
    }
}

/// A model whose upper camera has its own intrinsics (the V6 field of view at 640×480).
fn two_camera_model() -> Model {
    Model {
        upper_camera: Some(naocalib::sim::camera::CameraPreset::V6.camera()),
        ..Model::default()
    }
}

/// The upper camera's chain at zero offsets is the NAO V6 mount of docs/MODEL.md, computed
/// here independently with nalgebra: `T(0, 0, 211.5) · Rz(yaw) · Ry(pitch) · T(58.71, 0,
/// 63.64) · Ry(1.2°)`; each UpperCam* parameter turns it about its own axis.
#[test]
fn the_upper_camera_chain_is_the_v6_mount() {
    use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
    let mut joints = JointAngles::default();
    joints.set(naocalib::model::Joint::HeadYaw, 0.4);
    joints.set(naocalib::model::Joint::HeadPitch, 0.3);
    let geometry = naocalib::model::RobotGeometry::default();
    let chain = geometry.upper_camera_chain(&joints);
    let ry = |a: f64| UnitQuaternion::from_axis_angle(&Vector3::y_axis(), a);
    let rx = |a: f64| UnitQuaternion::from_axis_angle(&Vector3::x_axis(), a);
    let rz = |a: f64| UnitQuaternion::from_axis_angle(&Vector3::z_axis(), a);
    let (yaw, pitch, roll) = (0.01, -0.15, 0.03);
    let mut params = [0.0; PARAMETER_COUNT];
    params[Param::UpperCamYaw.index()] = yaw;
    params[Param::UpperCamPitch.index()] = pitch;
    params[Param::UpperCamRoll.index()] = roll;
    let expected = Isometry3::from_parts(Translation3::new(0.0, 0.0, 211.5), rz(0.4))
        * Isometry3::from_parts(Translation3::identity(), ry(0.3))
        * Isometry3::from_parts(
            Translation3::new(58.71, 0.0, 63.64),
            ry(1.2f64.to_radians()),
        )
        * Isometry3::rotation(Vector3::y() * pitch)
        * Isometry3::from_parts(Translation3::identity(), rx(roll))
        * Isometry3::from_parts(Translation3::identity(), rz(yaw));
    let pose = chain.eval(&params);
    let m = expected.to_homogeneous();
    for i in 0..3 {
        assert!((pose.translation[i] - m[(i, 3)]).abs() < 1e-9, "{pose:?}");
        for j in 0..3 {
            assert!((pose.rotation[i][j] - m[(i, j)]).abs() < 1e-12, "{pose:?}");
        }
    }
    // The lower camera's offsets do not move the upper camera, and the reverse.
    assert_eq!(
        chain.params(),
        [
            Param::NeckZ,
            Param::HeadYaw,
            Param::HeadPitch,
            Param::UpperCamPitch,
            Param::UpperCamRoll,
            Param::UpperCamYaw
        ]
    );
    let lower = geometry.camera_chain_of(CameraId::Lower, &joints).params();
    assert!(!lower.iter().any(|p| p.family() == Family::UpperCamera));
}

/// Noise-free data from both cameras: every parameter recovered to 1e-6 (report units)
/// from zero, by Ceres and by the pure-Rust backends.
#[test]
fn noise_free_both_cameras_recover_every_parameter() {
    let dataset = simulate(&two_camera_model(), &both_cameras(11, 3, 0.0, 0.0)).expect("sim");
    assert_eq!(
        dataset
            .captures
            .iter()
            .filter(|c| c.camera == CameraId::Upper)
            .count(),
        12
    );
    let truth = dataset.truth.as_ref().expect("truth");
    for p in CameraId::Upper.rotation_params() {
        assert!(truth.report_value(p).abs() > 0.01, "{p} drawn");
    }
    let problem = Problem::from_dataset(&dataset, FixedSet::default()).expect("problem");
    let free = problem.free();
    assert_eq!(free.len(), 24, "{free:?}");
    let mut backends = vec!["lm", "tiny"];
    if cfg!(feature = "ceres") {
        backends.push("ceres");
    }
    for name in backends {
        let b = backend(name, false).expect("backend");
        let s = crate::util::solve(&problem, b.as_ref()).expect("solved");
        for &p in &free {
            let err = s.report_value(p) - truth.report_value(p);
            assert!(err.abs() < 1e-6, "{name}: {p} off by {err:e}");
        }
    }
}

/// Both cameras' intrinsics off their a-priori values (focal lengths 1–2 %, centres up to
/// 9 px) in a noise-free session of both cameras with `--free intrinsics`: every free
/// parameter, the eight intrinsics among them, is recovered to 1e-6 (report units) from the
/// a-priori values, by Ceres and by the pure-Rust backends alike.
#[test]
fn noise_free_both_cameras_recover_both_cameras_intrinsics() {
    let model = two_camera_model();
    let drawn = simulate(&model, &both_cameras(11, 3, 0.0, 0.0)).expect("sim");
    let mut truth = drawn.truth.as_ref().expect("truth").values;
    for (p, px) in [
        (Param::Fx, 9.0),
        (Param::Fy, -6.0),
        (Param::Cx, 4.0),
        (Param::Cy, -7.5),
        (Param::UpperFx, -11.0),
        (Param::UpperFy, 8.0),
        (Param::UpperCx, -9.0),
        (Param::UpperCy, 6.5),
    ] {
        truth[p.index()] = px;
    }
    let options = SimOptions {
        truth: Some(truth),
        ..both_cameras(11, 3, 0.0, 0.0)
    };
    let dataset = simulate(&model, &options).expect("sim");
    let fixed = FixedSet::from_lists("intrinsics", "").expect("families");
    let problem = Problem::from_dataset(&dataset, fixed).expect("problem");
    let free = problem.free();
    assert_eq!(free.len(), 32, "{free:?}");
    assert!(free.contains(&Param::UpperFx) && free.contains(&Param::UpperCy));
    let mut backends = vec!["lm", "tiny"];
    if cfg!(feature = "ceres") {
        backends.push("ceres");
    }
    for name in backends {
        let b = backend(name, false).expect("backend");
        let s = crate::util::solve(&problem, b.as_ref()).expect("solved");
        assert!(s.undetermined.is_empty(), "{name}: {:?}", s.undetermined);
        for &p in &free {
            let err = s.report_value(p) - p.unit().to_report(truth[p.index()]);
            assert!(err.abs() < 1e-6, "{name}: {p} off by {err:e}");
        }
    }
}

/// Ceres' autodiff through the shim agrees with the Rust model on upper-camera captures:
/// residuals and Jacobian of a problem with both cameras, at a point away from zero.
#[cfg(feature = "ceres")]
#[test]
fn ceres_evaluates_the_upper_camera_as_rust_does() {
    let dataset = simulate(&two_camera_model(), &both_cameras(5, 2, 0.1, 0.0)).expect("sim");
    let fixed = FixedSet::from_lists("head,intrinsics", "").expect("families");
    let problem = Problem::from_dataset(&dataset, fixed).expect("problem");
    let x: Vec<f64> = problem
        .free()
        .iter()
        .enumerate()
        .map(|(k, _)| 0.01 * ((k * 7 % 5) as f64 - 2.0))
        .collect();
    let (r_rust, j_rust) = crate::util::brute_force_jacobian(&problem, &x);
    let (r_ceres, j_ceres) = naocalib::solve::ceres::evaluate(&problem, &x).expect("evaluated");
    assert_eq!(r_rust.len(), r_ceres.len());
    for (a, b) in r_rust.iter().zip(&r_ceres) {
        assert!((a - b).abs() < 1e-9, "{a} vs {b}");
    }
    let scale = j_rust.amax();
    assert!((j_rust - j_ceres).amax() < 1e-9 * scale);
}

/// The upper camera's parameters are free only with upper captures, and `--fix` holds
/// them even then.
#[test]
fn upper_parameters_are_free_only_with_upper_captures() {
    let lower = simulate(&Model::default(), &both_cameras(2, 0, 0.1, 0.0)).expect("sim");
    let both = simulate(&two_camera_model(), &both_cameras(2, 1, 0.1, 0.0)).expect("sim");
    let upper = CameraId::Upper.rotation_params();
    let p = Problem::from_dataset(&lower, FixedSet::default()).expect("problem");
    assert!(
        upper
            .iter()
            .all(|&u| p.fixed.is_fixed(u) && !p.fixed.in_model(u))
    );
    let p = Problem::from_dataset(&lower, FixedSet::from_lists("upper_camera", "").unwrap())
        .expect("problem");
    assert!(upper.iter().all(|&u| p.fixed.is_fixed(u)));
    let p = Problem::from_dataset(&both, FixedSet::default()).expect("problem");
    assert!(upper.iter().all(|&u| !p.fixed.is_fixed(u)));
    let p = Problem::from_dataset(&both, FixedSet::from_lists("", "UpperCamRoll").unwrap())
        .expect("problem");
    assert!(p.fixed.is_fixed(Param::UpperCamRoll) && p.fixed.in_model(Param::UpperCamRoll));
    assert!(!p.fixed.is_fixed(Param::UpperCamYaw));
    // `--free intrinsics` frees the upper camera's only with upper captures.
    let intrinsics = || FixedSet::from_lists("intrinsics,distortion", "").unwrap();
    let upper_projection = CameraId::Upper.projection_params();
    let p = Problem::from_dataset(&lower, intrinsics()).expect("problem");
    assert!(
        upper_projection
            .iter()
            .all(|&u| p.fixed.is_fixed(u) && !p.fixed.in_model(u))
    );
    assert!(
        CameraId::Lower
            .projection_params()
            .iter()
            .all(|&l| !p.fixed.is_fixed(l))
    );
    let p = Problem::from_dataset(&both, intrinsics()).expect("problem");
    assert!(
        upper_projection
            .iter()
            .all(|&u| !p.fixed.is_fixed(u) && p.fixed.in_model(u))
    );
    let p = Problem::from_dataset(&both, FixedSet::default()).expect("problem");
    assert!(upper_projection.iter().all(|&u| !p.fixed.in_model(u)));
}

/// Robots as the teams' files show them (upper-camera pitch down to −10.2°, head offsets up
/// to 6.8°, legs up to 2°; truth hidden from the solve): over repeated simulations with
/// fixed seeds, err/σ of every estimated parameter is consistent with N(0, 1): its RMS
/// lies within the 99.9 % χ² bounds for the number of estimates, and no |err/σ| exceeds 4.5.
#[test]
fn team_robots_give_honest_sigmas_with_both_cameras() {
    let solver = backend(naocalib::solve::backend_names()[0], false).expect("a backend");
    let mut z = Vec::new();
    for seed in 1..=12u64 {
        let options = SimOptions {
            seed: 700 + seed,
            stances: 20,
            heads: 3,
            upper_stances: 4,
            px_noise: 0.1,
            joint_noise: 0.1f64.to_radians(),
            team_offsets: true,
            ..SimOptions::default()
        };
        let dataset = simulate(&two_camera_model(), &options).expect("sim");
        let truth = dataset.truth.clone().expect("truth").values;
        let mut hidden = dataset.clone();
        hidden.truth = None;
        let fixed = FixedSet::from_lists("head", "").expect("head");
        let problem = Problem::from_dataset(&hidden, fixed).expect("problem");
        let s =
            calibrate(&problem, solver.as_ref(), &UncertaintyOptions::default()).expect("solved");
        assert!(
            s.undetermined.is_empty(),
            "seed {seed}: {:?}",
            s.undetermined
        );
        for p in problem.free() {
            let sigma = s.std[p.index()];
            z.push((s.values[p.index()] - truth[p.index()]) / sigma);
        }
    }
    let n = z.len() as f64;
    let rms = (z.iter().map(|x| x * x).sum::<f64>() / n).sqrt();
    // Wilson–Hilferty: χ²_n/n ≈ (1 − 2/(9n) ± 3.09·√(2/(9n)))³ at 99.9 %.
    let k = 2.0 / (9.0 * n);
    let (lo, hi) = (
        (1.0 - k - 3.09 * k.sqrt()).powi(3).sqrt(),
        (1.0 - k + 3.09 * k.sqrt()).powi(3).sqrt(),
    );
    let worst = z.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    eprintln!("RMS err/σ {rms:.3} over {n} estimates (bounds {lo:.3}…{hi:.3}), worst {worst:.2}");
    assert!(
        (lo..=hi).contains(&rms) && worst < 4.5,
        "RMS err/σ {rms:.3} over {n} estimates (bounds {lo:.3}…{hi:.3}), worst {worst:.2}"
    );
}

/// A dataset with upper captures is written with a `camera` column and `[upper_camera]`,
/// and reads back as it was; one without is written without either.
#[test]
fn the_camera_column_and_upper_camera_round_trip() {
    let tmp = tempfile::tempdir().unwrap();
    let both = simulate(&two_camera_model(), &both_cameras(4, 1, 0.1, 0.0)).expect("sim");
    let dir = tmp.path().join("both");
    both.write(&dir, false).unwrap();
    let captures = std::fs::read_to_string(dir.join("captures.csv")).unwrap();
    assert!(
        captures.starts_with("capture,board,image,camera,HeadYaw,"),
        "{captures}"
    );
    assert!(captures.contains(",upper,") && captures.contains(",lower,"));
    let toml = std::fs::read_to_string(dir.join("dataset.toml")).unwrap();
    assert!(toml.contains("[upper_camera]") && toml.contains("upper_camera_tilt_deg"));
    let truth = std::fs::read_to_string(dir.join("truth.toml")).unwrap();
    assert!(truth.contains("UpperCamPitch = "));
    let mut back = Dataset::load(&dir).unwrap();
    back.dir = both.dir.clone();
    for c in &mut back.captures {
        c.line = 0;
    }
    for c in &mut back.corners {
        c.line = 0;
    }
    assert_eq!(back.model, both.model);
    assert_eq!(back.captures, both.captures);
    assert_eq!(back.truth, both.truth);

    // Upper captures of a model without upper intrinsics were taken with the lower
    // camera's, and the dataset says so.
    let borrowed = simulate(&Model::default(), &both_cameras(4, 1, 0.1, 0.0)).expect("sim");
    assert_eq!(borrowed.model.upper_camera, Some(Model::default().camera));
    borrowed.write(&tmp.path().join("borrowed"), false).unwrap();

    let lower = simulate(&Model::default(), &both_cameras(4, 0, 0.1, 0.0)).expect("sim");
    assert_eq!(lower.model.upper_camera, None);
    let dir = tmp.path().join("lower");
    lower.write(&dir, false).unwrap();
    let captures = std::fs::read_to_string(dir.join("captures.csv")).unwrap();
    assert!(captures.starts_with("capture,board,image,HeadYaw,"));
    for file in ["dataset.toml", "truth.toml", "captures.csv"] {
        let text = std::fs::read_to_string(dir.join(file)).unwrap();
        assert!(!text.to_lowercase().contains("upper"), "{file}: {text}");
    }
}

/// The `camera` column: empty means lower, any other name than lower/upper is an error
/// naming the file, line and field.
#[test]
fn camera_column_values() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let both = simulate(&two_camera_model(), &both_cameras(4, 1, 0.1, 0.0)).expect("sim");
    both.write(dir, false).unwrap();
    let path = dir.join("captures.csv");
    let text = std::fs::read_to_string(&path).unwrap();
    // Every lower row with an empty camera field: the same dataset.
    std::fs::write(&path, text.replace(",lower,", ",,")).unwrap();
    let back = Dataset::load(dir).unwrap();
    assert_eq!(
        back.captures.iter().map(|c| c.camera).collect::<Vec<_>>(),
        both.captures.iter().map(|c| c.camera).collect::<Vec<_>>()
    );
    let line = text.lines().position(|l| l.contains(",upper,")).unwrap() + 1;
    std::fs::write(&path, text.replacen(",upper,", ",top,", 1)).unwrap();
    let e = Dataset::load(dir).unwrap_err().to_string();
    assert!(
        e.contains(&format!(
            "captures.csv line {line}, field camera: unknown camera 'top'"
        )),
        "{e}"
    );
}

/// An upper capture in a dataset without `[upper_camera]`: `solve` and `detect` fail with
/// exit 1, naming captures.csv, the line and the missing table.
#[test]
fn an_upper_capture_needs_the_upper_camera_table() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let both = simulate(&two_camera_model(), &both_cameras(4, 1, 0.1, 0.0)).expect("sim");
    both.write(dir, false).unwrap();
    let toml = std::fs::read_to_string(dir.join("dataset.toml")).unwrap();
    let start = toml.find("[upper_camera]").unwrap();
    let end = start + toml[start..].find("\n\n").unwrap() + 2;
    std::fs::write(
        dir.join("dataset.toml"),
        format!("{}{}", &toml[..start], &toml[end..]),
    )
    .unwrap();
    let captures = std::fs::read_to_string(dir.join("captures.csv")).unwrap();
    let line = captures
        .lines()
        .position(|l| l.contains(",upper,"))
        .unwrap()
        + 1;
    let place = format!("captures.csv line {line}, field camera");
    for args in [&["solve"][..], &["solve", "--json"][..]] {
        let out = run(args, dir);
        assert_clean_failure(&out, &[&place, "upper camera", "[upper_camera]"]);
    }
}

/// `simulate --upper-stances` writes a dataset with both cameras that `solve` calibrates,
/// listing the upper camera's parameters in the table and the JSON; a lower-only one lists
/// none.
#[test]
fn simulate_and_solve_both_cameras_from_the_command_line() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("both");
    let out = naocalib()
        .args([
            "simulate",
            "--stances",
            "8",
            "--heads",
            "2",
            "--upper-stances",
            "2",
        ])
        .args(["--seed", "3", "--joint-noise-deg", "0.1"])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("40 captures") && text.contains("8 with the upper camera"),
        "{text}"
    );
    let out = run(&["solve", "--json"], &dir);
    assert!(out.status.success(), "{}", stderr(&out));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    for p in CameraId::Upper.rotation_params() {
        let entry = &json["parameters"][p.name()];
        assert_ne!(entry["fixed"], true, "{p}: {entry}");
        assert!(entry["std"].as_f64().unwrap() > 0.0, "{p}: {entry}");
        let err = entry["value"].as_f64().unwrap() - entry["truth"].as_f64().unwrap();
        assert!(
            err.abs() < 6.0 * entry["std"].as_f64().unwrap(),
            "{p}: {entry}"
        );
    }
    assert!(
        json["families"]
            .as_array()
            .unwrap()
            .contains(&"upper_camera".into())
    );
    let report = tmp.path().join("report.html");
    let out = naocalib()
        .arg("solve")
        .arg(&dir)
        .arg("--report")
        .arg(&report)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let table = String::from_utf8_lossy(&out.stdout);
    assert!(
        table.contains("UpperCamPitch") && table.contains("upper_camera"),
        "{table}"
    );
    let html = std::fs::read_to_string(&report).unwrap();
    assert!(html.contains("UpperCamRoll") && html.contains("(upper camera)"));

    let lower = tmp.path().join("lower");
    crate::util::simulate_small(&lower, 3);
    let out = run(&["solve", "--json"], &lower);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success() && !text.contains("UpperCam"), "{text}");
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(
        !json["families"]
            .as_array()
            .unwrap()
            .contains(&"upper_camera".into())
    );
    // Held, the upper camera's intrinsics are no part of any result; `--free intrinsics`
    // gives them σ with upper captures and leaves them out without.
    assert!(!text.contains("UpperFx"), "{text}");
    let out = run(&["solve", "--json", "--free", "intrinsics"], &lower);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success() && !text.contains("\"Upper"), "{text}");
    let out = run(&["solve", "--json", "--free", "intrinsics"], &dir);
    assert!(out.status.success(), "{}", stderr(&out));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    for p in CameraId::Upper.projection_params().into_iter().take(4) {
        let entry = &json["parameters"][p.name()];
        assert_eq!(entry["unit"], "px", "{p}: {entry}");
        assert!(entry["std"].as_f64().unwrap() > 0.0, "{p}: {entry}");
    }
    assert!(json["parameters"].get("UpperK1").is_none());
}

/// A plan's `camera` column chooses the camera of each simulated capture.
#[test]
fn simulate_follows_a_plans_camera_column() {
    let tmp = tempfile::tempdir().unwrap();
    let both = simulate(&two_camera_model(), &both_cameras(6, 1, 0.1, 0.0)).expect("sim");
    let source = tmp.path().join("source");
    both.write(&source, false).unwrap();
    let plan = tmp.path().join("plan.csv");
    std::fs::copy(source.join("captures.csv"), &plan).unwrap();
    let dir = tmp.path().join("replay");
    let out = naocalib()
        .args(["simulate", "--stance-file"])
        .arg(&plan)
        .arg("--board")
        .arg(source.join("dataset.toml"))
        .arg(&dir)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let replay = Dataset::load(&dir).unwrap();
    assert!(replay.model.upper_camera.is_some());
    let cameras = |d: &Dataset| d.captures.iter().map(|c| c.camera).collect::<Vec<_>>();
    assert_eq!(cameras(&replay), cameras(&both));
    assert_eq!(
        replay.captures.iter().map(|c| c.joints).collect::<Vec<_>>(),
        both.captures.iter().map(|c| c.joints).collect::<Vec<_>>()
    );
}

/// From rendered images of both cameras to a calibration: `simulate --images` renders the
/// upper captures through the upper camera, `solve --detect` finds their boards by
/// predicting through it, and recovers the upper camera's rotation within 4σ.
#[cfg(feature = "detect")]
#[test]
fn rendered_upper_images_are_detected_and_calibrated() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("images");
    let out = naocalib()
        .args(["simulate", "--images", "--stances", "5", "--heads", "2"])
        .args(["--upper-stances", "3", "--seed", "5"])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let dataset = Dataset::load(&dir).unwrap();
    let upper: Vec<_> = dataset
        .captures
        .iter()
        .filter(|c| c.camera == CameraId::Upper)
        .collect();
    assert_eq!(upper.len(), 12);
    assert!(upper.iter().all(|c| c.image.is_some()));
    let out = run(&["solve", "--detect", "--json"], &dir);
    assert!(out.status.success(), "{}", stderr(&out));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(json["captures"], 32, "every board found");
    for p in CameraId::Upper.rotation_params() {
        let entry = &json["parameters"][p.name()];
        let std = entry["std"].as_f64().unwrap();
        let err = entry["value"].as_f64().unwrap() - entry["truth"].as_f64().unwrap();
        assert!(std > 0.0 && err.abs() < 4.0 * std, "{p}: {entry}");
    }
}
