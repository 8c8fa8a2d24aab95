//! What `naocalib detect` is asked for: its checks before any image is read (the
//! corners.csv it may replace, the overlays, the prediction's parameters, the jobs), the
//! detection with its overlays, and the corners.csv written; and the same detection in
//! memory for `solve --detect`, with the guard that marks its captures that stand out.

use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;

use super::prediction::{self, PredictionError};
use crate::dataset::{CORNERS_CSV, Dataset, DatasetError};
use crate::model::PARAMETER_COUNT;
use crate::output::{WriteError, WriteOptions};
use crate::solve::Solution;

use super::assign::Grid;
use super::{
    DetectOptions, Detection, ImageResult, NoCorners, Outcome, Summary, board_grid, guard,
    max_jobs, overlay,
};

/// A dataset's images to detect the board in, as `naocalib detect` is asked for it.
#[derive(Debug, Clone, PartialEq)]
pub struct DetectRequest {
    /// The dataset directory.
    pub dataset: PathBuf,
    /// Replace a corners.csv that holds vertices, and existing overlays.
    pub force: bool,
    /// The pattern's inner vertices; the dataset's board when not given.
    pub pattern: Option<Grid>,
    /// Predict the board with the model and the logged joints.
    pub use_model: bool,
    /// Write an overlay per image into this directory.
    pub overlay: Option<PathBuf>,
    /// Also draw the projection with the parameters of this `solve --json` result.
    pub after: Option<PathBuf>,
    /// Images processed at once (all cores when not given).
    pub jobs: Option<usize>,
    /// Predict with this calibration instead of the nominal model.
    pub start_from: Option<PathBuf>,
    /// Calibrate from the boards found, predict again and detect again.
    pub repredict: bool,
    /// The pictures show the robot: drop every vertex its body stands in front of.
    pub body: bool,
}

/// Why the board could not be detected in a dataset, or its corners not written.
#[derive(Debug, thiserror::Error)]
pub enum DetectRequestError {
    /// The dataset could not be read, or its corners not written.
    #[error(transparent)]
    Dataset(#[from] DatasetError),
    /// The corners.csv holds vertices and `force` is not given.
    #[error("{}: already holds {count} vertices; use --force to overwrite", .path.display())]
    CornersHeld {
        /// The corners.csv.
        path: PathBuf,
        /// Its vertices.
        count: usize,
    },
    /// A prediction's parameters could not be read.
    #[error(transparent)]
    Prediction(#[from] PredictionError),
    /// An overlay would replace an input, or exists.
    #[error(transparent)]
    Output(#[from] WriteError),
    /// No job to process the images.
    #[error("--jobs must be at least 1")]
    NoJobs,
    /// OpenCV (naocalib's plugin) could not be loaded.
    #[error(transparent)]
    OpenCv(#[from] super::cv::Error),
    /// No vertex was found, and the corners.csv holds some: it is left as it was.
    #[error(
        "{}: no vertex found in any of {images} images ({summary}); {} and its {count} \
         vertices left as they were",
        .dir.display(),
        .corners.display()
    )]
    NothingFound {
        /// The dataset directory.
        dir: PathBuf,
        /// Images searched.
        images: usize,
        /// Their outcomes.
        summary: Box<Summary>,
        /// The corners.csv.
        corners: PathBuf,
        /// Its vertices.
        count: usize,
    },
}

/// A detection checked and ready to run: the dataset and everything read from the
/// request's files.
#[derive(Debug)]
pub struct Prepared<'a> {
    request: &'a DetectRequest,
    /// The dataset.
    pub dataset: Dataset,
    options: DetectOptions,
    after: Option<[f64; PARAMETER_COUNT]>,
    overlays: WriteOptions,
    replace: bool,
}

/// A detection made.
#[derive(Debug)]
pub struct Detected<'a> {
    prepared: Prepared<'a>,
    /// One result per capture, in capture order.
    pub results: Vec<ImageResult>,
    /// The overlays that could not be written, why.
    pub overlay_errors: Vec<String>,
}

impl DetectRequest {
    /// Reads the dataset and checks everything before any image is read: a corners.csv
    /// with vertices is replaced only with `force` (one without, as `simulate --images`
    /// writes, holds nothing to lose), the overlays never replace an input (an image, a
    /// dataset file) and an existing overlay only with `force`. `note` hears of `jobs`
    /// capped and of a `pattern` that differs from the dataset's board.
    pub fn prepare(&self, note: &mut dyn FnMut(&str)) -> Result<Prepared<'_>, DetectRequestError> {
        let dataset = Dataset::load(&self.dataset)?;
        let corners_path = self.dataset.join(CORNERS_CSV);
        let replace = corners_path.exists();
        if replace && !dataset.corners.is_empty() && !self.force {
            return Err(DetectRequestError::CornersHeld {
                path: corners_path,
                count: dataset.corners.len(),
            });
        }
        let after = self
            .after
            .as_deref()
            .map(prediction::solution_values)
            .transpose()?;
        let overlays = WriteOptions::protecting_dataset(&self.dataset, self.force)
            .protecting(
                dataset
                    .captures
                    .iter()
                    .filter_map(|c| dataset.image_path(c)),
            )
            .protecting(self.after.clone());
        if let Some(dir) = &self.overlay {
            for capture in dataset.captures.iter().filter(|c| c.image.is_some()) {
                crate::output::check_writable(&overlay::path(dir, capture.id), &overlays)?;
            }
        }
        let mut options = DetectOptions {
            pattern: self.pattern,
            use_model: self.use_model,
            params: self
                .start_from
                .as_deref()
                .map(|p| prediction::start_values_for(p, &dataset))
                .transpose()?,
            repredict: self.repredict,
            body: self.body.then(crate::body::BodyModel::default),
            ..DetectOptions::default()
        };
        if let Some(jobs) = self.jobs {
            if jobs == 0 {
                return Err(DetectRequestError::NoJobs);
            }
            let cap = max_jobs();
            if jobs > cap {
                note(&format!(
                    "naocalib: note: --jobs {jobs} capped at {cap} (4 per core, at most 64)"
                ));
            }
            options.jobs = jobs.min(cap);
        }
        if let Some(p) = self.pattern {
            let board = board_grid(&dataset.model);
            if p != board {
                note(&format!(
                    "naocalib: note: pattern {}x{} differs from the board in dataset.toml \
                     ({}x{}); corners.csv will only load with a matching [board]",
                    p.cols, p.rows, board.cols, board.rows
                ));
            }
        }
        super::cv::load()?;
        Ok(Prepared {
            request: self,
            dataset,
            options,
            after,
            overlays,
            replace,
        })
    }
}

impl<'a> Prepared<'a> {
    /// Detects the board in every image, writing each one's overlay (if asked for) as it
    /// is done; `done` is called for every result.
    pub fn detect(self, done: &(dyn Fn(&ImageResult) + Sync)) -> Detected<'a> {
        let overlay_errors = Mutex::new(Vec::new());
        let each = |r: &ImageResult| {
            if let Some(dir) = &self.request.overlay
                && let Some(Err(e)) =
                    overlay::write(&self.dataset, r, dir, self.after.as_ref(), &self.overlays)
            {
                overlay_errors
                    .lock()
                    .unwrap_or_else(|e| e.into_inner())
                    .push(e.to_string());
            }
            done(r);
        };
        let results = super::detect_dataset(&self.dataset, &self.options, &each);
        Detected {
            results,
            overlay_errors: overlay_errors.into_inner().unwrap_or_default(),
            prepared: self,
        }
    }
}

impl Detected<'_> {
    /// What to tell of the detection: every image's outcome, then every overlay not
    /// written.
    pub fn lines(&self) -> Vec<String> {
        let results = self.results.iter().map(ToString::to_string);
        let overlays = self
            .overlay_errors
            .iter()
            .map(|e| format!("naocalib: overlay: {e}"));
        results.chain(overlays).collect()
    }

    /// The counts of the outcomes.
    pub fn summary(&self) -> Summary {
        Summary::of(&self.results)
    }

    /// Whether there were images and no board was found in any of them.
    pub fn nothing_found(&self) -> bool {
        self.summary().found == 0 && !self.results.is_empty()
    }

    /// The cameras whose pictures are turned by 180° ([`super::turned::of_results`]), each
    /// said as an error line.
    pub fn turned(&self) -> Vec<String> {
        super::turned::of_results(&self.results)
            .iter()
            .map(|t| format!("naocalib: error: {t}"))
            .collect()
    }

    /// Writes the vertices found into the dataset's corners.csv, and says so; refused
    /// when none was found and the file holds vertices.
    pub fn write(&self) -> Result<String, DetectRequestError> {
        let (request, dataset) = (self.prepared.request, &self.prepared.dataset);
        let corners_path = request.dataset.join(CORNERS_CSV);
        let summary = self.summary();
        let corners = super::corners(&self.results);
        if corners.is_empty() && !dataset.corners.is_empty() {
            return Err(DetectRequestError::NothingFound {
                dir: request.dataset.clone(),
                images: self.results.len(),
                summary: Box::new(summary),
                corners: corners_path,
                count: dataset.corners.len(),
            });
        }
        crate::dataset::write_corners(&request.dataset, &corners, self.prepared.replace)?;
        Ok(format!(
            "{}: {} images: {summary}; wrote {} vertices to {}",
            request.dataset.display(),
            self.results.len(),
            corners.len(),
            corners_path.display()
        ))
    }
}

/// Why `solve --detect` found no vertices to solve with.
#[derive(Debug, thiserror::Error)]
pub enum ForSolveError {
    /// The prediction's calibration could not be read.
    #[error(transparent)]
    Prediction(#[from] PredictionError),
    /// No vertex was found.
    #[error(transparent)]
    NoCorners(#[from] NoCorners),
}

/// A detection for `solve --detect`, made in memory.
#[derive(Debug)]
pub struct ForSolve {
    /// The results and their counts.
    pub detection: Detection,
    /// Its wall time (s).
    pub seconds: f64,
}

/// The options of `naocalib detect`'s defaults for `solve --detect`, the board predicted
/// with the calibration in `start_from` (`solve --start-from CAL.toml`) when given, the
/// body model with `body` (`solve --detect --body`).
pub fn options_for_solve(
    dataset: &Dataset,
    start_from: Option<&Path>,
    body: bool,
) -> Result<DetectOptions, ForSolveError> {
    Ok(DetectOptions {
        params: start_from
            .map(|p| prediction::start_values_for(p, dataset))
            .transpose()?,
        body: body.then(crate::body::BodyModel::default),
        ..DetectOptions::default()
    })
}

/// Detects the vertices in `dataset`'s images with `options` and puts them in place of
/// its corners (nothing is written); `done` is called for every result.
pub fn detect_for_solve(
    dataset: &mut Dataset,
    options: &DetectOptions,
    done: &(dyn Fn(&ImageResult) + Sync),
) -> Result<ForSolve, ForSolveError> {
    let start = Instant::now();
    let detection = super::detect_into(dataset, options, done)?;
    Ok(ForSolve {
        detection,
        seconds: start.elapsed().as_secs_f64(),
    })
}

impl ForSolve {
    /// What to tell: the images that gave no vertices (every image when `verbose`), and
    /// the summary line.
    pub fn lines(&self, dataset: &Dataset, verbose: bool) -> Vec<String> {
        let d = &self.detection;
        let mut lines: Vec<String> = d
            .results
            .iter()
            .filter(|r| verbose || !matches!(r.outcome, Outcome::Found { .. }))
            .map(ToString::to_string)
            .collect();
        lines.push(format!(
            "{}: {} images: {}; {} vertices detected in {:.2} s (corners.csv not used)",
            dataset.dir.display(),
            d.results.len(),
            d.summary,
            dataset.corners.len(),
            self.seconds
        ));
        lines
    }
}

/// The warnings of `solve --detect`'s guard: the captures whose residuals after the fit
/// are many times the others' ([`guard::suspects`]) and, when there are any, that the run
/// is marked; empty when none stands out.
pub fn guard_warnings(solution: &Solution) -> Vec<String> {
    let suspects = guard::suspects(solution);
    let mut lines: Vec<String> = suspects
        .iter()
        .map(|s| format!("naocalib: warning: {s}"))
        .collect();
    if !suspects.is_empty() {
        lines.push(format!(
            "naocalib: warning: {} capture(s) with residuals more than {}× the median \
             capture's: this run is marked (exit code 3); look at their images, or leave \
             them out",
            suspects.len(),
            guard::SUSPECT_RATIO
        ));
    }
    lines
}

/// Parses a pattern `CxR` (inner vertices per row x rows, 3 … 100 each: OpenCV's
/// chessboard finder needs more than 2 each way).
pub fn parse_pattern(text: &str) -> Result<Grid, String> {
    let err = || format!("'{text}' is not a pattern like 9x6 (inner vertices per row x rows)");
    let (c, r) = text.split_once(['x', 'X']).ok_or_else(err)?;
    let cols: u32 = c.trim().parse().map_err(|_| err())?;
    let rows: u32 = r.trim().parse().map_err(|_| err())?;
    if cols < 3 || rows < 3 || cols > 100 || rows > 100 {
        return Err(format!(
            "pattern '{text}': 3 … 100 vertices per row and rows (the minimum is 3x3)"
        ));
    }
    Ok(Grid { cols, rows })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn request(dataset: &Path) -> DetectRequest {
        DetectRequest {
            dataset: dataset.to_path_buf(),
            force: false,
            pattern: None,
            use_model: true,
            overlay: None,
            after: None,
            jobs: None,
            start_from: None,
            repredict: true,
            body: false,
        }
    }

    fn copy_of_sample(dir: &Path) -> PathBuf {
        let to = dir.join("sample");
        std::fs::create_dir(&to).unwrap();
        for name in ["dataset.toml", "captures.csv", "corners.csv"] {
            std::fs::copy(Path::new("data/sample").join(name), to.join(name)).unwrap();
        }
        to
    }

    #[test]
    fn corners_are_replaced_only_with_force_and_jobs_are_checked() {
        let dir = tempfile::tempdir().unwrap();
        let sample = copy_of_sample(dir.path());
        let mut notes = Vec::new();
        let mut note = |l: &str| notes.push(l.to_string());
        let held = request(&sample).prepare(&mut note).unwrap_err();
        let rows = std::fs::read_to_string(sample.join("corners.csv"))
            .unwrap()
            .lines()
            .count();
        assert!(
            held.to_string().ends_with(&format!(
                "already holds {} vertices; use --force to overwrite",
                rows - 1
            )),
            "{held}"
        );
        let forced = DetectRequest {
            force: true,
            jobs: Some(0),
            ..request(&sample)
        };
        assert!(matches!(
            forced.prepare(&mut note),
            Err(DetectRequestError::NoJobs)
        ));
        let capped = DetectRequest {
            jobs: Some(100_000),
            pattern: Some(Grid { cols: 5, rows: 4 }),
            ..forced
        };
        let prepared = capped.prepare(&mut note).unwrap();
        assert_eq!(prepared.options.jobs, max_jobs());
        assert!(notes[0].contains("--jobs 100000 capped at"), "{notes:?}");
        assert!(
            notes[1].contains("pattern 5x4 differs from the board"),
            "{notes:?}"
        );
    }

    #[test]
    fn an_existing_overlay_is_replaced_only_with_force() {
        let dir = tempfile::tempdir().unwrap();
        let sample = copy_of_sample(dir.path());
        // A corners.csv without vertices holds nothing to lose.
        let corners = sample.join(CORNERS_CSV);
        let header = std::fs::read_to_string(&corners).unwrap();
        std::fs::write(&corners, format!("{}\n", header.lines().next().unwrap())).unwrap();
        let overlays = dir.path().join("overlays");
        std::fs::create_dir(&overlays).unwrap();
        std::fs::write(overlay::path(&overlays, 0), "an earlier overlay").unwrap();
        let r = DetectRequest {
            overlay: Some(overlays),
            ..request(&sample)
        };
        let e = r.prepare(&mut |_| {}).unwrap_err();
        assert!(matches!(e, DetectRequestError::Output(_)), "{e}");
        let forced = DetectRequest { force: true, ..r };
        assert!(forced.prepare(&mut |_| {}).unwrap().replace);
    }

    #[test]
    fn patterns_are_parsed_within_opencvs_bounds() {
        assert_eq!(parse_pattern("9x6"), Ok(Grid { cols: 9, rows: 6 }));
        assert_eq!(parse_pattern(" 4 X 3"), Ok(Grid { cols: 4, rows: 3 }));
        assert!(
            parse_pattern("2x2")
                .unwrap_err()
                .contains("the minimum is 3x3")
        );
        assert!(parse_pattern("101x3").is_err());
        assert!(
            parse_pattern("9-6")
                .unwrap_err()
                .contains("not a pattern like 9x6")
        );
    }
}
