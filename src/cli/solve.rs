//! `naocalib solve`: calibrate one dataset and print the result.

use std::io::IsTerminal as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::Args;

use super::options::{ProblemArgs, SolverArgs, UncertaintyArgs};
use naocalib::dataset::Dataset;
use naocalib::solve::{self, Problem};

#[derive(Debug, Args)]
pub struct SolveArgs {
    /// Dataset directory (dataset.toml, captures.csv, corners.csv).
    dataset: PathBuf,
    /// Detect the vertices in the dataset's images (as `naocalib detect` does, in memory)
    /// and solve with them instead of corners.csv, which is neither needed nor written.
    #[arg(long)]
    detect: bool,
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

fn load(path: &Path) -> Result<Dataset> {
    Ok(Dataset::load(path)?)
}

/// The dataset with the vertices detected in its images instead of its corners.csv.
#[cfg(feature = "detect")]
fn load_detected(path: &Path, verbose: bool, start_from: Option<&Path>) -> Result<Dataset> {
    let mut dataset = Dataset::load_without_corners(path)?;
    super::detect::detect_for_solve(&mut dataset, verbose, start_from)?;
    Ok(dataset)
}

#[cfg(not(feature = "detect"))]
fn load_detected(_: &Path, _: bool, _: Option<&Path>) -> Result<Dataset> {
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
    let fixed = args.problem.fixed_set()?;
    let backend = args.solver.backend(verbose)?;
    // Every output against the dataset's files, before the solve.
    naocalib::output::check_outputs(
        &args.report.as_deref().into_iter().collect::<Vec<_>>(),
        &args
            .plots
            .iter()
            .chain(&args.export)
            .map(PathBuf::as_path)
            .collect::<Vec<_>>(),
        &naocalib::output::WriteOptions::protecting_dataset(&args.dataset, args.force),
    )?;
    let dataset = if args.detect {
        load_detected(&args.dataset, verbose, args.start_from.as_deref())?
    } else {
        load(&args.dataset)?
    };
    let mut problem = Problem::from_dataset(&dataset, fixed)?;
    problem.loss = args.problem.loss();
    let corrected = dataset.angles.kind == naocalib::dataset::AngleKind::Corrected;
    let previous = match &args.start_from {
        Some(path) => {
            let previous = naocalib::export::read_start_from(path)
                .with_context(|| format!("--start-from {}", path.display()))?;
            let values: Vec<_> = previous
                .parameters
                .iter()
                .filter(|e| e.is_determined())
                .map(|e| (e.param, e.value))
                .collect();
            problem.start_from(&values, corrected);
            Some(previous)
        }
        None => None,
    };
    let options = args.uncertainty.options();
    let calibrate = || solve::calibrate(&problem, backend.as_ref(), &options);
    let solution = if options.bootstrap > 0 && std::io::stderr().is_terminal() {
        // A long bootstrap shows its progress.
        let bar = super::progress_bar(options.bootstrap, "bootstrap refits");
        let shown = bar.clone();
        let hook = Box::new(move |done: usize, _: usize| shown.set_position(done as u64));
        let solution = solve::uncertainty::with_bootstrap_progress(hook, calibrate);
        bar.finish_and_clear();
        solution
    } else {
        calibrate()
    }
    .with_context(|| format!("solving {}", args.dataset.display()))?;
    let changes = previous
        .as_ref()
        .map(|p| naocalib::report::changes(&solution, p, corrected));
    let mut calibration =
        naocalib::calibration::Calibration::from_solution(&solution, Some(&dataset.dir))
            .with_lying_torques(&dataset);
    calibration.angles = Some(dataset.angles.clone());
    super::export::solve_outputs(
        &solution,
        &calibration,
        &dataset,
        args.plots.as_deref(),
        args.export.as_deref(),
        args.report.as_deref(),
        changes.as_deref(),
        args.force,
    )?;
    // A capture whose residuals are many times the others' is named, and the run marked.
    let marked = args.detect && detect_guard(&solution);
    let truth = dataset.truth.as_ref().map(|t| &t.values[..]);
    use std::fmt::Write as _;
    let mut out = String::new();
    if args.json {
        let mut result =
            naocalib::report::ResultJson::new(&solution, truth).with_standing(&calibration);
        result.dataset = Some(args.dataset.display().to_string());
        result.angles = Some(dataset.angles.kind);
        result.corrected_by = dataset.angles.corrected_by.clone();
        if let Some(changes) = &changes {
            result = result.with_changes(changes);
        }
        let value = result.to_value();
        writeln!(out, "{}", serde_json::to_string_pretty(&value)?)?;
    } else {
        writeln!(out, "{}", args.dataset.display())?;
        write!(out, "{}", naocalib::report::table(&solution, truth))?;
        write!(out, "{}", naocalib::report::standing_table(&calibration))?;
        if let Some(changes) = &changes {
            write!(out, "{}", naocalib::report::changes_table(changes))?;
        }
    }
    if marked && !args.json {
        writeln!(
            out,
            "MARKED: captures with residuals many times the others' (see the warnings above)"
        )?;
    }
    super::print_out(out)?;
    Ok(if solution.is_calibration() && !marked {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(3)
    })
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
