//! `naocalib sandal`: write the files to make the checkerboard sandals.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use clap::Args;

use naocalib::sandal::request::{self, SandalRequest};

use super::print_out;

#[derive(Debug, Args)]
pub struct SandalArgs {
    /// Directory to write the files into (created if missing).
    out_dir: PathBuf,
    /// The dataset.toml whose [board] describes the sandals (default: naocalib's sandal,
    /// 7 × 5 squares of 25 mm with its seven columns across the foot, centred 200 mm ahead
    /// of the ankle; a file without [board] means the paper's board).
    #[arg(long, value_name = "DATASET_TOML")]
    config: Option<PathBuf>,
    /// Replace the files of an earlier run in OUT_DIR.
    #[arg(long)]
    force: bool,
}

/// Runs `naocalib sandal`.
pub fn run(args: &SandalArgs) -> Result<ExitCode> {
    let request = SandalRequest {
        out_dir: args.out_dir.clone(),
        config: args.config.clone(),
        force: args.force,
    };
    let made = request::run(&request)?;
    for n in &made.notes {
        note!("naocalib sandal: note: {n}");
    }
    print_out(request::summary(&request, &made))?;
    Ok(ExitCode::SUCCESS)
}
