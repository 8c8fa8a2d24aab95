//! Datasets on disk (SPEC section 6): `dataset.toml`, `captures.csv`, `corners.csv`,
//! `truth.toml`, and an optional `images/` folder.

use std::path::PathBuf;

use crate::model::{JointAngles, Model, PARAMETER_COUNT, Side, Vertex};

/// One captured image: which board is in view and the logged joint angles.
#[derive(Debug, Clone, PartialEq)]
pub struct Capture {
    /// Unique capture id.
    pub id: u64,
    /// The foot whose board is in view.
    pub side: Side,
    /// Image path relative to the dataset directory, if any.
    pub image: Option<PathBuf>,
    /// Logged joint angles [rad].
    pub joints: JointAngles,
    /// Line in `captures.csv` (1-based, header is line 1); 0 when not read from a file.
    pub line: u64,
}

/// One detected (or logged) vertex.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Corner {
    /// The capture it belongs to.
    pub capture: u64,
    /// Which vertex of the board.
    pub vertex: Vertex,
    /// Its position in the image [px].
    pub pixel: [f64; 2],
    /// Line in `corners.csv` (1-based, header is line 1); 0 when not read from a file.
    pub line: u64,
}

/// The true parameters of a simulated dataset (`truth.toml`).
#[derive(Debug, Clone, PartialEq)]
pub struct Truth {
    /// True values of every parameter, internal units (rad / mm); parameters not named in
    /// the file are zero.
    pub values: [f64; PARAMETER_COUNT],
    /// Free-form `[simulation]` keys (noise levels, seed, …).
    pub simulation: toml::Table,
}

/// A whole dataset, in memory.
#[derive(Debug, Clone, PartialEq)]
pub struct Dataset {
    /// The directory it was read from (or will be written to).
    pub dir: PathBuf,
    /// Camera intrinsics, board and robot geometry from `dataset.toml`.
    pub model: Model,
    /// Rows of `captures.csv`, in file order.
    pub captures: Vec<Capture>,
    /// Rows of `corners.csv`, in file order (empty when there is no such file).
    pub corners: Vec<Corner>,
    /// `truth.toml`, when present.
    pub truth: Option<Truth>,
}
