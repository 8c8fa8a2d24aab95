//! The command line: thin wrappers that parse arguments, call the library and print.

#[cfg(feature = "detect")]
mod detect;
mod simulate;
mod solve;

use std::process::ExitCode;

use anyhow::{Result, bail};
use clap::{Parser, Subcommand};

use crate::solve::Backend;

/// The backend used when `--solver` is not given.
pub const DEFAULT_SOLVER: &str = if cfg!(feature = "ceres") {
    "ceres"
} else {
    "lm"
};

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
    /// Calibrate: fit the offsets to a dataset's corners and print them with their
    /// uncertainty.
    Solve(solve::SolveArgs),
    /// Find the sandal's vertices in a dataset's images with OpenCV; write corners.csv.
    #[cfg(feature = "detect")]
    Detect(detect::DetectArgs),
}

/// Parses the command line, runs it, and maps errors to a message and exit code 1.
pub fn main() -> ExitCode {
    let cli = Cli::parse();
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
        Command::Solve(args) => solve::run(args, cli.verbose),
        #[cfg(feature = "detect")]
        Command::Detect(args) => detect::run(args),
    }
}

/// The backend called `name`, or an error listing the available ones.
pub fn backend(name: &str, verbose: bool) -> Result<Box<dyn Backend>> {
    match crate::solve::backend(name, verbose) {
        Some(b) => Ok(b),
        None => bail!(
            "unknown solver '{name}' (available: {})",
            crate::solve::backend_names().join(", ")
        ),
    }
}
