//! Pure-Rust backend: the `levenberg-marquardt` crate (a port of MINPACK's `lmder`), with
//! the exact Jacobian from dual numbers through the same Rust model.

use std::time::Instant;

use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt, TerminationReason};
use nalgebra::{DMatrix, DVector, Dyn, Owned};

use super::jacobian::Evaluator;
use super::{Backend, BackendResult, Problem, SolveError, Summary, covariance};

/// The MINPACK-style Levenberg–Marquardt backend (`--solver lm`).
#[derive(Debug, Clone, Copy, Default)]
pub struct MinpackLm;

struct Target<'a> {
    eval: &'a Evaluator<'a>,
    x: DVector<f64>,
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
        self.eval.residuals(self.x.as_slice())
    }

    fn jacobian(&self) -> Option<DMatrix<f64>> {
        self.eval
            .residuals_and_jacobian(self.x.as_slice())
            .map(|(_, j)| j)
    }
}

fn cost(r: &DVector<f64>) -> f64 {
    0.5 * r.norm_squared()
}

impl Backend for MinpackLm {
    fn name(&self) -> &'static str {
        "lm"
    }

    fn solve(&self, problem: &Problem) -> Result<BackendResult, SolveError> {
        let start = Instant::now();
        let eval = Evaluator::new(problem);
        let free = eval.free().to_vec();
        let x0 =
            DVector::from_iterator(free.len(), free.iter().map(|p| problem.initial[p.index()]));
        let fail = |message: String| SolveError::Backend {
            solver: self.name().into(),
            message,
        };
        let initial_cost = cost(
            &eval
                .residuals(x0.as_slice())
                .ok_or_else(|| fail("a vertex is behind the camera at the start".into()))?,
        );
        if problem.loss != super::Loss::Squared {
            return Err(fail(
                "robust losses are not supported by this backend yet".into(),
            ));
        }
        let tol = problem.tolerances;
        let lm = LevenbergMarquardt::new()
            .with_ftol(tol.function.max(f64::EPSILON))
            .with_xtol(tol.parameter.max(f64::EPSILON))
            .with_gtol(tol.gradient.max(f64::EPSILON))
            .with_patience(tol.max_iterations);
        let target = Target { eval: &eval, x: x0 };
        let (target, report) = lm.minimize(target);
        let x = target.x;
        let (r, jac) = eval
            .residuals_and_jacobian(x.as_slice())
            .ok_or_else(|| fail("the solution puts a vertex behind the camera".into()))?;
        let (cov, _rank) = covariance::from_jacobian(&jac);
        let converged = report.termination.was_successful()
            || matches!(
                report.termination,
                TerminationReason::NoImprovementPossible(_)
            );
        Ok(BackendResult {
            free_values: x.iter().copied().collect(),
            covariance: Some(cov),
            summary: Summary {
                solver: self.name().into(),
                converged,
                iterations: report.number_of_evaluations,
                initial_cost,
                final_cost: cost(&r),
                termination: format!("{:?}", report.termination),
                seconds: start.elapsed().as_secs_f64(),
            },
        })
    }
}
