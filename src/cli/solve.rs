//! `naocalib solve`: calibrate one dataset and print the result.

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::Args;

use super::DEFAULT_SOLVER;
use crate::dataset::Dataset;
use crate::model::{FixedSet, parameters::parse_param_list};
use crate::solve::{self, Problem};

#[derive(Debug, Args)]
pub struct SolveArgs {
    /// Dataset directory (dataset.toml, captures.csv, corners.csv).
    dataset: PathBuf,
    /// Detect the vertices in the dataset's images (as `naocalib detect` does, in memory)
    /// and solve with them instead of corners.csv, which is neither needed nor written.
    #[arg(long)]
    detect: bool,
    /// Print the result as JSON (SPEC section 7).
    #[arg(long)]
    json: bool,
    /// Parameters to hold fixed at zero, comma-separated (e.g. CamYaw,LBoardRotZ).
    #[arg(long, value_name = "NAMES")]
    fix: Option<String>,
    /// Parameters to estimate that are held fixed by default (HeadYaw,HeadPitch).
    #[arg(long, value_name = "NAMES")]
    free: Option<String>,
    /// Pixel noise σ [px] for the noise model; estimated from the residuals if not given.
    #[arg(long, value_name = "PX")]
    px_noise: Option<f64>,
    /// Joint-angle noise σ per joint and capture [deg]; estimated if not given.
    #[arg(long, value_name = "DEG")]
    joint_noise_deg: Option<f64>,
    /// Report the plain σ̂²(JᵀJ)⁻¹ instead of the noise model (over-confident under joint
    /// noise).
    #[arg(long)]
    plain_std: bool,
    /// Also estimate the uncertainty by a capture bootstrap with N refits.
    #[arg(long, value_name = "N", default_value_t = 0)]
    bootstrap: usize,
    /// Robust first fit: huber or cauchy, optionally with a scale in px (huber:2);
    /// outlier vertices are listed and left out of the final fit.
    #[arg(long, value_name = "LOSS[:PX]")]
    loss: Option<String>,
    /// Least-squares backend: ceres (default), lm (levenberg-marquardt crate), tiny
    /// (tiny-solver).
    #[arg(long, default_value = DEFAULT_SOLVER)]
    solver: String,
    /// Write plots (PNG and SVG) into this directory: residuals before/after, per capture.
    #[arg(long, value_name = "DIR")]
    plots: Option<PathBuf>,
    /// Write the calibration files into this directory: calibration.toml/.json and B-Human
    /// style cameraCalibration.cfg and jointCalibration.cfg.
    #[arg(long, value_name = "DIR")]
    export: Option<PathBuf>,
    /// Replace existing --plots/--export files (never the dataset's).
    #[arg(long)]
    force: bool,
}

/// The held parameters for `--fix` and `--free`.
pub fn fixed_set(fix: Option<&str>, free: Option<&str>) -> Result<FixedSet> {
    let mut fixed = FixedSet::default();
    for p in parse_param_list(free.unwrap_or(""))
        .map_err(anyhow::Error::msg)
        .context("--free")?
    {
        fixed.set(p, false);
    }
    for p in parse_param_list(fix.unwrap_or(""))
        .map_err(anyhow::Error::msg)
        .context("--fix")?
    {
        fixed.set(p, true);
    }
    Ok(fixed)
}

fn load(path: &Path) -> Result<Dataset> {
    Ok(Dataset::load(path)?)
}

/// The dataset with the vertices detected in its images instead of its corners.csv.
#[cfg(feature = "detect")]
fn load_detected(path: &Path, verbose: bool) -> Result<Dataset> {
    let mut dataset = Dataset::load_without_corners(path)?;
    super::detect::detect_for_solve(&mut dataset, verbose)?;
    Ok(dataset)
}

#[cfg(not(feature = "detect"))]
fn load_detected(_: &Path, _: bool) -> Result<Dataset> {
    anyhow::bail!(
        "--detect needs naocalib built with the `detect` feature (OpenCV), which this build \
         lacks; rebuild with default features, or run `naocalib detect` elsewhere and solve \
         with its corners.csv"
    )
}

/// Runs `naocalib solve`.
pub fn run(args: &SolveArgs, verbose: bool) -> Result<ExitCode> {
    // The options first: a mistake in them should not wait for a detection run.
    let fixed = fixed_set(args.fix.as_deref(), args.free.as_deref())?;
    let backend = super::backend(&args.solver, verbose)?;
    let loss = args.loss.as_deref().map(parse_loss).transpose()?;
    for (name, value) in [
        ("--px-noise", args.px_noise),
        ("--joint-noise-deg", args.joint_noise_deg),
    ] {
        if let Some(v) = value
            && !(v.is_finite() && v > 0.0)
        {
            anyhow::bail!("{name} must be a positive number, got {v}");
        }
    }
    let dataset = if args.detect {
        load_detected(&args.dataset, verbose)?
    } else {
        load(&args.dataset)?
    };
    let mut problem = Problem::from_dataset(&dataset, fixed)?;
    if let Some(loss) = loss {
        problem.loss = loss;
    }
    let options = solve::UncertaintyOptions {
        noise_model: !args.plain_std,
        noise: solve::noise::NoiseOptions {
            px: args.px_noise,
            joint: args.joint_noise_deg.map(f64::to_radians),
        },
        bootstrap: args.bootstrap,
        seed: 1,
    };
    let solution = solve::calibrate(&problem, backend.as_ref(), &options)
        .with_context(|| format!("solving {}", args.dataset.display()))?;
    super::export::solve_outputs(
        &solution,
        &dataset,
        args.plots.as_deref(),
        args.export.as_deref(),
        args.force,
    )?;
    let truth = dataset.truth.as_ref().map(|t| &t.values[..]);
    let mut stdout = std::io::stdout().lock();
    if args.json {
        let mut value = crate::report::json(&solution, truth);
        value["dataset"] = serde_json::Value::String(args.dataset.display().to_string());
        writeln!(stdout, "{}", serde_json::to_string_pretty(&value)?)?;
    } else {
        writeln!(stdout, "{}", args.dataset.display())?;
        write!(stdout, "{}", crate::report::table(&solution, truth))?;
    }
    Ok(if solution.summary.converged {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(3)
    })
}

/// Parses `huber`, `cauchy`, `huber:2.5`.
pub fn parse_loss(text: &str) -> Result<solve::Loss> {
    let (name, scale) = match text.split_once(':') {
        Some((n, s)) => {
            let v: f64 = s
                .parse()
                .ok()
                .filter(|v: &f64| v.is_finite() && *v > 0.0)
                .with_context(|| format!("--loss {text}: the scale must be a positive number"))?;
            (n, v)
        }
        None => (text, 1.0),
    };
    match name {
        "huber" => Ok(solve::Loss::Huber(scale)),
        "cauchy" => Ok(solve::Loss::Cauchy(scale)),
        _ => anyhow::bail!("--loss {text}: unknown loss '{name}' (huber or cauchy)"),
    }
}
