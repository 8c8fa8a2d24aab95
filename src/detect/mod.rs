//! Finding the sandal's vertices in camera images (the paper's measurement phase).
//!
//! For each capture with an image: the image is read as grey levels (`image.rs`: the
//! header checked before any pixel is decoded), and with the model the board is first
//! looked for where the model and the logged joints predict it, by its pattern of saddles
//! ([`guided`]); its vertices are refined with `cornerSubPix`. Their (row, col) is decided
//! by the image ([`numbering`]): the vertices found, the pattern's outer squares against
//! the white plate (no saddle on the ring around the 6 × 4 vertices) fix the numbering up
//! to the pattern's 180° symmetry, which the prediction resolves only when the board is
//! turned against it by far less than 90°; a board whose visible part fits several
//! numberings is rejected with the reason, and the log says how each board was numbered.
//! OpenCV's chessboard finder (`chessboard.rs`, [`find`]) is the fallback: when the
//! guided search finds nothing, in the predicted region (`predict.rs`) and then the whole
//! image at half resolution (refined at full), and with a calibrated prediction also its
//! full search without the fast check where the board is predicted wholly in view; when
//! the guided search finds part of a board, only if the board is wholly in view and a
//! vertex was missed well inside the image. Its whole grid is numbered by comparing
//! OpenCV's order with the prediction ([`assign::assign`]).
//!
//! The prediction is the robot's current calibration when given
//! ([`DetectOptions::params`], `--start-from`), else the nominal model; then (with
//! [`DetectOptions::repredict`]) the paper's calibration from the boards found predicts
//! again, and the images without a whole board are searched again, until nothing
//! changes; the body (`--body`) stays posed with the prediction given
//! ([`DetectOptions::body_prediction`]). An image with no board that is too dark to show
//! one says so (its camera and brightness). A camera whose boards the model explains only
//! with its pictures turned by 180° (its sensor's flip not as it needs, [`turned`]) is
//! said so, and its boards are not used. Nothing here stops a run: every image gets an
//! [`Outcome`] (`outcome.rs`); [`guard`] names the captures whose residuals after a fit
//! stand out.

pub mod assign;
pub mod behind;
mod chessboard;
pub mod cv;
pub mod find;
pub mod guard;
pub mod guided;
mod image;
pub mod numbering;
mod outcome;
pub mod overlay;
mod predict;
pub mod prediction;
pub mod request;
pub mod saddle;
pub mod turned;

use std::path::Path;

use crate::sim::render::GreyImage;
use rayon::prelude::*;

use crate::dataset::{Capture, Corner, Dataset};
use crate::model::{Model, PARAMETER_COUNT};
use assign::Grid;
use image::read_sized;
pub use image::{MAX_PIXELS, MAX_SIDE, decode_grey, header_size, read_grey, resolve_image};
pub use outcome::{DetectError, Detection, ImageResult, NoCorners, Outcome, Summary};
pub use predict::predict;

/// What to detect and how.
#[derive(Debug, Clone, PartialEq)]
pub struct DetectOptions {
    /// Inner vertices per row and rows of the pattern; from the dataset's board when `None`.
    pub pattern: Option<Grid>,
    /// Use the nominal model and logged joints to predict the board (ROI, row/col
    /// assignment); without it, (row, col) follow OpenCV's order.
    pub use_model: bool,
    /// With the model: search the predicted pattern of saddles first ([`guided`]), and
    /// OpenCV's chessboard finder only when that finds too little; without it, only the
    /// chessboard finder (numbered by the model's orientation).
    pub guided: bool,
    /// Half-window of `cornerSubPix` in squares (of the local square size in pixels).
    pub subpix_factor: f64,
    /// Images processed at once.
    pub jobs: usize,
    /// The parameters (internal units) the board is predicted with: the robot's current
    /// calibration (`--start-from`); `None` for the nominal model (all offsets zero).
    pub params: Option<[f64; PARAMETER_COUNT]>,
    /// The re-predict loop's calibration from the boards found: where the images are
    /// searched once it is made, in place of `params`. The body is still posed with
    /// `params` ([`DetectOptions::body_prediction`]).
    pub calibrated: Option<[f64; PARAMETER_COUNT]>,
    /// With the model: calibrate from the boards found (numbered by the image), predict
    /// again with that calibration and detect again where no whole board was found, until
    /// nothing changes ([`MAX_PASSES`] at most).
    pub repredict: bool,
    /// With the model: the robot's body, whose parts the pictures show; every vertex it
    /// stands in front of is dropped ([`behind`]). `None` for pictures of the boards
    /// alone (as the simulator draws them without `--body`).
    pub body: Option<crate::body::BodyModel>,
}

/// Most detection passes of the re-predict loop (the first with the given prediction).
pub const MAX_PASSES: usize = 4;
/// Fewest boards found before the re-predict loop calibrates from them.
pub const MIN_BOARDS_TO_REPREDICT: usize = 6;

/// How far (deg, as an angle of view) the nominal model's prediction may be off for a
/// real robot: lower-camera tilt corrections down to −8°, with leg offsets of up to 2°.
pub const NOMINAL_UNCERTAINTY_DEG: f64 = 10.0;
/// How far a calibrated prediction (`--start-from`, the re-predict loop) may be off.
pub const CALIBRATED_UNCERTAINTY_DEG: f64 = 2.0;

impl DetectOptions {
    /// The parameters the board is predicted with in the image.
    pub fn prediction(&self) -> [f64; PARAMETER_COUNT] {
        self.calibrated
            .or(self.params)
            .unwrap_or([0.0; PARAMETER_COUNT])
    }

    /// The parameters the body is posed with against the board ([`behind`]): the
    /// prediction given (`--start-from`, else the nominal model), the one a plan counts its
    /// vertices in plain sight by. Not the re-predict loop's calibration: that fits the
    /// paper's model, which matches the boards in the image also where the robot has
    /// effects it lacks (a head offset taken up by the camera's and the legs'), and places
    /// the legs against the torso worse than the nominal model.
    pub fn body_prediction(&self) -> [f64; PARAMETER_COUNT] {
        self.params.unwrap_or([0.0; PARAMETER_COUNT])
    }

    /// Whether the board is predicted with a calibration (`--start-from`, or the
    /// re-predict loop's), not the nominal model.
    pub fn is_calibrated(&self) -> bool {
        self.calibrated.is_some() || self.params.is_some()
    }

    /// How far (deg) the prediction may be off: it sets the guided search's widest window.
    pub fn uncertainty_deg(&self) -> f64 {
        if self.is_calibrated() {
            CALIBRATED_UNCERTAINTY_DEG
        } else {
            NOMINAL_UNCERTAINTY_DEG
        }
    }
}

impl Default for DetectOptions {
    /// The dataset's pattern, with the model, a 0.3-square window, all cores.
    fn default() -> Self {
        DetectOptions {
            pattern: None,
            use_model: true,
            guided: true,
            subpix_factor: 0.3,
            jobs: std::thread::available_parallelism()
                .map(|n| n.get())
                .unwrap_or(1),
            params: None,
            calibrated: None,
            repredict: true,
            body: None,
        }
    }
}

/// Detects the vertices in every image of `dataset` (as [`detect_dataset`]) and puts them
/// in place of `dataset.corners`, for solving without a `corners.csv`; nothing is written.
///
/// Images in which no board is found (or that cannot be read, or are rejected) are only
/// reported in the returned results; it is an error when no capture names an image, when
/// a camera's pictures are turned by 180° ([`turned`]), or when no board is found in any
/// of them (the dataset is then left unchanged).
pub fn detect_into(
    dataset: &mut Dataset,
    options: &DetectOptions,
    done: &(dyn Fn(&ImageResult) + Sync),
) -> Result<Detection, NoCorners> {
    let images = dataset
        .captures
        .iter()
        .filter(|c| c.image.is_some())
        .count();
    if images == 0 {
        return Err(NoCorners::NoImages {
            dir: dataset.dir.clone(),
        });
    }
    cv::load()?;
    let results = detect_dataset(dataset, options, done);
    let summary = Summary::of(&results);
    let turned = turned::of_results(&results);
    if !turned.is_empty() {
        return Err(NoCorners::Turned {
            dir: dataset.dir.clone(),
            cameras: turned,
        });
    }
    if summary.found == 0 {
        let first = results
            .iter()
            .find(|r| !matches!(r.outcome, Outcome::NoImage))
            .map(ToString::to_string)
            .unwrap_or_default();
        return Err(NoCorners::NothingFound {
            dir: dataset.dir.clone(),
            images,
            summary,
            first,
        });
    }
    dataset.corners = corners(&results);
    Ok(Detection { results, summary })
}

/// Every corner found, in capture order.
pub fn corners(results: &[ImageResult]) -> Vec<Corner> {
    results
        .iter()
        .filter_map(|r| match &r.outcome {
            Outcome::Found { corners, .. } => Some(corners.iter().copied()),
            _ => None,
        })
        .flatten()
        .collect()
}

/// The grid of inner vertices of `model`'s board.
pub fn board_grid(model: &Model) -> Grid {
    Grid {
        cols: model.board.cols(),
        rows: model.board.rows(),
    }
}

/// Most images processed at once: `-j` beyond this is capped (4 per core, at most 64).
pub fn max_jobs() -> usize {
    let cores = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1);
    (4 * cores).min(64)
}

/// Detects the board in the image of one capture of `dataset`.
pub fn detect_capture(
    dataset: &Dataset,
    capture: &Capture,
    options: &DetectOptions,
) -> ImageResult {
    detect_capture_in(dataset, capture, options, Mode::Full)
}

/// How thoroughly one image is searched.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Mode {
    /// The re-predict loop's first pass: only the guided search near the prediction; what
    /// it misses is searched again with the calibrated prediction, or in full at the end.
    Quick,
    /// Every search: the guided one as far as the prediction's uncertainty reaches, then
    /// OpenCV's chessboard finder.
    Full,
}

fn detect_capture_in(
    dataset: &Dataset,
    capture: &Capture,
    options: &DetectOptions,
    mode: Mode,
) -> ImageResult {
    let outcome = match &capture.image {
        None => Outcome::NoImage,
        Some(image) => match detect_image(dataset, capture, image, options, mode) {
            Ok(outcome) => outcome,
            Err(e) => Outcome::Failed(e),
        },
    };
    ImageResult {
        capture: capture.id,
        image: capture.image.clone(),
        outcome,
    }
}

/// Detects the board in the image `image` of `capture`: first by the model-guided search
/// (with the model), then by OpenCV's chessboard finder where that finds no whole board.
fn detect_image(
    dataset: &Dataset,
    capture: &Capture,
    image: &Path,
    options: &DetectOptions,
    mode: Mode,
) -> Result<Outcome, DetectError> {
    let model = &dataset.model;
    let path = resolve_image(&dataset.dir, image)?;
    let intrinsics = model.intrinsics(capture.camera);
    let grey = read_sized(&path, [intrinsics.width, intrinsics.height], capture.camera)?;
    let cv = |e: cv::Error| DetectError::OpenCv {
        path: path.clone(),
        message: e.message,
    };
    let grid = options.pattern.unwrap_or_else(|| board_grid(model));
    // What the body hides (with `--body`), predicted once for the search and the outcome.
    let hidden = behind::predicted(dataset, capture, options);
    let mut search = chessboard::Search::Predicted;
    let mut guided_partial = None;
    if options.use_model && options.guided && grid == board_grid(model) {
        match guided_search(dataset, capture, &grey, options, mode, &hidden).map_err(cv)? {
            Guided::Done(outcome) => {
                return Ok(behind::drop_hidden(&hidden, outcome));
            }
            Guided::Partial { found, half } => {
                search = chessboard::Search::Whole { half };
                guided_partial = Some(found);
            }
            Guided::NotFound => {}
        }
    }
    let outcome =
        chessboard::chessboard(dataset, capture, &grey, grid, options, search).map_err(cv)?;
    let outcome = match (outcome, guided_partial) {
        (found @ Outcome::Found { .. }, _) => found,
        (_, Some(partial)) => partial,
        (other, None) => other,
    };
    let outcome = if grid == board_grid(model) {
        behind::drop_hidden(&hidden, outcome)
    } else {
        outcome
    };
    if mode == Mode::Full && matches!(outcome, Outcome::NotFound) {
        // No board at all: say so when the picture is too dark to show one.
        let bytes = &grey.pixels;
        let brightness = bytes.iter().map(|&b| b as f64).sum::<f64>() / bytes.len().max(1) as f64;
        if brightness < crate::robot::check::MIN_BRIGHTNESS {
            return Ok(Outcome::TooDark {
                camera: capture.camera,
                brightness,
            });
        }
    }
    Ok(outcome)
}

/// What the model-guided search makes of one image.
enum Guided {
    /// The outcome to keep.
    Done(Outcome),
    /// Part of the board, which OpenCV's chessboard finder may complete by searching the
    /// whole image (at half resolution with `half`).
    Partial {
        /// The part found, kept when the finder finds no whole board.
        found: Outcome,
        /// The board's squares are large enough for the finder at half resolution.
        half: bool,
    },
    /// No board: the chessboard finder searches where the model predicts it.
    NotFound,
}

/// The model-guided search ([`guided::detect`]) in `grey`, the image of `capture`; in the
/// quick `mode`, its outcome is final. `hidden`: the vertices the body model puts behind
/// the body ([`behind::predicted`]).
fn guided_search(
    dataset: &Dataset,
    capture: &Capture,
    grey: &GreyImage,
    options: &DetectOptions,
    mode: Mode,
    hidden: &[behind::Hidden],
) -> cv::Result<Guided> {
    let model = &dataset.model;
    let params = options.prediction();
    let pose = model
        .chains_for(capture.camera, capture.side, &capture.joints)
        .camera_to_board(&params);
    let integral = guided::Integral::new(grey);
    let camera = model.intrinsics_at(capture.camera, &params);
    let uncertainty_deg = match mode {
        Mode::Quick => 0.0,
        Mode::Full => options.uncertainty_deg(),
    };
    let found = guided::detect(
        grey,
        &integral,
        model,
        &camera,
        &pose,
        options.subpix_factor,
        uncertainty_deg,
    )?;
    // What the guided search found, as the capture's outcome.
    let outcome_of = |board: &guided::Board| Outcome::Found {
        corners: board
            .vertices
            .iter()
            .map(|&(vertex, pixel)| Corner {
                capture: capture.id,
                vertex,
                pixel,
                line: 0,
            })
            .collect(),
        order: None,
        whole_image: false,
        numbered: board.numbered.clone(),
        dropped: board.dropped.clone(),
    };
    if mode == Mode::Quick {
        return Ok(Guided::Done(
            found.map_or(Outcome::NotFound, |board| outcome_of(&board)),
        ));
    }
    let Ok(board) = found else {
        return Ok(Guided::NotFound);
    };
    let found = outcome_of(&board);
    // Part of the board: OpenCV's chessboard finder may still find all of it, but only
    // where every vertex is in view, and it gives up slowly where one is not: not where
    // the body model (`--body`) puts a vertex the search missed behind the body.
    let intrinsics = model.intrinsics(capture.camera);
    let missed_behind_body = hidden
        .iter()
        .any(|h| !board.vertices.iter().any(|(v, _)| *v == h.vertex));
    if board.vertices.len() == board_grid(model).len()
        || !chessboard::worth_trying(&board, intrinsics, options.subpix_factor)
        || missed_behind_body
    {
        return Ok(Guided::Done(found));
    }
    Ok(Guided::Partial {
        found,
        half: board
            .square()
            .is_some_and(|s| s >= 2.0 * chessboard::MIN_SQUARE),
    })
}

/// Detects the board in every capture of `dataset`, `options.jobs` images at once, then
/// (with `options.repredict`) calibrates from the boards found, predicts again and detects
/// again where no whole board was found, until nothing changes. `done` is called for every
/// final result, in capture order. The results are in capture order.
pub fn detect_dataset(
    dataset: &Dataset,
    options: &DetectOptions,
    done: &(dyn Fn(&ImageResult) + Sync),
) -> Vec<ImageResult> {
    // The images are the unit of parallelism: OpenCV's own worker threads would only compete
    // with them.
    if options.jobs > 1 {
        let _ = cv::set_num_threads(1);
    }
    let passes = Passes {
        dataset,
        pool: rayon::ThreadPoolBuilder::new()
            .num_threads(options.jobs.clamp(1, max_jobs()))
            .build()
            .ok(),
        grid: options
            .pattern
            .unwrap_or_else(|| board_grid(&dataset.model)),
    };
    let all: Vec<usize> = (0..dataset.captures.len()).collect();
    let repredict = options.use_model
        && options.guided
        && options.repredict
        && passes.grid == board_grid(&dataset.model);
    // With the re-predict loop, the first pass is quick: what it misses, the calibrated
    // prediction finds near where it says, and the rest gets the full search at the end.
    let first = if repredict { Mode::Quick } else { Mode::Full };
    let mut results = passes.run(options, &all, first);
    // Pictures turned by 180° are judged with the prediction given, against the boards
    // the model numbered (not in OpenCV's order, not another pattern).
    let judged = options.use_model && passes.grid == board_grid(&dataset.model);
    if repredict {
        // The boards of a camera whose pictures are turned take no part in the
        // calibration that predicts again.
        let turned = turned::turned_cameras(dataset, &results, &options.prediction());
        passes.repredict(options, &mut results, &turned);
    }
    if judged {
        for t in turned::turned_cameras(dataset, &results, &options.prediction()) {
            mark_turned(dataset, &mut results, t);
        }
        // Then each picture on its own: one turned among upright ones is left out; where
        // its camera has too few boards, the picture says it could not be judged.
        for (capture, turn) in turned::judge_pictures(dataset, &results, &options.prediction()) {
            let Some(r) = results.iter_mut().find(|r| r.capture == capture) else {
                continue;
            };
            match (&mut r.outcome, turn) {
                (Outcome::Found { corners, .. }, turned::PictureTurn::Turned { .. }) => {
                    r.outcome = Outcome::TurnedAlone {
                        found: corners.len(),
                        turn,
                    };
                }
                (Outcome::Found { numbered, .. }, turned::PictureTurn::Unjudged { .. }) => {
                    numbered.push_str(&format!("; {turn}"));
                }
                _ => {}
            }
        }
    }
    for r in &results {
        done(r);
    }
    results
}

/// Passes over a dataset's images, several images at once.
struct Passes<'a> {
    /// The dataset.
    dataset: &'a Dataset,
    /// The threads the images are searched on (rayon's global pool when `None`).
    pool: Option<rayon::ThreadPool>,
    /// The pattern looked for.
    grid: Grid,
}

impl Passes<'_> {
    /// The results of the captures `which` (indices), searched with `options` in `mode`.
    fn run(&self, options: &DetectOptions, which: &[usize], mode: Mode) -> Vec<ImageResult> {
        let dataset = self.dataset;
        let go = || {
            which
                .par_iter()
                .map(|&i| detect_capture_in(dataset, &dataset.captures[i], options, mode))
                .collect()
        };
        match &self.pool {
            Some(pool) => pool.install(go),
            None => go(),
        }
    }

    /// The re-predict loop after a quick first pass over every capture (`results`):
    /// calibrates from the boards found, predicts again and searches again where no whole
    /// board was found, until nothing changes; then gives what only the quick pass looked
    /// at the full search, with the best prediction there is.
    fn repredict(
        &self,
        options: &DetectOptions,
        results: &mut [ImageResult],
        turned: &[turned::Turned],
    ) {
        let mut quick = vec![true; results.len()];
        let mut options = options.clone();
        for _ in 1..MAX_PASSES {
            // Nothing to look for again: every image holds a whole board (or none).
            if results.iter().all(|r| whole(r, self.grid)) {
                break;
            }
            let Some(params) = calibrate_from(self.dataset, results, turned) else {
                break;
            };
            options.calibrated = Some(params);
            if !self.again(&options, results, &mut quick) {
                break;
            }
        }
        // What only the quick pass looked at and it did not find whole: the full search,
        // with the best prediction there is.
        let rest: Vec<usize> = (0..results.len())
            .filter(|&i| quick[i] && !whole(&results[i], self.grid))
            .collect();
        if !rest.is_empty() {
            let again = self.run(&options, &rest, Mode::Full);
            for (i, r) in rest.into_iter().zip(again) {
                if found_count(&r) > found_count(&results[i]) || found_count(&results[i]) == 0 {
                    results[i] = r;
                }
            }
        }
    }

    /// One pass of the re-predict loop with the calibrated prediction of `options`: the
    /// captures worth it are searched again in full (`quick` marks those only the quick
    /// pass has searched). Returns whether a result changed.
    fn again(
        &self,
        options: &DetectOptions,
        results: &mut [ImageResult],
        quick: &mut [bool],
    ) -> bool {
        let (dataset, params) = (self.dataset, options.prediction());
        let redo: Vec<usize> = (0..results.len())
            .filter(|&i| {
                // A board found in part is searched in full once; an image without a
                // board again with every better prediction.
                (quick[i] || found_count(&results[i]) == 0)
                    && worth_again(
                        dataset,
                        &dataset.captures[i],
                        &results[i],
                        self.grid,
                        &params,
                    )
            })
            .collect();
        if redo.is_empty() {
            return false;
        }
        // A result is replaced only by one with more vertices (both are numbered by
        // the image; the new prediction may find more, never needs fewer).
        let mut changed = false;
        let again = self.run(options, &redo, Mode::Full);
        for (i, r) in redo.into_iter().zip(again) {
            if found_count(&r) > found_count(&results[i]) {
                changed = true;
                results[i] = r;
            } else if found_count(&results[i]) == 0 {
                // Why the full search found nothing.
                results[i] = r;
            }
            quick[i] = false;
        }
        changed
    }
}

/// Marks every board found in a picture of the camera `turned` judged turned by 180° as
/// not used.
fn mark_turned(dataset: &Dataset, results: &mut [ImageResult], turned: turned::Turned) {
    for r in results {
        let camera = dataset
            .captures
            .iter()
            .find(|c| c.id == r.capture)
            .map(|c| c.camera);
        if camera == Some(turned.camera)
            && let Outcome::Found { corners, .. } = &r.outcome
        {
            r.outcome = Outcome::Turned {
                found: corners.len(),
                turned,
            };
        }
    }
}

/// Whether `result` leaves nothing to search again: a whole board, no image, or an image
/// that cannot be used.
fn whole(result: &ImageResult, grid: Grid) -> bool {
    match &result.outcome {
        Outcome::NoImage
        | Outcome::Failed(_)
        | Outcome::TooDark { .. }
        | Outcome::Turned { .. }
        | Outcome::TurnedAlone { .. } => true,
        Outcome::Found { corners, .. } => corners.len() == grid.len(),
        Outcome::NotFound | Outcome::Rejected { .. } => false,
    }
}

/// Vertices found in a result.
fn found_count(result: &ImageResult) -> usize {
    match &result.outcome {
        Outcome::Found { corners, .. } => corners.len(),
        _ => 0,
    }
}

/// Whether to search `capture` again with the prediction `params`: no board was found
/// (or it was rejected), or fewer vertices than the prediction puts well inside the image.
fn worth_again(
    dataset: &Dataset,
    capture: &Capture,
    result: &ImageResult,
    grid: Grid,
    params: &[f64; PARAMETER_COUNT],
) -> bool {
    match &result.outcome {
        Outcome::NoImage
        | Outcome::Failed(_)
        | Outcome::TooDark { .. }
        | Outcome::Turned { .. }
        | Outcome::TurnedAlone { .. } => false,
        Outcome::NotFound | Outcome::Rejected { .. } => true,
        Outcome::Found { corners, .. } => {
            corners.len() < grid.len()
                && predict(&dataset.model, capture, params).is_some_and(|points| {
                    let inside = points
                        .iter()
                        .filter(|p| dataset.model.intrinsics(capture.camera).contains(**p, 8.0))
                        .count();
                    inside > corners.len()
                })
        }
    }
}

/// The paper's calibration (plain least squares) from the boards found in `results`, as
/// the re-predict loop's prediction, leaving out the cameras whose pictures are `turned`;
/// `None` when too few were found or the fit is not a calibration.
fn calibrate_from(
    dataset: &Dataset,
    results: &[ImageResult],
    turned: &[turned::Turned],
) -> Option<[f64; PARAMETER_COUNT]> {
    let left_out: std::collections::HashSet<u64> = dataset
        .captures
        .iter()
        .filter(|c| turned.iter().any(|t| t.camera == c.camera))
        .map(|c| c.id)
        .collect();
    let used: Vec<&ImageResult> = results
        .iter()
        .filter(|r| matches!(r.outcome, Outcome::Found { .. }) && !left_out.contains(&r.capture))
        .collect();
    if used.len() < MIN_BOARDS_TO_REPREDICT {
        return None;
    }
    let mut found = dataset.clone();
    found.corners = used
        .iter()
        .filter_map(|r| match &r.outcome {
            Outcome::Found { corners, .. } => Some(corners.iter().copied()),
            _ => None,
        })
        .flatten()
        .collect();
    let problem =
        crate::solve::Problem::from_dataset(&found, crate::model::FixedSet::default()).ok()?;
    let backend = crate::solve::backend(crate::solve::backend_names()[0], false)?;
    let solution = crate::solve::calibrate(
        &problem,
        backend.as_ref(),
        &crate::solve::UncertaintyOptions::plain(),
    )
    .ok()?;
    solution.is_calibration().then_some(solution.values)
}
