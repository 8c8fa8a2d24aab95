//! A planned session for both cameras with their intrinsics free, on robots as the teams'
//! files show them: focal lengths 1–3 % and optical centres up to 10 px off the a-priori
//! values, both cameras; camera and leg offsets of the sizes in SPQR's files. The plan is
//! made around what the robot's files say, with the a-priori intrinsics; the truth stays
//! hidden. The whole statistic (many robots, 300 s sessions, the σ table) is
//! `examples/intrinsics_session.rs` (docs/PERFORMANCE.md).

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use naocalib::model::{CameraId, Family, FixedSet, Model, Param};
use naocalib::plan::{self, PlanOptions};
use naocalib::run::{self, RunOptions};
use naocalib::sim::camera::CameraPreset;
use naocalib::sim::{self, SimOptions};

use crate::util::missed_by_a_team;

/// Four robots whose truths differ from one robot's files by what a team's calibration
/// misses, each with its own intrinsics, measured with one plan made around those files
/// (96 captures from a small pool, the lower camera's offsets within ±1° of the files so
/// that its boards sweep the image): every free parameter determined by the plan and by
/// `solve --free intrinsics`, the upper camera's focal lengths to 0.3 px and centre to
/// 0.5 px, and err/σ over every estimate consistent with N(0, 1).
#[test]
fn a_planned_session_recovers_both_cameras_intrinsics_on_team_sized_robots() {
    let model = Model {
        camera: CameraPreset::V6.camera(),
        upper_camera: Some(CameraPreset::V6.camera()),
        ..Model::default()
    };
    let mut rng = ChaCha8Rng::seed_from_u64(40);
    let files = sim::draw_team_truth_with_intrinsics(&model, &mut rng);
    let mut fixed = FixedSet::default();
    for p in Family::Intrinsics.params() {
        fixed.set(p, false);
    }
    let mut options = PlanOptions {
        captures: 96,
        fixed,
        cameras: CameraId::ALL.to_vec(),
        pool_stances: 100,
        upper_pool_stances: 100,
        refine_rounds: 1,
        upper_sigma_ratio: 0.7,
        ..PlanOptions::default()
    };
    // The files know the camera and leg offsets, not the intrinsics.
    for p in Param::ALL
        .into_iter()
        .filter(|p| p.family() == Family::Paper)
    {
        if !matches!(
            p.group(),
            naocalib::model::ParamGroup::LeftBoard | naocalib::model::ParamGroup::RightBoard
        ) {
            options.feasibility.centre[p.index()] = files[p.index()];
        }
    }
    for p in CameraId::Upper.rotation_params() {
        options.feasibility.centre[p.index()] = files[p.index()];
    }
    options.feasibility.offset_angle = 1f64.to_radians();
    options.feasibility.offset_length = 1.0;
    let planned = plan::plan(&model, &options).expect("plan");
    let upper = planned
        .captures
        .iter()
        .filter(|c| c.camera == CameraId::Upper)
        .count();
    assert!(upper > 0 && upper < planned.captures.len());
    let predicted = &planned.prediction;
    assert_eq!(predicted.undetermined_params(), Vec::<Param>::new());
    let px = |p: Param| predicted.std_of(p).expect("free");
    for (p, most) in [
        (Param::UpperFx, 0.3),
        (Param::UpperFy, 0.3),
        (Param::UpperCx, 0.5),
        (Param::UpperCy, 0.5),
    ] {
        assert!(px(p) <= most, "{} predicted σ {} px", p.name(), px(p));
    }
    // The boards sweep both images.
    for c in &planned.coverage {
        assert!(
            c.corners() >= 2,
            "{:?} camera: {} corners",
            c.camera,
            c.corners()
        );
    }

    let (stances, cameras) = plan::to_schedule(&planned.captures);
    let mut z = Vec::new();
    for robot in 0..4u64 {
        let mut truth = missed_by_a_team(&files, &mut rng);
        let own = sim::draw_team_truth_with_intrinsics(&model, &mut rng);
        for camera in CameraId::ALL {
            for p in camera.projection_params() {
                truth[p.index()] = own[p.index()];
            }
        }
        for p in Param::ALL.into_iter().filter(|p| {
            matches!(
                p.group(),
                naocalib::model::ParamGroup::LeftBoard | naocalib::model::ParamGroup::RightBoard
            )
        }) {
            truth[p.index()] = own[p.index()];
        }
        let dataset = sim::simulate(
            &model,
            &SimOptions {
                seed: 100 + robot,
                px_noise: 0.1,
                joint_noise: 0.1f64.to_radians(),
                truth: Some(truth),
                schedule: Some(stances.clone()),
                schedule_cameras: cameras.clone(),
                ..SimOptions::default()
            },
        )
        .expect("simulated");
        let run = run::calibrate(
            &dataset,
            &RunOptions {
                fixed: FixedSet::from_lists("intrinsics", "").expect("families"),
                ..RunOptions::default()
            },
        )
        .expect("solved");
        let s = &run.solution;
        assert!(
            s.undetermined.is_empty(),
            "robot {robot}: solve held {:?}",
            s.undetermined.iter().map(|u| u.param).collect::<Vec<_>>()
        );
        let free = s.fixed.free();
        for p in CameraId::Upper.projection_params().into_iter().take(4) {
            assert!(free.contains(&p), "{} free", p.name());
        }
        for p in free {
            z.push((s.values[p.index()] - truth[p.index()]) / s.std[p.index()]);
        }
    }
    let n = z.len() as f64;
    let mean = z.iter().sum::<f64>() / n;
    let rms = (z.iter().map(|v| v * v).sum::<f64>() / n).sqrt();
    let worst = z.iter().map(|v| v.abs()).fold(0.0, f64::max);
    eprintln!(
        "{} captures ({upper} upper), {:.0} s; err/σ over {n} estimates: mean {mean:.3}, rms \
         {rms:.3}, worst {worst:.2}",
        planned.captures.len(),
        planned.duration
    );
    assert!(mean.abs() < 0.3, "mean err/σ {mean}");
    assert!((0.75..=1.3).contains(&rms), "rms err/σ {rms}");
    assert!(worst < 4.0, "an estimate {worst}σ off");
}

/// A plan for the lower camera's intrinsics whose boards must stay in view over the default
/// ±3° of offsets cannot sweep the image: it names the centre's coordinate it leaves
/// undetermined and says how to plan one that sweeps it; with `--offset-deg 1` every free
/// parameter is determined and nothing is said.
#[test]
fn a_plan_that_cannot_sweep_the_image_says_how_to_plan_one_that_does() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("plan.csv");
    let config = crate::util::sample().join("dataset.toml");
    let run = |offset: &str| {
        let o = crate::util::naocalib()
            .args(["plan", out.to_str().unwrap(), "--force", "--camera"])
            .arg(&config)
            .args([
                "--families",
                "paper,intrinsics",
                "--captures",
                "48",
                "--pool",
                "60",
            ])
            .args(["--offset-deg", offset])
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8(o.stdout).unwrap()
    };
    let wide = run("3");
    let hint = wide
        .lines()
        .find(|l| l.contains("so that they sweep the image"))
        .unwrap_or_else(|| panic!("no hint:\n{wide}"));
    assert!(hint.starts_with("Cy") || hint.starts_with("Cx"), "{hint}");
    assert!(
        hint.contains("±3°") && hint.contains("--offset-deg 1"),
        "{hint}"
    );
    let narrow = run("1");
    assert!(
        narrow.contains("every free parameter determined"),
        "{narrow}"
    );
    assert!(!narrow.contains("sweep the image"), "{narrow}");
}
