//! What the upper camera adds to a 144-capture session: the reported one-sigma of the upper
//! camera's rotation and the worst one-sigma of the 15 lower-camera and leg offsets, for
//! 144 lower-camera captures against 144 with 24 and with 48 upper-camera captures (upper
//! stances found by the simulator's search among random stances), on robots drawn as the
//! teams' files show them (head offsets left at zero: they are not estimated here), at
//! 0.1 px and 0.1° of joint noise per capture; mean over `SEEDS` datasets, with the RMS of
//! err/σ over every estimate.
//!
//!     cargo run --release --example upper_camera_sigma

use naocalib::model::{CameraId, FixedSet, Model, Param, ParamGroup};
use naocalib::sim::{SimOptions, draw_team_truth, simulate};
use naocalib::solve::{Problem, UncertaintyOptions, backend, calibrate};
use rand::SeedableRng;

const SEEDS: u64 = 20;

fn main() {
    let model = Model {
        upper_camera: Some(Model::default().camera),
        ..Model::default()
    };
    let solver = backend(naocalib::solve::backend_names()[0], false).expect("a backend");
    let lower_and_legs = |p: &Param| {
        matches!(
            p.group(),
            ParamGroup::Camera | ParamGroup::LeftLeg | ParamGroup::RightLeg
        )
    };
    println!(
        "| captures (lower + upper) | UpperCamYaw σ | UpperCamPitch σ | UpperCamRoll σ | worst of 15 lower-camera + leg σ | RMS err/σ |"
    );
    println!("| --- | --- | --- | --- | --- | --- |");
    for (lower, upper) in [(24, 0), (20, 4), (16, 8)] {
        let mut upper_sigma = [0.0; 3];
        let mut worst = 0.0;
        let (mut z2, mut n) = (0.0, 0usize);
        for seed in 1..=SEEDS {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9000 + seed);
            let mut truth = draw_team_truth(&mut rng);
            truth[Param::HeadYaw.index()] = 0.0;
            truth[Param::HeadPitch.index()] = 0.0;
            let options = SimOptions {
                seed: 500 + seed,
                stances: lower,
                heads: 3,
                upper_stances: upper,
                px_noise: 0.1,
                joint_noise: 0.1f64.to_radians(),
                truth: Some(truth),
                ..SimOptions::default()
            };
            let dataset = simulate(&model, &options).expect("simulated");
            let problem = Problem::from_dataset(&dataset, FixedSet::default()).expect("problem");
            let s = calibrate(&problem, solver.as_ref(), &UncertaintyOptions::default())
                .expect("solved");
            for (k, p) in CameraId::Upper.rotation_params().iter().enumerate() {
                upper_sigma[k] += s.report_std(*p) / SEEDS as f64;
            }
            worst += Param::ALL
                .iter()
                .filter(|p| lower_and_legs(p))
                .map(|p| s.report_std(*p))
                .fold(0.0, f64::max)
                / SEEDS as f64;
            for p in problem.free() {
                let z = (s.values[p.index()] - truth[p.index()]) / s.std[p.index()];
                z2 += z * z;
                n += 1;
            }
        }
        let cell = |x: f64| {
            if upper == 0 {
                "–".to_string()
            } else {
                format!("{x:.4}°")
            }
        };
        println!(
            "| {} + {} | {} | {} | {} | {worst:.4}° | {:.2} |",
            2 * lower * 3,
            2 * upper * 3,
            cell(upper_sigma[0]),
            cell(upper_sigma[1]),
            cell(upper_sigma[2]),
            (z2 / n as f64).sqrt()
        );
    }
}
