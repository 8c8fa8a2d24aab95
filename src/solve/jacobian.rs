//! Residuals and their exact Jacobian in Rust, by forward-mode dual numbers through the same
//! generic model: what the pure-Rust backends and the Rust covariance use.

use nalgebra::{Const, DMatrix, DVector, U1};
use num_dual::{Derivative, DualSVec64};

use super::problem::{CaptureTerm, Problem};
use crate::model::{Camera, PARAMETER_COUNT, Param};

/// Parameters differentiated at once per pass (the Jet width of the Ceres shim, too).
const WIDTH: usize = 12;
type Dual = DualSVec64<WIDTH>;

/// Precomputed data to evaluate a problem quickly: chains with held parameters frozen, and
/// the column of each free parameter.
#[derive(Debug, Clone)]
pub struct Evaluator<'a> {
    problem: &'a Problem,
    /// The captures with their chains frozen.
    terms: Vec<CaptureTerm>,
    free: Vec<Param>,
    column: [Option<usize>; PARAMETER_COUNT],
    /// Each capture's free parameters (columns), in chain order.
    used: Vec<Vec<Param>>,
}

impl<'a> Evaluator<'a> {
    /// Prepares `problem` for evaluation.
    pub fn new(problem: &'a Problem) -> Self {
        let terms: Vec<CaptureTerm> = problem
            .captures
            .iter()
            .zip(problem.frozen_chains())
            .map(|(term, chains)| CaptureTerm {
                chains,
                ..term.clone()
            })
            .collect();
        let free = problem.free();
        let mut column = [None; PARAMETER_COUNT];
        for (k, p) in free.iter().enumerate() {
            column[p.index()] = Some(k);
        }
        let used = terms
            .iter()
            .map(|t| &t.chains)
            .map(|c| {
                let mut ps = c.camera.params();
                for p in c.board.params() {
                    if !ps.contains(&p) {
                        ps.push(p);
                    }
                }
                ps
            })
            .collect();
        Evaluator {
            problem,
            terms,
            free,
            column,
            used,
        }
    }

    /// The free parameters (the Jacobian's columns).
    pub fn free(&self) -> &[Param] {
        &self.free
    }

    /// Weighted residuals at the free values `x`, or `None` if a vertex falls behind the
    /// camera.
    pub fn residuals(&self, x: &[f64]) -> Option<DVector<f64>> {
        let params = self.problem.expand(x);
        let mut out = Vec::with_capacity(self.problem.residual_count());
        for term in &self.terms {
            out.extend(term.weighted_residuals(&self.problem.camera, &params)?);
        }
        Some(DVector::from_vec(out))
    }

    /// Weighted residuals and the dense Jacobian (m × free) at the free values `x`.
    pub fn residuals_and_jacobian(&self, x: &[f64]) -> Option<(DVector<f64>, DMatrix<f64>)> {
        let params = self.problem.expand(x);
        let m = self.problem.residual_count();
        let mut r = DVector::zeros(m);
        let mut jac = DMatrix::zeros(m, self.free.len());
        let mut row = 0;
        for (term, used) in self.terms.iter().zip(&self.used) {
            let rows = term.residual_count();
            let chunks: Vec<&[Param]> = if used.is_empty() {
                vec![&[][..]]
            } else {
                used.chunks(WIDTH).collect()
            };
            for chunk in chunks {
                let (values, derivs) = capture_pass(term, &self.problem.camera, &params, chunk)?;
                for (i, value) in values.iter().enumerate() {
                    r[row + i] = *value;
                    for (c, p) in chunk.iter().enumerate() {
                        if let Some(col) = self.column[p.index()] {
                            jac[(row + i, col)] = derivs[i][c];
                        }
                    }
                }
            }
            row += rows;
        }
        Some((r, jac))
    }
}

/// One forward-mode pass over a capture, differentiating with respect to `chunk`.
fn capture_pass(
    term: &CaptureTerm,
    camera: &Camera,
    params: &[f64; PARAMETER_COUNT],
    chunk: &[Param],
) -> Option<(Vec<f64>, Vec<[f64; WIDTH]>)> {
    let mut x: Vec<Dual> = params.iter().map(|&v| Dual::from(v)).collect();
    for (k, p) in chunk.iter().enumerate() {
        x[p.index()] = Dual::new(
            params[p.index()],
            Derivative::derivative_generic(Const::<WIDTH>, U1, k),
        );
    }
    let residuals = term.weighted_residuals(camera, &x)?;
    let values = residuals.iter().map(|d| d.re).collect();
    let derivs = residuals
        .iter()
        .map(|d| {
            let eps = d.eps.unwrap_generic(Const::<WIDTH>, U1);
            std::array::from_fn(|c| eps[c])
        })
        .collect();
    Some((values, derivs))
}
