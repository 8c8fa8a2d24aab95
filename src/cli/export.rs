//! `naocalib export`: turn a result or calibration file into the calibration files robots
//! load.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result, bail};
use clap::Args;

use naocalib::export::{
    self, Calibration, ExportError, Format, Posture, Updated, WriteOptions, read_calibration,
};

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

/// `naocalib export --update FILE`.
fn run_update(
    args: &ExportArgs,
    file: &Path,
    format: Option<&'static dyn Format>,
    calibration: &Calibration,
) -> Result<ExitCode> {
    let (format, updated) =
        export::update(calibration, format, file, std::slice::from_ref(&args.input))?;
    if !format.joints() {
        let head = |p: naocalib::model::Param| calibration.value(p);
        note!(
            "note: the cameras' corrections hold for head offsets HeadYaw {} deg, \
             HeadPitch {} deg (as this calibration had them); if the robot's joint \
             calibration holds others, solve with --start-from (naocalib import) first",
            head(naocalib::model::Param::HeadYaw),
            head(naocalib::model::Param::HeadPitch)
        );
    }
    let message = match updated {
        Updated::Written {
            file: written,
            backup,
            new_backup,
        } => {
            let link = file
                .symlink_metadata()
                .is_ok_and(|m| m.file_type().is_symlink());
            let through = if link {
                format!(" through {}", written.display())
            } else {
                String::new()
            };
            let kept = if new_backup {
                "kept as"
            } else {
                "already kept in"
            };
            format!(
                "updated {}{through} ({}); previous file {kept} {}\n",
                file.display(),
                format.name(),
                backup.display()
            )
        }
        Updated::Unchanged(why) => format!(
            "not updated: {} ({}): {why}; nothing written\n",
            file.display(),
            format.name()
        ),
    };
    super::print_out(message)?;
    Ok(ExitCode::SUCCESS)
}

/// The `--format NAME` of `export` and `import`, if given: a name of the list
/// ([`export::named`]).
pub(super) fn format_arg(name: Option<&str>) -> Result<Option<&'static dyn Format>> {
    name.map(|name| {
        export::named(name)
            .with_context(|| format!("unknown --format '{name}' ({})", export::names()))
    })
    .transpose()
}

/// Runs `naocalib export`.
pub fn run(args: &ExportArgs) -> Result<ExitCode> {
    if args.out.is_empty() && args.dir.is_none() && args.update.is_none() {
        bail!("nothing to write: give --out FILE, --dir DIR or --update FILE");
    }
    let format = format_arg(args.format.as_deref())?;
    let mut calibration = read_calibration(&args.input)?;
    calibration.posture = match args.posture {
        PostureArg::Standing => Posture::Standing,
        PostureArg::Lying => Posture::Lying,
    };
    let problems = calibration.problems();
    if !problems.is_empty() {
        note!(
            "warning: {} is not a calibration: {}",
            args.input.display(),
            problems.join("; ")
        );
    }
    if calibration.posture == Posture::Standing {
        if let Some(summary) = naocalib::report::standing_summary(&calibration) {
            note!(
                "standing leg offsets for the team files (α + κ·τ_stand + ½π·sgn τ_stand): {summary}"
            );
        }
        for caveat in calibration.standing_caveats() {
            note!("warning: standing leg offset {caveat}");
        }
    }
    if let Some(file) = &args.update {
        return run_update(args, file, format, &calibration);
    }
    let options = WriteOptions {
        force: args.force,
        inputs: vec![args.input.clone()],
    };
    let mut targets: Vec<(&'static dyn Format, PathBuf)> = Vec::new();
    for path in &args.out {
        let format = match format.or_else(|| export::from_path(path)) {
            Some(f) => f,
            None => bail!(ExportError::UnknownFormat { path: path.clone() }),
        };
        targets.push((format, path.clone()));
    }
    if let Some(dir) = &args.dir {
        targets.extend(export::every_file(&calibration, dir));
    }
    // The library's outputs policy: every path is checked before any file is written, a
    // result that is not a calibration becomes no robot file without --allow-unconverged,
    // and the --dir set is all or nothing.
    let written = export::write_files(
        &calibration,
        &targets,
        args.dir.as_deref(),
        &options,
        args.allow_unconverged,
    )
    .map_err(|e| match e {
        e @ ExportError::NotACalibration { .. } => anyhow::Error::new(e)
            .context("give --allow-unconverged to write it anyway, marked NOT A CALIBRATION"),
        e => e.into(),
    })?;
    let mut out = String::new();
    for path in written {
        out.push_str(&format!("wrote {}\n", path.display()));
    }
    super::print_out(out)?;
    Ok(ExitCode::SUCCESS)
}
