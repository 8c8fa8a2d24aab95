//! `naocalib solve`: calibrate one dataset and print the result.

use std::io::IsTerminal as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::Args;

use super::options::{ProblemArgs, SolverArgs, UncertaintyArgs, run_options};
use naocalib::dataset::Dataset;
use naocalib::report::RunFiles;
use naocalib::report::printed;
use naocalib::run::{self, Run, RunError, RunOptions};
use naocalib::solve::{self, uncertainty::with_bootstrap_progress};

#[derive(Debug, Args)]
pub struct SolveArgs {
    /// Dataset directory (dataset.toml, captures.csv, corners.csv).
    dataset: PathBuf,
    /// Detect the vertices in the dataset's images (as `naocalib detect` does, in memory)
    /// and solve with them instead of corners.csv, which is neither needed nor written.
    #[arg(long)]
    detect: bool,
    /// With --detect: the pictures show the robot lying on its back; drop every vertex its
    /// body (docs/BODY.md) stands in front of, as `naocalib detect --body` does.
    #[arg(long, requires = "detect")]
    body: bool,
    /// Print the result as JSON (docs/MODEL.md §8).
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    problem: ProblemArgs,
    #[command(flatten)]
    uncertainty: UncertaintyArgs,
    #[command(flatten)]
    solver: SolverArgs,
    /// Write plots (PNG and SVG) into this directory: residuals before/after, per capture.
    #[arg(long, value_name = "DIR")]
    plots: Option<PathBuf>,
    /// Write the calibration files into this directory (one per export format).
    #[arg(long, value_name = "DIR", long_help = export_dir_help())]
    export: Option<PathBuf>,
    /// Write one self-contained HTML report (parameters, diagnosis, residual plots,
    /// per-capture RMS, overlays of the worst captures) to this file.
    #[arg(long, value_name = "FILE.html")]
    report: Option<PathBuf>,
    /// Replace existing --plots/--export/--report files (never the dataset's).
    #[arg(long)]
    force: bool,
    /// Start from the robot's current calibration (`naocalib import`, or an earlier
    /// calibration TOML/JSON): its values are the start values, the head offsets are held
    /// at its values unless the head family is freed (the framework applies them before
    /// the camera correction), and the report shows the change since it, z = change/σ.
    #[arg(long, value_name = "CAL.toml")]
    start_from: Option<PathBuf>,
}

/// The dataset with the vertices detected in its images instead of its corners.csv.
#[cfg(feature = "detect")]
fn load_detected(
    path: &Path,
    verbose: bool,
    start_from: Option<&Path>,
    body: bool,
) -> Result<Dataset> {
    let mut dataset = Dataset::load_without_corners(path)?;
    super::detect::detect_for_solve(&mut dataset, verbose, start_from, body)?;
    Ok(dataset)
}

#[cfg(not(feature = "detect"))]
fn load_detected(_: &Path, _: bool, _: Option<&Path>, _: bool) -> Result<Dataset> {
    anyhow::bail!(
        "--detect needs naocalib built with the `detect` feature (OpenCV), which this build \
         lacks; rebuild with default features, or run `naocalib detect` elsewhere and solve \
         with its corners.csv"
    )
}

/// `solve --detect`'s guard (see `naocalib::detect::guard`): `true` when captures stand out.
#[cfg(feature = "detect")]
fn detect_guard(solution: &solve::Solution) -> bool {
    super::detect::guard(solution)
}

#[cfg(not(feature = "detect"))]
fn detect_guard(_: &solve::Solution) -> bool {
    false
}

/// Runs `naocalib solve`.
pub fn run(args: &SolveArgs, verbose: bool) -> Result<ExitCode> {
    // The options first: a mistake in them should not wait for a detection run.
    let mut options = run_options(&args.problem, &args.solver, &args.uncertainty, verbose)?;
    let files = RunFiles {
        plots: args.plots.clone(),
        export: args.export.clone(),
        report: args.report.clone(),
        force: args.force,
        inputs: args.start_from.iter().cloned().collect(),
    };
    files.check(&args.dataset)?;
    let dataset = if args.detect {
        load_detected(
            &args.dataset,
            verbose,
            args.start_from.as_deref(),
            args.body,
        )?
    } else {
        Dataset::load(&args.dataset)?
    };
    if let Some(path) = &args.start_from {
        options.start_from = Some(
            naocalib::export::read_start_from(path)
                .with_context(|| format!("--start-from {}", path.display()))?,
        );
    }
    let run = calibrate(&dataset, &options).map_err(|e| match e {
        RunError::Solve(_) => {
            anyhow::Error::new(e).context(format!("solving {}", args.dataset.display()))
        }
        e => e.into(),
    })?;
    files.write(&run, &dataset, &mut |line| note!("{line}"))?;
    // A capture whose residuals are many times the others' is named, and the run marked.
    let marked = args.detect && detect_guard(&run.solution);
    super::print_out(printed::solve_output(&run, args.json, marked)?)?;
    Ok(ExitCode::from(printed::solve_exit_code(&run, marked)))
}

/// [`run::calibrate`], with a progress bar for a long bootstrap on a terminal.
fn calibrate(dataset: &Dataset, options: &RunOptions) -> Result<Run, RunError> {
    let refits = options.uncertainty.bootstrap;
    if refits == 0 || !std::io::stderr().is_terminal() {
        return run::calibrate(dataset, options);
    }
    let bar = super::progress_bar(refits, "bootstrap refits");
    let shown = bar.clone();
    let hook = Box::new(move |done: usize, _: usize| shown.set_position(done as u64));
    let run = with_bootstrap_progress(hook, || run::calibrate(dataset, options));
    bar.finish_and_clear();
    run
}

/// The `--export` help: the files it writes, one per export format of the registry.
fn export_dir_help() -> String {
    let files: Vec<&str> = naocalib::export::FORMATS.iter().map(|f| f.file()).collect();
    format!(
        "Write the calibration files into this directory, one per export format \
         (docs/EXPORTS.md, `naocalib export --help`): {}",
        files.join(", ")
    )
}
