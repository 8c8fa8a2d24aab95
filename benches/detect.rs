//! Detection on hard rendered sets: 24 stances × 3 head postures × 2 legs = 144 images
//! with boards near and across the image border (`SimOptions::near_border`, default
//! rendering: clutter, blur σ 0.8 px, grey noise σ 2, vignetting), at the NAO V4/V5
//! resolution 640×480 and the V6's 1280×960; and 144 ordinary images of a robot with the
//! lower camera tilted by −7.2°, which the nominal prediction misses. The whole `detect_dataset` (PNG decoding,
//! model-guided search, `cornerSubPix`, checks) on all cores and on one.
//!
//! Printed once per set: boards and vertices found against the truth, RMS error, images/s
//! (wall and per core), peak memory; also for OpenCV's chessboard finder alone
//! (`guided: false`) beside it.
//!
//! The whole-process figure (`naocalib detect` on a dataset written by `simulate --images
//! --near-border`) and the Python OpenCV loop (`scripts/detect_opencv.py`) are measured
//! outside criterion; see docs/PERFORMANCE.md.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use naocalib::dataset::Dataset;
use naocalib::detect::{self, DetectOptions, Outcome};
use naocalib::model::{Model, PARAMETER_COUNT, Param};
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

/// A robot as teams' files describe them: lower-camera tilt −7.2°, roll 2.5°,
/// leg offsets of 1–2°.
fn tilted_robot() -> [f64; PARAMETER_COUNT] {
    let mut truth = [0.0; PARAMETER_COUNT];
    for (k, p) in Param::ALL.iter().take(15).enumerate() {
        let deg = match p {
            Param::CamPitch => -7.2,
            Param::CamRoll => 2.5,
            Param::CamYaw => 0.5,
            _ if k % 2 == 0 => 1.0 + 0.1 * k as f64,
            _ => -1.5,
        };
        truth[p.index()] = deg.to_radians();
    }
    truth
}

/// The set for `model` rendered into `dir`: the hard one (boards near and across the
/// border, a random robot), or ordinary images of [`tilted_robot`].
fn rendered(dir: &std::path::Path, model: &Model, tilted: bool) -> Dataset {
    let options = SimOptions {
        seed: 5,
        px_noise: 0.0,
        near_border: !tilted,
        truth: tilted.then(tilted_robot),
        images: Some(ImageOutput {
            dir: dir.to_path_buf(),
            options: RenderOptions {
                seed: 5,
                ..RenderOptions::default()
            },
            force: false,
        }),
        ..SimOptions::default()
    };
    let mut dataset = simulate(model, &options).expect("simulated");
    dataset.dir = dir.to_path_buf();
    dataset
}

/// Prints what `options` find in `dataset` against the truth, and its speed.
fn report(name: &str, dataset: &Dataset, options: &DetectOptions) {
    let n = dataset.captures.len();
    let results = detect::detect_dataset(dataset, options, &|_| {});
    let truth = dataset.corners_by_capture();
    let camera = &dataset.model.camera;
    let (mut full, mut full_found, mut inside, mut inside_found) = (0, 0, 0, 0);
    let (mut sum2, mut count, mut worst) = (0.0, 0usize, 0.0f64);
    for r in &results {
        let expected = &truth[&r.capture];
        let visible: Vec<_> = expected
            .iter()
            .filter(|t| camera.contains(t.pixel, 3.0))
            .collect();
        let corners = match &r.outcome {
            Outcome::Found { corners, .. } => corners.as_slice(),
            _ => &[],
        };
        if visible.len() == 24 {
            full += 1;
            full_found += !corners.is_empty() as usize;
        }
        inside += visible.len();
        inside_found += visible
            .iter()
            .filter(|t| corners.iter().any(|c| c.vertex == t.vertex))
            .count();
        for c in corners {
            if let Some(t) = expected.iter().find(|t| t.vertex == c.vertex) {
                let e2 = (c.pixel[0] - t.pixel[0]).powi(2) + (c.pixel[1] - t.pixel[1]).powi(2);
                sum2 += e2;
                worst = worst.max(e2.sqrt());
                count += 1;
            }
        }
    }
    let runs = 3;
    let (wall, cpu) = (std::time::Instant::now(), cpu_seconds());
    for _ in 0..runs {
        detect::detect_dataset(dataset, options, &|_| {});
    }
    let wall = wall.elapsed().as_secs_f64();
    let per_core = match (cpu, cpu_seconds()) {
        (Some(a), Some(b)) => format!("{:.0}", (runs * n) as f64 / (b - a)),
        _ => "?".into(),
    };
    eprintln!(
        "{name}: {n} images; fully visible boards found {full_found}/{full}, vertices ≥ 3 px \
         inside found {inside_found}/{inside}; RMS {:.4} px, worst {worst:.3} px; \
         {:.0} images/s on {} threads ({per_core}/s per core)",
        (sum2 / count.max(1) as f64).sqrt(),
        (runs * n) as f64 / wall,
        options.jobs
    );
}

fn bench_detect(c: &mut Criterion) {
    let tmp = tempfile::tempdir().expect("tempdir");
    let vga = Model::default();
    let mut v6 = Model::default();
    for x in [
        &mut v6.camera.fx,
        &mut v6.camera.fy,
        &mut v6.camera.cx,
        &mut v6.camera.cy,
    ] {
        *x *= 2.0;
    }
    v6.camera.width *= 2;
    v6.camera.height *= 2;
    let sets = [
        ("640x480", rendered(&tmp.path().join("vga"), &vga, false)),
        ("1280x960", rendered(&tmp.path().join("v6"), &v6, false)),
        (
            "640x480_tilted",
            rendered(&tmp.path().join("tilt"), &vga, true),
        ),
    ];
    let guided = DetectOptions::default();
    let chessboard = DetectOptions {
        guided: false,
        ..DetectOptions::default()
    };
    for (name, dataset) in &sets {
        report(&format!("{name} model-guided"), dataset, &guided);
        report(&format!("{name} chessboard finder"), dataset, &chessboard);
    }

    let one = DetectOptions {
        jobs: 1,
        ..DetectOptions::default()
    };
    let mut group = c.benchmark_group("detect_hard_144");
    group.sample_size(10);
    for (name, dataset) in &sets {
        group.throughput(Throughput::Elements(dataset.captures.len() as u64));
        group.bench_function(*name, |b| {
            b.iter(|| detect::detect_dataset(dataset, &guided, &|_| {}))
        });
        group.bench_function(format!("{name}_1_thread"), |b| {
            b.iter(|| detect::detect_dataset(dataset, &one, &|_| {}))
        });
    }
    group.finish();
    if let Some(mb) = peak_memory_mb() {
        eprintln!("detect: peak memory (VmHWM) {mb:.0} MB");
    }
}

criterion_group!(benches, bench_detect);
criterion_main!(benches);
