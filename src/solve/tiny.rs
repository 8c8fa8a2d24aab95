//! Pure-Rust backend: `tiny-solver`'s Levenberg–Marquardt (sparse Cholesky), with its own
//! dual-number autodiff over the same generic Rust model.

use std::collections::HashMap;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use nalgebra::DVector;
use num_dual::DualDVec64;
use tiny_solver::factors::Factor;
use tiny_solver::loss_functions::{CauchyLoss, HuberLoss, Loss as TinyLoss};
use tiny_solver::optimizer::Optimizer;
use tiny_solver::{LevenbergMarquardtOptimizer, OptimizerOptions};

use super::jacobian::Evaluator;
use super::{Backend, BackendResult, CaptureTerm, Loss, Problem, SolveError, Summary, covariance};
use crate::model::{Camera, PARAMETER_COUNT, Param, ParamGroup, Scalar};

/// tiny-solver's Levenberg–Marquardt backend (`--solver tiny`).
#[derive(Debug, Clone, Copy, Default)]
pub struct Tiny;

/// Residual when a trial step puts a vertex behind the camera: large, so the step is
/// rejected, but finite.
const BEHIND_CAMERA_RESIDUAL: f64 = 1e4;

/// One capture as a tiny-solver factor over the parameter groups it uses.
struct CaptureFactor {
    term: CaptureTerm,
    camera: Camera,
    /// Fixed values of every parameter (internal units).
    base: [f64; PARAMETER_COUNT],
    /// The free parameters of each variable this factor takes, in variable order.
    variables: Vec<Vec<Param>>,
    /// Counts Jacobian evaluations (shared by all factors; only the first one counts).
    counter: Option<Arc<AtomicUsize>>,
}

impl CaptureFactor {
    fn eval<T: Scalar>(&self, params: &[DVector<T>]) -> DVector<T> {
        let mut all: Vec<T> = self.base.iter().map(|&v| T::from(v)).collect();
        for (values, names) in params.iter().zip(&self.variables) {
            for (v, p) in values.iter().zip(names) {
                all[p.index()] = v.clone();
            }
        }
        let r = self
            .term
            .weighted_residuals(&self.camera, &all)
            .unwrap_or_else(|| vec![T::from(BEHIND_CAMERA_RESIDUAL); self.term.residual_count()]);
        DVector::from_vec(r)
    }
}

impl Factor<f64> for CaptureFactor {
    fn residual_func(&self, params: &[DVector<f64>]) -> DVector<f64> {
        self.eval(params)
    }
}

impl Factor<DualDVec64> for CaptureFactor {
    fn residual_func(&self, params: &[DVector<DualDVec64>]) -> DVector<DualDVec64> {
        if let Some(c) = &self.counter {
            c.fetch_add(1, Ordering::Relaxed);
        }
        self.eval(params)
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
        let eval = Evaluator::new(problem);
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
        for (k, (term, chains)) in problem
            .captures
            .iter()
            .zip(problem.frozen_chains())
            .enumerate()
        {
            let mut used: Vec<ParamGroup> = Vec::new();
            for p in chains
                .camera
                .params()
                .into_iter()
                .chain(chains.board.params())
            {
                if !used.contains(&p.group()) {
                    used.push(p.group());
                }
            }
            used.sort();
            let variables: Vec<Vec<Param>> = used
                .iter()
                .map(|g| {
                    groups
                        .iter()
                        .find(|(h, _)| h == g)
                        .map(|(_, ps)| ps.clone())
                        .unwrap_or_default()
                })
                .collect();
            let names: Vec<&str> = used.iter().map(|g| g.name()).collect();
            let loss: Option<Box<dyn TinyLoss + Send>> = match problem.loss {
                Loss::Squared => None,
                Loss::Huber(s) => Some(Box::new(HuberLoss::new(s))),
                Loss::Cauchy(s) => Some(Box::new(CauchyLoss::new(s))),
            };
            let factor = CaptureFactor {
                term: CaptureTerm {
                    chains,
                    ..term.clone()
                },
                camera: problem.camera,
                base: problem.initial,
                variables,
                counter: (k == 0).then(|| counter.clone()),
            };
            tiny.add_residual_block(term.residual_count(), &names, Box::new(factor), loss);
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
        let r0 = eval
            .residuals(&x0)
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
        let (cov, _rank) = covariance::from_jacobian(&jac);
        // tiny-solver does not say why it stopped: call it converged when one more
        // Gauss–Newton step could remove only a negligible part of the cost.
        let gradient = jac.transpose() * &r;
        let decrease = 0.5 * (gradient.transpose() * &cov * &gradient)[(0, 0)];
        let final_cost = 0.5 * r.norm_squared();
        let iterations = counter.load(Ordering::Relaxed);
        let converged =
            iterations < tol.max_iterations && decrease <= (1e-9 * final_cost).max(1e-12);
        Ok(BackendResult {
            free_values: x,
            covariance: Some(cov),
            summary: Summary {
                solver: self.name().into(),
                converged,
                iterations,
                initial_cost: 0.5 * r0.norm_squared(),
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
