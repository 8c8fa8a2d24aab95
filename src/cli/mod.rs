//! The command line: thin wrappers that parse arguments, call the library and print.

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result, bail};
use clap::{Args, Parser, Subcommand};

use crate::dataset::Dataset;
use crate::model::{FixedSet, Model, Param, parameters::parse_param_list};
use crate::sim::SimOptions;
use crate::solve::{self, Backend, Problem};

/// The backend used when `--solver` is not given.
pub const DEFAULT_SOLVER: &str = if cfg!(feature = "ceres") { "ceres" } else { "lm" };

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
    Simulate(SimulateArgs),
    /// Calibrate: fit the offsets to a dataset's corners and print them with their
    /// uncertainty.
    Solve(SolveArgs),
}

#[derive(Debug, Args)]
struct SimulateArgs {
    /// Directory to write the dataset into.
    out: PathBuf,
    /// Seed of the random generator.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Stances per leg.
    #[arg(long, default_value_t = 24)]
    stances: usize,
    /// Head postures per stance.
    #[arg(long, default_value_t = 3)]
    heads: usize,
    /// Pixel noise σ per coordinate [px].
    #[arg(long, default_value_t = 0.1)]
    px_noise: f64,
    /// Joint-angle noise σ per joint and capture [deg].
    #[arg(long, default_value_t = 0.0)]
    joint_noise_deg: f64,
    /// Take the true parameters from this truth.toml instead of drawing them.
    #[arg(long)]
    truth: Option<PathBuf>,
    /// Replace files of an existing dataset in OUT.
    #[arg(long)]
    force: bool,
}

#[derive(Debug, Args)]
struct SolveArgs {
    /// Dataset directory (dataset.toml, captures.csv, corners.csv).
    dataset: PathBuf,
    /// Print the result as JSON (SPEC section 7).
    #[arg(long)]
    json: bool,
    /// Parameters to hold fixed at zero, comma-separated (e.g. CamYaw,LBoardRotZ).
    #[arg(long, value_name = "NAMES")]
    fix: Option<String>,
    /// Parameters to estimate that are held fixed by default (HeadYaw,HeadPitch).
    #[arg(long, value_name = "NAMES")]
    free: Option<String>,
    /// Least-squares backend: ceres (default), lm (levenberg-marquardt crate), tiny
    /// (tiny-solver).
    #[arg(long, default_value = DEFAULT_SOLVER)]
    solver: String,
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
        Command::Simulate(args) => simulate(args),
        Command::Solve(args) => solve_command(args, cli.verbose),
    }
}

fn simulate(args: &SimulateArgs) -> Result<ExitCode> {
    let truth = match &args.truth {
        Some(path) => Some(crate::dataset::read_truth(path)?.values),
        None => None,
    };
    let options = SimOptions {
        seed: args.seed,
        stances: args.stances,
        heads: args.heads,
        px_noise: args.px_noise,
        joint_noise: args.joint_noise_deg.to_radians(),
        truth,
        noise_seed: None,
    };
    let mut dataset = crate::sim::simulate(&Model::default(), &options)?;
    dataset.dir = args.out.clone();
    dataset.write(&args.out, args.force)?;
    println!(
        "wrote {}: {} captures, {} vertices (seed {}, {} px, {}° joint noise)",
        args.out.display(),
        dataset.captures.len(),
        dataset.corners.len(),
        args.seed,
        args.px_noise,
        args.joint_noise_deg
    );
    Ok(ExitCode::SUCCESS)
}

/// The held parameters for `--fix` and `--free`.
fn fixed_set(fix: Option<&str>, free: Option<&str>) -> Result<FixedSet> {
    let mut fixed = FixedSet::default();
    for p in parse_param_list(free.unwrap_or("")).map_err(anyhow::Error::msg).context("--free")? {
        fixed.set(p, false);
    }
    for p in parse_param_list(fix.unwrap_or("")).map_err(anyhow::Error::msg).context("--fix")? {
        fixed.set(p, true);
    }
    Ok(fixed)
}

/// The backend called `name`.
pub fn backend(name: &str, verbose: bool) -> Result<Box<dyn Backend>> {
    match name {
        #[cfg(feature = "ceres")]
        "ceres" => Ok(Box::new(solve::ceres::Ceres { verbose })),
        "lm" => Ok(Box::new(solve::lm::MinpackLm)),
        "tiny" => Ok(Box::new(solve::tiny::Tiny)),
        _ => {
            let _ = verbose;
            bail!("unknown solver '{name}' (available: {})", available_solvers().join(", "))
        }
    }
}

/// Names accepted by `--solver`.
pub fn available_solvers() -> Vec<&'static str> {
    let mut names = Vec::new();
    if cfg!(feature = "ceres") {
        names.push("ceres");
    }
    names.extend(["lm", "tiny"]);
    names
}

fn load(path: &Path) -> Result<Dataset> {
    Ok(Dataset::load(path)?)
}

fn solve_command(args: &SolveArgs, verbose: bool) -> Result<ExitCode> {
    let dataset = load(&args.dataset)?;
    let fixed = fixed_set(args.fix.as_deref(), args.free.as_deref())?;
    let backend = backend(&args.solver, verbose)?;
    let problem = Problem::from_dataset(&dataset, fixed)?;
    let solution = solve::solve(&problem, backend.as_ref())
        .with_context(|| format!("solving {}", args.dataset.display()))?;
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
    let _ = Param::ALL;
    Ok(if solution.summary.converged { ExitCode::SUCCESS } else { ExitCode::from(3) })
}
