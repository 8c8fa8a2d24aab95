//! The least-squares problem a backend solves: captures, their chains and observed vertices.
//!
//! A backend sees a [`Problem`], never files. The residual of a vertex is the model's
//! projection minus the observed pixel position, `u` then `v` (docs/MODEL.md §2.5).

use nalgebra::{DMatrix, DVector};

use crate::model::{FixedSet, PARAMETER_COUNT, Param, Scalar, StanceChains, Vertex};

/// One observed vertex of a capture.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Observation {
    /// Which vertex of the pattern.
    pub vertex: Vertex,
    /// Its position in the board frame (mm).
    pub point: [f64; 3],
    /// Where it was seen in the image (px).
    pub pixel: [f64; 2],
}

/// One capture as a residual block: its chains and the vertices seen.
#[derive(Debug, Clone, PartialEq)]
pub struct CaptureTerm {
    /// The capture id from `captures.csv`.
    pub capture: u64,
    /// The chains for this capture's logged joint angles.
    pub chains: StanceChains,
    /// The vertices seen, in any order.
    pub observations: Vec<Observation>,
    /// Optional whitening `W` (2k × 2k for k observations, residuals ordered
    /// u₀, v₀, u₁, v₁, …): the backend minimises `‖W·r‖²` for this capture.
    pub whitening: Option<Whitening>,
}

/// A capture's whitening matrix `W`, usually `Σ_c^{-1/2}` of its residual covariance.
#[derive(Debug, Clone, PartialEq)]
pub enum Whitening {
    /// Any square matrix.
    Dense(DMatrix<f64>),
    /// `scale · (I − U·diag(shrink)·Uᵀ)` with orthonormal columns `U` (2k × q, q small):
    /// the noise model's form (pixel noise plus joint noise along q joint directions),
    /// applied in O(k·q) instead of O(k²).
    LowRank {
        /// The directions, orthonormal columns.
        u: DMatrix<f64>,
        /// How much of each direction is taken out, one per column of `u`.
        shrink: DVector<f64>,
        /// The overall factor.
        scale: f64,
    },
}

impl Whitening {
    /// Rows (= columns) of `W`.
    pub fn size(&self) -> usize {
        match self {
            Whitening::Dense(w) => w.nrows(),
            Whitening::LowRank { u, .. } => u.nrows(),
        }
    }

    /// Whether the parts fit together (square, matching lengths) and are finite.
    pub fn is_well_formed(&self) -> bool {
        match self {
            Whitening::Dense(w) => w.nrows() == w.ncols() && w.iter().all(|x| x.is_finite()),
            Whitening::LowRank { u, shrink, scale } => {
                shrink.len() == u.ncols()
                    && scale.is_finite()
                    && u.iter().chain(shrink.iter()).all(|x| x.is_finite())
            }
        }
    }

    /// `W` as a dense matrix.
    pub fn to_dense(&self) -> DMatrix<f64> {
        match self {
            Whitening::Dense(w) => w.clone(),
            Whitening::LowRank { u, shrink, scale } => {
                let n = u.nrows();
                (DMatrix::identity(n, n) - u * DMatrix::from_diagonal(shrink) * u.transpose())
                    * *scale
            }
        }
    }

    /// `W·r` on any scalar type.
    pub fn apply<T: Scalar>(&self, r: &[T]) -> Vec<T> {
        let zero = || crate::model::scalar::lift::<T>(0.0);
        match self {
            Whitening::Dense(w) => (0..w.nrows())
                .map(|i| (0..w.ncols()).fold(zero(), |acc, j| acc + r[j].clone() * w[(i, j)]))
                .collect(),
            Whitening::LowRank { u, shrink, scale } => {
                // z = diag(shrink)·Uᵀ·r, then scale·(r − U·z).
                let z: Vec<T> = (0..u.ncols())
                    .map(|c| {
                        (0..u.nrows()).fold(zero(), |acc, i| acc + r[i].clone() * u[(i, c)])
                            * shrink[c]
                    })
                    .collect();
                (0..u.nrows())
                    .map(|i| {
                        let taken =
                            (0..u.ncols()).fold(zero(), |acc, c| acc + z[c].clone() * u[(i, c)]);
                        (r[i].clone() - taken) * *scale
                    })
                    .collect()
            }
        }
    }

    /// `W·M` for a matrix `M` with [`Whitening::size`] rows.
    pub fn apply_matrix(&self, plain: &DMatrix<f64>) -> DMatrix<f64> {
        match self {
            Whitening::Dense(w) => w * plain,
            Whitening::LowRank { u, shrink, scale } => {
                let mut z = u.transpose() * plain;
                for (c, mut row) in z.row_iter_mut().enumerate() {
                    row *= shrink[c];
                }
                (plain - u * z) * *scale
            }
        }
    }

    /// `W·M` in place for a row-major `M` with `cols` columns (`cols = 1`: a vector).
    pub fn apply_in_place(&self, m: &mut [f64], cols: usize) {
        let rows = self.size();
        let weighted = self.apply_matrix(&DMatrix::from_row_slice(rows, cols, m));
        for i in 0..rows {
            for c in 0..cols {
                m[i * cols + c] = weighted[(i, c)];
            }
        }
    }
}

impl CaptureTerm {
    /// Number of residuals (two per observed vertex).
    pub fn residual_count(&self) -> usize {
        2 * self.observations.len()
    }

    /// Unweighted residuals (projection − observation), `u₀, v₀, u₁, v₁, …`, or `None`
    /// when a vertex falls behind the camera.
    pub fn residuals<T: Scalar>(&self, params: &[T]) -> Option<Vec<T>> {
        let pose = self.chains.camera_to_board(params);
        let projection = &self.chains.projection;
        let coefficients = projection.coefficients_at(params);
        let mut out = Vec::with_capacity(self.residual_count());
        for obs in &self.observations {
            let p = obs.point.map(crate::model::scalar::lift::<T>);
            let [u, v] = projection.project_with(&coefficients, &pose.apply(&p))?;
            out.push(u - obs.pixel[0]);
            out.push(v - obs.pixel[1]);
        }
        Some(out)
    }

    /// The first observed vertex (index into `observations`) that falls behind the camera
    /// at `params`, if any.
    pub fn behind_camera(&self, params: &[f64]) -> Option<usize> {
        let pose = self.chains.camera_to_board(params);
        let projection = &self.chains.projection;
        let coefficients = projection.coefficients_at(params);
        self.observations.iter().position(|obs| {
            projection
                .project_with(&coefficients, &pose.apply(&obs.point))
                .is_none()
        })
    }

    /// Residuals as the backend minimises them: whitened if the capture has a whitening.
    pub fn weighted_residuals<T: Scalar>(&self, params: &[T]) -> Option<Vec<T>> {
        let r = self.residuals(params)?;
        Some(match &self.whitening {
            None => r,
            Some(w) => w.apply(&r),
        })
    }
}

/// A robust loss on each vertex's squared residual norm.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Loss {
    /// Plain least squares.
    #[default]
    Squared,
    /// Huber loss with the given scale (px).
    Huber(f64),
    /// Cauchy loss with the given scale (px).
    Cauchy(f64),
}

/// Stopping rules shared by every backend (Ceres' meanings).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tolerances {
    /// Maximum number of iterations.
    pub max_iterations: usize,
    /// Stop when the relative decrease of the cost is below this.
    pub function: f64,
    /// Stop when the max-norm of the gradient is below this.
    pub gradient: f64,
    /// Stop when the relative step size is below this.
    pub parameter: f64,
}

impl Default for Tolerances {
    fn default() -> Self {
        Tolerances {
            max_iterations: 100,
            function: 1e-12,
            gradient: 1e-14,
            parameter: 1e-12,
        }
    }
}

/// The calibration as a non-linear least-squares problem (docs/MODEL.md §2.5).
#[derive(Debug, Clone, PartialEq)]
pub struct Problem {
    /// The lower camera's intrinsics (each capture's projection is in its chains).
    pub camera: crate::model::Camera,
    /// One term per capture with at least one observed vertex.
    pub captures: Vec<CaptureTerm>,
    /// Start values, internal units (rad / mm); also the values of held parameters.
    pub initial: [f64; PARAMETER_COUNT],
    /// Which parameters are held fixed.
    pub fixed: FixedSet,
    /// Robust loss (per vertex).
    pub loss: Loss,
    /// Stopping rules.
    pub tolerances: Tolerances,
}

impl Problem {
    /// Per-vertex residuals at the start values and at `values` (NaN where a vertex is behind
    /// the camera, which [`crate::solve::validate`] rules out at the start).
    pub fn vertex_residuals(&self, values: &[f64]) -> Vec<super::VertexResidual> {
        let mut out = Vec::with_capacity(self.observation_count());
        for term in &self.captures {
            let before = term.residuals(&self.initial);
            let after = term.residuals(values);
            for (k, obs) in term.observations.iter().enumerate() {
                let pick = |r: &Option<Vec<f64>>| {
                    r.as_ref()
                        .map_or([f64::NAN; 2], |r| [r[2 * k], r[2 * k + 1]])
                };
                out.push(super::VertexResidual {
                    capture: term.capture,
                    vertex: obs.vertex,
                    initial: pick(&before),
                    solved: pick(&after),
                });
            }
        }
        out
    }

    /// The free parameters, in order.
    pub fn free(&self) -> Vec<Param> {
        self.fixed.free()
    }

    /// Total number of residuals.
    pub fn residual_count(&self) -> usize {
        self.captures.iter().map(CaptureTerm::residual_count).sum()
    }

    /// Number of observed vertices.
    pub fn observation_count(&self) -> usize {
        self.captures.iter().map(|c| c.observations.len()).sum()
    }

    /// The full parameter vector with the free parameters set to `free_values`.
    pub fn expand(&self, free_values: &[f64]) -> [f64; PARAMETER_COUNT] {
        let mut all = self.initial;
        for (p, v) in self.free().iter().zip(free_values) {
            all[p.index()] = *v;
        }
        all
    }

    /// Each capture's chains with the held parameters frozen at their values.
    pub fn frozen_chains(&self) -> Vec<StanceChains> {
        self.captures
            .iter()
            .map(|c| c.chains.freeze(self.fixed.mask(), &self.initial))
            .collect()
    }

    /// All unweighted residuals at `params` (full vector, internal units), or `None` when a
    /// vertex falls behind the camera.
    pub fn residuals(&self, params: &[f64]) -> Option<Vec<f64>> {
        let mut out = Vec::with_capacity(self.residual_count());
        for c in &self.captures {
            out.extend(c.residuals(params)?);
        }
        Some(out)
    }

    /// Root mean square of the unweighted residuals in u and in v (px).
    pub fn rms(&self, params: &[f64]) -> Option<[f64; 2]> {
        let r = self.residuals(params)?;
        let n = (r.len() / 2).max(1) as f64;
        let sum = |k: usize| r.iter().skip(k).step_by(2).map(|x| x * x).sum::<f64>();
        Some([(sum(0) / n).sqrt(), (sum(1) / n).sqrt()])
    }
}

/// Whether `param` is a joint offset (legs or head): the part of a robot's calibration that
/// a team framework applies to the joint angles it logs.
pub fn is_joint_offset(param: Param) -> bool {
    use crate::model::ParamGroup as G;
    matches!(param.group(), G::LeftLeg | G::RightLeg | G::Head)
}

impl Problem {
    /// Starts from a robot's current calibration (`naocalib solve --start-from`): each
    /// `(parameter, value in report units)` becomes its start value, and a parameter held
    /// fixed (the head offsets, unless the head family is freed) is held at it — so that
    /// the camera correction is estimated behind the head offsets the robot's framework
    /// applies. With `corrected_angles` (the logged angles were already corrected by that
    /// calibration) the joint offsets start at zero instead: what is estimated is their
    /// change.
    pub fn start_from(&mut self, previous: &[(Param, f64)], corrected_angles: bool) {
        for &(p, value) in previous {
            let value = if corrected_angles && is_joint_offset(p) {
                0.0
            } else {
                p.unit().from_report(value)
            };
            if value.is_finite() {
                self.initial[p.index()] = value;
            }
        }
    }
}

impl Problem {
    /// Turns a dataset's measurements into the least-squares problem: one term per capture
    /// with at least one corner, all parameters starting at zero (docs/MODEL.md §5), and the
    /// parameters in `fixed` held at zero (or at `initial` values set afterwards). The upper
    /// camera's parameters are free when the dataset has upper-camera captures (unless
    /// `fixed` holds them on purpose) and held otherwise ([`FixedSet::for_upper_camera`]).
    ///
    /// Fails as [`super::validate`] does, naming the dataset's file and line: when a vertex
    /// lies behind the camera at the start values (a sign of wrong joint angles or a wrong
    /// `board` column), or the corners are too few for the free parameters.
    pub fn from_dataset(
        dataset: &crate::dataset::Dataset,
        fixed: FixedSet,
    ) -> Result<Problem, super::SolveError> {
        let model = &dataset.model;
        let mut by_capture: std::collections::BTreeMap<u64, Vec<Observation>> = Default::default();
        for corner in &dataset.corners {
            by_capture
                .entry(corner.capture)
                .or_default()
                .push(Observation {
                    vertex: corner.vertex,
                    point: model.board.vertex_position(corner.vertex),
                    pixel: corner.pixel,
                });
        }
        let captures = dataset
            .captures
            .iter()
            .filter_map(|capture| {
                let observations = by_capture.remove(&capture.id)?;
                Some(CaptureTerm {
                    capture: capture.id,
                    chains: model.chains_for(capture.camera, capture.side, &capture.joints),
                    observations,
                    whitening: None,
                })
            })
            .collect();
        let problem = Problem {
            camera: model.camera,
            captures,
            initial: [0.0; PARAMETER_COUNT],
            fixed: fixed.for_upper_camera(dataset.has_upper_captures()),
            loss: Loss::Squared,
            tolerances: Tolerances::default(),
        };
        super::check::check(&problem, Some(dataset))?;
        Ok(problem)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The low-rank whitening applied directly (generic and in place) equals its dense form.
    #[test]
    fn low_rank_whitening_matches_its_dense_form() {
        let raw = DMatrix::from_fn(8, 3, |i, j| {
            ((i * 7 + j * 3) % 5) as f64 - 2.0 + 0.1 * j as f64
        });
        let w = Whitening::LowRank {
            u: raw.clone().qr().q(),
            shrink: DVector::from_vec(vec![0.9, 0.5, 0.1]),
            scale: 2.5,
        };
        assert!(w.is_well_formed() && w.size() == 8);
        let dense = w.to_dense();
        let r: Vec<f64> = (0..8).map(|i| (i as f64 * 0.7).sin()).collect();
        let expected = &dense * DVector::from_column_slice(&r);
        let generic = w.apply(&r);
        let mut in_place = r.clone();
        w.apply_in_place(&mut in_place, 1);
        for i in 0..8 {
            assert!((generic[i] - expected[i]).abs() < 1e-12);
            assert!((in_place[i] - expected[i]).abs() < 1e-12);
        }
        // Row-major with two columns: each column whitened.
        let mut m: Vec<f64> = r.iter().flat_map(|x| [*x, 2.0 * x]).collect();
        w.apply_in_place(&mut m, 2);
        for i in 0..8 {
            assert!((m[2 * i] - expected[i]).abs() < 1e-12);
            assert!((m[2 * i + 1] - 2.0 * expected[i]).abs() < 1e-12);
        }
        let bad = Whitening::LowRank {
            u: raw,
            shrink: DVector::from_vec(vec![0.5]),
            scale: 1.0,
        };
        assert!(!bad.is_well_formed());
    }
}
