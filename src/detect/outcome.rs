//! What detection makes of each capture: the outcome types, their counts and errors.

use std::fmt;
use std::path::PathBuf;

use super::assign;
use super::image::{MAX_PIXELS, MAX_SIDE};
use super::saddle::Dropped;
use super::turned::verdict::{PictureTurn, Turned};
use crate::dataset::Corner;
use crate::model::CameraId;
use crate::robot::check::MIN_BRIGHTNESS;

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
    /// The image does not have the resolution of the camera that took it.
    #[error(
        "{}: the image is {}×{} pixels, but the {} camera that took it (its capture's \
         camera column) is {}×{} in [{}] of dataset.toml",
        path.display(), size[0], size[1], camera_id.name(), camera[0], camera[1],
        crate::dataset::camera_table(*camera_id)
    )]
    Size {
        /// The image.
        path: PathBuf,
        /// Its size.
        size: [u32; 2],
        /// The camera's resolution.
        camera: [u32; 2],
        /// The camera that took it.
        camera_id: CameraId,
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
    #[error(transparent)]
    Write(#[from] crate::output::WriteError),
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
        /// and numbered by the model-guided search ([`super::guided`]).
        order: Option<assign::Order>,
        /// Whether the board was found only in the whole image, not where predicted.
        whole_image: bool,
        /// How the vertices got their (row, col).
        numbered: String,
        /// Vertices refined but not reported: they fail the image test of a clean saddle
        /// ([`super::saddle`]), pulled by an occluding edge or in danger of it.
        dropped: Vec<Dropped>,
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
    /// No board, and the picture is too dark to show one (the camera; its mean
    /// brightness, 0 … 255).
    TooDark {
        /// The camera.
        camera: CameraId,
        /// The picture's mean brightness.
        brightness: f64,
    },
    /// A board was found, but its camera's pictures are turned by 180° (its sensor's
    /// flip not as the camera needs, [`super::turned`]): not used.
    Turned {
        /// Vertices found.
        found: usize,
        /// What says the camera's pictures are turned.
        turned: Turned,
    },
    /// A board was found, but this picture on its own is turned by 180° (its camera's
    /// other pictures are not, [`super::turned::judge_pictures`]): not used.
    TurnedAlone {
        /// Vertices found.
        found: usize,
        /// The judgement.
        turn: PictureTurn,
    },
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
                numbered,
                dropped,
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
                if !numbered.is_empty() {
                    write!(f, "; {numbered}")?;
                }
                if !dropped.is_empty() {
                    let each: Vec<String> = dropped.iter().map(ToString::to_string).collect();
                    write!(
                        f,
                        "; {} dropped for an occluding edge: {}",
                        dropped.len(),
                        each.join(", ")
                    )?;
                }
                Ok(())
            }
            Outcome::NotFound => write!(f, ": not found"),
            Outcome::Rejected { reason } => write!(f, ": rejected: {reason}"),
            Outcome::Failed(e) => write!(f, ": error: {e}"),
            Outcome::NoImage => write!(f, ": no image"),
            Outcome::TooDark { camera, brightness } => write!(
                f,
                ": too dark: the {camera} camera's picture has a mean brightness of \
                 {brightness:.0} of 255 (at least {MIN_BRIGHTNESS:.0} is needed); raise \
                 its exposure or gain"
            ),
            Outcome::Turned { found, turned } => write!(
                f,
                ": found {found} vertices, not used: the {} camera's pictures are turned by \
                 180° (set its flip, see the summary)",
                turned.camera.name()
            ),
            Outcome::TurnedAlone { found, turn } => {
                write!(f, ": found {found} vertices, not used: {turn}")
            }
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
    /// Boards found but not used: their camera's pictures are turned by 180°.
    pub turned: usize,
    /// The cameras (lower, upper) whose pictures are turned by 180°.
    pub cameras_turned: [bool; 2],
    /// Boards found but not used: their picture on its own is turned by 180° (a `u32`,
    /// so that the summary fits the errors that carry it).
    pub turned_alone: u32,
    /// Vertices of the boards found dropped for an occluding edge ([`super::saddle`]).
    pub dropped: usize,
}

impl Summary {
    /// Counts the outcomes of `results`.
    pub fn of(results: &[ImageResult]) -> Summary {
        let mut s = Summary::default();
        for r in results {
            match &r.outcome {
                Outcome::Found { dropped, .. } => {
                    s.found += 1;
                    s.dropped += dropped.len();
                }
                Outcome::NotFound => s.not_found += 1,
                Outcome::Rejected { .. } | Outcome::TooDark { .. } => s.rejected += 1,
                Outcome::Failed(_) => s.failed += 1,
                Outcome::NoImage => s.no_image += 1,
                Outcome::Turned { turned, .. } => {
                    s.turned += 1;
                    s.cameras_turned[turned.camera as usize] = true;
                }
                Outcome::TurnedAlone { .. } => s.turned_alone += 1,
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
        if self.dropped > 0 {
            write!(
                f,
                ", {} vertices dropped for an occluding edge",
                self.dropped
            )?;
        }
        if self.no_image > 0 {
            write!(f, ", {} without an image", self.no_image)?;
        }
        if self.turned > 0 {
            let cameras: Vec<&str> = CameraId::ALL
                .into_iter()
                .filter(|c| self.cameras_turned[*c as usize])
                .map(CameraId::name)
                .collect();
            write!(
                f,
                ", {} not used: the {} camera's pictures are turned by 180° (set its flip)",
                self.turned,
                cameras.join(" and the ")
            )?;
        }
        if self.turned_alone > 0 {
            write!(
                f,
                ", {} not used: their pictures on their own are turned by 180° (see each)",
                self.turned_alone
            )?;
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
    /// OpenCV (naocalib's plugin) could not be loaded.
    #[error(transparent)]
    OpenCv(#[from] super::cv::Error),
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
    /// A camera's pictures are turned by 180°: no calibration is given from them.
    #[error("{}: {}", dir.display(), turned_message(cameras))]
    Turned {
        /// The dataset directory.
        dir: PathBuf,
        /// What says each turned camera's pictures are turned.
        cameras: Vec<Turned>,
    },
}

/// What is said of the cameras `turned`, one after the other.
fn turned_message(turned: &[Turned]) -> String {
    let each: Vec<String> = turned.iter().map(ToString::to_string).collect();
    each.join("; and ")
}

/// The result of detecting the vertices of a whole dataset in memory.
#[derive(Debug)]
pub struct Detection {
    /// One result per capture, in capture order.
    pub results: Vec<ImageResult>,
    /// Their counts.
    pub summary: Summary,
}
