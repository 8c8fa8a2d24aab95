//! `naocalib compare`: every solver on the same dataset, side by side.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::Args;

use super::options::ProblemArgs;
use naocalib::dataset::Dataset;
use naocalib::report::compare::{comparison_json, comparison_text};
use naocalib::run::RunOptions;
use naocalib::solve::compare::compare;

/// Arguments of `naocalib compare`.
#[derive(Debug, Args)]
pub struct CompareArgs {
    /// Dataset directory (dataset.toml, captures.csv, corners.csv).
    dataset: PathBuf,
    /// Print the comparison as JSON.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    problem: ProblemArgs,
    /// Solvers to run, comma-separated (default: all of this build).
    #[arg(long, value_name = "NAMES")]
    solvers: Option<String>,
}

/// Runs `naocalib compare`. Exit code 0 when every solver converged, 3 otherwise (the
/// comparison is printed either way).
pub fn run(args: &CompareArgs) -> Result<ExitCode> {
    let dataset = Dataset::load(&args.dataset)?;
    let options = RunOptions {
        fixed: args.problem.fixed_set()?,
        loss: args.problem.loss(),
        ..RunOptions::default()
    };
    let problem = options.problem(&dataset)?;
    let solvers: Vec<&str> = args
        .solvers
        .iter()
        .flat_map(|s| s.split(','))
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .collect();
    let comparison = compare(&problem, &solvers)
        .with_context(|| format!("comparing solvers on {}", args.dataset.display()))?;
    super::print_out(if args.json {
        let value = comparison_json(&comparison, &args.dataset);
        format!("{}\n", serde_json::to_string_pretty(&value)?)
    } else {
        comparison_text(&comparison, &args.dataset)
    })?;
    Ok(if comparison.runs.iter().all(|r| r.converged()) {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(3)
    })
}
