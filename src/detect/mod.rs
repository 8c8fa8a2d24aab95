//! Finding the sandal's vertices in camera images (the paper's measurement phase).
//!
//! For each capture with an image: the image is read as grey levels (`image.rs`: the
//! header checked before any pixel is decoded), and with the model the board is first
//! looked for where the nominal model (all offsets zero) and the logged joint angles
//! predict it, by its pattern of saddles ([`guided`]); its vertices are refined with
//! `cornerSubPix` and numbered by the prediction. OpenCV's chessboard finder
//! (`chessboard.rs`, [`find`]) is the fallback: when the guided search finds nothing, in
//! the predicted region (`predict.rs`) and then the whole image at half resolution
//! (refined at full); when it finds part of a board, only if the board is wholly in view
//! and a vertex was missed well inside the image (the finder needs the whole board, and
//! gives up slowly where it is cut by the border). Its points are numbered by comparing
//! OpenCV's order with the prediction ([`assign::assign`]). Images whose order is
//! ambiguous or whose points do not fit one homography are rejected with the reason.
//! Nothing here stops a run: every image gets an [`Outcome`] (`outcome.rs`).

pub mod assign;
mod chessboard;
pub mod find;
pub mod guided;
mod image;
mod outcome;
pub mod overlay;
mod predict;

use std::path::Path;

use opencv::prelude::*;
use rayon::prelude::*;

use crate::dataset::{Capture, Corner, Dataset};
use crate::model::{Model, PARAMETER_COUNT};
use assign::Grid;
pub use image::{MAX_PIXELS, MAX_SIDE, decode_grey, header_size, read_grey, resolve_image};
use image::{check_header, read_bytes};
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
        }
    }
}

/// Detects the vertices in every image of `dataset` (as [`detect_dataset`]) and puts them
/// in place of `dataset.corners`, for solving without a `corners.csv`; nothing is written.
///
/// Images in which no board is found (or that cannot be read, or are rejected) are only
/// reported in the returned results; it is an error when no capture names an image, or
/// when no board is found in any of them (the dataset is then left unchanged).
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
    let results = detect_dataset(dataset, options, done);
    let summary = Summary::of(&results);
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
    let outcome = match &capture.image {
        None => Outcome::NoImage,
        Some(image) => match detect_image(dataset, capture, image, options) {
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

fn detect_image(
    dataset: &Dataset,
    capture: &Capture,
    image: &Path,
    options: &DetectOptions,
) -> Result<Outcome, DetectError> {
    let model = &dataset.model;
    let path = resolve_image(&dataset.dir, image)?;
    let bytes = read_bytes(&path)?;
    // The size is checked from the header, before any pixel is decoded.
    let camera = [model.camera.width, model.camera.height];
    if !bytes.is_empty() {
        let size = check_header(&path, &bytes)?;
        if size != camera {
            return Err(DetectError::Size { path, size, camera });
        }
    }
    let grey = decode_grey(&path, &bytes)?;
    drop(bytes);
    let cv = |e: opencv::Error| DetectError::OpenCv {
        path: path.clone(),
        message: e.message,
    };
    let size = [grey.cols() as u32, grey.rows() as u32];
    if size != camera {
        return Err(DetectError::Size { path, size, camera });
    }
    let grid = options.pattern.unwrap_or_else(|| board_grid(model));
    let mut search = chessboard::Search::Predicted;
    let mut guided_partial = None;
    if options.use_model && options.guided && grid == board_grid(model) {
        let params = [0.0; PARAMETER_COUNT];
        let pose = model
            .chains(capture.side, &capture.joints)
            .camera_to_board(&params);
        let integral = guided::Integral::new(&grey).map_err(cv)?;
        let camera = model.camera_at(&params);
        let found = guided::detect(
            &grey,
            &integral,
            model,
            &camera,
            &pose,
            options.subpix_factor,
        )
        .map_err(cv)?;
        if let Ok(board) = found {
            let complete = board.vertices.len() == grid.len();
            let corners: Vec<Corner> = board
                .vertices
                .iter()
                .map(|&(vertex, pixel)| Corner {
                    capture: capture.id,
                    vertex,
                    pixel,
                    line: 0,
                })
                .collect();
            let found = Outcome::Found {
                corners,
                order: None,
                whole_image: false,
            };
            if complete {
                return Ok(found);
            }
            // Part of the board: OpenCV's chessboard finder may still find all of it, but
            // only where every vertex is in view, and it gives up slowly where one is not.
            if !chessboard::worth_trying(&board, &model.camera, options.subpix_factor) {
                return Ok(found);
            }
            search = chessboard::Search::Whole;
            guided_partial = Some(found);
        }
    }
    let outcome =
        chessboard::chessboard(dataset, capture, &grey, grid, options, search).map_err(cv)?;
    Ok(match (outcome, guided_partial) {
        (found @ Outcome::Found { .. }, _) => found,
        (_, Some(partial)) => partial,
        (other, None) => other,
    })
}

/// Detects the board in every capture of `dataset`, `options.jobs` images at once, calling
/// `done` as each finishes (from the worker threads). The results are in capture order.
pub fn detect_dataset(
    dataset: &Dataset,
    options: &DetectOptions,
    done: &(dyn Fn(&ImageResult) + Sync),
) -> Vec<ImageResult> {
    // The images are the unit of parallelism: OpenCV's own worker threads would only compete
    // with them.
    if options.jobs > 1 {
        let _ = opencv::core::set_num_threads(1);
    }
    let run = || {
        dataset
            .captures
            .par_iter()
            .map(|c| {
                let r = detect_capture(dataset, c, options);
                done(&r);
                r
            })
            .collect()
    };
    match rayon::ThreadPoolBuilder::new()
        .num_threads(options.jobs.clamp(1, max_jobs()))
        .build()
    {
        Ok(pool) => pool.install(run),
        Err(_) => run(),
    }
}
