//! Helpers shared by the integration tests: running the binary, reading its output, and a
//! brute-force dual-number Jacobian to check the fast paths against.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Output;

use assert_cmd::Command;
use nalgebra::{DMatrix, Dyn, U1};
use naocalib::solve::Problem;
use naocalib::solve::jacobian::robust_weight;
use num_dual::{Derivative, DualDVec64};

/// The `naocalib` binary of this build.
pub fn naocalib() -> Command {
    Command::cargo_bin("naocalib").expect("binary built")
}

/// `naocalib ARGS DATASET`.
pub fn run(args: &[&str], dataset: impl AsRef<std::ffi::OsStr>) -> Output {
    naocalib().args(args).arg(dataset).output().expect("ran")
}

/// The run's standard error as text.
pub fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// The run failed cleanly: exit code 1 (not a panic's 101, not a signal), and its message
/// names every one of `needles`.
pub fn assert_clean_failure(out: &Output, needles: &[&str]) {
    let err = stderr(out);
    assert_eq!(
        out.status.code(),
        Some(1),
        "expected exit 1, got {:?}: {err}",
        out.status
    );
    assert!(!err.contains("panicked"), "panic: {err}");
    for needle in needles {
        assert!(err.contains(needle), "message lacks '{needle}': {err}");
    }
}

/// `naocalib simulate` of a small dataset (6 stances × 2 head postures per leg) into `dir`.
pub fn simulate_small(dir: &Path, seed: u64) {
    let out = naocalib()
        .args(["simulate", "--stances", "6", "--heads", "2", "--seed"])
        .arg(seed.to_string())
        .arg(dir)
        .output()
        .expect("ran");
    assert!(out.status.success(), "simulate failed: {}", stderr(&out));
}

/// The residuals as the backends minimise them (whitened where a capture has a whitening,
/// robust rescaling per vertex included) and their Jacobian with respect to the free
/// parameters at `x`, by brute force: the whole model on dynamic duals.
pub fn brute_force_jacobian(problem: &Problem, x: &[f64]) -> (Vec<f64>, DMatrix<f64>) {
    let free = problem.free();
    let n = free.len();
    let all = problem.expand(x);
    let mut params: Vec<DualDVec64> = all.iter().map(|&v| DualDVec64::from_re(v)).collect();
    for (i, p) in free.iter().enumerate() {
        params[p.index()] = DualDVec64::new(
            all[p.index()],
            Derivative::derivative_generic(Dyn(n), U1, i),
        );
    }
    let mut values = Vec::new();
    let mut rows = Vec::new();
    for c in &problem.captures {
        let r = c
            .weighted_residuals(&params)
            .expect("in front of the camera");
        for pair in r.chunks(2) {
            let s = pair[0].clone() * pair[0].clone() + pair[1].clone() * pair[1].clone();
            let w = robust_weight(problem.loss, s);
            for d in pair {
                let d = d.clone() * w.clone();
                values.push(d.re);
                rows.push(d.eps.unwrap_generic(Dyn(n), U1).transpose());
            }
        }
    }
    (values, DMatrix::from_rows(&rows))
}

/// One plain least-squares calibration (no noise model): what most backend tests compare.
pub fn solve(
    problem: &Problem,
    backend: &dyn naocalib::solve::Backend,
) -> Result<naocalib::solve::Solution, naocalib::solve::SolveError> {
    naocalib::solve::calibrate(
        problem,
        backend,
        &naocalib::solve::UncertaintyOptions::plain(),
    )
}

/// The truth moved along the solution's undetermined directions (see
/// [`naocalib::solve::identify::determined_truth`]).
pub fn determined_truth(
    solution: &naocalib::solve::Solution,
    truth: &[f64; naocalib::model::PARAMETER_COUNT],
) -> [f64; naocalib::model::PARAMETER_COUNT] {
    naocalib::solve::identify::determined_truth(&solution.undetermined, truth)
}

/// A random estimate of `param` (report units) of at most `size` that lies within its
/// physical bounds (`naocalib::model::bounds`): non-negative compliance and play, small
/// distortion coefficients.
pub fn plausible_value(rng: &mut impl rand::Rng, param: naocalib::model::Param, size: f64) -> f64 {
    use naocalib::model::Param;
    match param {
        Param::K1 | Param::K2 | Param::UpperK1 | Param::UpperK2 => rng.random_range(-0.5..0.5),
        _ if naocalib::model::bounds::bound(param).min == 0.0 => rng.random_range(0.0..size),
        _ => rng.random_range(-size..size),
    }
}

/// Every family beyond the paper's, comma-separated, from the family registry (for
/// `--free` and [`naocalib::model::FixedSet::from_lists`]): a family added to the registry
/// is freed by the tests that free them all.
pub fn every_family() -> String {
    use naocalib::model::Family;
    Family::ALL
        .into_iter()
        .filter(|f| *f != Family::Paper)
        .map(Family::name)
        .collect::<Vec<_>>()
        .join(",")
}

/// A converged calibration (solver `test`, RMS 0.4/0.5 px) whose robot files carry the
/// offsets of `posture`, with `entry` of every parameter in registry order.
pub fn converged_calibration(
    posture: naocalib::export::Posture,
    entry: impl FnMut(naocalib::model::Param) -> naocalib::export::Entry,
) -> naocalib::calibration::Calibration {
    naocalib::calibration::Calibration {
        origin: naocalib::calibration::Origin::Solved,
        solver: Some("test".into()),
        dataset: None,
        converged: Some(true),
        rms_px: Some([0.4, 0.5]),
        parameters: naocalib::model::Param::ALL.into_iter().map(entry).collect(),
        angles: None,
        posture,
        standing: Default::default(),
        cameras: Default::default(),
    }
}

/// `naocalib export --update` of `path` in `format` with `cal`, which must change it: the
/// backup kept.
pub fn updated(
    cal: &naocalib::calibration::Calibration,
    format: &'static dyn naocalib::export::Format,
    path: &Path,
) -> PathBuf {
    use naocalib::export::{Updated, update};
    match update(cal, Some(format), path, &[]).unwrap() {
        (f, Updated::Written { backup, .. }) if f == format => backup,
        other => panic!("{}: not updated: {other:?}", path.display()),
    }
}

/// Writes `truth` (internal units, every parameter) as a truth.toml at `path`.
pub fn write_truth(path: &Path, truth: &[f64; naocalib::model::PARAMETER_COUNT]) {
    let mut toml = String::from("[parameters]\n");
    for p in naocalib::model::Param::ALL {
        toml += &format!("{} = {}\n", p.name(), p.unit().to_report(truth[p.index()]));
    }
    std::fs::write(path, toml).unwrap();
}

/// The paper-sized plan (144 captures, the paper's family, the default model and options),
/// made once per test binary for every module that needs it.
pub fn paper_plan() -> &'static naocalib::plan::Plan {
    static PLAN: std::sync::OnceLock<naocalib::plan::Plan> = std::sync::OnceLock::new();
    PLAN.get_or_init(|| {
        naocalib::plan::plan(
            &naocalib::model::Model::default(),
            &naocalib::plan::PlanOptions::default(),
        )
        .expect("plan")
    })
}

/// Reads a grey PNG (as `naocalib simulate --images` renders them).
pub fn read_grey_png(path: &Path) -> naocalib::sim::render::GreyImage {
    let file = std::fs::File::open(path).unwrap();
    let decoder = png::Decoder::new(std::io::BufReader::new(file));
    let mut reader = decoder.read_info().unwrap();
    let mut pixels = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut pixels).unwrap();
    assert_eq!(info.color_type, png::ColorType::Grayscale);
    pixels.truncate(info.buffer_size());
    naocalib::sim::render::GreyImage {
        width: info.width,
        height: info.height,
        pixels,
    }
}

/// `robot` off by what a team's calibration misses (each camera angle by up to 0.3°, each
/// leg offset by up to 0.5°), the rest as `robot` has it: what the files say of a robot
/// whose truth this is, or the truth of a robot whose files `robot` is.
pub fn missed_by_a_team(
    robot: &[f64; naocalib::model::PARAMETER_COUNT],
    rng: &mut impl rand::Rng,
) -> [f64; naocalib::model::PARAMETER_COUNT] {
    use naocalib::model::{Param, ParamGroup};
    let mut out = *robot;
    for p in Param::ALL {
        let miss: f64 = match p.group() {
            ParamGroup::Camera | ParamGroup::UpperCamera => 0.3,
            ParamGroup::LeftLeg | ParamGroup::RightLeg => 0.5,
            _ => continue,
        };
        out[p.index()] += rng.random_range(-miss..=miss).to_radians();
    }
    out
}

/// The bundled sample, `data/sample`.
pub fn sample() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("data/sample")
}

/// A `dataset.toml` whose `[board]` is the paper's (the bundled sample's), for
/// `simulate --board`: the tests whose few random stances were drawn for that board.
pub fn paper_board() -> std::path::PathBuf {
    sample().join("dataset.toml")
}
