//! Pure-Rust backend: the `levenberg-marquardt` crate (a port of MINPACK's `lmder`), with
//! the exact Jacobian from dual numbers through the same Rust model.
//!
//! A robust loss is honoured by the [`Evaluator`]'s per-vertex rescaling of the residuals,
//! so MINPACK minimises the same cost `½Σρ(‖r_v‖²)` as Ceres.

use std::cell::{Cell, RefCell};
use std::time::Instant;

use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt, TerminationReason};
use nalgebra::{DMatrix, DVector, Dyn, Owned};

use super::jacobian::{Evaluator, LOSS_WITH_WHITENING};
use super::{Backend, BackendResult, Problem, SolveError, Summary};

/// The MINPACK-style Levenberg–Marquardt backend (`--solver lm`).
#[derive(Debug, Clone, Copy, Default)]
pub struct MinpackLm;

/// Residual norm reported for a trial point that puts a vertex behind the camera: large, so
/// MINPACK rejects the step and shrinks its trust region, but finite.
const BEHIND_CAMERA_NORM: f64 = 1e10;

/// The problem as the crate sees it, compressed to `n + 1` residuals.
///
/// MINPACK uses the Jacobian `J` and the residuals `r` of an accepted point only through
/// `JᵀJ`, `Jᵀr` and `‖r‖` (its pivoted QR of `J` solves `min ‖J·p + r‖² + λ‖D·p‖²`), and
/// the residuals of a trial point only through `‖r‖`. With `JᵀJ = V·Λ·Vᵀ`, the pair
/// `J̃ = Λ^½·Vᵀ` (plus a zero row) and `r̃ = (Λ^-½·Vᵀ·Jᵀr, √(‖r‖² − ‖Λ^-½·Vᵀ·Jᵀr‖²))` has the
/// same three, so MINPACK takes exactly the same steps, but its QR now costs `O(n³)`
/// instead of `O(m·n²)` for `m ≫ n` residuals. As the compressed residuals depend on the
/// Jacobian, it is computed with the residuals at every trial point (most are accepted).
struct Target<'a> {
    eval: &'a Evaluator<'a>,
    x: DVector<f64>,
    /// The compressed Jacobian at `x`.
    current: RefCell<Option<Compressed>>,
    /// Jacobian requests so far (MINPACK's outer iterations).
    jacobians: Cell<usize>,
    /// At most this many ([`super::Tolerances::max_iterations`]).
    max_jacobians: usize,
}

/// The compressed problem at one point.
struct Compressed {
    x: DVector<f64>,
    jacobian: DMatrix<f64>,
}

impl Target<'_> {
    /// Compressed residuals at `self.x`, keeping the compressed Jacobian; `None` when a
    /// vertex falls behind the camera.
    fn compress(&self) -> Option<DVector<f64>> {
        let n = self.x.len();
        let (r, jac) = self.eval.residuals_and_jacobian(self.x.as_slice())?;
        // JᵀJ from the upper triangle's column dot products (half of `tr_mul`'s work).
        let mut normal = DMatrix::zeros(n, n);
        for i in 0..n {
            let column = jac.column(i);
            for j in i..n {
                let value = column.dot(&jac.column(j));
                normal[(i, j)] = value;
                normal[(j, i)] = value;
            }
        }
        let gradient = jac.tr_mul(&r);
        let eigen = normal.symmetric_eigen();
        let max = eigen.eigenvalues.max().max(0.0);
        let mut compressed_jac = DMatrix::zeros(n + 1, n);
        let mut compressed_r = DVector::zeros(n + 1);
        let mut explained = 0.0;
        for (k, &l) in eigen.eigenvalues.iter().enumerate() {
            // Directions at rounding level carry no information (nor, in exact arithmetic,
            // any part of the gradient).
            if l <= max * 1e-15 || l <= 0.0 {
                continue;
            }
            let v = eigen.eigenvectors.column(k);
            let root = l.sqrt();
            compressed_jac.row_mut(k).copy_from(&(v.transpose() * root));
            let c = v.dot(&gradient) / root;
            compressed_r[k] = c;
            explained += c * c;
        }
        compressed_r[n] = (r.norm_squared() - explained).max(0.0).sqrt();
        *self.current.borrow_mut() = Some(Compressed {
            x: self.x.clone(),
            jacobian: compressed_jac,
        });
        Some(compressed_r)
    }
}

impl LeastSquaresProblem<f64, Dyn, Dyn> for Target<'_> {
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, Dyn>;
    type ParameterStorage = Owned<f64, Dyn>;

    fn set_params(&mut self, x: &DVector<f64>) {
        self.x.copy_from(x);
    }

    fn params(&self) -> DVector<f64> {
        self.x.clone()
    }

    fn residuals(&self) -> Option<DVector<f64>> {
        let n = self.x.len();
        Some(self.compress().unwrap_or_else(|| {
            let mut r = DVector::zeros(n + 1);
            r[n] = BEHIND_CAMERA_NORM;
            r
        }))
    }

    fn jacobian(&self) -> Option<DMatrix<f64>> {
        if self.jacobians.get() >= self.max_jacobians {
            // Stops the crate with `User("jacobian")`: the iteration limit.
            return None;
        }
        self.jacobians.set(self.jacobians.get() + 1);
        let fresh = matches!(&*self.current.borrow(), Some(c) if c.x == self.x);
        if !fresh {
            self.compress()?;
        }
        self.current.borrow().as_ref().map(|c| c.jacobian.clone())
    }
}

impl Backend for MinpackLm {
    fn name(&self) -> &'static str {
        "lm"
    }

    fn solve(&self, problem: &Problem) -> Result<BackendResult, SolveError> {
        let start = Instant::now();
        let eval = Evaluator::new(problem);
        let fail = |message: String| SolveError::Backend {
            solver: self.name().into(),
            message,
        };
        if eval.loss_with_whitening() {
            return Err(fail(LOSS_WITH_WHITENING.into()));
        }
        let free = eval.free().to_vec();
        let x0 =
            DVector::from_iterator(free.len(), free.iter().map(|p| problem.initial[p.index()]));
        let initial_cost = eval
            .cost(x0.as_slice())
            .ok_or_else(|| fail("a vertex is behind the camera at the start".into()))?;
        let tol = problem.tolerances;
        // MINPACK counts residual evaluations against `patience·(n + 1)`; the iteration
        // limit proper is enforced on the Jacobian evaluations by the target.
        let patience = tol.max_iterations.max(1);
        let lm = LevenbergMarquardt::new()
            .with_ftol(tol.function.max(f64::EPSILON))
            .with_xtol(tol.parameter.max(f64::EPSILON))
            .with_gtol(tol.gradient.max(f64::EPSILON))
            .with_patience(patience);
        let target = Target {
            eval: &eval,
            x: x0,
            current: RefCell::new(None),
            jacobians: Cell::new(0),
            max_jacobians: tol.max_iterations.max(1),
        };
        let (target, report) = lm.minimize(target);
        let x = target.x;
        let final_cost = eval
            .cost(x.as_slice())
            .ok_or_else(|| fail("the solution puts a vertex behind the camera".into()))?;
        let converged = report.termination.was_successful()
            || matches!(
                report.termination,
                TerminationReason::NoImprovementPossible(_)
            );
        let iterations = target.jacobians.get();
        let termination = match report.termination {
            TerminationReason::User("jacobian") => format!(
                "iteration limit: {iterations} iterations ({} residual evaluations)",
                report.number_of_evaluations
            ),
            TerminationReason::LostPatience => format!(
                "evaluation limit: {} residual evaluations",
                report.number_of_evaluations
            ),
            ref other => format!(
                "{other:?} after {iterations} iterations ({} residual evaluations)",
                report.number_of_evaluations
            ),
        };
        Ok(BackendResult {
            free_values: x.iter().copied().collect(),
            summary: Summary {
                solver: self.name().into(),
                converged,
                iterations,
                initial_cost,
                final_cost,
                termination,
                seconds: start.elapsed().as_secs_f64(),
            },
        })
    }
}
