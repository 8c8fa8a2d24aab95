//! `naocalib export`: turn a result or calibration file into the calibration files robots
//! load; and the `--plots`/`--export` outputs of `naocalib solve`.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result, bail};
use clap::Args;

use naocalib::report::export::{
    Calibration, ExportFormat, WriteOptions, export, export_all, read_calibration,
};
use naocalib::report::plot;
use naocalib::solve::Solution;

#[derive(Debug, Args)]
pub struct ExportArgs {
    /// A result JSON (`naocalib solve --json`, a run file of `naocalib batch --out`) or a
    /// calibration TOML/JSON written by naocalib.
    input: PathBuf,
    /// Write one file; the format comes from --format or the name (*.toml, *.json,
    /// *camera*.cfg, *joint*.cfg). May be given several times.
    #[arg(long, value_name = "FILE")]
    out: Vec<PathBuf>,
    /// Format of the --out files: toml, json, bhuman-camera, bhuman-joints.
    #[arg(long, value_name = "FORMAT")]
    format: Option<String>,
    /// Write every format into this directory (calibration.toml, calibration.json,
    /// cameraCalibration.cfg, jointCalibration.cfg).
    #[arg(long, value_name = "DIR")]
    dir: Option<PathBuf>,
    /// Replace existing files (never the input).
    #[arg(long)]
    force: bool,
}

/// Runs `naocalib export`.
pub fn run(args: &ExportArgs) -> Result<ExitCode> {
    if args.out.is_empty() && args.dir.is_none() {
        bail!("nothing to write: give --out FILE or --dir DIR");
    }
    let format = match &args.format {
        Some(name) => Some(ExportFormat::from_name(name).with_context(|| {
            format!("unknown --format '{name}' (toml, json, bhuman-camera, bhuman-joints)")
        })?),
        None => None,
    };
    let calibration = read_calibration(&args.input)?;
    let options = WriteOptions {
        force: args.force,
        inputs: vec![args.input.clone()],
    };
    let mut written = Vec::new();
    for path in &args.out {
        let format = match format.or_else(|| ExportFormat::from_path(path)) {
            Some(f) => f,
            None => {
                bail!(naocalib::report::export::ExportError::UnknownFormat { path: path.clone() })
            }
        };
        export(&calibration, format, path, &options)?;
        written.push(path.clone());
    }
    if let Some(dir) = &args.dir {
        written.extend(export_all(&calibration, dir, &options)?);
    }
    for path in written {
        println!("wrote {}", path.display());
    }
    Ok(ExitCode::SUCCESS)
}

/// The extra outputs of `naocalib solve`: plots into `plots` and the calibration files
/// into `export_dir`, never over a file of the dataset in `dataset`. Reports on stderr.
pub fn solve_outputs(
    solution: &Solution,
    dataset: &naocalib::dataset::Dataset,
    plots: Option<&Path>,
    export_dir: Option<&Path>,
    force: bool,
) -> Result<()> {
    let options = WriteOptions::protecting_dataset(&dataset.dir, force);
    if let Some(dir) = plots {
        let sides = plot::capture_sides(dataset);
        let files = plot::solution_plots(solution, Some(&sides), dir, "solve", &options)
            .context("--plots")?;
        eprintln!("wrote {} plot files into {}", files.len(), dir.display());
    }
    if let Some(dir) = export_dir {
        let calibration = Calibration::from_solution(solution, Some(&dataset.dir));
        let files: Vec<PathBuf> = export_all(&calibration, dir, &options).context("--export")?;
        for f in files {
            eprintln!("wrote {}", f.display());
        }
    }
    Ok(())
}
