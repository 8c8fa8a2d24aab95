//! `naocalib import`: read a robot's current team calibration files into naocalib's
//! calibration TOML (α = −stored for joints), for `solve --start-from` and `plan --around`.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Result, bail};
use clap::Args;

use naocalib::export::{WriteOptions, export, from_path, import_calibration};

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
    let format = super::export::format_arg(args.format.as_deref())?;
    let (calibration, read) = import_calibration(&args.files, format)?;
    let out_format = match from_path(&args.out) {
        Some(f) if !f.robot() => f,
        _ => bail!(
            "{}: --out must be a .toml or .json calibration file",
            args.out.display()
        ),
    };
    let options = WriteOptions {
        force: args.force,
        inputs: args.files.clone(),
    };
    export(&calibration, out_format, &args.out, &options)?;
    for (file, format, count) in read {
        note!("read {} ({format}): {count} values", file.display());
    }
    super::print_out(format!("wrote {}\n", args.out.display()))?;
    Ok(ExitCode::SUCCESS)
}
