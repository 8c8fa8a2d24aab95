//! The command line: thin wrappers that parse arguments, call the library and print.
//!
//! Nothing here prints with `println!`/`eprintln!`, which panic when the stream is closed
//! or full: standard output goes through [`print_out`] (a closed pipe ends the command
//! quietly, a full device is an error), messages on standard error through [`note!`]
//! (whose failure is ignored: there is nowhere left to report it).

/// Like `eprintln!`, but a closed or full standard error is ignored instead of a panic.
macro_rules! note {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr(), $($arg)*);
    }};
}

mod batch;
mod capture;
mod compare;
#[cfg(feature = "detect")]
mod detect;
mod export;
mod import;
mod options;
mod plan;
mod sandal;
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
    /// Write a result as calibration files: TOML/JSON and the teams' formats, fresh or
    /// updating a robot's own file (--update).
    Export(export::ExportArgs),
    /// Read a robot's current team calibration files into naocalib's calibration TOML.
    Import(import::ImportArgs),
    /// Run a plan's stances on a NAO V6 over LoLA and write the dataset: the measurement
    /// phase (needs neither Ceres nor OpenCV; docs/CAPTURE.md).
    Capture(capture::CaptureArgs),
    /// A simulated NAO lying on its back that serves LoLA (for testing capture), and
    /// `snap`, its lower camera.
    SimulateRobot(simulate_robot::SimulateRobotArgs),
    /// Write the sandals to make: the pattern to print at 1:1 (SVG, PDF on A4 and US
    /// Letter), a drilling and cutting template and an OpenSCAD plate, for both feet.
    Sandal(sandal::SandalArgs),
    /// Find the sandal's vertices in a dataset's images with OpenCV; write corners.csv.
    #[cfg(feature = "detect")]
    Detect(detect::DetectArgs),
    /// The guard of a `command:` camera's processes (capture's own use).
    #[command(name = "camera-guard", hide = true)]
    CameraGuard(capture::CameraGuardArgs),
    /// The guard that takes the robot to rest when capture dies (capture's own use).
    #[command(name = "rest-guard", hide = true)]
    RestGuard(capture::RestGuardArgs),
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

/// Writes `text` to standard output and flushes it; a failure is an error saying so (a
/// closed pipe among them, which [`main`] ends quietly).
pub(crate) fn print_out(text: impl AsRef<str>) -> Result<()> {
    use std::io::Write as _;
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_ref().as_bytes())
        .and_then(|()| out.flush())
        .map_err(|e| anyhow::Error::new(e).context("cannot write to standard output"))
}

/// Whether `e` comes from writing into a closed pipe (the reader went away: not an error
/// worth a message).
fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

/// The error with its causes, `a: b: c`, each said once (an error whose message already
/// holds its cause's text, such as the operating system's, does not repeat it).
fn message(e: &anyhow::Error) -> String {
    let mut out = String::new();
    for cause in e.chain() {
        let text = cause.to_string();
        if text.is_empty() || out.contains(&text) {
            continue;
        }
        if !out.is_empty() {
            out.push_str(": ");
        }
        out.push_str(&text);
    }
    out
}

/// Parses the command line, runs it, and maps errors (a bad flag included) to a message
/// and exit code 1; output into a closed pipe ends quietly (exit 0).
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
        Err(e) if is_broken_pipe(&e) => ExitCode::SUCCESS,
        Err(e) => {
            note!("naocalib: error: {}", message(&e));
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
        Command::Import(args) => import::run(args),
        Command::Capture(args) => capture::run(args),
        Command::SimulateRobot(args) => simulate_robot::run(args),
        Command::Sandal(args) => sandal::run(args),
        #[cfg(feature = "detect")]
        Command::Detect(args) => detect::run(args),
        Command::CameraGuard(args) => capture::guard(args),
        Command::RestGuard(args) => capture::rest_guard(args),
    }
}
