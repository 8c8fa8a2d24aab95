//! Solving the paper-sized dataset (24 stances × 3 head postures × 2 legs = 144 captures,
//! 3456 vertices, 21 free parameters, 0.1 px noise) with covariance, with every backend.
//!
//! Three groups: `backend_paper_sized` times the backend alone (optimisation and covariance,
//! what the solvers differ in); `solve_paper_sized` the whole [`solve`] with the
//! backend-independent statistics (identifiability, sandwich covariance), the same for all.
//! Every backend runs single-threaded in its own numerics (Ceres with one thread); only
//! tiny-solver's residual-block loop uses rayon internally.
//!
//! `backend_extended` times the backends on the extended model: a paper-sized dataset of a
//! robot with realistic effects (head, intrinsics, links, compliance, play), every family
//! free, the undetermined parameters held as `calibrate` holds them (docs/MODEL.md).
//! `calibrate_auto` is `naocalib solve --model auto` on that dataset. `misfit_paper_sized`
//! times what the misfit diagnosis (score tests of every unfitted family) adds to every
//! calibration.
//!
//! Targets: Ceres median ≤ 10 ms; fastest pure-Rust backend within 1.5× of Ceres; the
//! extended Ceres backend within 3× of the paper's.

use criterion::{Criterion, criterion_group, criterion_main};
use naocalib::model::{Family, FixedSet, Model};
use naocalib::sim::{SimOptions, simulate};
use naocalib::solve::{Problem, UncertaintyOptions, backend, backend_names, calibrate};

fn paper_sized() -> Problem {
    // As the CLI does at start (see its doc).
    naocalib::solve::retain_freed_memory();
    let dataset = simulate(&Model::default(), &SimOptions::default()).expect("simulated");
    Problem::from_dataset(&dataset, FixedSet::default()).expect("problem")
}

/// A paper-sized dataset of a robot with realistic effects (0.1° joint noise).
fn realistic() -> naocalib::dataset::Dataset {
    let options = SimOptions {
        effects: vec![
            Family::Head,
            Family::Intrinsics,
            Family::Links,
            Family::Compliance,
            Family::Play,
        ],
        joint_noise: 0.1f64.to_radians(),
        ..SimOptions::default()
    };
    simulate(&Model::default(), &options).expect("simulated")
}

/// The realistic robot with every family free and the undetermined parameters held.
fn extended() -> Problem {
    naocalib::solve::retain_freed_memory();
    let dataset = realistic();
    let all = FixedSet::from_lists("head,intrinsics,distortion,links,compliance,play", "")
        .expect("families");
    let problem = Problem::from_dataset(&dataset, all).expect("problem");
    let undetermined = naocalib::solve::identify::undetermined(&problem).expect("analysed");
    naocalib::solve::identify::hold(&problem, &undetermined)
}

fn bench_extended(c: &mut Criterion) {
    let problem = extended();
    let mut group = c.benchmark_group("backend_extended");
    group.sample_size(10);
    for name in backend_names() {
        let backend = backend(name, false).expect("listed backend");
        group.bench_function(backend.name(), |b| {
            b.iter(|| backend.solve(&problem).expect("solved"))
        });
    }
    group.finish();
}

fn bench_auto(c: &mut Criterion) {
    naocalib::solve::retain_freed_memory();
    let dataset = realistic();
    let problem = Problem::from_dataset(&dataset, FixedSet::default()).expect("problem");
    let auto = UncertaintyOptions {
        model: naocalib::solve::ModelChoice::Auto,
        ..Default::default()
    };
    let mut group = c.benchmark_group("calibrate_auto");
    group.sample_size(10);
    let backend = backend(backend_names()[0], false).expect("listed backend");
    group.bench_function(backend.name(), |b| {
        b.iter(|| calibrate(&problem, backend.as_ref(), &auto).expect("calibrated"))
    });
    group.finish();
}

fn bench_backend(c: &mut Criterion) {
    let problem = paper_sized();
    let mut group = c.benchmark_group("backend_paper_sized");
    group.sample_size(20);
    for name in backend_names() {
        let backend = backend(name, false).expect("listed backend");
        group.bench_function(backend.name(), |b| {
            b.iter(|| backend.solve(&problem).expect("solved"))
        });
    }
    group.finish();
}

fn bench_solve(c: &mut Criterion) {
    let problem = paper_sized();
    let mut group = c.benchmark_group("solve_paper_sized");
    group.sample_size(20);
    for name in backend_names() {
        let backend = backend(name, false).expect("listed backend");
        group.bench_function(backend.name(), |b| {
            b.iter(|| {
                calibrate(&problem, backend.as_ref(), &UncertaintyOptions::plain()).expect("solved")
            })
        });
    }
    group.finish();
}

/// The whole identification phase as `naocalib solve` runs it: first fit, noise estimate,
/// the whitened refit, the misfit tests, the covariance and the statistics.
fn bench_calibrate(c: &mut Criterion) {
    let problem = paper_sized();
    let options = UncertaintyOptions::default();
    let mut group = c.benchmark_group("calibrate_paper_sized");
    group.sample_size(20);
    for name in backend_names() {
        let backend = backend(name, false).expect("listed backend");
        group.bench_function(backend.name(), |b| {
            b.iter(|| calibrate(&problem, backend.as_ref(), &options).expect("calibrated"))
        });
    }
    group.finish();
}

/// What the misfit diagnosis adds to that (target: at most 20 % of the calibration without
/// it). A calibration evaluates each capture's Jacobian once at the plain and once at the
/// whitened fit and shares it between the noise estimate, the statistics and the tests
/// (the pipeline's `Point`s, docs/MODEL.md §13); the diagnosis adds the candidate
/// families' columns to those two evaluations and the score tests on them. Three timings: the tests on the
/// plain and on the whitened residuals (`tests_plain_and_whitened`), and one evaluation
/// with and without the candidate columns. Added cost = tests + 2 × (with − without).
fn bench_misfit(c: &mut Criterion) {
    use naocalib::solve::linearisation::Linearisation;
    use naocalib::solve::{misfit, noise};
    let problem = paper_sized();
    let backend = backend(backend_names()[0], false).expect("listed backend");
    let solution =
        calibrate(&problem, backend.as_ref(), &UncertaintyOptions::default()).expect("calibrated");
    let held = [false; naocalib::model::PARAMETER_COUNT];
    let with_joints = |mut columns: Vec<naocalib::model::Param>| {
        for p in noise::joint_offsets() {
            if !columns.contains(&p) {
                columns.push(p);
            }
        }
        columns
    };
    let with = with_joints(misfit::tested_columns(&problem, &held));
    let without = with_joints(problem.free());
    let at = Linearisation::at(&problem, with.clone(), &solution.values).expect("in view");
    let fitted = problem.free().len();
    let (levels, captures) = noise::estimate_from(&at, fitted, Default::default());
    let mut whitened = problem.clone();
    for (term, noise) in whitened.captures.iter_mut().zip(&captures) {
        term.whitening = Some(noise.whitening(levels));
    }
    let mut group = c.benchmark_group("misfit_paper_sized");
    group.sample_size(20);
    group.bench_function("tests_plain_and_whitened", |b| {
        b.iter(|| {
            let plain = misfit::family_tests_at(&problem, &at, &held);
            let whitened = misfit::family_tests_at(&whitened, &at, &held);
            misfit::combined_tests(plain, whitened)
        })
    });
    group.bench_function("evaluation_with_candidates", |b| {
        b.iter(|| Linearisation::at(&problem, with.clone(), &solution.values))
    });
    group.bench_function("evaluation_without_candidates", |b| {
        b.iter(|| Linearisation::at(&problem, without.clone(), &solution.values))
    });
    group.finish();
}

criterion_group!(
    benches,
    bench_backend,
    bench_solve,
    bench_calibrate,
    bench_misfit,
    bench_extended,
    bench_auto
);
criterion_main!(benches);
