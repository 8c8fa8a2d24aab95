//! `naocalib import`: read a robot's current team calibration files into naocalib's
//! calibration TOML (α = −stored for joints), for `solve --start-from` and `plan --around`.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use clap::Args;

use naocalib::export::request::{self, ImportRequest};

#[derive(Debug, Args)]
pub struct ImportArgs {
    /// The robot's team files (cameraCalibration.cfg, jointCalibration.cfg, head.<id>.json,
    /// body.<id>.json, CameraMatrixOffset.cfg, …); each one's layout is recognised from its
    /// content unless --format is given.
    #[arg(required = true)]
    files: Vec<PathBuf>,
    /// The calibration TOML (or .json) to write.
    #[arg(long, value_name = "CAL.toml")]
    out: PathBuf,
    /// The layout of every FILE (see `naocalib export --help`), instead of recognising it.
    #[arg(long, value_name = "FORMAT")]
    format: Option<String>,
    /// Replace an existing --out file (never an input).
    #[arg(long)]
    force: bool,
}

/// Runs `naocalib import`.
pub fn run(args: &ImportArgs) -> Result<ExitCode> {
    let read = request::import(&ImportRequest {
        files: args.files.clone(),
        out: args.out.clone(),
        format: args.format.clone(),
        force: args.force,
    })?;
    for (file, format, count) in read {
        note!("read {} ({format}): {count} values", file.display());
    }
    super::print_out(format!("wrote {}\n", args.out.display()))?;
    Ok(ExitCode::SUCCESS)
}
