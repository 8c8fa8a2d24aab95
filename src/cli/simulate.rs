//! `naocalib simulate`: write a simulated dataset.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use clap::Args;

use crate::model::Model;
use crate::sim::SimOptions;

#[derive(Debug, Args)]
pub struct SimulateArgs {
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

/// Runs `naocalib simulate`.
pub fn run(args: &SimulateArgs) -> Result<ExitCode> {
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
