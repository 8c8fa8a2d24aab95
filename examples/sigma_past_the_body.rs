//! The one-sigma of the 21 on a robot that sees its own body: the default plan (naocalib's
//! sandal, planned past the body) against the plan the paper's planner makes (the paper's
//! board, `--ignore-body`). Each is predicted as planned, then photographed `RUNS` times by
//! one robot drawn with its body (the same truth, 0.1 px and 0.1° of joint noise, new noise
//! each time) and solved; per parameter the scatter of the estimates (1.4826 × their median
//! absolute deviation: a run flagged as misfit does not decide it) and the mean vertex count.
//!
//!     cargo run --release --example sigma_past_the_body -- [RUNS]

use naocalib::body::BodyModel;
use naocalib::model::{FixedSet, Model, PAPER_PARAMETERS, PARAMETER_COUNT, Param};
use naocalib::plan::{Plan, PlanOptions, plan, to_stances};
use naocalib::sim::{SimOptions, draw_truth, simulate};
use naocalib::solve::{Problem, UncertaintyOptions, backend, calibrate};
use rand::SeedableRng;

/// A plan's estimates over the runs, its mean count of vertices found and how many runs'
/// fits failed.
struct Measured {
    estimates: Vec<Vec<f64>>,
    vertices: f64,
    failed: usize,
}

/// `planned` photographed `runs` times by the robot `truth` drawn with its body, and solved.
fn photographed(
    model: &Model,
    planned: &Plan,
    truth: [f64; PARAMETER_COUNT],
    runs: u64,
) -> Measured {
    let solver = backend(naocalib::solve::backend_names()[0], false).expect("a backend");
    let mut measured = Measured {
        estimates: vec![Vec::new(); PAPER_PARAMETERS],
        vertices: 0.0,
        failed: 0,
    };
    for run in 0..runs {
        let options = SimOptions {
            seed: 5,
            px_noise: 0.1,
            joint_noise: 0.1f64.to_radians(),
            truth: Some(truth),
            schedule: Some(to_stances(&planned.captures)),
            body: Some(BodyModel::default()),
            noise_seed: Some(1000 + run),
            ..SimOptions::default()
        };
        let dataset = simulate(model, &options).expect("simulated");
        measured.vertices += dataset.corners.len() as f64 / runs as f64;
        let solved = Problem::from_dataset(&dataset, FixedSet::default())
            .map_err(|e| e.to_string())
            .and_then(|problem| {
                calibrate(&problem, solver.as_ref(), &UncertaintyOptions::default())
                    .map_err(|e| e.to_string())
            });
        match solved {
            Ok(s) => {
                for p in &Param::ALL[..PAPER_PARAMETERS] {
                    measured.estimates[p.index()].push(s.report_value(*p));
                }
            }
            Err(_) => measured.failed += 1,
        }
    }
    measured
}

/// 1.4826 × the median absolute deviation.
fn scatter(xs: &[f64]) -> f64 {
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let m = median(&mut xs.to_vec());
    1.4826 * median(&mut xs.iter().map(|x| (x - m).abs()).collect())
}

fn main() {
    let runs: u64 = std::env::args()
        .nth(1)
        .map_or(40, |a| a.parse().expect("RUNS: a count"));
    let truth = draw_truth(&mut rand_chacha::ChaCha8Rng::seed_from_u64(11));
    let ours_model = Model::unconfigured();
    let mut ours_options = PlanOptions::default();
    ours_options.feasibility.sight = Some(BodyModel::default());
    let ours = plan(&ours_model, &ours_options).expect("the default plan");
    let paper_model = Model::default();
    let paper = plan(&paper_model, &PlanOptions::default()).expect("the paper's plan");
    let ours_measured = photographed(&ours_model, &ours, truth, runs);
    let paper_measured = photographed(&paper_model, &paper, truth, runs);
    println!(
        "{runs} runs each; vertices found per run (mean): paper's plan {:.0}, default plan {:.0}; \
         failed fits: {} and {}",
        paper_measured.vertices,
        ours_measured.vertices,
        paper_measured.failed,
        ours_measured.failed
    );
    println!(
        "| parameter | unit | paper's plan: predicted | paper's plan: measured past the body | default plan: predicted | default plan: measured past the body |"
    );
    println!("| --- | --- | --- | --- | --- | --- |");
    let mut worst = [0.0f64; 4];
    for p in &Param::ALL[..PAPER_PARAMETERS] {
        let unit = p.unit();
        let predicted = |planned: &Plan| {
            planned
                .prediction
                .std_of(*p)
                .map_or(f64::NAN, |s| unit.to_report(s))
        };
        let row = [
            predicted(&paper),
            scatter(&paper_measured.estimates[p.index()]),
            predicted(&ours),
            scatter(&ours_measured.estimates[p.index()]),
        ];
        if p.index() < 15 {
            for (w, v) in worst.iter_mut().zip(row) {
                *w = w.max(v);
            }
        }
        println!(
            "| {} | {} | {:.4} | {:.4} | {:.4} | {:.4} |",
            p.name(),
            unit.name(),
            row[0],
            row[1],
            row[2],
            row[3]
        );
    }
    println!(
        "| worst of the 15 | deg | {:.4} | {:.4} | {:.4} | {:.4} |",
        worst[0], worst[1], worst[2], worst[3]
    );
}
