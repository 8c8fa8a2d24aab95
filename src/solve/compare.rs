//! Every backend on the same [`Problem`], side by side (`naocalib compare`).
//!
//! Each backend runs through [`calibrate`](super::calibrate) (plain) from the same start values. The
//! reference is Ceres when it is among the backends (the default build), otherwise the
//! first backend; every other run is measured by its largest parameter difference from the
//! reference in units of the reference's one-sigma. A backend that fails or does not
//! converge stays in the comparison, marked as such.

use std::time::Instant;

use super::covariance::rank_of_covariance;
use super::{Problem, Solution, backend, backend_names};
use crate::model::Param;

/// Why a comparison could not be made at all.
#[derive(Debug, thiserror::Error)]
pub enum CompareError {
    /// A solver name that no backend answers to.
    #[error("unknown solver '{name}' (available: {available})")]
    UnknownSolver {
        /// The name asked for.
        name: String,
        /// The backends of this build.
        available: String,
    },
    /// No solver to compare.
    #[error("no solver to compare")]
    NoSolvers,
}

/// One backend's run.
#[derive(Debug, Clone)]
pub struct Run {
    /// Backend name.
    pub solver: String,
    /// The solution, or why the backend failed.
    pub outcome: Result<Box<Solution>, String>,
    /// Wall time of the whole [`calibrate`](super::calibrate) (plain) call, statistics included (s).
    pub wall_seconds: f64,
    /// Numerical rank of the run's covariance ([`rank_of_covariance`]); `None` on failure.
    pub rank: Option<usize>,
    /// The largest `|value − reference value| / reference std` over the free parameters,
    /// with that parameter; `None` when this run or the reference failed. A parameter the
    /// reference leaves undetermined (std 0) counts as 0 when both agree exactly and as
    /// infinite otherwise.
    pub max_sigma: Option<(f64, Param)>,
}

impl Run {
    /// The solution, if the backend returned one.
    pub fn solution(&self) -> Option<&Solution> {
        self.outcome.as_deref().ok()
    }

    /// Whether the backend returned a solution and reports convergence.
    pub fn converged(&self) -> bool {
        self.solution().is_some_and(|s| s.summary.converged)
    }
}

/// All backends' runs on one problem.
#[derive(Debug, Clone)]
pub struct Comparison {
    /// The free parameters, in order.
    pub free: Vec<Param>,
    /// Index into [`Comparison::runs`] of the reference run.
    pub reference: usize,
    /// Whether the reference is Ceres (otherwise the first backend, as in a build without
    /// Ceres).
    pub reference_is_ceres: bool,
    /// One run per backend, in the order asked for.
    pub runs: Vec<Run>,
}

impl Comparison {
    /// The reference run.
    pub fn reference_run(&self) -> &Run {
        &self.runs[self.reference]
    }
}

/// Runs the backends called `solvers` (all of [`backend_names`] when empty) on `problem`
/// and compares them with the reference (Ceres if present, else the first).
pub fn compare(problem: &Problem, solvers: &[&str]) -> Result<Comparison, CompareError> {
    let names: Vec<&str> = if solvers.is_empty() {
        backend_names()
    } else {
        solvers.to_vec()
    };
    if names.is_empty() {
        return Err(CompareError::NoSolvers);
    }
    let backends = names
        .iter()
        .map(|name| {
            backend(name, false).ok_or_else(|| CompareError::UnknownSolver {
                name: (*name).to_string(),
                available: backend_names().join(", "),
            })
        })
        .collect::<Result<Vec<_>, _>>()?;
    let mut runs: Vec<Run> = backends
        .iter()
        .map(|b| {
            let start = Instant::now();
            let outcome =
                super::calibrate(problem, b.as_ref(), &super::UncertaintyOptions::plain())
                    .map(Box::new)
                    .map_err(|e| e.to_string());
            let wall_seconds = start.elapsed().as_secs_f64();
            let rank = outcome
                .as_ref()
                .ok()
                .map(|s| rank_of_covariance(&s.covariance));
            Run {
                solver: b.name().to_string(),
                outcome,
                wall_seconds,
                rank,
                max_sigma: None,
            }
        })
        .collect();
    let ceres = runs.iter().position(|r| r.solver == "ceres");
    let reference = ceres.unwrap_or(0);
    let free = problem.free();
    if let Some(reference_solution) = runs[reference].solution().cloned() {
        for run in &mut runs {
            run.max_sigma = run
                .solution()
                .map(|s| max_sigma_difference(s, &reference_solution, &free));
        }
    }
    Ok(Comparison {
        free,
        reference,
        reference_is_ceres: ceres.is_some(),
        runs,
    })
}

/// `|a − b| / σ_b` for one parameter (0 when equal, infinite when `σ_b = 0` and they
/// differ).
pub fn sigma_difference(solution: &Solution, reference: &Solution, p: Param) -> f64 {
    let d = (solution.values[p.index()] - reference.values[p.index()]).abs();
    let sigma = reference.std[p.index()];
    if d == 0.0 {
        0.0
    } else if sigma > 0.0 {
        d / sigma
    } else {
        f64::INFINITY
    }
}

/// The largest [`sigma_difference`] over `free`, with its parameter.
pub fn max_sigma_difference(
    solution: &Solution,
    reference: &Solution,
    free: &[Param],
) -> (f64, Param) {
    free.iter()
        .map(|&p| (sigma_difference(solution, reference, p), p))
        .fold(
            (0.0, free.first().copied().unwrap_or(Param::CamYaw)),
            |a, b| {
                if b.0 > a.0 { b } else { a }
            },
        )
}
