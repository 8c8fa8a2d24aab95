//! `naocalib plan` for both cameras: a `camera` column (only when some capture is upper),
//! the upper camera's rotation offsets determined to 0.025° by a 144-capture plan while the
//! 15 lower-camera and leg offsets stay within 10 % of a lower-only plan, every upper capture
//! feasible by the same rules (its box of offsets centred on the robot's calibration), every
//! move collision-free, and `--cameras` defaulting to both when the dataset names an upper
//! camera.

use naocalib::model::{Camera, CameraId, Model, PARAMETER_COUNT, Param};
use naocalib::plan::{self, Plan, PlanOptions, feasible, is_angle_offset};

use crate::plan_moves::assert_every_move_is_free;
use crate::util::{assert_clean_failure, naocalib, stderr};

/// The default robot with an upper camera (the NAO V6's 640×480 at the lower one's focal
/// length).
fn two_camera_model() -> Model {
    Model {
        upper_camera: Some(Camera {
            width: 640,
            height: 480,
            fx: 562.5,
            fy: 562.5,
            cx: 320.0,
            cy: 240.0,
            distortion: [0.0; 5],
        }),
        ..Model::default()
    }
}

fn worst_angle_offset(plan: &Plan) -> f64 {
    plan.prediction
        .free
        .iter()
        .zip(&plan.prediction.std)
        .filter(|(p, _)| is_angle_offset(**p))
        .map(|(_, s)| *s)
        .fold(0.0, f64::max)
}

#[test]
fn a_144_capture_plan_for_both_cameras_meets_the_sigma_targets() {
    let model = two_camera_model();
    let lower = plan::plan(&model, &PlanOptions::default()).expect("lower-only plan");
    assert!(lower.captures.iter().all(|c| c.camera == CameraId::Lower));
    let options = PlanOptions {
        cameras: vec![CameraId::Lower, CameraId::Upper],
        ..PlanOptions::default()
    };
    let both = plan::plan(&model, &options).expect("plan for both cameras");
    assert_eq!(both.captures.len(), 144);
    let upper = both
        .captures
        .iter()
        .filter(|c| c.camera == CameraId::Upper)
        .count();
    let (worst_lower, worst_both) = (worst_angle_offset(&lower), worst_angle_offset(&both));
    let sigma = |p: Param| both.prediction.std_of(p).unwrap().to_degrees();
    eprintln!(
        "{upper} upper captures; UpperCam σ yaw {:.4}° pitch {:.4}° roll {:.4}°; worst of \
         the 15: {:.4}° (lower-only {:.4}°, ratio {:.3}); {:.0} s",
        sigma(Param::UpperCamYaw),
        sigma(Param::UpperCamPitch),
        sigma(Param::UpperCamRoll),
        worst_both.to_degrees(),
        worst_lower.to_degrees(),
        worst_both / worst_lower,
        both.duration
    );
    assert!((24..=72).contains(&upper), "{upper} upper captures");
    for p in CameraId::Upper.rotation_params() {
        assert!(sigma(p) <= 0.025, "{} σ {:.4}°", p.name(), sigma(p));
    }
    assert!(worst_both <= 1.10 * worst_lower);
    assert!(both.duration <= 300.0, "{} s", both.duration);
    // Every capture feasible for its camera; every move collision-free.
    let f = &options.feasibility;
    for c in &both.captures {
        assert_eq!(
            feasible::check_for(&model, c.camera, c.side, &c.joints, f),
            Ok(())
        );
    }
    let postures: Vec<_> = both.captures.iter().map(|c| c.joints).collect();
    assert_every_move_is_free(&model, &postures);
    // The lower camera's captures alone do not determine the upper camera.
    assert_eq!(lower.prediction.std_of(Param::UpperCamYaw), None);
}

/// A robot whose upper camera pitch correction is −8.5° (as the teams' files show): its
/// upper captures are planned around that value and keep the board in view at it, and
/// the plan's CSV names each row's camera, read back as written.
#[test]
fn upper_captures_are_planned_around_the_robots_calibration() {
    let model = two_camera_model();
    let mut centre = [0.0; PARAMETER_COUNT];
    centre[Param::UpperCamPitch.index()] = (-8.5f64).to_radians();
    centre[Param::CamPitch.index()] = (-5.0f64).to_radians();
    let mut options = PlanOptions {
        captures: 24,
        pool_stances: 60,
        upper_pool_stances: 60,
        cameras: vec![CameraId::Lower, CameraId::Upper],
        ..PlanOptions::default()
    };
    options.feasibility.centre = centre;
    let around = plan::plan(&model, &options).expect("plan");
    let upper: Vec<_> = around
        .captures
        .iter()
        .filter(|c| c.camera == CameraId::Upper)
        .collect();
    assert!(!upper.is_empty());
    let mut at_zero = options.feasibility;
    at_zero.centre = [0.0; PARAMETER_COUNT];
    let mut lost_at_zero = 0;
    for c in &upper {
        assert!(feasible::board_in_view_of(
            &model,
            CameraId::Upper,
            c.side,
            &c.joints,
            &options.feasibility
        ));
        lost_at_zero +=
            !feasible::board_in_view_of(&model, CameraId::Upper, c.side, &c.joints, &at_zero)
                as usize;
    }
    // An 8.5° pitch moves the board by about 80 rows: the box around zero would not hold.
    assert!(lost_at_zero > 0, "every upper capture also holds at zero");
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("plan.csv");
    std::fs::write(&path, plan::render_csv(&around.captures)).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(
        text.lines()
            .next()
            .unwrap()
            .ends_with(",RElbowRoll,RWristYaw,camera")
    );
    assert_eq!(plan::read_csv(&path).unwrap(), around.captures);
}

/// Writes the sample's dataset.toml, with an `[upper_camera]` table when `upper`.
fn dataset_toml(dir: &std::path::Path, upper: bool) -> std::path::PathBuf {
    let mut text = std::fs::read_to_string(crate::util::sample().join("dataset.toml")).unwrap();
    if upper {
        text.push_str(
            "\n[upper_camera]\nwidth = 640\nheight = 480\nfx = 562.5\nfy = 562.5\ncx = 320.0\n\
             cy = 240.0\ndistortion = [0.0, 0.0, 0.0, 0.0, 0.0]\n",
        );
    }
    let path = dir.join(if upper { "both.toml" } else { "lower.toml" });
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn cli_plans_both_cameras_when_the_dataset_names_an_upper_camera() {
    let dir = tempfile::tempdir().unwrap();
    let plan_with = |toml: &std::path::Path, extra: &[&str], out: &str| {
        let out = dir.path().join(out);
        let run = naocalib()
            .args(["plan", "--captures", "24", "--pool", "40", "--seed", "3"])
            .args(extra)
            .arg("--camera")
            .arg(toml)
            .arg(&out)
            .output()
            .unwrap();
        (run, out)
    };
    let both = dataset_toml(dir.path(), true);
    let (run, out) = plan_with(&both, &[], "both.csv");
    assert!(run.status.success(), "{}", stderr(&run));
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(stdout.contains("upper camera: the same rules"), "{stdout}");
    assert!(stdout.contains("UpperCamYaw"), "{stdout}");
    let csv = std::fs::read_to_string(&out).unwrap();
    assert!(
        csv.lines()
            .next()
            .unwrap()
            .ends_with(",RElbowRoll,RWristYaw,camera")
    );
    let rows: Vec<&str> = csv.lines().skip(1).collect();
    assert_eq!(rows.len(), 24);
    assert!(rows.iter().any(|r| r.ends_with(",upper")));
    assert!(rows.iter().any(|r| r.ends_with(",lower")));

    // --cameras lower on that dataset, and the default on one without [upper_camera]:
    // the same lower-only plan, without a camera column.
    let (run, lower_of_both) = plan_with(&both, &["--cameras", "lower"], "lower1.csv");
    assert!(run.status.success(), "{}", stderr(&run));
    let lower = dataset_toml(dir.path(), false);
    let (run, lower_only) = plan_with(&lower, &[], "lower2.csv");
    assert!(run.status.success(), "{}", stderr(&run));
    let (a, b) = (
        std::fs::read(&lower_of_both).unwrap(),
        std::fs::read(&lower_only).unwrap(),
    );
    assert_eq!(a, b);
    assert!(!String::from_utf8_lossy(&a).contains("camera"));

    // The upper camera asked for without its intrinsics, and an unknown camera: refused.
    let (run, _) = plan_with(&lower, &["--cameras", "lower,upper"], "no.csv");
    assert_clean_failure(&run, &["upper_camera"]);
    let (run, _) = plan_with(&both, &["--cameras", "middle"], "no.csv");
    assert_clean_failure(&run, &["middle"]);
}
