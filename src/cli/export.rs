//! `naocalib export`: turn a result or calibration file into the calibration files robots
//! load.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use clap::Args;

use naocalib::export::request::{self, ExportRequest};
use naocalib::export::{self, Posture};

#[derive(Debug, Args)]
pub struct ExportArgs {
    /// A result JSON (`naocalib solve --json`, a run file of `naocalib batch --out`) or a
    /// calibration TOML/JSON written by naocalib.
    input: PathBuf,
    /// Write one file; the format comes from --format or the name. May be given several
    /// times.
    #[arg(long, value_name = "FILE", help = out_help())]
    out: Vec<PathBuf>,
    /// Format of the --out / --update files (docs/EXPORTS.md).
    #[arg(long, value_name = "FORMAT", long_help = format_help())]
    format: Option<String>,
    /// Write every format into this directory, under the file names listed for --format.
    #[arg(long, value_name = "DIR")]
    dir: Option<PathBuf>,
    /// Update a robot's existing file in its team's layout (--format, or recognised from
    /// the content): replace only what this calibration determined, keep every other byte,
    /// keep the previous file as FILE.bak (FILE.bak.2, … when that exists: never replaced).
    /// A symbolic link is followed; mode, owner and hard links are kept.
    #[arg(long, value_name = "FILE", conflicts_with_all = ["out", "dir"])]
    update: Option<PathBuf>,
    /// Replace existing files (never the input).
    #[arg(long)]
    force: bool,
    /// The posture whose leg offsets the robot files carry when compliance or play have
    /// values: `standing` (the standard stand, α + κ·τ_stand + ½π·sgn τ_stand; docs/MODEL.md
    /// §6) or `lying` (the offsets α as calibrated, lying on the back).
    #[arg(long, value_enum, default_value_t = PostureArg::Standing)]
    posture: PostureArg,
    /// Write robot files even for a result that is not a calibration (not converged,
    /// non-finite, implausible residuals); they start with a NOT A CALIBRATION marker.
    #[arg(long)]
    allow_unconverged: bool,
}

/// `--posture`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum PostureArg {
    /// The standard stand.
    Standing,
    /// Lying on the back, as calibrated.
    Lying,
}

/// The `--format` help: one line per format of the list ([`export::FORMATS`]).
fn format_help() -> String {
    format!(
        "Format of the --out / --update files (docs/EXPORTS.md):\n{}",
        export::help()
    )
}

/// The `--out` help, with the file names that imply a format ([`export::name_patterns`]).
fn out_help() -> String {
    format!(
        "Write one file; the format comes from --format or the name ({}). May be given \
         several times",
        export::name_patterns()
    )
}

/// Runs `naocalib export`.
pub fn run(args: &ExportArgs) -> Result<ExitCode> {
    let request = ExportRequest {
        input: args.input.clone(),
        out: args.out.clone(),
        format: args.format.clone(),
        dir: args.dir.clone(),
        update: args.update.clone(),
        force: args.force,
        posture: match args.posture {
            PostureArg::Standing => Posture::Standing,
            PostureArg::Lying => Posture::Lying,
        },
        allow_unconverged: args.allow_unconverged,
    };
    super::print_out(request::run(&request, &mut |line| note!("{line}"))?)?;
    Ok(ExitCode::SUCCESS)
}
