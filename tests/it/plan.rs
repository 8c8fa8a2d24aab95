//! `naocalib plan`: planned stances are feasible on an uncalibrated robot, determine the
//! offsets better than the simulator's random stances, free compliance and play, and run
//! through the CLI and `simulate --stance-file`.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use naocalib::model::{Family, FixedSet, Joint, JointAngles, Model, PARAMETER_COUNT, Param, Side};
use naocalib::plan::{self, Feasibility, Infeasible, PlanOptions, feasible};
use naocalib::sim::{self, SimOptions};
use naocalib::solve::{Problem, UncertaintyOptions, backend, backend_names, calibrate};

use crate::util::{assert_clean_failure, naocalib, paper_plan, stderr};

/// The 15 angle offsets: camera rotation and the 12 leg joints.
fn angle_offsets() -> Vec<Param> {
    Param::ALL[..15].to_vec()
}

#[test]
fn planned_stances_are_within_limits_and_collision_free() {
    let plan = paper_plan();
    let model = Model::default();
    let f = Feasibility::default();
    assert_eq!(plan.captures.len(), 144);
    for c in &plan.captures {
        for j in Joint::ALL {
            let (lo, hi) = j.limits();
            let q = c.joints.get(j);
            assert!(
                q >= lo + f.joint_margin && q <= hi - f.joint_margin,
                "{} = {q} outside [{lo}, {hi}] less the margin",
                j.name()
            );
        }
        assert_eq!(
            c.joints.get(Joint::LHipYawPitch),
            c.joints.get(Joint::RHipYawPitch)
        );
        assert_eq!(
            plan::collision::collision(&model.robot, &f.body, &c.joints),
            None
        );
        assert_eq!(feasible::check(&model, c.side, &c.joints, &f), Ok(()));
    }
    // Both legs are measured.
    for side in Side::BOTH {
        assert!(plan.captures.iter().filter(|c| c.side == side).count() >= 36);
    }
}

#[test]
fn planned_boards_stay_in_view_for_random_offsets_of_three_degrees() {
    let plan = paper_plan();
    let model = Model::default();
    let f = Feasibility::default();
    let vertices: Vec<_> = model.board.vertices().collect();
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let bound = 3f64.to_radians();
    let mut draws = 0;
    for c in &plan.captures {
        let chains = model.chains(c.side, &c.joints);
        for k in 0..100 {
            let mut params = [0.0; PARAMETER_COUNT];
            // The head offsets (not in the paper's model) within ±0.5°.
            for p in [Param::HeadYaw, Param::HeadPitch] {
                params[p.index()] = rng.random_range(-f.head_offset..=f.head_offset);
            }
            let mut angles: Vec<Param> = vec![Param::CamYaw, Param::CamPitch, Param::CamRoll];
            angles.extend(c.side.leg_joints().map(|j| j.offset()));
            let [rot_z, tx, ty] = c.side.board_params();
            angles.push(rot_z);
            for p in angles {
                // Every tenth draw at a corner of the box, the others inside it.
                params[p.index()] = if k % 10 == 0 {
                    if rng.random_bool(0.5) { bound } else { -bound }
                } else {
                    rng.random_range(-bound..=bound)
                };
            }
            params[tx.index()] = rng.random_range(-3.0..=3.0);
            params[ty.index()] = rng.random_range(-3.0..=3.0);
            let uv = model.project(&chains, &params, &vertices);
            for p in &uv {
                let p = p.expect("in front of the camera");
                assert!(
                    model.camera.contains(p, f.margin_px),
                    "capture {c:?}: vertex at {p:?} with offsets {params:?}"
                );
            }
            // Facing the camera: the line of sight within 60° of the board normal.
            let pose = chains.camera_to_board(&params);
            let to_camera: Vec<f64> = (0..3)
                .map(|j| {
                    -(0..3)
                        .map(|i| pose.rotation[i][j] * pose.translation[i])
                        .sum::<f64>()
                })
                .collect();
            let dist = to_camera.iter().map(|x| x * x).sum::<f64>().sqrt();
            assert!(to_camera[2] / dist >= f.max_view_angle.cos());
            draws += 1;
        }
    }
    assert_eq!(draws, 14_400);
}

#[test]
fn known_colliding_and_unseen_stances_are_refused() {
    let model = Model::default();
    let f = Feasibility::default();
    let base = paper_plan().captures[0];
    let with = |pairs: &[(Joint, f64)]| {
        let mut j: JointAngles = base.joints;
        for (joint, v) in pairs {
            j.set(*joint, *v);
        }
        j
    };
    use Joint::*;
    // Both hips rolled inward: the legs cross.
    let crossed = with(&[
        (LHipRoll, -0.27),
        (RHipRoll, 0.27),
        (LHipPitch, -0.3),
        (RHipPitch, -0.3),
    ]);
    assert!(matches!(
        feasible::check(&model, base.side, &crossed, &f),
        Err(Infeasible::Collision(_))
    ));
    // A straight leg pushed back into the floor.
    let floor = with(&[
        (LHipPitch, 0.39),
        (LKneePitch, 0.0),
        (RHipPitch, 0.39),
        (RKneePitch, 0.0),
    ]);
    match feasible::check(&model, base.side, &floor, &f) {
        Err(Infeasible::Collision(what)) => assert!(what.contains("floor"), "{what}"),
        other => panic!("expected a floor collision, got {other:?}"),
    }
    // Two motors for one joint.
    let split = with(&[(LHipYawPitch, -0.2), (RHipYawPitch, -0.1)]);
    assert_eq!(
        feasible::check(&model, base.side, &split, &f),
        Err(Infeasible::HipYawPitch)
    );
    // Too close to a limit.
    let (lo, _) = LKneePitch.limits();
    let limit = with(&[(LKneePitch, lo + 0.01)]);
    assert_eq!(
        feasible::check(&model, base.side, &limit, &f),
        Err(Infeasible::Limits(LKneePitch))
    );
    // The head turned away from the board.
    // (towards yaw 0, where the head's pitch range is widest).
    let yaw = base.joints.get(HeadYaw);
    let away = with(&[(HeadYaw, yaw - 0.4 * yaw.signum())]);
    assert_eq!(
        feasible::check(&model, base.side, &away, &f),
        Err(Infeasible::View)
    );
}

#[test]
fn planning_past_the_body_refuses_a_posture_the_body_model_puts_in_contact() {
    use Joint::*;
    let model = Model::default();
    // The left leg raised and rolled out, the right one parked flexed: the collision
    // model's capsules pass, the body model's thighs touch.
    let mut joints = JointAngles::default();
    for (joint, q) in [
        (LHipYawPitch, 0.0451),
        (RHipYawPitch, 0.0451),
        (LHipRoll, 0.4576),
        (LHipPitch, -0.7102),
        (LAnklePitch, -0.393),
        (LAnkleRoll, 0.5269),
        (RHipRoll, -0.3),
        (RHipPitch, -0.9),
        (RKneePitch, 1.6),
        (RAnklePitch, -0.7),
    ] {
        joints.set(joint, q);
    }
    let plain = Feasibility::default();
    let refused = feasible::check(&model, Side::Left, &joints, &plain);
    assert!(
        !matches!(refused, Err(Infeasible::Collision(_))),
        "{refused:?}"
    );
    let past = Feasibility {
        sight: Some(naocalib::body::BodyModel::default()),
        ..Feasibility::default()
    };
    match feasible::check(&model, Side::Left, &joints, &past) {
        Err(Infeasible::Collision(what)) => assert!(what.contains("thigh"), "{what}"),
        other => panic!("{other:?}"),
    }
}

/// The scatter (robust std across runs, degrees) of each of the 15 angle offsets over
/// `runs` calibrations of datasets simulated with `options` and new noise each time.
fn scatter(options: &SimOptions, runs: u64) -> Vec<f64> {
    let model = Model::default();
    let solver = backend(backend_names()[0], false).expect("a backend");
    let offsets = angle_offsets();
    let mut estimates: Vec<Vec<f64>> = vec![Vec::new(); offsets.len()];
    for run in 0..runs {
        let dataset = sim::simulate(
            &model,
            &SimOptions {
                noise_seed: Some(1000 + run),
                ..options.clone()
            },
        )
        .expect("simulate");
        let problem = Problem::from_dataset(&dataset, FixedSet::default()).expect("problem");
        let solution =
            calibrate(&problem, solver.as_ref(), &UncertaintyOptions::default()).expect("solve");
        for (k, p) in offsets.iter().enumerate() {
            estimates[k].push(solution.report_value(*p));
        }
    }
    // A robust scale (1.4826 × the median absolute deviation): in about one run in 20 the
    // misfit tests flag clean data (their family-wise level is 5 %), the noise model is
    // then set aside and that run's plain least-squares fit, several times less efficient
    // under joint noise, lands a knee or hip pitch several σ away; such a run does not
    // decide the scale.
    let median = |xs: &mut Vec<f64>| {
        xs.sort_by(f64::total_cmp);
        xs[xs.len() / 2]
    };
    estimates
        .iter()
        .map(|xs| {
            let m = median(&mut xs.clone());
            1.4826 * median(&mut xs.iter().map(|x| (x - m).abs()).collect())
        })
        .collect()
}

#[test]
fn plan_lowers_the_worst_scatter_of_the_angle_offsets() {
    let plan = paper_plan();
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let truth = sim::draw_truth(&mut rng);
    let common = SimOptions {
        seed: 5,
        px_noise: 0.1,
        joint_noise: 0.1f64.to_radians(),
        truth: Some(truth),
        ..SimOptions::default()
    };
    // 120 runs per design: at 40 the worst of 15 robust scales is too noisy to judge a 2×
    // target (40 runs gave 1.76×; 200 runs 2.05×).
    let runs = 120;
    let planned = scatter(
        &SimOptions {
            schedule: Some(plan::to_stances(&plan.captures)),
            ..common.clone()
        },
        runs,
    );
    let random = scatter(&common, runs);
    // The prediction agrees with the scatter, parameter by parameter: on average over the
    // 15 (each robust scale from 120 runs is off by about 10 %).
    let mean_ratio = |measured: &[f64], p: &plan::Prediction| {
        angle_offsets()
            .iter()
            .zip(measured)
            .map(|(q, m)| m / p.std_of(*q).expect("free").to_degrees())
            .sum::<f64>()
            / 15.0
    };
    let (agree_plan, agree_random) = (
        mean_ratio(&planned, &plan.prediction),
        mean_ratio(&random, &plan.baseline),
    );
    eprintln!("measured/predicted σ, mean of 15: plan {agree_plan:.2}, random {agree_random:.2}");
    assert!((agree_plan - 1.0).abs() < 0.2, "plan: {agree_plan}");
    assert!((agree_random - 1.0).abs() < 0.2, "random: {agree_random}");
    let (planned, random) = (
        planned.iter().copied().fold(0.0, f64::max),
        random.iter().copied().fold(0.0, f64::max),
    );
    eprintln!(
        "worst scatter of the 15 angle offsets over {runs} runs: plan {planned:.4}°, random \
         {random:.4}°, ratio {:.2}",
        random / planned
    );
    let worst = |p: &plan::Prediction| {
        angle_offsets()
            .iter()
            .map(|q| p.std_of(*q).expect("free").to_degrees())
            .fold(0.0, f64::max)
    };
    let (predicted, predicted_random) = (worst(&plan.prediction), worst(&plan.baseline));
    eprintln!(
        "predicted worst σ: plan {predicted:.4}°, random {predicted_random:.4}°, ratio {:.2}",
        predicted_random / predicted
    );
    // The design's promise: half the random stances' worst σ.
    assert!(
        predicted_random >= 2.0 * predicted,
        "predicted: plan {predicted}°, random {predicted_random}°"
    );
    // Measured: 2.01× with these seeds; the bound leaves room for
    // the sampling error of 120 runs (about 10 % on each robust scale). Random stances
    // against themselves give 1.0.
    assert!(random >= 1.8 * planned, "plan {planned}°, random {random}°");
}

#[test]
fn compliance_and_play_are_determined_with_144_planned_captures() {
    let mut fixed = FixedSet::default();
    for family in [Family::Compliance, Family::Play] {
        for p in family.params() {
            fixed.set(p, false);
        }
    }
    // With the default bounds of ±3°: the stances that load a HipRoll the other way need a
    // positive HipYawPitch, with the resting leg flexed off the floor.
    let options = PlanOptions {
        fixed,
        ..PlanOptions::default()
    };
    assert_eq!(options.feasibility.offset_angle, 3f64.to_radians());
    let plan = plan::plan(&Model::default(), &options).expect("plan");
    assert_eq!(plan.captures.len(), 144);
    let p = &plan.prediction;
    assert_eq!(p.free.len(), 45);
    assert!(
        p.undetermined.is_empty(),
        "undetermined: {:?}",
        p.undetermined
    );
    assert_eq!(p.rank, 45);
    assert!(p.std.iter().all(|s| s.is_finite() && *s > 0.0));
}

#[test]
fn cli_plans_simulates_and_solves() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("plan.csv");
    let run = naocalib()
        .args(["plan", "--captures", "24", "--pool", "40", "--seed", "3"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(run.status.success(), "{}", stderr(&run));
    let text = String::from_utf8_lossy(&run.stdout);
    assert!(
        text.contains("predicted one-sigma") && text.contains("measurement phase"),
        "{text}"
    );
    let csv = std::fs::read_to_string(&out).unwrap();
    let mut lines = csv.lines();
    let header = lines.next().unwrap();
    assert!(header.starts_with("capture,board,HeadYaw,HeadPitch,LHipYawPitch"));
    assert!(header.ends_with("RAnkleRoll,LShoulderPitch,LShoulderRoll,LElbowYaw,LElbowRoll,LWristYaw,RShoulderPitch,RShoulderRoll,RElbowYaw,RElbowRoll,RWristYaw") && !header.contains("image"));
    assert_eq!(lines.count(), 24);

    // Not replaced without --force.
    let again = naocalib()
        .args(["plan", "--captures", "24"])
        .arg(&out)
        .output()
        .unwrap();
    assert_clean_failure(&again, &["exists", "--force"]);

    let data = dir.path().join("data");
    let sim = naocalib()
        .args(["simulate", "--joint-noise-deg", "0.1", "--stance-file"])
        .arg(&out)
        .arg(&data)
        .output()
        .unwrap();
    assert!(sim.status.success(), "{}", stderr(&sim));
    let dataset = naocalib::dataset::Dataset::load(&data).unwrap();
    let planned = plan::read_csv(&out).unwrap();
    assert_eq!(dataset.captures.len(), 24);
    for (c, p) in dataset.captures.iter().zip(&planned) {
        assert_eq!((c.side, c.joints), (p.side, p.joints));
    }
    assert_eq!(dataset.corners.len(), 24 * 24);
    let solve = naocalib()
        .args(["solve", "--json"])
        .arg(&data)
        .output()
        .unwrap();
    assert!(solve.status.success(), "{}", stderr(&solve));
}

#[test]
fn cli_refuses_bad_input_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("plan.csv");
    let bad = naocalib()
        .args(["plan", "--families", "paper,elasticity"])
        .arg(&out)
        .output()
        .unwrap();
    assert_clean_failure(&bad, &["elasticity"]);
    assert!(!out.exists());
    // A broken plan: the file, line and field are named.
    let mut text = String::from("capture,board");
    for j in Joint::ALL {
        text.push(',');
        text.push_str(j.name());
    }
    text.push_str("\n0,left");
    for j in Joint::ALL {
        text.push_str(if j == Joint::LKneePitch {
            ",abc"
        } else {
            ",0.1"
        });
    }
    text.push('\n');
    std::fs::write(&out, text).unwrap();
    let sim = naocalib()
        .args(["simulate", "--stance-file"])
        .arg(&out)
        .arg(dir.path().join("data"))
        .output()
        .unwrap();
    assert_clean_failure(&sim, &["plan.csv", "line 2", "LKneePitch"]);
    assert!(!dir.path().join("data").exists());
}

/// The default plan photographed by robots whose own body stands between the camera and
/// the boards (`simulate --body`): every vertex the plan's audit predicts in plain sight
/// (`body::sight`, the parts grown for the offsets, at the nominal model) is seen on
/// robots with hidden offsets, the body hides most of the rest, and the calibration on
/// the partial boards left stays honest (its offsets within their σ).
#[test]
fn the_body_hides_the_plans_vertices_as_predicted_and_the_fit_stays_honest() {
    use naocalib::body::{BodyModel, sight};
    use std::collections::HashSet;
    let plan = paper_plan();
    let model = Model::default();
    let body = BodyModel::default();
    let solver = backend(backend_names()[0], false).expect("a backend");
    let zero = [0.0; PARAMETER_COUNT];
    let mut z2 = Vec::new();
    for seed in [21, 22, 23] {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let truth = sim::draw_truth(&mut rng);
        let options = SimOptions {
            seed,
            truth: Some(truth),
            px_noise: 0.1,
            schedule: Some(plan::to_stances(&plan.captures)),
            body: Some(body),
            ..SimOptions::default()
        };
        let dataset = sim::simulate(&model, &options).expect("simulate");
        let seen: HashSet<_> = dataset
            .corners
            .iter()
            .map(|c| (c.capture, c.vertex))
            .collect();
        let all = dataset.captures.len() * model.board.vertices().count();
        let mut predicted = 0;
        for c in &dataset.captures {
            for v in sight::in_sight(&model, &body, c.camera, c.side, &c.joints, &zero) {
                predicted += 1;
                assert!(
                    seen.contains(&(c.id, v)),
                    "seed {seed}: capture {} vertex {v:?} predicted in sight, hidden",
                    c.id
                );
            }
        }
        eprintln!(
            "seed {seed}: {} of {all} vertices seen past the body, {predicted} predicted in sight",
            seen.len()
        );
        assert!(
            predicted > 300 && seen.len() < all / 2,
            "{predicted} {}",
            seen.len()
        );
        let problem = Problem::from_dataset(&dataset, FixedSet::default()).expect("problem");
        let solution =
            calibrate(&problem, solver.as_ref(), &UncertaintyOptions::default()).expect("solve");
        for p in solution.fixed.free() {
            let z = (solution.values[p.index()] - truth[p.index()]) / solution.std[p.index()];
            z2.push(z * z);
        }
    }
    let rms_z = (z2.iter().sum::<f64>() / z2.len() as f64).sqrt();
    eprintln!("RMS z of {} offsets: {rms_z:.2}", z2.len());
    assert!(rms_z <= 1.5, "RMS z {rms_z}");
}

/// A plan made past the body (`naocalib plan`) keeps at least half of every board in plain
/// sight, and photographed by a robot whose body stands in its own way (`simulate
/// --body`) it determines the offsets as it predicts, many times better than the default
/// plan photographed the same way.
#[test]
fn a_plan_past_the_body_is_seen_and_determines_the_offsets_as_predicted() {
    use naocalib::body::{BodyModel, sight};
    let model = Model::default();
    let body = BodyModel::default();
    let mut options = PlanOptions::default();
    options.feasibility.sight = Some(body);
    let planned = plan::plan(&model, &options).expect("plan");
    let zero = [0.0; PARAMETER_COUNT];
    let of = model.board.vertices().count();
    for (k, c) in planned.captures.iter().enumerate() {
        let seen = sight::in_sight(&model, &body, c.camera, c.side, &c.joints, &zero).len();
        assert!(2 * seen >= of, "capture {k}: {seen} of {of} in sight");
    }
    // Planned past the body, no capture brings two of its parts into contact (the default
    // plan, held against the same body, does: see docs/BODY.md).
    assert!(
        planned.body.contacts.is_empty(),
        "{:?}",
        planned.body.contacts
    );
    assert!(!paper_plan().body.contacts.is_empty());
    // Nor does any move between them, walked in the body model.
    assert_eq!(planned.body.moves, planned.captures.len() + 1);
    assert!(
        planned.body.moves_through_contact.is_empty(),
        "{:?}",
        planned.body.moves_through_contact
    );
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let truth = sim::draw_truth(&mut rng);
    let past_body = |captures: &[plan::PlannedCapture]| SimOptions {
        seed: 5,
        px_noise: 0.1,
        joint_noise: 0.1f64.to_radians(),
        truth: Some(truth),
        schedule: Some(plan::to_stances(captures)),
        body: Some(body),
        ..SimOptions::default()
    };
    let runs = 60;
    let measured = scatter(&past_body(&planned.captures), runs);
    let ratios: Vec<f64> = angle_offsets()
        .iter()
        .zip(&measured)
        .map(|(q, m)| m / planned.prediction.std_of(*q).expect("free").to_degrees())
        .collect();
    let mean = ratios.iter().sum::<f64>() / ratios.len() as f64;
    let worst = measured.iter().copied().fold(0.0, f64::max);
    // The default plan past the body: one calibration's σ (honest, as
    // `the_body_hides_the_plans_vertices_as_predicted_and_the_fit_stays_honest` checks).
    let dataset = sim::simulate(&model, &past_body(&paper_plan().captures)).expect("simulate");
    let problem = Problem::from_dataset(&dataset, FixedSet::default()).expect("problem");
    let solver = backend(backend_names()[0], false).expect("a backend");
    let solution =
        calibrate(&problem, solver.as_ref(), &UncertaintyOptions::default()).expect("solve");
    let default_worst = angle_offsets()
        .iter()
        .map(|q| solution.report_std(*q))
        .fold(0.0, f64::max);
    eprintln!(
        "past the body: measured/predicted σ, mean of 15: {mean:.2}; worst scatter {worst:.4}° \
         over {runs} runs; the default plan's worst σ {default_worst:.4}°"
    );
    assert!((mean - 1.0).abs() < 0.2, "measured/predicted {mean}");
    assert!(default_worst > 5.0 * worst, "{default_worst}° vs {worst}°");
}
