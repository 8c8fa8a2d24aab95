//! Solving the paper-sized dataset (24 stances × 3 head postures × 2 legs = 144 captures,
//! 3456 vertices, 0.1 px noise) with covariance, with every backend.
//!
//! Targets: Ceres median ≤ 10 ms (issue 2); fastest pure-Rust backend within 1.5× of Ceres
//! (issue 4).

use criterion::{Criterion, criterion_group, criterion_main};
use naocalib::model::{FixedSet, Model};
use naocalib::sim::{SimOptions, simulate};
use naocalib::solve::{Problem, backend, backend_names, solve};

fn paper_sized() -> Problem {
    let dataset = simulate(&Model::default(), &SimOptions::default()).expect("simulated");
    Problem::from_dataset(&dataset, FixedSet::default()).expect("problem")
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

criterion_group!(benches, bench_solve);
criterion_main!(benches);
