//! Rigid transforms (rotation + translation) over any [`Scalar`].

use super::scalar::{Scalar, lift};

/// A coordinate axis of the current (local) frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Axis {
    /// The local x axis.
    X,
    /// The local y axis.
    Y,
    /// The local z axis.
    Z,
}

impl Axis {
    /// Index of the axis (x = 0, y = 1, z = 2).
    pub fn index(self) -> usize {
        match self {
            Axis::X => 0,
            Axis::Y => 1,
            Axis::Z => 2,
        }
    }
}

/// A rigid transform `p ↦ R·p + t`, mapping child-frame coordinates into the parent frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Pose<T> {
    /// Row-major rotation matrix.
    pub rotation: [[T; 3]; 3],
    /// Translation (position of the child origin in the parent frame).
    pub translation: [T; 3],
}

impl<T: Scalar> Pose<T> {
    /// The identity transform.
    pub fn identity() -> Self {
        let one = || lift::<T>(1.0);
        let zero = || lift::<T>(0.0);
        Pose {
            rotation: [
                [one(), zero(), zero()],
                [zero(), one(), zero()],
                [zero(), zero(), one()],
            ],
            translation: [zero(), zero(), zero()],
        }
    }

    /// Converts a constant pose into this scalar type.
    pub fn lift(pose: &Pose<f64>) -> Self {
        Pose {
            rotation: pose.rotation.map(|row| row.map(lift)),
            translation: pose.translation.map(lift),
        }
    }

    /// `self · Rot_axis(angle)`: rotates the current frame about one of its own axes.
    pub fn rotate(&mut self, axis: Axis, angle: &T) {
        let (s, c) = (angle.sin(), angle.cos());
        // Columns (a, b) of R change: a' = c·a + s·b, b' = −s·a + c·b, with (a, b) the two
        // axes orthogonal to `axis` in right-handed order.
        let (a, b) = match axis {
            Axis::X => (1, 2),
            Axis::Y => (2, 0),
            Axis::Z => (0, 1),
        };
        for row in self.rotation.iter_mut() {
            let ra = row[a].clone();
            let rb = row[b].clone();
            row[a] = ra.clone() * c.clone() + rb.clone() * s.clone();
            row[b] = rb * c.clone() - ra * s.clone();
        }
    }

    /// `self · Trans_axis(distance)`: moves along one of the current frame's axes.
    pub fn translate(&mut self, axis: Axis, distance: &T) {
        let k = axis.index();
        for (i, t) in self.translation.iter_mut().enumerate() {
            *t += self.rotation[i][k].clone() * distance.clone();
        }
    }

    /// `self · other` for a constant `other`.
    pub fn then_fixed(&self, other: &Pose<f64>) -> Self {
        let mut out = Pose::identity();
        for i in 0..3 {
            for j in 0..3 {
                out.rotation[i][j] = self.rotation[i][0].clone() * other.rotation[0][j]
                    + self.rotation[i][1].clone() * other.rotation[1][j]
                    + self.rotation[i][2].clone() * other.rotation[2][j];
            }
            out.translation[i] = self.rotation[i][0].clone() * other.translation[0]
                + self.rotation[i][1].clone() * other.translation[1]
                + self.rotation[i][2].clone() * other.translation[2]
                + self.translation[i].clone();
        }
        out
    }

    /// Maps a point of the child frame into the parent frame.
    pub fn apply(&self, p: &[T; 3]) -> [T; 3] {
        std::array::from_fn(|i| {
            self.rotation[i][0].clone() * p[0].clone()
                + self.rotation[i][1].clone() * p[1].clone()
                + self.rotation[i][2].clone() * p[2].clone()
                + self.translation[i].clone()
        })
    }

    /// `self⁻¹ · other`: `other` expressed in the frame of `self`.
    pub fn inverse_then(&self, other: &Pose<T>) -> Pose<T> {
        let mut out = Pose::identity();
        let d: [T; 3] =
            std::array::from_fn(|i| other.translation[i].clone() - self.translation[i].clone());
        for i in 0..3 {
            for j in 0..3 {
                out.rotation[i][j] = self.rotation[0][i].clone() * other.rotation[0][j].clone()
                    + self.rotation[1][i].clone() * other.rotation[1][j].clone()
                    + self.rotation[2][i].clone() * other.rotation[2][j].clone();
            }
            out.translation[i] = self.rotation[0][i].clone() * d[0].clone()
                + self.rotation[1][i].clone() * d[1].clone()
                + self.rotation[2][i].clone() * d[2].clone();
        }
        out
    }
}

impl Pose<f64> {
    /// A pure translation.
    pub fn translation(x: f64, y: f64, z: f64) -> Self {
        let mut p = Pose::identity();
        p.translation = [x, y, z];
        p
    }

    /// A pure rotation about one axis.
    pub fn rotation(axis: Axis, angle: f64) -> Self {
        let mut p = Pose::identity();
        p.rotate(axis, &angle);
        p
    }

    /// Composition `self · other` of two constant transforms.
    pub fn compose(&self, other: &Pose<f64>) -> Self {
        self.then_fixed(other)
    }
}
