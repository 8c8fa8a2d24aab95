//! The measurement phase end to end against the simulated robot at 10× real time:
//! `naocalib plan --captures 48` (once), then per sample `naocalib capture` of that plan
//! with `simulate-robot --speed 10` and its rendered lower camera. The target: the whole
//! capture run under 60 s of wall time.
//!
//! Run: `cargo bench --bench capture`.

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use criterion::{Criterion, SamplingMode, criterion_group, criterion_main};
use naocalib::dataset::Dataset;
use naocalib::model::Model;

const BIN: &str = env!("CARGO_BIN_EXE_naocalib");

fn ok(out: std::process::Output, what: &str) {
    assert!(
        out.status.success(),
        "{what}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// One capture run of `plan` into a fresh directory under `dir`; its wall time.
fn run(dir: &Path, plan: &Path, config: &Path, k: usize) -> Duration {
    let sock = dir.join(format!("lola-{k}.sock"));
    let state = dir.join(format!("state-{k}.json"));
    let out = dir.join(format!("ds-{k}"));
    let start = Instant::now();
    let mut robot = Command::new(BIN)
        .arg("simulate-robot")
        .arg("--lola")
        .arg(&sock)
        .arg("--config")
        .arg(config)
        .arg("--state")
        .arg(&state)
        .args(["--speed", "10", "--seed", "3"])
        .stderr(Stdio::null())
        .spawn()
        .expect("robot");
    while !sock.exists() {
        std::thread::sleep(Duration::from_millis(2));
    }
    let camera = format!(
        "command:'{BIN}' simulate-robot snap {{path}} --state '{}'",
        state.display()
    );
    ok(
        Command::new(BIN)
            .arg("capture")
            .arg(plan)
            .arg(&out)
            .arg("--config")
            .arg(config)
            .arg("--lola")
            .arg(&sock)
            .arg("--camera")
            .arg(&camera)
            .output()
            .expect("capture"),
        "capture",
    );
    let elapsed = start.elapsed();
    robot.wait().expect("robot exits");
    let n = Dataset::load_without_corners(&out)
        .expect("a dataset")
        .captures
        .len();
    // The plan's order does not check the moves between its stances; capture skips the
    // few it finds colliding (7 of this plan's 48 at the time of writing).
    assert!(n >= 40, "{n} of 48 captures taken");
    elapsed
}

fn capture(c: &mut Criterion) {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let cfg = dir.join("cfg");
    Dataset::new(&cfg, Model::default())
        .write(&cfg, false)
        .unwrap();
    let config = cfg.join("dataset.toml");
    let plan = dir.join("plan.csv");
    ok(
        Command::new(BIN)
            .arg("plan")
            .arg(&plan)
            .args(["--captures", "48"])
            .arg("--camera")
            .arg(&config)
            .output()
            .expect("plan"),
        "plan",
    );
    let mut group = c.benchmark_group("capture");
    group.sample_size(10);
    group.sampling_mode(SamplingMode::Flat);
    group.warm_up_time(Duration::from_millis(1));
    group.measurement_time(Duration::from_secs(1));
    let mut k = 0;
    group.bench_function("plan_48_at_10x", |b| {
        b.iter_custom(|iters| {
            (0..iters)
                .map(|_| {
                    k += 1;
                    run(dir, &plan, &config, k)
                })
                .sum()
        })
    });
    group.finish();
}

criterion_group!(benches, capture);
criterion_main!(benches);
