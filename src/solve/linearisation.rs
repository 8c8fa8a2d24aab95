//! One linearisation of a problem at a point, shared by what follows a fit: every
//! capture's residuals and Jacobian there (from [`super::jacobian::Evaluator`]), from which
//! the misfit tests, the noise estimate and the statistics each take their own columns and
//! weights, and the normal equations they sum capture by capture.

use nalgebra::{DMatrix, DVector};

use super::jacobian::Evaluator;
use super::problem::{Problem, Whitening};
use crate::model::{PARAMETER_COUNT, Param};

/// Every capture's unweighted residuals and Jacobian at one point, over a set of
/// parameters: the one evaluation that the misfit tests, the noise estimate and the
/// statistics at that point share, each taking its own columns and weights from it.
#[derive(Debug, Clone)]
pub struct Linearisation {
    values: [f64; PARAMETER_COUNT],
    captures: Vec<Linearised>,
}

/// One capture of a [`Linearisation`].
#[derive(Debug, Clone)]
struct Linearised {
    /// The parameters the capture depends on (of the linearisation's).
    params: Vec<Param>,
    /// Where each parameter is in `params`.
    column: [Option<usize>; PARAMETER_COUNT],
    residuals: DVector<f64>,
    /// One column per parameter of `params`.
    jacobian: DMatrix<f64>,
}

/// One capture's residuals and Jacobian over chosen parameters, weighted as asked (see
/// [`Linearisation::capture`]).
#[derive(Debug, Clone)]
pub struct CaptureSlice {
    /// The residuals (`u₀, v₀, …`).
    pub residuals: DVector<f64>,
    /// One column per chosen parameter (zero where the capture does not depend on it).
    pub jacobian: DMatrix<f64>,
}

/// The normal equations of a weighted problem at one point over chosen columns (see
/// [`Linearisation::normal_sums`]).
#[derive(Debug, Clone)]
pub struct NormalSums {
    /// `JᵀJ`.
    pub gram: DMatrix<f64>,
    /// One row per capture: `J_cᵀ r_c`.
    pub gradients: DMatrix<f64>,
    /// `‖r‖²`.
    pub rss: f64,
    /// The number of residuals.
    pub rows: usize,
}

impl Linearisation {
    /// Evaluates every capture of `problem` at the full parameter vector `values`, over the
    /// parameters `free` (others held there), unweighted; `None` when a vertex falls behind
    /// the camera.
    pub fn at(
        problem: &Problem,
        free: Vec<Param>,
        values: &[f64; PARAMETER_COUNT],
    ) -> Option<Self> {
        let eval = Evaluator::over(problem, free, values, false);
        let captures = (0..eval.capture_count())
            .map(|c| {
                let local = eval.capture_at(c, values)?;
                let used = eval.capture_parameters(c);
                let rows = local.residuals.len();
                Some(Linearised {
                    params: used.to_vec(),
                    column: positions(used),
                    jacobian: DMatrix::from_row_slice(rows, used.len(), &local.jacobian),
                    residuals: DVector::from_vec(local.residuals),
                })
            })
            .collect::<Option<Vec<_>>>()?;
        Some(Linearisation {
            values: *values,
            captures,
        })
    }

    /// The point (full parameter vector, internal units).
    pub fn values(&self) -> &[f64; PARAMETER_COUNT] {
        &self.values
    }

    /// Number of captures (problem order).
    pub fn capture_count(&self) -> usize {
        self.captures.len()
    }

    /// Root mean square of the unweighted residuals in u and in v (px), as
    /// [`Problem::rms`].
    pub fn rms(&self) -> [f64; 2] {
        let mut sum = [0.0; 2];
        let mut n = 0usize;
        for c in &self.captures {
            for pair in c.residuals.as_slice().chunks_exact(2) {
                sum[0] += pair[0] * pair[0];
                sum[1] += pair[1] * pair[1];
            }
            n += c.residuals.len() / 2;
        }
        let n = n.max(1) as f64;
        sum.map(|s| (s / n).sqrt())
    }

    /// `½‖r‖²` of the unweighted residuals.
    pub fn cost(&self) -> f64 {
        0.5 * self
            .captures
            .iter()
            .map(|c| c.residuals.norm_squared())
            .sum::<f64>()
    }

    /// The parameters capture `index` depends on (of those the linearisation
    /// differentiates by).
    pub fn capture_params(&self, index: usize) -> &[Param] {
        &self.captures[index].params
    }

    /// The normal equations of `problem` (whose captures this linearises, each weighted by
    /// its whitening) over `columns`, summed capture by capture from the captures' own
    /// Jacobians, so the tall Jacobian is never formed.
    pub fn normal_sums(&self, problem: &Problem, columns: &[Param]) -> NormalSums {
        let n = columns.len();
        let positions = positions(columns);
        let captures = self.capture_count();
        let mut sums = NormalSums {
            gram: DMatrix::zeros(n, n),
            gradients: DMatrix::zeros(captures, n),
            rss: 0.0,
            rows: 0,
        };
        for (c, stored) in self.captures.iter().enumerate() {
            let (local, at) = self.own_columns(c, &positions);
            let whitening = problem.captures[c].whitening.as_ref();
            let sliced;
            let (jacobian, residuals) = if local.len() == stored.params.len() && whitening.is_none()
            {
                (&stored.jacobian, &stored.residuals)
            } else {
                sliced = self.capture(c, &local, whitening);
                (&sliced.jacobian, &sliced.residuals)
            };
            let jtr = jacobian.tr_mul(residuals);
            for (a, &ca) in at.iter().enumerate() {
                sums.gradients[(c, ca)] = jtr[a];
            }
            add_block(&mut sums.gram, &at, &(jacobian.transpose() * jacobian));
            sums.rss += residuals.norm_squared();
            sums.rows += residuals.len();
        }
        sums
    }

    /// Every capture of `problem` (whose captures this linearises) over its own parameters
    /// among `columns`, weighted by its whitening.
    pub fn own_slices(&self, problem: &Problem, columns: &[Param]) -> Vec<OwnSlice> {
        let positions = positions(columns);
        (0..self.capture_count())
            .map(|c| {
                let (local, columns) = self.own_columns(c, &positions);
                OwnSlice {
                    slice: self.capture(c, &local, problem.captures[c].whitening.as_ref()),
                    columns,
                }
            })
            .collect()
    }

    /// Capture `c`'s parameters among the chosen columns (`positions`: where each
    /// parameter is among them), and where each goes.
    fn own_columns(
        &self,
        c: usize,
        positions: &[Option<usize>; PARAMETER_COUNT],
    ) -> (Vec<Param>, Vec<usize>) {
        self.captures[c]
            .params
            .iter()
            .filter_map(|p| positions[p.index()].map(|k| (*p, k)))
            .unzip()
    }

    /// Capture `index`'s residuals and Jacobian over `params` (zero columns for those it
    /// does not depend on), weighted by `whitening` if given.
    pub fn capture(
        &self,
        index: usize,
        params: &[Param],
        whitening: Option<&Whitening>,
    ) -> CaptureSlice {
        let local = &self.captures[index];
        let rows = local.residuals.len();
        let mut jacobian = DMatrix::zeros(rows, params.len());
        for (j, p) in params.iter().enumerate() {
            if let Some(l) = local.column[p.index()] {
                jacobian.set_column(j, &local.jacobian.column(l));
            }
        }
        match whitening {
            Some(w) => CaptureSlice {
                residuals: w.apply(local.residuals.as_slice()).into(),
                jacobian: w.apply_matrix(&jacobian),
            },
            None => CaptureSlice {
                residuals: local.residuals.clone(),
                jacobian,
            },
        }
    }
}

/// One capture's weighted residuals and Jacobian over its own parameters among chosen
/// columns ([`Linearisation::own_slices`]), and where each of its columns is among them.
pub struct OwnSlice {
    /// The residuals and the Jacobian's columns.
    pub slice: CaptureSlice,
    /// Per column of the slice, its index among the chosen columns.
    pub columns: Vec<usize>,
}

/// Where each parameter is among `columns`.
fn positions(columns: &[Param]) -> [Option<usize>; PARAMETER_COUNT] {
    let mut out = [None; PARAMETER_COUNT];
    for (k, p) in columns.iter().enumerate() {
        out[p.index()] = Some(k);
    }
    out
}

/// Adds a capture's `block` (`JᵀJ` over its own columns, which go to `at`) into the square
/// `gram`, column by column.
pub fn add_block(gram: &mut DMatrix<f64>, at: &[usize], block: &DMatrix<f64>) {
    let n = gram.nrows();
    let gram = gram.as_mut_slice();
    for (&cb, products) in at.iter().zip(block.column_iter()) {
        let into = &mut gram[cb * n..(cb + 1) * n];
        for (&ca, &v) in at.iter().zip(products.iter()) {
            into[ca] += v;
        }
    }
}
