//! Batch solving of 100 paper-sized corner datasets (24 stances × 3 head postures × 2
//! legs = 144 captures, 3456 vertices, 0.1 px noise each), simulated once in memory, on
//! all cores and on one, each solved as `naocalib solve` does (Ceres, noise model); the
//! throughput in datasets per second gives the cost of one dataset.
//!
//! This is the solving alone, in memory. `naocalib batch` as a whole process adds loading
//! and validating the datasets (about 1.1 ms CPU each) and the summary; docs/PERFORMANCE.md quotes
//! the whole process beside one Python scipy solve (`scripts/solve_scipy.py`).

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use naocalib::batch::{BatchOptions, solve_datasets};
use naocalib::model::Model;
use naocalib::sim::{SimOptions, simulate};
use naocalib::solve::UncertaintyOptions;

fn bench_batch(c: &mut Criterion) {
    // As the CLI does at start (see its doc).
    naocalib::solve::retain_freed_memory();
    let datasets: Vec<_> = (1..=100)
        .map(|seed| {
            let options = SimOptions {
                seed,
                ..SimOptions::default()
            };
            let mut d = simulate(&Model::default(), &options).expect("simulated");
            d.dir = format!("sim/run{seed:03}").into();
            d
        })
        .collect();
    let options = BatchOptions::default();
    let mut group = c.benchmark_group("batch_100_paper_sized");
    group.sample_size(10);
    // Criterion's throughput is then datasets per second; its inverse the cost of one.
    group.throughput(Throughput::Elements(datasets.len() as u64));
    group.bench_function(options.run.solver.clone(), |b| {
        b.iter(|| {
            let batch = solve_datasets(&datasets, &options, &|_| {});
            assert_eq!(batch.runs.len(), 100, "{:?}", batch.failures.first());
            batch
        })
    });
    // On one worker thread: the CPU time of one dataset is the time over 100.
    let one = BatchOptions {
        threads: 1,
        ..BatchOptions::default()
    };
    group.bench_function(format!("{}_one_thread", one.run.solver), |b| {
        b.iter(|| solve_datasets(&datasets, &one, &|_| {}))
    });
    // The same with the plain σ̂²(JᵀJ)⁻¹ (one fit, no noise model): `--plain-std`.
    let plain = BatchOptions::default().with_uncertainty(UncertaintyOptions {
        noise_model: false,
        ..UncertaintyOptions::default()
    });
    group.bench_function(format!("{}_plain_std", plain.run.solver), |b| {
        b.iter(|| solve_datasets(&datasets, &plain, &|_| {}))
    });
    group.finish();
}

criterion_group!(benches, bench_batch);
criterion_main!(benches);
