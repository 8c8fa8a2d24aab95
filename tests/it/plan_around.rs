//! `plan --around`: stances designed around a robot's current calibration keep the board in
//! view for every offset within ±3° of the robot's values — a lower-camera tilt correction
//! of −7°, which the default box of ±3° around zero does not hold.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use naocalib::model::{Model, PARAMETER_COUNT, Param};
use naocalib::plan::{self, Plan, PlanOptions};

/// The robot as it is: tilt correction −7°, roll 2.5°, leg offsets up to 2°.
fn robot() -> [f64; PARAMETER_COUNT] {
    let mut centre = [0.0; PARAMETER_COUNT];
    for (p, deg) in [
        (Param::CamPitch, -7.0f64),
        (Param::CamRoll, 2.5),
        (Param::CamYaw, -1.0),
        (Param::LKneePitch, 1.5),
        (Param::RHipPitch, -2.0),
        (Param::LAnkleRoll, 1.0),
    ] {
        centre[p.index()] = deg.to_radians();
    }
    centre
}

fn small_plan(centre: [f64; PARAMETER_COUNT]) -> Plan {
    let mut options = PlanOptions {
        captures: 24,
        pool_stances: 60,
        ..PlanOptions::default()
    };
    options.feasibility.centre = centre;
    plan::plan(&Model::default(), &options).expect("plan")
}

/// How many of `plan`'s captures lose a vertex (or face away) for some of 200 offset draws
/// within ±3° (±3 mm) around `centre`.
fn captures_losing_the_board(plan: &Plan, centre: &[f64; PARAMETER_COUNT]) -> usize {
    let model = Model::default();
    let vertices: Vec<_> = model.board.vertices().collect();
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let bound = 3f64.to_radians();
    let margin = naocalib::plan::Feasibility::default().margin_px;
    plan.captures
        .iter()
        .filter(|c| {
            let chains = model.chains(c.side, &c.joints);
            (0..200).any(|k| {
                let mut params = *centre;
                let mut angles = vec![Param::CamYaw, Param::CamPitch, Param::CamRoll];
                angles.extend(c.side.leg_joints().map(|j| j.offset()));
                for p in angles {
                    params[p.index()] += if k % 10 == 0 {
                        if rng.random_bool(0.5) { bound } else { -bound }
                    } else {
                        rng.random_range(-bound..=bound)
                    };
                }
                model
                    .project(&chains, &params, &vertices)
                    .iter()
                    .any(|p| p.is_none_or(|p| !model.camera.contains(p, margin)))
            })
        })
        .count()
}

#[test]
fn stances_planned_around_the_robot_keep_its_board_in_view() {
    let centre = robot();
    let around = small_plan(centre);
    assert_eq!(around.captures.len(), 24);
    assert_eq!(captures_losing_the_board(&around, &centre), 0);
    let at_zero = small_plan([0.0; PARAMETER_COUNT]);
    let lost = captures_losing_the_board(&at_zero, &centre);
    assert!(
        lost > 0,
        "the plan around zero happens to hold this robot too ({lost} captures lost)"
    );
}

/// A robot at the edge of SPQR's per-robot files (upper camera pitch −10.2°), whose upper
/// camera sees its right sandal only for offsets within less than ±0.5° of its files: the
/// plan narrows the upper camera's box of offsets, says so and plans, unless the box was
/// asked for, then it says that no capture of the right leg stays in view.
#[test]
fn the_upper_cameras_box_is_narrowed_only_when_no_capture_stays_in_view() {
    use naocalib::export::{Entry, Posture};
    use naocalib::plan::request::{PlanRequest, run};
    let dir = tempfile::tempdir().unwrap();
    let files: [(Param, f64); 18] = [
        (Param::CamYaw, 1.384),
        (Param::CamPitch, -4.738),
        (Param::CamRoll, 0.537),
        (Param::LHipYawPitch, -0.627),
        (Param::LHipRoll, 0.889),
        (Param::LHipPitch, 0.530),
        (Param::LKneePitch, 1.149),
        (Param::LAnklePitch, 0.585),
        (Param::LAnkleRoll, 0.122),
        (Param::RHipYawPitch, -1.133),
        (Param::RHipRoll, 1.228),
        (Param::RHipPitch, 0.986),
        (Param::RKneePitch, 0.301),
        (Param::RAnklePitch, -2.301),
        (Param::RAnkleRoll, 1.462),
        (Param::UpperCamYaw, -0.010),
        (Param::UpperCamPitch, -10.216),
        (Param::UpperCamRoll, 0.036),
    ];
    let cal = crate::util::converged_calibration(Posture::Lying, |p| Entry {
        param: p,
        value: files.iter().find(|(q, _)| *q == p).map_or(0.0, |(_, v)| *v),
        std: Some(0.05),
        fixed: false,
    });
    let around = dir.path().join("nao.toml");
    std::fs::write(&around, cal.to_toml()).unwrap();
    let camera = dir.path().join("dataset.toml");
    let v6 = "width = 640\nheight = 480\nfx = 598.3\nfy = 598.0\ncx = 320.0\ncy = 240.0\n";
    std::fs::write(&camera, format!("[camera]\n{v6}\n[upper_camera]\n{v6}")).unwrap();
    let request = |upper_offset_deg| PlanRequest {
        out: dir.path().join("plan.csv"),
        force: true,
        captures: Some(24),
        budget_s: None,
        families: vec![naocalib::model::Family::Paper],
        px_noise: 0.1,
        joint_noise_deg: 0.1,
        seed: 1,
        camera: Some(camera.clone()),
        offset_deg: 1.0,
        cameras: None,
        upper_offset_deg,
        upper_sigma_ratio: 0.88,
        pool: 40,
        around: Some(around.clone()),
        sight: false,
    };
    let asked = run(&request(Some(0.5))).expect_err("no capture in view over ±0.5°");
    let text = asked.to_string();
    assert!(
        text.contains("upper-camera captures for the right leg"),
        "{text}"
    );
    let planned = run(&request(None)).expect("planned with a narrower box");
    let narrowed = planned.narrowed.expect("narrowed");
    assert!((0.125..0.5).contains(&narrowed), "{narrowed}");
    let upper = planned
        .plan
        .captures
        .iter()
        .filter(|c| c.camera == naocalib::model::CameraId::Upper)
        .count();
    assert!(upper > 0, "no upper captures");
    let report = naocalib::plan::report::summary(&request(None), &planned);
    assert!(
        report.contains(&format!("narrowed to ±{narrowed}°")),
        "{report}"
    );
}
