//! The command line: thin wrappers that parse arguments, call the library and print.

mod batch;
mod capture;
mod compare;
#[cfg(feature = "detect")]
mod detect;
mod export;
mod options;
mod plan;
mod simulate;
mod simulate_robot;
mod solve;

use std::process::ExitCode;

use anyhow::Result;
use clap::{Parser, Subcommand};

/// Automatic kinematic calibration of the NAO (Kastner, Röfer, Laue).
#[derive(Debug, Parser)]
#[command(name = "naocalib", version, about)]
pub struct Cli {
    /// Show solver progress and library logging on stderr.
    #[arg(short, long, global = true)]
    pub verbose: bool,
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Simulate a dataset: true offsets, stances with a board in view, noisy corners.
    Simulate(simulate::SimulateArgs),
    /// Design a stance schedule for a robot: feasible before calibration, chosen to
    /// determine the free parameters best, ordered to run quickly.
    Plan(plan::PlanArgs),
    /// Calibrate: fit the offsets to a dataset's corners and print them with their
    /// uncertainty.
    Solve(solve::SolveArgs),
    /// Run every solver on the same dataset: a table of convergence, cost, RMS, time and
    /// the largest difference from Ceres in sigma, and the parameters side by side.
    Compare(compare::CompareArgs),
    /// Calibrate many datasets in parallel: a table of all runs with mean ± std across
    /// runs, drift between runs of the same robot, and failures reported and skipped.
    Batch(batch::BatchArgs),
    /// Write a result as calibration files: TOML/JSON and B-Human style .cfg.
    Export(export::ExportArgs),
    /// Run a plan's stances on a NAO V6 over LoLA and write the dataset: the measurement
    /// phase (needs neither Ceres nor OpenCV; docs/CAPTURE.md).
    Capture(capture::CaptureArgs),
    /// A simulated NAO lying on its back that serves LoLA (for testing capture), and
    /// `snap`, its lower camera.
    SimulateRobot(simulate_robot::SimulateRobotArgs),
    /// Find the sandal's vertices in a dataset's images with OpenCV; write corners.csv.
    #[cfg(feature = "detect")]
    Detect(detect::DetectArgs),
}

/// A progress bar on stderr over `len` items called `what` (`images`, `datasets`): done,
/// the bar's message (e.g. failures so far), elapsed time and the ETA.
fn progress_bar(len: usize, what: &str) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(len as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template(&format!(
            "{{bar:40}} {{pos}}/{{len}} {what}{{msg}}, {{elapsed}} elapsed, {{eta}} left"
        ))
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar
}

/// Parses the command line, runs it, and maps errors (a bad flag included) to a message
/// and exit code 1.
pub fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            let _ = e.print();
            return ExitCode::from(if e.use_stderr() { 1 } else { 0 });
        }
    };
    naocalib::solve::retain_freed_memory();
    match run(&cli) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("naocalib: error: {e:#}");
            ExitCode::from(1)
        }
    }
}

/// Runs one parsed command line.
pub fn run(cli: &Cli) -> Result<ExitCode> {
    match &cli.command {
        Command::Simulate(args) => simulate::run(args),
        Command::Plan(args) => plan::run(args),
        Command::Solve(args) => solve::run(args, cli.verbose),
        Command::Compare(args) => compare::run(args),
        Command::Batch(args) => batch::run(args, cli.verbose),
        Command::Export(args) => export::run(args),
        Command::Capture(args) => capture::run(args),
        Command::SimulateRobot(args) => simulate_robot::run(args),
        #[cfg(feature = "detect")]
        Command::Detect(args) => detect::run(args),
    }
}
