//! `naocalib detect`: find the sandal's vertices in a dataset's images and write
//! `corners.csv`.

use std::io::IsTerminal as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Mutex;

use anyhow::{Context, Result, bail};
use clap::Args;

use naocalib::dataset::{CORNERS_CSV, Dataset};
use naocalib::detect::assign::Grid;
use naocalib::detect::{self, DetectOptions, ImageResult, Summary};
use naocalib::export::WriteOptions;
use naocalib::model::{PARAMETER_COUNT, Param};

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

/// The parameters (internal units) of the calibration file `path`.
///
/// With `corrected` angles (`[joints] angles = "corrected"`) the robot's joint offsets are
/// already in the logged angles, and the prediction keeps them at zero.
pub fn read_start(
    path: &Path,
    model: &naocalib::model::Model,
    corrected: bool,
) -> Result<[f64; PARAMETER_COUNT]> {
    let calibration = naocalib::export::read_start_from(path)
        .with_context(|| format!("--start-from {}", path.display()))?;
    let mut problem_values = [0.0; PARAMETER_COUNT];
    for e in &calibration.parameters {
        let joint = naocalib::solve::problem::is_joint_offset(e.param);
        if !(corrected && joint) {
            problem_values[e.param.index()] = e.param.unit().from_report(e.value);
        }
    }
    // Intrinsics the calibration carries with their prior, relative to this dataset's.
    for (p, value) in calibration.intrinsics_relative_to(model).0 {
        problem_values[p.index()] = value;
    }
    Ok(problem_values)
}

/// Whether `dataset`'s joint angles are already corrected by the robot's calibration.
fn corrected(dataset: &Dataset) -> bool {
    dataset.angles.kind == naocalib::dataset::AngleKind::Corrected
}

/// For `naocalib solve --detect`: names the captures whose residuals after the fit are
/// many times the others' ([`detect::guard::suspects`]) on stderr; `true` when there are.
pub fn guard(solution: &naocalib::solve::Solution) -> bool {
    let suspects = detect::guard::suspects(solution);
    for s in &suspects {
        note!("naocalib: warning: {s}");
    }
    if !suspects.is_empty() {
        note!(
            "naocalib: warning: {} capture(s) with residuals more than {}× the median \
             capture's: this run is marked (exit code 3); look at their images, or leave \
             them out",
            suspects.len(),
            detect::guard::SUSPECT_RATIO
        );
    }
    !suspects.is_empty()
}

fn parse_pattern(text: &str) -> Result<Grid, String> {
    let err = || format!("'{text}' is not a pattern like 9x6 (inner vertices per row x rows)");
    let (c, r) = text.split_once(['x', 'X']).ok_or_else(err)?;
    let cols: u32 = c.trim().parse().map_err(|_| err())?;
    let rows: u32 = r.trim().parse().map_err(|_| err())?;
    // OpenCV's chessboard finder needs more than 2 inner vertices each way (it asserts).
    if cols < 3 || rows < 3 || cols > 100 || rows > 100 {
        return Err(format!(
            "pattern '{text}': 3 … 100 vertices per row and rows (the minimum is 3x3)"
        ));
    }
    Ok(Grid { cols, rows })
}

/// Reads the parameters of a `naocalib solve --json` result (report units) as internal
/// values; parameters not named stay zero.
fn read_solution(path: &Path) -> Result<[f64; PARAMETER_COUNT]> {
    let text = std::fs::read_to_string(path).with_context(|| format!("{}", path.display()))?;
    let json: serde_json::Value =
        serde_json::from_str(&text).with_context(|| format!("{}: not JSON", path.display()))?;
    let Some(map) = json.get("parameters").and_then(|p| p.as_object()) else {
        bail!(
            "{}: no \"parameters\" object (a `naocalib solve --json` result?)",
            path.display()
        );
    };
    let mut values = [0.0; PARAMETER_COUNT];
    for (name, entry) in map {
        let param = Param::from_name(name)
            .with_context(|| format!("{}: unknown parameter {name}", path.display()))?;
        let value = entry
            .get("value")
            .and_then(|v| v.as_f64())
            .with_context(|| {
                format!("{}: parameter {name} has no numeric value", path.display())
            })?;
        values[param.index()] = param.unit().from_report(value);
    }
    Ok(values)
}

/// What overlays must not replace: every image and file of the dataset; existing
/// overlays only with `--force`.
fn overlay_write_options(dataset: &Dataset, args: &DetectArgs) -> WriteOptions {
    let mut options = WriteOptions::protecting_dataset(&args.dataset, args.force);
    options.inputs.extend(
        dataset
            .captures
            .iter()
            .filter_map(|c| dataset.image_path(c)),
    );
    if let Some(after) = &args.after {
        options.inputs.push(after.clone());
    }
    options
}

/// A progress bar over `images` images on stderr, when stderr is a terminal.
fn progress_bar(images: usize) -> Option<indicatif::ProgressBar> {
    std::io::stderr()
        .is_terminal()
        .then(|| super::progress_bar(images, "images"))
}

/// For `naocalib solve --detect`: detects the vertices in `dataset`'s images with the
/// defaults of `naocalib detect` and puts them in place of its corners (nothing is
/// written). Prints the images that gave no vertices (every image with `verbose`) and the
/// summary line on stderr.
/// The board is predicted with the calibration in `start_from` (`solve --start-from
/// CAL.toml`) when given.
pub fn detect_for_solve(
    dataset: &mut Dataset,
    verbose: bool,
    start_from: Option<&Path>,
) -> Result<()> {
    let options = DetectOptions {
        params: start_from
            .map(|p| read_start(p, &dataset.model, corrected(dataset)))
            .transpose()?,
        ..DetectOptions::default()
    };
    let start = std::time::Instant::now();
    let bar = progress_bar(dataset.captures.len());
    let done = |_: &ImageResult| {
        if let Some(bar) = &bar {
            bar.inc(1);
        }
    };
    let detection = detect::detect_into(dataset, &options, &done);
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    let detection = detection?;
    for r in &detection.results {
        if verbose || !matches!(r.outcome, detect::Outcome::Found { .. }) {
            note!("{r}");
        }
    }
    note!(
        "{}: {} images: {}; {} vertices detected in {:.2} s (corners.csv not used)",
        dataset.dir.display(),
        detection.results.len(),
        detection.summary,
        dataset.corners.len(),
        start.elapsed().as_secs_f64()
    );
    Ok(())
}

/// Runs `naocalib detect`.
pub fn run(args: &DetectArgs) -> Result<ExitCode> {
    let dataset = Dataset::load(&args.dataset)?;
    let corners_path = args.dataset.join(CORNERS_CSV);
    // An existing corners.csv without vertices (as `simulate --images` writes) holds nothing
    // to lose; one with vertices is only replaced with --force.
    let replace = corners_path.exists();
    if replace && !dataset.corners.is_empty() && !args.force {
        bail!(
            "{}: already holds {} vertices; use --force to overwrite",
            corners_path.display(),
            dataset.corners.len()
        );
    }
    let after = args.after.as_deref().map(read_solution).transpose()?;
    // Overlays never replace an input (an image, a dataset file) and replace an existing
    // overlay only with --force; all of them are checked before any image is read.
    let overlay_options = overlay_write_options(&dataset, args);
    if let Some(dir) = &args.overlay {
        for capture in dataset.captures.iter().filter(|c| c.image.is_some()) {
            naocalib::output::check_writable(
                &detect::overlay::path(dir, capture.id),
                &overlay_options,
            )?;
        }
    }
    let mut options = DetectOptions {
        pattern: args.pattern,
        use_model: !args.no_model,
        params: args
            .start_from
            .as_deref()
            .map(|p| read_start(p, &dataset.model, corrected(&dataset)))
            .transpose()?,
        repredict: !args.no_repredict,
        ..DetectOptions::default()
    };
    if let Some(jobs) = args.jobs {
        if jobs == 0 {
            bail!("--jobs must be at least 1");
        }
        let cap = detect::max_jobs();
        if jobs > cap {
            note!("naocalib: note: --jobs {jobs} capped at {cap} (4 per core, at most 64)");
        }
        options.jobs = jobs.min(cap);
    }
    if let Some(p) = args.pattern {
        let board = detect::board_grid(&dataset.model);
        if p != board {
            note!(
                "naocalib: note: pattern {}x{} differs from the board in dataset.toml ({}x{}); \
                 corners.csv will only load with a matching [board]",
                p.cols,
                p.rows,
                board.cols,
                board.rows
            );
        }
    }

    let bar = progress_bar(dataset.captures.len());
    let overlay_options =
        naocalib::output::WriteOptions::protecting_dataset(&args.dataset, args.force)
            .protecting(
                dataset
                    .captures
                    .iter()
                    .filter_map(|c| dataset.image_path(c)),
            )
            .protecting(args.after.clone());
    let overlay_errors = Mutex::new(Vec::new());
    let done = |r: &ImageResult| {
        if let Some(dir) = &args.overlay
            && let Some(Err(e)) =
                detect::overlay::write(&dataset, r, dir, after.as_ref(), &overlay_options)
        {
            overlay_errors
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .push(e.to_string());
        }
        if let Some(bar) = &bar {
            bar.inc(1);
        }
    };
    let results = detect::detect_dataset(&dataset, &options, &done);
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    for r in &results {
        note!("{r}");
    }
    for e in overlay_errors.into_inner().unwrap_or_default() {
        note!("naocalib: overlay: {e}");
    }
    let summary = Summary::of(&results);
    let corners = detect::corners(&results);
    if corners.is_empty() && !dataset.corners.is_empty() {
        bail!(
            "{}: no vertex found in any of {} images ({summary}); {} and its {} vertices \
             left as they were",
            args.dataset.display(),
            results.len(),
            corners_path.display(),
            dataset.corners.len()
        );
    }
    naocalib::dataset::write_corners(&args.dataset, &corners, replace)?;
    note!(
        "{}: {} images: {summary}; wrote {} vertices to {}",
        args.dataset.display(),
        results.len(),
        corners.len(),
        corners_path.display()
    );
    let turned = detect::turned::of_results(&results);
    for t in &turned {
        note!("naocalib: error: {t}");
    }
    Ok(
        if (summary.found == 0 && !results.is_empty()) || !turned.is_empty() {
            ExitCode::from(2)
        } else {
            ExitCode::SUCCESS
        },
    )
}
