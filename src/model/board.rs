//! The checkerboard sandal: pattern geometry and its mount on the sole (docs/MODEL.md §4).

use super::pose::{Axis, Pose};

/// A checkerboard sandal: the printed pattern and how it is mounted in the sole frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Board {
    /// Squares along the board's x axis (columns of squares).
    pub squares_x: u32,
    /// Squares along the board's y axis (rows of squares).
    pub squares_y: u32,
    /// Edge length of one square (mm).
    pub square: f64,
    /// Pattern centre in the sole frame (mm).
    pub mount_origin: [f64; 3],
    /// Mount angles roll, pitch, yaw (rad).
    pub mount_rpy: [f64; 3],
    /// Mass of the sandal (g) (for the gravity torques of compliance and play).
    pub mass_g: f64,
    /// The sandal's centre of mass in the sole frame (mm).
    pub com_mm: [f64; 3],
}

impl Default for Board {
    /// The paper's sandal: 7 × 5 squares of 25 mm, centred 17 cm ahead of the ankle, its
    /// seven columns along the foot. This is what a `dataset.toml` without `[board]` means
    /// (SPEC §4); the toes stand on its first column ([`Board::turned`] is naocalib's).
    fn default() -> Self {
        Board {
            squares_x: 7,
            squares_y: 5,
            square: 25.0,
            mount_origin: [170.0, 0.0, 0.0],
            mount_rpy: [0.0; 3],
            mass_g: 120.0,
            com_mm: [150.0, 0.0, 0.0],
        }
    }
}

impl Board {
    /// naocalib's sandal: the paper's pattern turned by 90° in the sole's plane (seven
    /// columns across the foot) and centred 200 mm ahead of the ankle, its squares 35 mm
    /// clear of the toes (docs/SANDALS.md). What `sandal`, `plan`, `simulate` and
    /// `simulate-robot` make and assume when no `dataset.toml` is given.
    pub fn turned() -> Self {
        Board {
            mount_origin: [200.0, 0.0, 0.0],
            mount_rpy: [0.0, 0.0, 90f64.to_radians()],
            ..Board::default()
        }
    }
}

/// An inner vertex of the pattern, where four squares meet.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Vertex {
    /// Row, `0 … squares_y − 2`.
    pub row: u32,
    /// Column, `0 … squares_x − 2`.
    pub col: u32,
}

impl Board {
    /// Number of vertex rows (`squares_y − 1`).
    pub fn rows(&self) -> u32 {
        self.squares_y - 1
    }

    /// Number of vertex columns (`squares_x − 1`).
    pub fn cols(&self) -> u32 {
        self.squares_x - 1
    }

    /// Every inner vertex, row by row.
    pub fn vertices(&self) -> impl Iterator<Item = Vertex> + '_ {
        (0..self.rows()).flat_map(move |row| (0..self.cols()).map(move |col| Vertex { row, col }))
    }

    /// Whether `(row, col)` is an inner vertex of this board.
    pub fn contains(&self, v: Vertex) -> bool {
        v.row < self.rows() && v.col < self.cols()
    }

    /// Position of a vertex in the board frame `B` (mm).
    pub fn vertex_position(&self, v: Vertex) -> [f64; 3] {
        [
            (v.col as f64 - (self.squares_x as f64 - 2.0) / 2.0) * self.square,
            (v.row as f64 - (self.squares_y as f64 - 2.0) / 2.0) * self.square,
            0.0,
        ]
    }

    /// `T_SB`: the board frame in the sole frame.
    pub fn mount(&self) -> Pose<f64> {
        let [x, y, z] = self.mount_origin;
        let [roll, pitch, yaw] = self.mount_rpy;
        Pose::translation(x, y, z)
            .compose(&Pose::rotation(Axis::Z, yaw))
            .compose(&Pose::rotation(Axis::Y, pitch))
            .compose(&Pose::rotation(Axis::X, roll))
    }
}
