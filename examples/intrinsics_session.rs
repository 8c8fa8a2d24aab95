//! What a planned session for both cameras with their intrinsics free recovers, on robots as
//! the teams' files show them, measured by repeated simulation (docs/PERFORMANCE.md,
//! "A session for both cameras' intrinsics").
//!
//! Each robot's truth is drawn as SPL teams' per-robot files show robots
//! ([`naocalib::sim::draw_team_truth`]: lower camera pitch −7.8…−3.1°, upper camera pitch
//! −10.2…−2.2°, yaw and roll within ±2° (upper roll ±2.7°), legs within ±2°, sandals as
//! mounted), the head offsets at zero (the fit holds them there), and both cameras' focal
//! lengths 1–3 % off the a-priori value (fx and fy together, within 0.2 % of each other)
//! and their optical centres up to 10 px off. The planner sees only what the robot's files
//! say (the truth's camera angles off by up to 0.3°, the legs by up to 0.5°) and the
//! a-priori intrinsics (the V6 cameras' nominal 56.3° × 43.7° at 640×480); the truth stays
//! hidden. Per robot: a plan within 300 s of robot time for both cameras with the
//! intrinsics free (`plan --families paper,intrinsics --cameras lower,upper --around FILES
//! --offset-deg 1 --budget-s 300`), beside it lower-only 144-capture plans with and without
//! the intrinsics and a plan for both cameras without them (300 s) for comparison; then the session measured REPEATS times
//! (0.1 px, 0.1° joint noise per capture; a board partly out of the true image is lost, as
//! detection loses it) and solved with `--free intrinsics`.
//!
//! ```sh
//! cargo run --release --example intrinsics_session -- [ROBOTS [REPEATS [RATIO [OFFSET_DEG]]]]
//! ```
//!
//! (default 8 robots, 5 sessions each, `--upper-sigma-ratio` 0.88 as `plan`'s default, the
//! lower camera's box of offsets ±1°: the robot's files know its offsets within 0.5°).

use std::time::Instant;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use naocalib::model::{CameraId, Family, FixedSet, Model, PARAMETER_COUNT, Param, ParamGroup};
use naocalib::plan::{self, Plan, PlanOptions};
use naocalib::run::{self, RunOptions};
use naocalib::sim::camera::CameraPreset;
use naocalib::sim::{self, SimOptions};

/// What the robot's files say: the truth's camera angles off by up to 0.3°, its leg offsets
/// by up to 0.5° (what a team's calibration misses); nothing of the sandals or intrinsics.
fn files_of(truth: &[f64; PARAMETER_COUNT], rng: &mut impl Rng) -> [f64; PARAMETER_COUNT] {
    let mut files = [0.0; PARAMETER_COUNT];
    for p in Param::ALL {
        let miss: f64 = match p.group() {
            ParamGroup::Camera | ParamGroup::UpperCamera => 0.3,
            ParamGroup::LeftLeg | ParamGroup::RightLeg => 0.5,
            _ => continue,
        };
        files[p.index()] = truth[p.index()] + rng.random_range(-miss..=miss).to_radians();
    }
    files
}

/// The plan's options: `families` freed beside the paper's, `cameras`, around `files`, the
/// lower camera's box of offsets ±`offset_deg` (`--offset-deg`).
fn options(
    families: &[Family],
    cameras: &[CameraId],
    files: &[f64; PARAMETER_COUNT],
    ratio: f64,
    offset_deg: f64,
) -> PlanOptions {
    let mut fixed = FixedSet::default();
    for f in families {
        for p in f.params() {
            fixed.set(p, false);
        }
    }
    let mut options = PlanOptions {
        fixed,
        cameras: cameras.to_vec(),
        upper_sigma_ratio: ratio,
        ..PlanOptions::default()
    };
    options.feasibility.centre = *files;
    options.feasibility.offset_angle = offset_deg.to_radians();
    options.feasibility.offset_length = offset_deg;
    options
}

/// Drops the captures whose board is not wholly inside the true image (detection would not
/// find it); returns how many.
fn drop_unseen(dataset: &mut naocalib::dataset::Dataset) -> usize {
    let model = dataset.model;
    let cameras: std::collections::BTreeMap<u64, CameraId> =
        dataset.captures.iter().map(|c| (c.id, c.camera)).collect();
    let lost: std::collections::BTreeSet<u64> = dataset
        .corners
        .iter()
        .filter(|c| !model.intrinsics(cameras[&c.capture]).contains(c.pixel, 0.0))
        .map(|c| c.capture)
        .collect();
    dataset.captures.retain(|c| !lost.contains(&c.id));
    dataset.corners.retain(|c| !lost.contains(&c.capture));
    lost.len()
}

/// One parameter's figures over the sessions.
#[derive(Default, Clone)]
struct Figures {
    predicted: Vec<f64>,
    reported: Vec<f64>,
    z: Vec<f64>,
    /// Sessions in which `solve` left it undetermined (held at its nominal value).
    held: usize,
}

fn mean(x: &[f64]) -> f64 {
    x.iter().sum::<f64>() / x.len().max(1) as f64
}

fn rms(x: &[f64]) -> f64 {
    (x.iter().map(|v| v * v).sum::<f64>() / x.len().max(1) as f64).sqrt()
}

/// The worst σ of the 15 lower-camera and leg offsets, and the upper camera's three (deg).
fn angles(plan: &Plan) -> (f64, [f64; 3]) {
    let sigma = |p: Param| plan.prediction.std_of(p).map_or(f64::NAN, f64::to_degrees);
    let worst = Param::ALL[..15]
        .iter()
        .map(|p| sigma(*p))
        .fold(0.0, f64::max);
    (worst, CameraId::Upper.rotation_params().map(sigma))
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let robots: u64 = args.get(1).map_or(8, |a| a.parse().expect("ROBOTS"));
    let repeats: u64 = args.get(2).map_or(5, |a| a.parse().expect("REPEATS"));
    let ratio: f64 = args.get(3).map_or(0.88, |a| a.parse().expect("RATIO"));
    let offset_deg: f64 = args.get(4).map_or(1.0, |a| a.parse().expect("OFFSET_DEG"));
    let model = Model {
        camera: CameraPreset::V6.camera(),
        upper_camera: Some(CameraPreset::V6.camera()),
        ..Model::default()
    };
    let both = [CameraId::Lower, CameraId::Upper];
    let mut figures = vec![Figures::default(); PARAMETER_COUNT];
    // worst 15 (lower only, both, both + I), upper yaw (both, both + I), worst 15 (lower only + I)
    let mut rows: Vec<[f64; 6]> = Vec::new();
    let mut table = Vec::new();
    let mut lost = 0;
    let mut sessions = 0;
    for robot in 1..=robots {
        let mut rng = ChaCha8Rng::seed_from_u64(4000 + robot);
        let truth = sim::draw_team_truth_with_intrinsics(&model, &mut rng);
        let files = files_of(&truth, &mut rng);
        let pitches = format!(
            "lower pitch {:.1}°, upper pitch {:.1}°",
            truth[Param::CamPitch.index()].to_degrees(),
            truth[Param::UpperCamPitch.index()].to_degrees()
        );
        let made = (|| {
            let lower = plan::plan(
                &model,
                &options(&[], &[CameraId::Lower], &files, ratio, offset_deg),
            )?;
            let lower_intrinsics = plan::plan(
                &model,
                &options(
                    &[Family::Intrinsics],
                    &[CameraId::Lower],
                    &files,
                    ratio,
                    offset_deg,
                ),
            )?;
            let (paper, _, _) = plan::request::narrowing_the_upper_box(
                options(&[], &both, &files, ratio, offset_deg),
                plan::request::UPPER_OFFSET_DEG,
                |o| plan::plan_within(&model, o, 300.0, None),
            )?;
            let start = Instant::now();
            let intrinsics = options(&[Family::Intrinsics], &both, &files, ratio, offset_deg);
            // As `naocalib plan` does: the upper camera's box narrowed if it must be.
            let (planned, _, narrowed) = plan::request::narrowing_the_upper_box(
                intrinsics,
                plan::request::UPPER_OFFSET_DEG,
                |o| plan::plan_within(&model, o, 300.0, None),
            )?;
            Ok::<_, plan::PlanError>((
                lower,
                lower_intrinsics,
                paper,
                planned,
                start.elapsed().as_secs_f64(),
                narrowed,
            ))
        })();
        let (lower, lower_intrinsics, paper, planned, seconds, narrowed) = match made {
            Ok(made) => made,
            Err(e) => {
                table.push(format!("robot {robot}: {pitches}: no plan: {e}"));
                continue;
            }
        };
        let (w_lower, _) = angles(&lower);
        let (w_lower_i, _) = angles(&lower_intrinsics);
        let (w_paper, u_paper) = angles(&paper);
        let (w_intr, u_intr) = angles(&planned);
        rows.push([w_lower, w_paper, w_intr, u_paper[0], u_intr[0], w_lower_i]);
        let upper_count = planned
            .captures
            .iter()
            .filter(|c| c.camera == CameraId::Upper)
            .count();
        table.push(format!(
            "robot {robot}: {pitches}; {} captures ({} upper) in {:.1} s of robot time, planned in {seconds:.1} s; worst of 15 {w_lower:.4}° / {w_lower_i:.4}° / {w_paper:.4}° / {w_intr:.4}° (lower only 144 / lower only 144 + intrinsics / both / both + intrinsics); UpperCam {:.4}/{:.4}/{:.4}°{}",
            planned.captures.len(),
            upper_count,
            planned.duration,
            u_intr[0], u_intr[1], u_intr[2],
            narrowed.map_or(String::new(), |b| format!("; the upper camera's box narrowed to ±{b}°")),
        ));
        let (stances, cameras) = plan::to_schedule(&planned.captures);
        for repeat in 0..repeats {
            let seed = robot * 100 + repeat;
            let mut dataset = sim::simulate(
                &model,
                &SimOptions {
                    seed,
                    px_noise: 0.1,
                    joint_noise: 0.1f64.to_radians(),
                    truth: Some(truth),
                    schedule: Some(stances.clone()),
                    schedule_cameras: cameras.clone(),
                    ..SimOptions::default()
                },
            )
            .expect("simulated");
            lost += drop_unseen(&mut dataset);
            if let Some(dir) = std::env::var_os("KEEP") {
                let dir = std::path::PathBuf::from(dir).join(format!("r{robot}-{repeat}"));
                dataset.write(&dir, true).expect("written");
            }
            let run = run::calibrate(
                &dataset,
                &RunOptions {
                    fixed: FixedSet::from_lists("intrinsics", "").expect("families"),
                    ..RunOptions::default()
                },
            )
            .expect("solved");
            sessions += 1;
            let s = &run.solution;
            for p in Param::ALL {
                let f = &mut figures[p.index()];
                let held = s.undetermined.iter().any(|u| u.param == p);
                f.held += held as usize;
                if held || s.fixed.is_fixed(p) || !s.fixed.in_model(p) {
                    continue;
                }
                f.predicted
                    .push(planned.prediction.std_of(p).unwrap_or(f64::NAN));
                f.reported.push(s.std[p.index()]);
                f.z.push((s.values[p.index()] - truth[p.index()]) / s.std[p.index()]);
            }
        }
    }
    for line in &table {
        println!("{line}");
    }
    println!(
        "\n{sessions} sessions ({robots} robots × {repeats}), {lost} captures lost off the true image; --upper-sigma-ratio {ratio}\n"
    );
    println!(
        "| parameter | unit | predicted σ | reported σ (mean) | RMS error | mean err/σ | RMS err/σ | held |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- |");
    let mut all_z: Vec<f64> = Vec::new();
    for p in Param::ALL {
        let f = &figures[p.index()];
        if f.z.is_empty() && f.held == 0 {
            continue;
        }
        let u = p.unit();
        let err: Vec<f64> = f.z.iter().zip(&f.reported).map(|(z, s)| z * s).collect();
        println!(
            "| {} | {} | {:.4} | {:.4} | {:.4} | {:+.2} | {:.2} | {} |",
            p.name(),
            u.name(),
            u.to_report(mean(&f.predicted)),
            u.to_report(mean(&f.reported)),
            u.to_report(rms(&err)),
            mean(&f.z),
            rms(&f.z),
            f.held
        );
        all_z.extend(&f.z);
    }
    let beyond3 = all_z.iter().filter(|z| z.abs() > 3.0).count();
    println!(
        "\nerr/σ over {} estimates: mean {:+.3}, RMS {:.3}, beyond 3σ {beyond3}",
        all_z.len(),
        mean(&all_z),
        rms(&all_z)
    );
    let col = |k: usize| mean(&rows.iter().map(|r| r[k]).collect::<Vec<_>>());
    let worst = |k: usize| rows.iter().map(|r| r[k]).fold(0.0, f64::max);
    println!(
        "predicted worst σ of the 15 (mean / worst robot): lower only 144 {:.4}/{:.4}°, both 300 s {:.4}/{:.4}°, both + intrinsics 300 s {:.4}/{:.4}° ({:+.1} % of lower only); UpperCamYaw both {:.4}°, both + intrinsics {:.4}/{:.4}°",
        col(0),
        worst(0),
        col(1),
        worst(1),
        col(2),
        worst(2),
        100.0 * (col(2) / col(0) - 1.0),
        col(3),
        col(4),
        worst(4)
    );
    println!(
        "lower only 144 with intrinsics free: {:.4}/{:.4}°; both + intrinsics {:+.1} % of it",
        col(5),
        worst(5),
        100.0 * (col(2) / col(5) - 1.0)
    );
}
