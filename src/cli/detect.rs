//! `naocalib detect`: find the sandal's vertices in a dataset's images and write
//! `corners.csv`.

use std::io::IsTerminal as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Result;
use clap::Args;

use naocalib::dataset::Dataset;
use naocalib::detect::assign::Grid;
use naocalib::detect::request::{self, DetectRequest, parse_pattern};

#[derive(Debug, Args)]
pub struct DetectArgs {
    /// Dataset directory (dataset.toml, captures.csv naming the images).
    dataset: PathBuf,
    /// Replace an existing corners.csv that holds vertices, and existing overlays.
    #[arg(long)]
    force: bool,
    /// Inner vertices per row and rows, e.g. 9x6 (default: the board in dataset.toml).
    #[arg(long, value_name = "CxR", value_parser = parse_pattern)]
    pattern: Option<Grid>,
    /// Do not use the model and logged joints: search whole images and number the
    /// vertices in OpenCV's order.
    #[arg(long)]
    no_model: bool,
    /// The pictures show the robot lying on its back: drop every vertex its body
    /// (docs/BODY.md, the arms beyond the head) stands in front of, as the model predicts
    /// it, whatever the image shows there.
    #[arg(long, conflicts_with = "no_model")]
    body: bool,
    /// Write an overlay PNG per image into DIR: detected vertices (green crosses) and the
    /// nominal model's projection (red circles).
    #[arg(long, value_name = "DIR")]
    overlay: Option<PathBuf>,
    /// With --overlay, also draw the projection with the parameters of this result of
    /// `naocalib solve --json` (blue circles).
    #[arg(long, value_name = "JSON", requires = "overlay")]
    after: Option<PathBuf>,
    /// Images processed at once (default: the number of cores).
    #[arg(long, short = 'j', value_name = "N")]
    jobs: Option<usize>,
    /// Predict the board with the robot's current calibration (a calibration.toml or
    /// .json from `naocalib solve --export`/`export`) instead of the nominal model.
    #[arg(long, value_name = "CAL.toml")]
    start_from: Option<PathBuf>,
    /// Detect once with the given prediction: do not calibrate from the boards found,
    /// predict again and detect again.
    #[arg(long)]
    no_repredict: bool,
}

/// For `naocalib solve --detect`: names the captures whose residuals after the fit are
/// many times the others' on stderr; `true` when there are.
pub fn guard(solution: &naocalib::solve::Solution) -> bool {
    let warnings = request::guard_warnings(solution);
    for w in &warnings {
        note!("{w}");
    }
    !warnings.is_empty()
}

/// A progress bar over `images` images on stderr, when stderr is a terminal.
fn progress_bar(images: usize) -> Option<indicatif::ProgressBar> {
    std::io::stderr()
        .is_terminal()
        .then(|| super::progress_bar(images, "images"))
}

/// For `naocalib solve --detect`: detects the vertices in `dataset`'s images with the
/// defaults of `naocalib detect` and puts them in place of its corners (nothing is
/// written), the board predicted with the calibration in `start_from` when given, the
/// vertices behind the body dropped with `body` (`detect --body`). Prints
/// the images that gave no vertices (every image with `verbose`) and the summary line on
/// stderr.
pub fn detect_for_solve(
    dataset: &mut Dataset,
    verbose: bool,
    start_from: Option<&Path>,
    body: bool,
) -> Result<()> {
    let options = request::options_for_solve(dataset, start_from, body)?;
    let bar = progress_bar(dataset.captures.len());
    let detection = request::detect_for_solve(dataset, &options, &|_| {
        if let Some(bar) = &bar {
            bar.inc(1);
        }
    });
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    for line in detection?.lines(dataset, verbose) {
        note!("{line}");
    }
    Ok(())
}

/// Runs `naocalib detect`.
pub fn run(args: &DetectArgs) -> Result<ExitCode> {
    let request = DetectRequest {
        dataset: args.dataset.clone(),
        force: args.force,
        pattern: args.pattern,
        use_model: !args.no_model,
        overlay: args.overlay.clone(),
        after: args.after.clone(),
        jobs: args.jobs,
        start_from: args.start_from.clone(),
        repredict: !args.no_repredict,
        body: args.body,
    };
    let prepared = request.prepare(&mut |line| note!("{line}"))?;
    let bar = progress_bar(prepared.dataset.captures.len());
    let detected = prepared.detect(&|_| {
        if let Some(bar) = &bar {
            bar.inc(1);
        }
    });
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    for line in detected.lines() {
        note!("{line}");
    }
    note!("{}", detected.write()?);
    let turned = detected.turned();
    for line in &turned {
        note!("{line}");
    }
    Ok(if detected.nothing_found() || !turned.is_empty() {
        ExitCode::from(2)
    } else {
        ExitCode::SUCCESS
    })
}
