//! Solving the paper-sized dataset (24 stances × 3 head postures × 2 legs = 144 captures,
//! 3456 vertices, 21 free parameters, 0.1 px noise) with covariance, with every backend.
//!
//! Three groups: `backend_paper_sized` times the backend alone (optimisation and covariance,
//! what the solvers differ in); `solve_paper_sized` the whole [`solve`] with the
//! backend-independent statistics (identifiability, sandwich covariance), the same for all.
//! Every backend runs single-threaded in its own numerics (Ceres with one thread); only
//! tiny-solver's residual-block loop uses rayon internally.
//!
//! Targets: Ceres median ≤ 10 ms (issue 2); fastest pure-Rust backend within 1.5× of Ceres
//! (issue 4).

use criterion::{Criterion, criterion_group, criterion_main};
use naocalib::model::{FixedSet, Model};
use naocalib::sim::{SimOptions, simulate};
use naocalib::solve::{Problem, UncertaintyOptions, backend, backend_names, calibrate, solve};

fn paper_sized() -> Problem {
    // As the CLI does at start (see its doc).
    naocalib::solve::retain_freed_memory();
    let dataset = simulate(&Model::default(), &SimOptions::default()).expect("simulated");
    Problem::from_dataset(&dataset, FixedSet::default()).expect("problem")
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
            b.iter(|| solve(&problem, backend.as_ref()).expect("solved"))
        });
    }
    group.finish();
}

/// The whole identification phase as `naocalib solve` runs it: first fit, noise estimate,
/// two whitened refits, covariance and statistics.
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

criterion_group!(benches, bench_backend, bench_solve, bench_calibrate);
criterion_main!(benches);
