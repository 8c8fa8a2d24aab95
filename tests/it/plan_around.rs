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
