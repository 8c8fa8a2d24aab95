//! Pure-Rust backend: `tiny-solver`'s Levenberg–Marquardt (sparse Cholesky) over the same
//! Rust model.
//!
//! tiny-solver differentiates its factors with its own dynamic dual numbers. Each capture is
//! one factor; rather than running the whole model on those (slow: a heap allocation per
//! operation), the factor computes the capture's residuals and exact Jacobian with the
//! [`Evaluator`] and hands them back as duals by the chain rule,
//! `ε(r_i) = Σ_c J_ic · ε(x_c)` — the same numbers tiny-solver's autodiff would produce.
//! The robust loss is the [`Evaluator`]'s per-vertex rescaling, so tiny-solver minimises
//! the same `½Σρ(‖r_v‖²)` as Ceres (its own loss functions act on a whole block).

use std::collections::HashMap;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use nalgebra::{DVector, Dyn, U1};
use num_dual::{Derivative, DualDVec64};
use tiny_solver::factors::Factor;
use tiny_solver::optimizer::Optimizer;
use tiny_solver::{LevenbergMarquardtOptimizer, OptimizerOptions};

use super::jacobian::{Evaluator, LOSS_WITH_WHITENING};
use super::{Backend, BackendResult, Problem, SolveError, Summary, covariance};
use crate::model::{PARAMETER_COUNT, Param, ParamGroup};

/// tiny-solver's Levenberg–Marquardt backend (`--solver tiny`).
#[derive(Debug, Clone, Copy, Default)]
pub struct Tiny;

/// Residual when a trial step puts a vertex behind the camera: large, so the step is
/// rejected, but finite.
const BEHIND_CAMERA_RESIDUAL: f64 = 1e4;

/// One capture as a tiny-solver factor over the parameter groups it uses.
struct CaptureFactor {
    eval: Arc<Evaluator<'static>>,
    /// The capture's index in the problem.
    index: usize,
    /// Number of residuals.
    rows: usize,
    /// The free parameters of each variable this factor takes, in variable order.
    variables: Vec<Vec<Param>>,
    /// For each local Jacobian column of the capture: (variable, position in it).
    slots: Vec<(usize, usize)>,
    /// Counts Jacobian evaluations (shared by all factors; only the first one counts).
    counter: Option<Arc<AtomicUsize>>,
}

impl CaptureFactor {
    /// The full parameter vector for the variables' values.
    fn params(&self, values: impl Fn(usize, usize) -> f64) -> [f64; PARAMETER_COUNT] {
        let mut all = self.eval.expand(&[]);
        for (v, names) in self.variables.iter().enumerate() {
            for (j, p) in names.iter().enumerate() {
                all[p.index()] = values(v, j);
            }
        }
        all
    }
}

impl Factor<f64> for CaptureFactor {
    fn residual_func(&self, params: &[DVector<f64>]) -> DVector<f64> {
        let all = self.params(|v, j| params[v][j]);
        let r = self
            .eval
            .capture_residuals_at(self.index, &all)
            .unwrap_or_else(|| vec![BEHIND_CAMERA_RESIDUAL; self.rows]);
        DVector::from_vec(r)
    }
}

impl Factor<DualDVec64> for CaptureFactor {
    fn residual_func(&self, params: &[DVector<DualDVec64>]) -> DVector<DualDVec64> {
        if let Some(c) = &self.counter {
            c.fetch_add(1, Ordering::Relaxed);
        }
        let all = self.params(|v, j| params[v][j].re);
        // tiny-solver seeds one lane per entry of the factor's variables.
        let width: usize = params.iter().map(|p| p.len()).sum();
        let Some(local) = self.eval.capture_at(self.index, &all) else {
            return DVector::from_element(
                self.rows,
                DualDVec64::new(
                    BEHIND_CAMERA_RESIDUAL,
                    Derivative::some(DVector::zeros(width)),
                ),
            );
        };
        let k = self.slots.len();
        let inputs: Vec<DVector<f64>> = self
            .slots
            .iter()
            .map(|&(v, j)| params[v][j].eps.clone().unwrap_generic(Dyn(width), U1))
            .collect();
        DVector::from_iterator(
            self.rows,
            (0..self.rows).map(|i| {
                let mut eps = DVector::zeros(width);
                for (c, input) in inputs.iter().enumerate() {
                    eps.axpy(local.jacobian[i * k + c], input, 1.0);
                }
                DualDVec64::new(local.residuals[i], Derivative::some(eps))
            }),
        )
    }
}

impl Backend for Tiny {
    fn name(&self) -> &'static str {
        "tiny"
    }

    fn solve(&self, problem: &Problem) -> Result<BackendResult, SolveError> {
        let start = Instant::now();
        let fail = |message: String| SolveError::Backend {
            solver: self.name().into(),
            message,
        };
        let eval: Arc<Evaluator<'static>> = Arc::new(Evaluator::new(problem));
        if eval.loss_with_whitening() {
            return Err(fail(LOSS_WITH_WHITENING.into()));
        }
        let free = eval.free().to_vec();
        // One variable per parameter group, holding that group's free parameters.
        let mut groups: Vec<(ParamGroup, Vec<Param>)> = Vec::new();
        for p in &free {
            match groups.iter_mut().find(|(g, _)| *g == p.group()) {
                Some((_, ps)) => ps.push(*p),
                None => groups.push((p.group(), vec![*p])),
            }
        }
        let counter = Arc::new(AtomicUsize::new(0));
        let mut tiny = tiny_solver::Problem::new();
        for (k, term) in problem.captures.iter().enumerate() {
            let used = eval.capture_parameters(k);
            let mut used_groups: Vec<ParamGroup> = used.iter().map(|p| p.group()).collect();
            used_groups.sort();
            used_groups.dedup();
            let variables: Vec<Vec<Param>> = used_groups
                .iter()
                .map(|g| {
                    groups
                        .iter()
                        .find(|(h, _)| h == g)
                        .map(|(_, ps)| ps.clone())
                        .unwrap_or_default()
                })
                .collect();
            let slots = used
                .iter()
                .map(|p| {
                    let v = used_groups
                        .iter()
                        .position(|g| *g == p.group())
                        .expect("group listed");
                    let j = variables[v].iter().position(|q| q == p).expect("in group");
                    (v, j)
                })
                .collect();
            let names: Vec<&str> = used_groups.iter().map(|g| g.name()).collect();
            let factor = CaptureFactor {
                eval: eval.clone(),
                index: k,
                rows: term.residual_count(),
                variables,
                slots,
                counter: (k == 0).then(|| counter.clone()),
            };
            tiny.add_residual_block(term.residual_count(), &names, Box::new(factor), None);
        }
        let initial: HashMap<String, DVector<f64>> = groups
            .iter()
            .map(|(g, ps)| {
                (
                    g.name().to_string(),
                    DVector::from_iterator(ps.len(), ps.iter().map(|p| problem.initial[p.index()])),
                )
            })
            .collect();
        let x0: Vec<f64> = free.iter().map(|p| problem.initial[p.index()]).collect();
        let initial_cost = eval
            .cost(&x0)
            .ok_or_else(|| fail("a vertex is behind the camera at the start".into()))?;
        let tol = problem.tolerances;
        let options = OptimizerOptions {
            max_iteration: tol.max_iterations,
            min_rel_error_decrease_threshold: tol.function,
            min_abs_error_decrease_threshold: 0.0,
            min_error_threshold: 0.0,
            ..Default::default()
        };
        let result = LevenbergMarquardtOptimizer::default()
            .optimize(&tiny, &initial, Some(options))
            .ok_or_else(|| fail("the optimiser gave up (linear solve failed)".into()))?;
        let x: Vec<f64> = free
            .iter()
            .map(|p| {
                let (_, ps) = groups
                    .iter()
                    .find(|(g, _)| *g == p.group())
                    .expect("grouped");
                let k = ps.iter().position(|q| q == p).expect("in group");
                result[p.group().name()][k]
            })
            .collect();
        let (r, jac) = eval
            .residuals_and_jacobian(&x)
            .ok_or_else(|| fail("the solution puts a vertex behind the camera".into()))?;
        // tiny-solver does not say why it stopped: call it converged when one more
        // Gauss–Newton step could remove only a negligible part of the cost.
        let (cov, _rank) = covariance::from_jacobian(&jac);
        let gradient = jac.tr_mul(&r);
        let decrease = 0.5 * (gradient.transpose() * &cov * &gradient)[(0, 0)];
        let final_cost = 0.5 * r.norm_squared();
        let iterations = counter.load(Ordering::Relaxed);
        let converged =
            iterations < tol.max_iterations && decrease <= (1e-9 * final_cost).max(1e-12);
        Ok(BackendResult {
            free_values: x,
            summary: Summary {
                solver: self.name().into(),
                converged,
                iterations,
                initial_cost,
                final_cost,
                termination: format!(
                    "stopped after {iterations} Jacobian evaluations; one more Gauss-Newton \
                     step would lower the cost by {decrease:.1e}"
                ),
                seconds: start.elapsed().as_secs_f64(),
            },
        })
    }
}
