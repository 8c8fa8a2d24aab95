//! `naocalib batch`: calibrate many datasets in parallel and summarise them.

use std::io::IsTerminal as _;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicUsize, Ordering};

use anyhow::Result;
use clap::{Args, ValueEnum};

use super::options::{ProblemArgs, SolverArgs, UncertaintyArgs, run_options};
use naocalib::batch::{
    self, BatchFiles, BatchOptions, DriftMode, DriftOptions, Grouping, Progress,
};

/// Which runs are compared for drift.
#[derive(Debug, Clone, Copy, ValueEnum)]
enum DriftArg {
    /// Each run with the one before it.
    Consecutive,
    /// Each run with the first.
    First,
}

/// Which runs are of the same robot.
#[derive(Debug, Clone, Copy, ValueEnum)]
enum RobotsArg {
    /// Datasets in the same parent directory are one robot's.
    Parent,
    /// All runs are of one robot.
    All,
    /// No drift.
    None,
}

/// Exit codes: 0 all solved and converged; 2 some dataset failed (reported, skipped);
/// 3 all solved but some did not converge; 1 a usage or output error.
#[derive(Debug, Args)]
pub struct BatchArgs {
    /// Dataset directories, or directories holding dataset directories.
    #[arg(required = true, value_name = "DATASET")]
    datasets: Vec<PathBuf>,
    /// Print every run (docs/MODEL.md §8 form, with its dataset) and the summary as JSON.
    #[arg(long)]
    json: bool,
    /// Write each run's result JSON and summary.json into this directory.
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Write plots (PNG and SVG) into this directory: parameter estimates across runs, and
    /// each run's residuals and per-capture RMS.
    #[arg(long, value_name = "DIR")]
    plots: Option<PathBuf>,
    /// Write one self-contained HTML report of every run (summary, estimates across runs,
    /// each run's parameters, diagnosis and plots) to this file.
    #[arg(long, value_name = "FILE.html")]
    report: Option<PathBuf>,
    /// Replace existing output files (never a dataset's files).
    #[arg(long)]
    force: bool,
    #[command(flatten)]
    problem: ProblemArgs,
    #[command(flatten)]
    solver: SolverArgs,
    /// Worker threads (0: one per core).
    #[arg(long, default_value_t = 0)]
    threads: usize,
    /// Drift: compare each run with the one before it, or with the first.
    #[arg(long, value_enum, default_value = "consecutive")]
    drift: DriftArg,
    /// Flag a parameter whose change between two runs has |z| above this.
    #[arg(long, default_value_t = 3.0, value_name = "Z")]
    drift_threshold: f64,
    /// Which runs are of the same robot (for drift).
    #[arg(long, value_enum, default_value = "parent")]
    robots: RobotsArg,
    #[command(flatten)]
    uncertainty: UncertaintyArgs,
    /// No progress bar, even on a terminal.
    #[arg(long)]
    no_progress: bool,
}

/// Runs `naocalib batch`.
pub fn run(args: &BatchArgs, verbose: bool) -> Result<ExitCode> {
    let options = BatchOptions {
        run: run_options(&args.problem, &args.solver, &args.uncertainty, verbose)?,
        threads: args.threads,
        drift: drift_options(args)?,
    };
    let files = BatchFiles {
        out: args.out.clone(),
        plots: args.plots.clone(),
        report: args.report.clone(),
        force: args.force,
    };
    // Every output against every dataset's files, before anything is solved or written.
    files.check(&batch::find_datasets(&args.datasets).0)?;
    let show = !args.no_progress && !verbose && std::io::stderr().is_terminal();
    let bar = show.then(|| super::progress_bar(0, "datasets"));
    let failed = AtomicUsize::new(0);
    let progress = |p: Progress<'_>| {
        let Some(bar) = &bar else { return };
        bar.set_length(p.total as u64);
        if !p.ok {
            let n = failed.fetch_add(1, Ordering::Relaxed) + 1;
            bar.set_message(format!(" ({n} failed)"));
        }
        bar.inc(1);
    };
    let result = batch::run(&args.datasets, &options, &progress);
    if let Some(bar) = &bar {
        bar.finish_and_clear();
    }
    files.write(&result, &options.drift, &mut |line| note!("{line}"))?;
    let (text, failures) = batch::request::printed(&result, &options.drift, args.json)?;
    super::print_out(text)?;
    for f in failures {
        note!("{f}");
    }
    Ok(ExitCode::from(batch::request::exit_code(&result)))
}

/// The drift options of the flags.
fn drift_options(args: &BatchArgs) -> Result<DriftOptions> {
    let mode = match args.drift {
        DriftArg::Consecutive => DriftMode::Consecutive,
        DriftArg::First => DriftMode::First,
    };
    let grouping = match args.robots {
        RobotsArg::Parent => Grouping::Parent,
        RobotsArg::All => Grouping::All,
        RobotsArg::None => Grouping::None,
    };
    batch::request::drift_options(mode, args.drift_threshold, grouping).map_err(anyhow::Error::msg)
}
