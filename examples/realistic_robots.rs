//! How naocalib does on simulated robots with every effect the paper's model lacks (head
//! offsets 0.5°, 1 % focal length and 3 px principal point, 0.5 mm links, compliance
//! 0.3 deg/(N·m), play 0.5°), paper-sized datasets with 0.1 px and 0.1° joint noise:
//! the default solve, `--model auto`, and a fit told the true families.
//!
//! `cargo run --release --example realistic_robots -- [ROBOTS] [--verbose]`
//!
//! Prints per run the families chosen, the RMS, and rms(err/σ) over the paper's 21
//! parameters (against the truth moved along the named undetermined directions, which is
//! what the data determine), and the summary over all runs.

use naocalib::model::{Family, FixedSet, Model, PAPER_PARAMETERS, PARAMETER_COUNT, Param};
use naocalib::sim::{SimOptions, simulate};
use naocalib::solve::{
    ModelChoice, Problem, Solution, UncertaintyOptions, backend, backend_names, calibrate,
};

const EFFECTS: [Family; 5] = [
    Family::Head,
    Family::Intrinsics,
    Family::Links,
    Family::Compliance,
    Family::Play,
];

/// err/σ of the paper's determined parameters.
fn z_scores(s: &Solution, truth: &[f64; PARAMETER_COUNT]) -> Vec<(Param, f64)> {
    let truth = naocalib::solve::identify::determined_truth(&s.undetermined, truth);
    Param::ALL[..PAPER_PARAMETERS]
        .iter()
        .filter(|p| s.is_determined(**p) && s.std[p.index()] > 0.0)
        .map(|p| {
            (
                *p,
                (s.values[p.index()] - truth[p.index()]) / s.std[p.index()],
            )
        })
        .collect()
}

fn rms(v: impl Iterator<Item = f64>) -> f64 {
    let (n, sum) = v.fold((0usize, 0.0), |(n, s), x| (n + 1, s + x * x));
    (sum / n.max(1) as f64).sqrt()
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let robots: u64 = args.iter().find_map(|a| a.parse().ok()).unwrap_or(5);
    let verbose = args.iter().any(|a| a == "--verbose");
    naocalib::solve::retain_freed_memory();
    let solver = backend(backend_names()[0], false).expect("backend");
    let auto = UncertaintyOptions {
        model: ModelChoice::Auto,
        ..Default::default()
    };
    let mut all = [Vec::new(), Vec::new(), Vec::new()];
    for seed in 0..robots {
        let options = SimOptions {
            seed: 70 + seed,
            joint_noise: 0.1f64.to_radians(),
            effects: EFFECTS.to_vec(),
            ..SimOptions::default()
        };
        let dataset = simulate(&Model::default(), &options).expect("simulated");
        let truth = dataset.truth.as_ref().expect("truth").values;
        let problem = Problem::from_dataset(&dataset, FixedSet::default()).expect("problem");
        let mut told = problem.clone();
        for f in EFFECTS {
            for p in f.params() {
                told.fixed.set(p, false);
            }
        }
        let runs = [
            (
                "default",
                calibrate(&problem, solver.as_ref(), &Default::default()),
            ),
            ("auto", calibrate(&problem, solver.as_ref(), &auto)),
            (
                "told",
                calibrate(&told, solver.as_ref(), &Default::default()),
            ),
        ];
        for (k, (name, run)) in runs.into_iter().enumerate() {
            let s = run.expect("calibrated");
            let z = z_scores(&s, &truth);
            let families: Vec<&str> = s.families.iter().map(|f| f.name()).collect();
            let held: Vec<&str> = s.undetermined.iter().map(|u| u.param.name()).collect();
            println!(
                "robot {seed} {name:<7} rms {:.3}/{:.3} px  rms(err/σ) {:.2}  max |err/σ| {:.1}  \
                 {:.2} s  families {}  held {}  misfit {}",
                s.rms_px[0],
                s.rms_px[1],
                rms(z.iter().map(|x| x.1)),
                z.iter().map(|x| x.1.abs()).fold(0.0, f64::max),
                s.seconds,
                families.join(","),
                held.join(","),
                s.misfit.detected
            );
            if verbose {
                for (p, v) in &z {
                    println!("    {p:<14} err/σ {v:+.2}");
                }
            }
            all[k].extend(z.into_iter().map(|x| x.1));
        }
    }
    for (k, name) in ["default", "auto", "told"].iter().enumerate() {
        println!(
            "{name:<7}: rms(err/σ) {:.2} over {} estimates",
            rms(all[k].iter().copied()),
            all[k].len()
        );
    }
}
