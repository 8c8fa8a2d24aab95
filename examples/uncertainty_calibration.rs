//! Is the reported one-sigma honest? Repeats a paper-sized simulated calibration with the
//! same stances and truth but new noise, and compares each parameter's mean reported
//! one-sigma with the scatter of its estimates (the ratio must lie in 0.7–1.4).
//!
//! `cargo run --release --example uncertainty_calibration -- [REPETITIONS] [SOLVER]`

use naocalib::model::{FixedSet, Model, PAPER_PARAMETERS, Param};
use naocalib::sim::{SimOptions, simulate};
use naocalib::solve::{Problem, UncertaintyOptions, backend, calibrate};

fn main() {
    let mut args = std::env::args().skip(1);
    let reps: usize = args.next().map_or(100, |a| a.parse().expect("repetitions"));
    let solver = args
        .next()
        .unwrap_or_else(|| naocalib::solve::backend_names()[0].into());
    let backend = backend(&solver, false).expect("known solver");
    for (px, joint_deg) in [(0.1, 0.0), (0.1, 0.1)] {
        let mut estimates = vec![Vec::new(); PAPER_PARAMETERS];
        let mut stds = vec![Vec::new(); PAPER_PARAMETERS];
        let mut noise = Vec::new();
        for rep in 0..reps {
            let options = SimOptions {
                seed: 11,
                px_noise: px,
                joint_noise: f64::to_radians(joint_deg),
                noise_seed: Some(1000 + rep as u64),
                ..SimOptions::default()
            };
            let dataset = simulate(&Model::default(), &options).expect("simulated");
            let problem = Problem::from_dataset(&dataset, FixedSet::default()).expect("problem");
            let s = calibrate(&problem, backend.as_ref(), &UncertaintyOptions::default())
                .expect("solved");
            for p in &Param::ALL[..PAPER_PARAMETERS] {
                estimates[p.index()].push(s.report_value(*p));
                stds[p.index()].push(s.report_std(*p));
            }
            noise.push(s.noise.map_or((0.0, 0.0), |n| (n.px, n.joint.to_degrees())));
        }
        println!(
            "\npixel noise {px} px, joint noise {joint_deg}° per capture, {reps} repetitions, solver {solver}"
        );
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
        let (px_hat, joint_hat): (Vec<f64>, Vec<f64>) = noise.into_iter().unzip();
        println!(
            "estimated noise: pixel {:.4} px, joint {:.4}° (means)",
            mean(&px_hat),
            mean(&joint_hat)
        );
        println!(
            "{:<14} {:>12} {:>12} {:>7}",
            "parameter", "scatter", "mean σ", "ratio"
        );
        let mut worst: (f64, &str) = (1.0, "");
        for p in &Param::ALL[..PAPER_PARAMETERS] {
            let e = &estimates[p.index()];
            let m = mean(e);
            let scatter =
                (e.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (e.len() - 1) as f64).sqrt();
            let sigma = mean(&stds[p.index()]);
            let ratio = sigma / scatter;
            if (ratio.ln()).abs() > worst.0.ln().abs() {
                worst = (ratio, p.name());
            }
            println!(
                "{:<14} {:>12.5} {:>12.5} {:>7.2}",
                p.name(),
                scatter,
                sigma,
                ratio
            );
        }
        println!("worst ratio {:.2} ({})", worst.0, worst.1);
    }
}
