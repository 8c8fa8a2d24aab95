//! `naocalib batch`: calibrate many datasets in parallel and summarise them.

use std::io::IsTerminal as _;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicUsize, Ordering};

use anyhow::{Context, Result};
use clap::{Args, ValueEnum};

use super::options::{ProblemArgs, SolverArgs, UncertaintyArgs};
use naocalib::batch::{self, BatchOptions, DriftMode, DriftOptions, Grouping, Progress};
use naocalib::export::WriteOptions;

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
    let fixed = args.problem.fixed_set()?;
    if !(args.drift_threshold.is_finite() && args.drift_threshold > 0.0) {
        anyhow::bail!(
            "--drift-threshold must be a positive number, got {}",
            args.drift_threshold
        );
    }
    let options = BatchOptions {
        solver: args.solver.solver.clone(),
        loss: args.problem.loss(),
        fixed,
        threads: args.threads,
        verbose,
        drift: DriftOptions {
            mode: match args.drift {
                DriftArg::Consecutive => DriftMode::Consecutive,
                DriftArg::First => DriftMode::First,
            },
            threshold: args.drift_threshold,
            grouping: match args.robots {
                RobotsArg::Parent => Grouping::Parent,
                RobotsArg::All => Grouping::All,
                RobotsArg::None => Grouping::None,
            },
        },
        ..BatchOptions::default()
    }
    .with_uncertainty(args.uncertainty.options());
    // Every output against every dataset's files, before anything is solved or written.
    let (found, _) = batch::find_datasets(&args.datasets);
    let write_options = WriteOptions::new(args.force).protecting(
        found
            .iter()
            .flat_map(|d| naocalib::output::dataset_files(d))
            .collect::<Vec<_>>(),
    );
    naocalib::output::check_outputs(
        &args.report.as_deref().into_iter().collect::<Vec<_>>(),
        &args
            .out
            .iter()
            .chain(&args.plots)
            .map(PathBuf::as_path)
            .collect::<Vec<_>>(),
        &write_options,
    )?;
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
    let write_options = write_options.protecting(result.input_files());
    if let Some(dir) = &args.out {
        let files = result
            .write(dir, &options.drift, &write_options)
            .context("--out")?;
        note!(
            "wrote {} run results and {}",
            files.runs.len(),
            files.summary.display()
        );
    }
    if let Some(dir) = &args.plots {
        let files = result.plots(dir, &write_options).context("--plots")?;
        note!("wrote {} plot files into {}", files.len(), dir.display());
    }
    if let Some(path) = &args.report {
        naocalib::report::html::write_batch_report(&result, &options.drift, path, &write_options)
            .context("--report")?;
        note!("wrote {}", path.display());
    }
    super::print_out(if args.json {
        format!(
            "{}\n",
            serde_json::to_string_pretty(&result.json(&options.drift))?
        )
    } else {
        result.table(&options.drift)
    })?;
    for f in result.failures.iter().filter(|_| args.json) {
        note!("naocalib: {}: {}", f.dataset.display(), f.error);
    }
    Ok(if !result.all_solved() {
        ExitCode::from(2)
    } else if !result.all_converged() {
        ExitCode::from(3)
    } else {
        ExitCode::SUCCESS
    })
}
