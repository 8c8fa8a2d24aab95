//! The least-squares problem a backend solves: captures, their chains and observed vertices.
//!
//! A backend sees a [`Problem`], never files. The residual of a vertex is the model's
//! projection minus the observed pixel position, `u` then `v` (SPEC eq. 8).

use nalgebra::DMatrix;

use crate::model::{FixedSet, PARAMETER_COUNT, Param, Scalar, StanceChains, Vertex};

/// One observed vertex of a capture.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Observation {
    /// Which vertex of the pattern.
    pub vertex: Vertex,
    /// Its position in the board frame [mm].
    pub point: [f64; 3],
    /// Where it was seen in the image [px].
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
    /// Optional whitening matrix `W` (2k × 2k for k observations, residuals ordered
    /// u₀, v₀, u₁, v₁, …): the backend minimises `‖W·r‖²` for this capture.
    pub whitening: Option<DMatrix<f64>>,
}

impl CaptureTerm {
    /// Number of residuals (two per observed vertex).
    pub fn residual_count(&self) -> usize {
        2 * self.observations.len()
    }

    /// Unweighted residuals (projection − observation), `u₀, v₀, u₁, v₁, …`, or `None`
    /// when a vertex falls behind the camera.
    pub fn residuals<T: Scalar>(
        &self,
        camera: &crate::model::Camera,
        params: &[T],
    ) -> Option<Vec<T>> {
        let pose = self.chains.camera_to_board(params);
        let mut out = Vec::with_capacity(self.residual_count());
        for obs in &self.observations {
            let p = obs.point.map(crate::model::scalar::lift::<T>);
            let [u, v] = camera.project(&pose.apply(&p))?;
            out.push(u - obs.pixel[0]);
            out.push(v - obs.pixel[1]);
        }
        Some(out)
    }

    /// Residuals as the backend minimises them: whitened if the capture has a whitening.
    pub fn weighted_residuals<T: Scalar>(
        &self,
        camera: &crate::model::Camera,
        params: &[T],
    ) -> Option<Vec<T>> {
        let r = self.residuals(camera, params)?;
        Some(match &self.whitening {
            None => r,
            Some(w) => (0..w.nrows())
                .map(|i| {
                    (0..w.ncols()).fold(crate::model::scalar::lift::<T>(0.0), |acc, j| {
                        acc + r[j].clone() * w[(i, j)]
                    })
                })
                .collect(),
        })
    }
}

/// A robust loss on each vertex's squared residual norm.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Loss {
    /// Plain least squares.
    #[default]
    Squared,
    /// Huber loss with the given scale [px].
    Huber(f64),
    /// Cauchy loss with the given scale [px].
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

/// The calibration as a non-linear least-squares problem (SPEC eq. 9).
#[derive(Debug, Clone, PartialEq)]
pub struct Problem {
    /// Camera intrinsics (the projection `P`).
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
            out.extend(c.residuals(&self.camera, params)?);
        }
        Some(out)
    }

    /// Root mean square of the unweighted residuals in u and in v [px].
    pub fn rms(&self, params: &[f64]) -> Option<[f64; 2]> {
        let r = self.residuals(params)?;
        let n = (r.len() / 2).max(1) as f64;
        let sum = |k: usize| r.iter().skip(k).step_by(2).map(|x| x * x).sum::<f64>();
        Some([(sum(0) / n).sqrt(), (sum(1) / n).sqrt()])
    }
}

impl Problem {
    /// Turns a dataset's measurements into the least-squares problem: one term per capture
    /// with at least one corner, all parameters starting at zero (SPEC section 5), and the
    /// parameters in `fixed` held at zero (or at `initial` values set afterwards).
    ///
    /// Fails, naming the file and line, when a vertex lies behind the camera at the start
    /// values (a sign of wrong joint angles or a wrong `board` column).
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
        let initial = [0.0; PARAMETER_COUNT];
        let mut captures = Vec::new();
        for capture in &dataset.captures {
            let Some(observations) = by_capture.remove(&capture.id) else {
                continue;
            };
            let chains = model.chains(capture.side, &capture.joints);
            let vertices: Vec<Vertex> = observations.iter().map(|o| o.vertex).collect();
            let projected = model.project(&chains, &initial, &vertices);
            if let Some(k) = projected.iter().position(Option::is_none) {
                return Err(super::SolveError::Invalid(format!(
                    "{} line {}, capture {}: vertex ({}, {}) of the {} board lies behind the \
                     camera at the start values; check the joint angles and the board column",
                    dataset.dir.join("captures.csv").display(),
                    capture.line,
                    capture.id,
                    vertices[k].row,
                    vertices[k].col,
                    capture.side.name(),
                )));
            }
            captures.push(CaptureTerm {
                capture: capture.id,
                chains,
                observations,
                whitening: None,
            });
        }
        let free = fixed.free().len();
        let residuals: usize = captures.iter().map(CaptureTerm::residual_count).sum();
        if residuals <= free {
            return Err(super::SolveError::Invalid(format!(
                "{}: too few corners to calibrate: {} vertices of known captures give {residuals} \
                 residuals, but {free} parameters are free (hold some fixed with --fix, or \
                 add captures)",
                dataset.dir.join("corners.csv").display(),
                residuals / 2,
            )));
        }
        Ok(Problem {
            camera: model.camera,
            captures,
            initial,
            fixed,
            loss: Loss::Squared,
            tolerances: Tolerances::default(),
        })
    }
}
