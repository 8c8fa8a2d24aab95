//! Detection on a paper-sized rendered dataset (24 stances × 3 head postures × 2 legs = 144
//! images, blur σ 0.8 px, grey noise σ 2): the whole `detect_dataset` (PNG decoding,
//! `findChessboardCorners` in the predicted region, `cornerSubPix`, row/col assignment) on
//! all cores.
//!
//! Targets (issue 3): ≥ 200 images/s on 2 cores, ≥ 99 % of the boards found, peak memory
//! ≤ 200 MB. The detection rate, sub-pixel error and peak memory (VmHWM) are printed once.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use naocalib::detect::{self, DetectOptions, Outcome, Summary};
use naocalib::model::Model;
use naocalib::sim::render::{ImageOutput, RenderOptions};
use naocalib::sim::{SimOptions, simulate};

fn peak_memory_mb() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}

/// CPU time (user + system) of this process so far [s], from /proc/self/stat.
fn cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    let fields: Vec<&str> = stat.rsplit_once(')')?.1.split_whitespace().collect();
    let ticks: f64 = fields.get(11)?.parse::<f64>().ok()? + fields.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

fn bench_detect(c: &mut Criterion) {
    let tmp = tempfile::tempdir().expect("tempdir");
    let options = SimOptions {
        px_noise: 0.0,
        images: Some(ImageOutput {
            dir: tmp.path().to_path_buf(),
            options: RenderOptions::default(),
            force: false,
        }),
        ..SimOptions::default()
    };
    let mut dataset = simulate(&Model::default(), &options).expect("simulated");
    dataset.dir = tmp.path().to_path_buf();
    let n = dataset.captures.len();

    let detect_options = DetectOptions::default();
    let results = detect::detect_dataset(&dataset, &detect_options, &|_| {});
    let summary = Summary::of(&results);
    let truth = dataset.corners_by_capture();
    let (mut sum2, mut count) = (0.0, 0usize);
    for r in &results {
        if let Outcome::Found { corners, .. } = &r.outcome {
            for c in corners {
                if let Some(t) = truth[&r.capture].iter().find(|t| t.vertex == c.vertex) {
                    sum2 += (c.pixel[0] - t.pixel[0]).powi(2) + (c.pixel[1] - t.pixel[1]).powi(2);
                    count += 1;
                }
            }
        }
    }
    eprintln!(
        "detect: {n} images, {summary} ({:.1} % found), RMS error {:.4} px, {} threads",
        100.0 * summary.found as f64 / n as f64,
        (sum2 / count.max(1) as f64).sqrt(),
        detect_options.jobs
    );

    // Wall and CPU time of a few runs: on a busy machine the CPU time tells what the
    // detector needs, the wall time what it got.
    let runs = 5;
    let (wall, cpu) = (std::time::Instant::now(), cpu_seconds());
    for _ in 0..runs {
        detect::detect_dataset(&dataset, &detect_options, &|_| {});
    }
    let wall = wall.elapsed().as_secs_f64();
    if let (Some(before), Some(after)) = (cpu, cpu_seconds()) {
        eprintln!(
            "detect: {:.0} images/s wall, {:.2} ms CPU per image ({:.0} images/s per core)",
            (runs * n) as f64 / wall,
            1000.0 * (after - before) / (runs * n) as f64,
            (runs * n) as f64 / (after - before)
        );
    }

    let mut group = c.benchmark_group("detect_paper_sized");
    group.sample_size(10);
    group.throughput(Throughput::Elements(n as u64));
    group.bench_function("144_images", |b| {
        b.iter(|| detect::detect_dataset(&dataset, &detect_options, &|_| {}))
    });
    let one = DetectOptions {
        jobs: 1,
        ..DetectOptions::default()
    };
    group.bench_function("144_images_1_thread", |b| {
        b.iter(|| detect::detect_dataset(&dataset, &one, &|_| {}))
    });
    group.finish();
    if let Some(mb) = peak_memory_mb() {
        eprintln!("detect: peak memory (VmHWM) {mb:.0} MB");
    }
}

criterion_group!(benches, bench_detect);
criterion_main!(benches);
