//! Finding the sandal's vertices in camera images with OpenCV (the paper's measurement
//! phase).
//!
//! For each capture with an image: the image is read (PNG with the `png` crate, anything
//! else with OpenCV), the board is looked for with `findChessboardCorners` first in the
//! region where the nominal model (all offsets zero) and the logged joint angles predict
//! it, then in the whole image; the vertices are refined with `cornerSubPix` in a window
//! of about 0.3 squares; and each gets its (row, col) by comparing OpenCV's order with the
//! prediction ([`assign::assign`]): a 7 × 5 board looks the same turned by 180°, so
//! OpenCV's order flips between images. Images whose order is ambiguous or whose points
//! do not fit one homography are rejected with the reason. Nothing here stops a run:
//! every image gets an [`Outcome`].

pub mod assign;
pub mod find;
pub mod guided;
pub mod overlay;

use std::fmt;
use std::path::{Component, Path, PathBuf};

use opencv::core::{Mat, Rect};
use opencv::prelude::*;
use rayon::prelude::*;

use crate::dataset::{Capture, Corner, Dataset};
use crate::model::{Model, PARAMETER_COUNT, Vertex};
use assign::Grid;

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

/// Why an image could not be used at all (as opposed to a board not found in it).
#[derive(Debug, thiserror::Error)]
pub enum DetectError {
    /// The image file does not exist.
    #[error("{}: no such file", path.display())]
    Missing {
        /// The image.
        path: PathBuf,
    },
    /// The image file is empty.
    #[error("{}: the file is empty", path.display())]
    Empty {
        /// The image.
        path: PathBuf,
    },
    /// The image path leads out of the dataset directory.
    #[error("{}: the image path leaves the dataset directory {}", path.display(), dir.display())]
    OutsideDataset {
        /// The image.
        path: PathBuf,
        /// The dataset directory.
        dir: PathBuf,
    },
    /// The file could not be read.
    #[error("{}: cannot read: {source}", path.display())]
    Io {
        /// The image.
        path: PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// The file is not an image that can be decoded.
    #[error("{}: not a readable image: {message}", path.display())]
    Decode {
        /// The image.
        path: PathBuf,
        /// What the decoder said.
        message: String,
    },
    /// The image does not have the camera's resolution.
    #[error(
        "{}: the image is {}×{} pixels, but the camera in dataset.toml is {}×{}",
        path.display(), size[0], size[1], camera[0], camera[1]
    )]
    Size {
        /// The image.
        path: PathBuf,
        /// Its size.
        size: [u32; 2],
        /// The camera's resolution.
        camera: [u32; 2],
    },
    /// The image header claims a size beyond what detection reads (refused before decoding).
    #[error(
        "{}: the image header claims {}×{} pixels, more than the {} × {} pixels (and {} \
         megapixels) detection reads; refused before decoding",
        path.display(), size[0], size[1], MAX_SIDE, MAX_SIDE, MAX_PIXELS / 1_000_000
    )]
    TooLarge {
        /// The image.
        path: PathBuf,
        /// The size its header claims.
        size: [u32; 2],
    },
    /// An output (an overlay) could not be written.
    #[error("{message}")]
    Write {
        /// The output file.
        path: PathBuf,
        /// Why (names the file).
        message: String,
    },
    /// OpenCV failed.
    #[error("{}: OpenCV: {message}", path.display())]
    OpenCv {
        /// The image.
        path: PathBuf,
        /// OpenCV's message.
        message: String,
    },
}

/// What became of one capture.
#[derive(Debug)]
pub enum Outcome {
    /// The board was found; its vertices.
    Found {
        /// The vertices, in row-major order of the board.
        corners: Vec<Corner>,
        /// How OpenCV's order relates to the board's; `None` when the vertices were found
        /// and numbered by the model-guided search ([`guided`]).
        order: Option<assign::Order>,
        /// Whether the board was found only in the whole image, not where predicted.
        whole_image: bool,
    },
    /// No board was found.
    NotFound,
    /// A board was found but not used.
    Rejected {
        /// Why.
        reason: String,
    },
    /// The image could not be used.
    Failed(DetectError),
    /// The capture names no image.
    NoImage,
}

/// The result for one capture.
#[derive(Debug)]
pub struct ImageResult {
    /// The capture id.
    pub capture: u64,
    /// Its image path, relative to the dataset directory.
    pub image: Option<PathBuf>,
    /// What became of it.
    pub outcome: Outcome,
}

impl fmt::Display for ImageResult {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "capture {}", self.capture)?;
        if let Some(image) = &self.image {
            write!(f, " ({})", image.display())?;
        }
        match &self.outcome {
            Outcome::Found {
                corners,
                order,
                whole_image,
            } => {
                write!(f, ": found {} vertices", corners.len())?;
                match order {
                    None => write!(f, " (model-guided)")?,
                    Some(assign::Order::Same) => {}
                    Some(order) => write!(f, " ({order})")?,
                }
                if *whole_image {
                    write!(f, " (not where predicted; found in the whole image)")?;
                }
                Ok(())
            }
            Outcome::NotFound => write!(f, ": not found"),
            Outcome::Rejected { reason } => write!(f, ": rejected: {reason}"),
            Outcome::Failed(e) => write!(f, ": error: {e}"),
            Outcome::NoImage => write!(f, ": no image"),
        }
    }
}

/// Counts of outcomes.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Summary {
    /// Boards found.
    pub found: usize,
    /// Boards not found.
    pub not_found: usize,
    /// Boards rejected.
    pub rejected: usize,
    /// Images that could not be used.
    pub failed: usize,
    /// Captures without an image.
    pub no_image: usize,
}

impl Summary {
    /// Counts the outcomes of `results`.
    pub fn of(results: &[ImageResult]) -> Summary {
        let mut s = Summary::default();
        for r in results {
            match r.outcome {
                Outcome::Found { .. } => s.found += 1,
                Outcome::NotFound => s.not_found += 1,
                Outcome::Rejected { .. } => s.rejected += 1,
                Outcome::Failed(_) => s.failed += 1,
                Outcome::NoImage => s.no_image += 1,
            }
        }
        s
    }
}

impl fmt::Display for Summary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} found, {} not found, {} rejected, {} unreadable",
            self.found, self.not_found, self.rejected, self.failed
        )?;
        if self.no_image > 0 {
            write!(f, ", {} without an image", self.no_image)?;
        }
        Ok(())
    }
}

/// Why detection gave nothing to solve with.
#[derive(Debug, thiserror::Error)]
pub enum NoCorners {
    /// No capture names an image.
    #[error(
        "{}: no capture in captures.csv names an image (its image column is empty); \
         there is nothing to detect",
        dir.display()
    )]
    NoImages {
        /// The dataset directory.
        dir: PathBuf,
    },
    /// No board was found in any image.
    #[error(
        "{}: no board found in any of its {images} images ({summary}); first: {first}",
        dir.display()
    )]
    NothingFound {
        /// The dataset directory.
        dir: PathBuf,
        /// Captures with an image.
        images: usize,
        /// The counts.
        summary: Summary,
        /// The first capture's result line (why it failed).
        first: String,
    },
}

/// The result of detecting the vertices of a whole dataset in memory.
#[derive(Debug)]
pub struct Detection {
    /// One result per capture, in capture order.
    pub results: Vec<ImageResult>,
    /// Their counts.
    pub summary: Summary,
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

/// Where the nominal model (all offsets zero) puts every vertex of the board in view of
/// `capture` (row-major), or `None` when a vertex is behind the camera.
pub fn predict(model: &Model, capture: &Capture, params: &[f64]) -> Option<Vec<[f64; 2]>> {
    let vertices: Vec<Vertex> = model.board.vertices().collect();
    model
        .project(
            &model.chains(capture.side, &capture.joints),
            params,
            &vertices,
        )
        .into_iter()
        .collect()
}

/// The part of the image where the board (with a square's border and a margin for the
/// model's error) is predicted, or `None` when it cannot be predicted or fills most of the
/// image anyway.
fn predicted_roi(model: &Model, capture: &Capture) -> Option<Rect> {
    let b = &model.board;
    let (hx, hy) = (
        (b.squares_x as f64 / 2.0 + 1.0) * b.square,
        (b.squares_y as f64 / 2.0 + 1.0) * b.square,
    );
    let pose = model
        .chains(capture.side, &capture.joints)
        .camera_to_board(&[0.0; PARAMETER_COUNT]);
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for (x, y) in [(-hx, -hy), (hx, -hy), (-hx, hy), (hx, hy)] {
        let p = model.camera.project(&pose.apply(&[x, y, 0.0]))?;
        for i in 0..2 {
            lo[i] = lo[i].min(p[i]);
            hi[i] = hi[i].max(p[i]);
        }
    }
    let (w, h) = (model.camera.width as f64, model.camera.height as f64);
    let margin = 40.0 + 0.15 * (hi[0] - lo[0]).max(hi[1] - lo[1]);
    let x0 = (lo[0] - margin).max(0.0).floor();
    let y0 = (lo[1] - margin).max(0.0).floor();
    let x1 = (hi[0] + margin).min(w).ceil();
    let y1 = (hi[1] + margin).min(h).ceil();
    if x1 - x0 < 32.0 || y1 - y0 < 32.0 || (x1 - x0) * (y1 - y0) > 0.8 * w * h {
        return None;
    }
    Some(Rect::new(
        x0 as i32,
        y0 as i32,
        (x1 - x0) as i32,
        (y1 - y0) as i32,
    ))
}

/// The full path of `image` in `dir`, checked to stay inside `dir` (also through symbolic
/// links).
pub fn resolve_image(dir: &Path, image: &Path) -> Result<PathBuf, DetectError> {
    let path = dir.join(image);
    let outside = || DetectError::OutsideDataset {
        path: path.clone(),
        dir: dir.to_path_buf(),
    };
    if image
        .components()
        .any(|c| !matches!(c, Component::Normal(_) | Component::CurDir))
    {
        return Err(outside());
    }
    match (path.canonicalize(), dir.canonicalize()) {
        (Ok(real), Ok(real_dir)) if !real.starts_with(&real_dir) => Err(outside()),
        _ => Ok(path),
    }
}

/// Reads an image file as 8-bit greyscale.
pub fn read_grey(path: &Path) -> Result<Mat, DetectError> {
    decode_grey(path, &read_bytes(path)?)
}

/// Reads an image file's bytes.
fn read_bytes(path: &Path) -> Result<Vec<u8>, DetectError> {
    match std::fs::read(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Err(DetectError::Missing {
            path: path.to_path_buf(),
        }),
        Err(source) => Err(DetectError::Io {
            path: path.to_path_buf(),
            source,
        }),
        Ok(b) => Ok(b),
    }
}

/// Largest image side detection reads (px).
pub const MAX_SIDE: u32 = 16_384;
/// Largest image detection reads (pixels): 64 megapixels (64 MB of grey levels).
pub const MAX_PIXELS: u64 = 64_000_000;

/// Most images processed at once: `-j` beyond this is capped (4 per core, at most 64).
pub fn max_jobs() -> usize {
    let cores = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1);
    (4 * cores).min(64)
}

/// The width and height an image file's header claims (PNG, JPEG, BMP or PGM), read
/// without decoding the pixels.
pub fn header_size(path: &Path, bytes: &[u8]) -> Result<[u32; 2], DetectError> {
    let decode = |message: String| DetectError::Decode {
        path: path.to_path_buf(),
        message,
    };
    if bytes.starts_with(b"\x89PNG") {
        let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
        let reader = decoder.read_info().map_err(|e| decode(e.to_string()))?;
        let info = reader.info();
        return Ok([info.width, info.height]);
    }
    let reader = image::io::Reader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| decode(e.to_string()))?;
    let (w, h) = reader
        .into_dimensions()
        .map_err(|e| decode(e.to_string()))?;
    Ok([w, h])
}

/// Refuses an image whose header claims more than [`MAX_SIDE`] or [`MAX_PIXELS`] (and one
/// that is no PNG, JPEG, BMP or PGM).
fn check_header(path: &Path, bytes: &[u8]) -> Result<[u32; 2], DetectError> {
    const KNOWN: [&[u8]; 5] = [b"\x89PNG", b"\xff\xd8\xff", b"BM", b"P5", b"P2"];
    if !KNOWN.iter().any(|m| bytes.starts_with(m)) {
        return Err(DetectError::Decode {
            path: path.to_path_buf(),
            message: "not a PNG, JPEG, BMP or PGM file (unknown signature)".into(),
        });
    }
    let size = header_size(path, bytes)?;
    if size[0] > MAX_SIDE || size[1] > MAX_SIDE || size[0] as u64 * size[1] as u64 > MAX_PIXELS {
        return Err(DetectError::TooLarge {
            path: path.to_path_buf(),
            size,
        });
    }
    Ok(size)
}

/// Decodes image bytes (PNG, JPEG, BMP or PGM) as 8-bit greyscale. The size in the header
/// is checked against [`MAX_SIDE`] and [`MAX_PIXELS`] before anything is decoded.
pub fn decode_grey(path: &Path, bytes: &[u8]) -> Result<Mat, DetectError> {
    let decode = |message: String| DetectError::Decode {
        path: path.to_path_buf(),
        message,
    };
    let cv = |e: opencv::Error| DetectError::OpenCv {
        path: path.to_path_buf(),
        message: e.message,
    };
    if bytes.is_empty() {
        return Err(DetectError::Empty {
            path: path.to_path_buf(),
        });
    }
    check_header(path, bytes)?;
    if bytes.starts_with(b"\x89PNG") {
        let (grey, width, height) = decode_png(bytes).map_err(decode)?;
        let mat = Mat::new_rows_cols_with_data(height as i32, width as i32, &grey).map_err(cv)?;
        return mat.try_clone().map_err(cv);
    }
    let (grey, width, height) = decode_other(bytes).map_err(decode)?;
    let mat = Mat::new_rows_cols_with_data(height as i32, width as i32, &grey).map_err(cv)?;
    mat.try_clone().map_err(cv)
}

/// Decodes a JPEG, BMP or PGM into 8-bit grey levels (colour as in [`decode_png`]).
fn decode_other(bytes: &[u8]) -> Result<(Vec<u8>, u32, u32), String> {
    let img = image::load_from_memory(bytes).map_err(|e| e.to_string())?;
    let (width, height) = (img.width(), img.height());
    let grey = match img {
        image::DynamicImage::ImageLuma8(g) => g.into_raw(),
        other => other
            .to_rgb8()
            .pixels()
            .map(|p| bt601(p.0[0], p.0[1], p.0[2]))
            .collect(),
    };
    Ok((grey, width, height))
}

/// ITU-R BT.601 luma, as OpenCV's colour-to-grey conversion.
fn bt601(r: u8, g: u8, b: u8) -> u8 {
    (0.299 * r as f64 + 0.587 * g as f64 + 0.114 * b as f64).round() as u8
}

/// Decodes a PNG into 8-bit grey levels (colour converted with ITU-R BT.601 weights).
fn decode_png(bytes: &[u8]) -> Result<(Vec<u8>, u32, u32), String> {
    let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    decoder.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
    let mut reader = decoder.read_info().map_err(|e| e.to_string())?;
    let size = reader
        .output_buffer_size()
        .ok_or_else(|| "the image is too large".to_string())?;
    let mut buf = vec![0; size];
    let info = reader.next_frame(&mut buf).map_err(|e| e.to_string())?;
    buf.truncate(info.buffer_size());
    let channels = info.color_type.samples();
    let grey = match channels {
        1 => buf,
        2 => buf.chunks_exact(2).map(|p| p[0]).collect(),
        _ => buf
            .chunks_exact(channels)
            .map(|p| bt601(p[0], p[1], p[2]))
            .collect(),
    };
    Ok((grey, info.width, info.height))
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
        if let Ok(vertices) = found {
            let corners: Vec<Corner> = vertices
                .into_iter()
                .map(|(vertex, pixel)| Corner {
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
            if matches!(&found, Outcome::Found { corners, .. } if corners.len() == grid.len()) {
                return Ok(found);
            }
            // Part of the board: OpenCV's chessboard finder may still see all of it.
            guided_partial = Some(found);
        }
    }
    let outcome = chessboard(dataset, capture, &grey, grid, options).map_err(cv)?;
    Ok(match (outcome, guided_partial) {
        (
            Outcome::Found {
                corners,
                order,
                whole_image,
            },
            _,
        ) => Outcome::Found {
            corners,
            order,
            whole_image,
        },
        (_, Some(partial)) => partial,
        (other, None) => other,
    })
}

/// OpenCV's chessboard finder in the predicted region, then the whole image; numbered by
/// the model's orientation (or OpenCV's order without the model).
fn chessboard(
    dataset: &Dataset,
    capture: &Capture,
    grey: &Mat,
    grid: Grid,
    options: &DetectOptions,
) -> opencv::Result<Outcome> {
    let model = &dataset.model;
    let camera = [model.camera.width, model.camera.height];
    let cv = |e: opencv::Error| e;
    let roi = if options.use_model {
        predicted_roi(model, capture)
    } else {
        None
    };
    let mut whole_image = false;
    let mut points = match roi {
        Some(rect) => find::find_board(grey, grid, Some(rect)).map_err(cv)?,
        None => None,
    };
    if points.is_none() {
        whole_image = roi.is_some();
        points = find::find_board(grey, grid, None).map_err(cv)?;
    }
    let Some(mut points) = points else {
        return Ok(Outcome::NotFound);
    };
    find::refine(grey, &mut points, grid, options.subpix_factor).map_err(cv)?;

    // One homography must explain every point (after removing the lens distortion).
    let board_xy: Vec<[f64; 2]> = (0..grid.len())
        .map(|k| [(k as u32 % grid.cols) as f64, (k as u32 / grid.cols) as f64])
        .collect();
    let cam = &model.camera;
    let undistorted: Vec<[f64; 2]> = points
        .iter()
        .map(|p| {
            let [a, b] = cam.undistort(p[0], p[1]);
            [a * cam.fx + cam.cx, b * cam.fy + cam.cy]
        })
        .collect();
    let squares = find::local_square(&points, grid);
    let mut sorted = squares.clone();
    sorted.sort_by(f64::total_cmp);
    let square = sorted[sorted.len() / 2];
    let limit = if options.use_model {
        (0.1 * square).max(1.0)
    } else {
        (0.25 * square).max(1.0)
    };
    match assign::homography_residual(&board_xy, &undistorted) {
        None => {
            return Ok(Outcome::Rejected {
                reason: "the points are degenerate (no homography fits them)".into(),
            });
        }
        Some(r) if r > limit => {
            return Ok(Outcome::Rejected {
                reason: format!(
                    "the points do not fit one homography (a point is {r:.2} px off, more \
                     than {limit:.2} px)"
                ),
            });
        }
        Some(_) => {}
    }

    let (vertices, order) = if options.use_model {
        if grid != board_grid(model) {
            return Ok(Outcome::Rejected {
                reason: format!(
                    "the pattern {}x{} is not the board's {}x{} (use --no-model)",
                    grid.cols,
                    grid.rows,
                    model.board.cols(),
                    model.board.rows()
                ),
            });
        }
        let Some(predicted) = predict(model, capture, &[0.0; PARAMETER_COUNT]) else {
            return Ok(Outcome::Rejected {
                reason: "the model puts the board behind the camera".into(),
            });
        };
        match assign::assign(
            &points,
            &predicted,
            grid,
            [camera[0] as f64, camera[1] as f64],
        ) {
            Ok(a) => (a.vertices, a.order),
            Err(reason) => return Ok(Outcome::Rejected { reason }),
        }
    } else {
        let order = (0..grid.len() as u32)
            .map(|k| (k / grid.cols, k % grid.cols))
            .collect();
        (order, assign::Order::Same)
    };
    let order = Some(order);
    let mut corners: Vec<Corner> = vertices
        .iter()
        .zip(&points)
        .map(|(&(row, col), p)| Corner {
            capture: capture.id,
            vertex: Vertex { row, col },
            pixel: *p,
            line: 0,
        })
        .collect();
    corners.sort_by_key(|c| c.vertex);
    Ok(Outcome::Found {
        corners,
        order,
        whole_image,
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
