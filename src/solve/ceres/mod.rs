//! The Ceres backend, over the `cxx` bridge (`bridge.rs`) to the C++ shim in
//! `cpp/ceres_shim.{h,cc}`.
//!
//! Rust ships each capture's chains as data (elementary transforms, with the held parameters
//! already frozen) plus the observed vertices; the shim evaluates the transform list on Jets
//! in an autodiff cost function. Everything that could trip a glog CHECK is validated in
//! Rust first (see [`super::validate`]); C++ exceptions come back as `Err`.

mod bridge;

use bridge::ffi;

use nalgebra::DMatrix;

use super::{Backend, BackendResult, Loss, Problem, SolveError, Summary, Whitening};
use crate::model::chain::MAX_TERMS;
use crate::model::{Affine, Axis, PARAMETER_COUNT, Projection, Step};

/// Residuals per free parameter from which each step solves the normal equations
/// (`DENSE_NORMAL_CHOLESKY`) instead of a dense QR. A tall Jacobian (the paper's problem:
/// 6912 × 21) costs QR `2·m·n²` flops against `m·n²` for `JᵀJ`, and the dense QR was most of
/// Ceres' own time (docs/MODEL.md §13). Ceres scales the
/// columns first (Jacobi scaling) and the undetermined directions have been held
/// (docs/MODEL.md), so squaring the condition number costs no accuracy that matters here;
/// small problems, where QR costs little more, keep it.
pub const NORMAL_EQUATIONS_MIN_ROWS_PER_PARAMETER: usize = 10;

/// The Ceres backend: Levenberg–Marquardt with autodiff on Jets through the C++ shim in
/// `cpp/`; each step by the normal equations, or by dense QR for a small problem
/// ([`NORMAL_EQUATIONS_MIN_ROWS_PER_PARAMETER`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Ceres {
    /// Print Ceres' per-iteration progress and its full report to stderr.
    pub verbose: bool,
}

impl Backend for Ceres {
    fn name(&self) -> &'static str {
        "ceres"
    }

    fn solve(&self, problem: &Problem) -> Result<BackendResult, SolveError> {
        let ffi_problem = to_ffi(problem)?;
        let (loss, loss_scale) = match problem.loss {
            Loss::Squared => (ffi::LossKind::Squared, 0.0),
            Loss::Huber(s) => (ffi::LossKind::Huber, s),
            Loss::Cauchy(s) => (ffi::LossKind::Cauchy, s),
        };
        let t = &problem.tolerances;
        let options = ffi::FfiOptions {
            max_iterations: u32::try_from(t.max_iterations).unwrap_or(u32::MAX),
            function_tolerance: t.function,
            gradient_tolerance: t.gradient,
            parameter_tolerance: t.parameter,
            loss,
            loss_scale,
            linear_solver: if problem.residual_count()
                >= NORMAL_EQUATIONS_MIN_ROWS_PER_PARAMETER * problem.free().len()
            {
                ffi::LinearSolver::DenseNormalCholesky
            } else {
                ffi::LinearSolver::DenseQr
            },
            verbose: self.verbose,
        };
        let solution = ffi::solve(&ffi_problem, &options).map_err(backend_error)?;
        let n = ffi_problem.params.len();
        if solution.params.len() != n {
            return Err(backend_error(format!(
                "returned {} values for {n} free parameters",
                solution.params.len()
            )));
        }
        Ok(BackendResult {
            free_values: solution.params,
            summary: Summary {
                solver: self.name().into(),
                converged: solution.converged,
                iterations: solution.iterations as usize,
                initial_cost: solution.initial_cost,
                final_cost: solution.final_cost,
                termination: solution.termination,
                seconds: solution.seconds,
            },
        })
    }
}

/// Evaluates the problem in Ceres at the free-parameter values `free_values` (order of
/// [`Problem::free`]): the residuals as Ceres minimises them (whitened where a capture has
/// a whitening; no robust loss) and their dense Jacobian with respect to the free
/// parameters (one column per free parameter, same order). For comparing backends.
pub fn evaluate(
    problem: &Problem,
    free_values: &[f64],
) -> Result<(Vec<f64>, DMatrix<f64>), SolveError> {
    let ffi_problem = to_ffi(problem)?;
    let n = ffi_problem.params.len();
    if free_values.len() != n {
        return Err(backend_error(format!(
            "got {} values for {n} free parameters",
            free_values.len()
        )));
    }
    let eval = ffi::evaluate(&ffi_problem, free_values).map_err(backend_error)?;
    let m = eval.residuals.len();
    if eval.jacobian.len() != m * n {
        return Err(backend_error(format!(
            "returned a Jacobian of {} entries for {m} residuals and {n} parameters",
            eval.jacobian.len()
        )));
    }
    let jacobian = DMatrix::from_row_slice(m, n, &eval.jacobian);
    Ok((eval.residuals, jacobian))
}

fn backend_error(message: impl std::fmt::Display) -> SolveError {
    SolveError::Backend {
        solver: "ceres".into(),
        message: message.to_string(),
    }
}

fn count(n: usize, what: &str) -> Result<u32, SolveError> {
    u32::try_from(n).map_err(|_| backend_error(format!("too many {what} for the bridge")))
}

/// An amount over the free parameters (`free_index`: position among them, by parameter).
fn ffi_amount(
    amount: &Affine,
    free_index: &[Option<usize>; PARAMETER_COUNT],
) -> Result<ffi::FfiAmount, SolveError> {
    let mut out = ffi::FfiAmount {
        constant: amount.constant,
        params: [-1; MAX_TERMS],
        scales: [0.0; MAX_TERMS],
    };
    for (k, (p, scale)) in amount.terms().enumerate() {
        let index = free_index[p.index()].ok_or_else(|| {
            backend_error(format!("parameter {p} is held fixed but was not frozen"))
        })?;
        out.params[k] = i32::try_from(index).map_err(|_| backend_error("too many parameters"))?;
        out.scales[k] = scale;
    }
    Ok(out)
}

fn ffi_step(
    step: &Step,
    free_index: &[Option<usize>; PARAMETER_COUNT],
) -> Result<ffi::FfiStep, SolveError> {
    let axis = |a: &Axis| match a {
        Axis::X => ffi::StepAxis::X,
        Axis::Y => ffi::StepAxis::Y,
        Axis::Z => ffi::StepAxis::Z,
    };
    let mut out = ffi::FfiStep {
        kind: ffi::StepKind::Fixed,
        axis: ffi::StepAxis::X,
        amount: ffi_amount(&Affine::constant(0.0), free_index)?,
        rotation: [0.0; 9],
        translation: [0.0; 3],
    };
    match step {
        Step::Fixed(pose) => {
            for (i, row) in pose.rotation.iter().enumerate() {
                out.rotation[3 * i..3 * i + 3].copy_from_slice(row);
            }
            out.translation = pose.translation;
        }
        Step::Rotate(a, amount) | Step::Translate(a, amount) => {
            out.kind = if matches!(step, Step::Rotate(..)) {
                ffi::StepKind::Rotate
            } else {
                ffi::StepKind::Translate
            };
            out.axis = axis(a);
            out.amount = ffi_amount(amount, free_index)?;
        }
    }
    Ok(out)
}

/// The projection over the free parameters.
fn ffi_projection(
    projection: &Projection,
    free_index: &[Option<usize>; PARAMETER_COUNT],
) -> Result<ffi::FfiProjection, SolveError> {
    let a = |x: &Affine| ffi_amount(x, free_index);
    Ok(ffi::FfiProjection {
        fx: a(&projection.fx)?,
        fy: a(&projection.fy)?,
        cx: a(&projection.cx)?,
        cy: a(&projection.cy)?,
        k1: a(&projection.k1)?,
        k2: a(&projection.k2)?,
        p1: projection.p1,
        p2: projection.p2,
        k3: projection.k3,
        distorted: projection.is_distorted(),
    })
}

/// Ships a problem across the bridge: chains with the held parameters frozen, parameter
/// indices among [`Problem::free`], vertices, whitening and the cameras' projections.
fn to_ffi(problem: &Problem) -> Result<ffi::FfiProblem, SolveError> {
    let free = problem.free();
    let mut free_index = [None; PARAMETER_COUNT];
    for (i, p) in free.iter().enumerate() {
        free_index[p.index()] = Some(i);
    }
    let frozen = problem.frozen_chains();
    // Every vector at its final size at once: grown step by step, the weights (some
    // hundred kB) would be copied and their fresh pages touched several times over.
    let steps: usize = frozen
        .iter()
        .map(|c| c.camera.steps().len() + c.board.steps().len())
        .sum();
    let weights: usize = problem
        .captures
        .iter()
        .map(|term| match &term.whitening {
            None => 0,
            Some(Whitening::Dense(w)) => w.len(),
            Some(Whitening::LowRank { u, shrink, .. }) => 1 + u.len() + shrink.len(),
        })
        .sum();
    let mut out = ffi::FfiProblem {
        params: free.iter().map(|p| problem.initial[p.index()]).collect(),
        param_block: free.iter().map(|p| p.group().id()).collect(),
        steps: Vec::with_capacity(steps),
        captures: Vec::with_capacity(problem.captures.len()),
        points: Vec::with_capacity(3 * problem.observation_count()),
        pixels: Vec::with_capacity(2 * problem.observation_count()),
        weights: Vec::with_capacity(weights),
        projections: Vec::new(),
    };
    // The distinct projections (one per camera), each shipped once.
    let mut projections: Vec<Projection> = Vec::new();
    for (term, chains) in problem.captures.iter().zip(frozen) {
        let projection = match projections.iter().position(|p| *p == chains.projection) {
            Some(k) => k,
            None => {
                out.projections
                    .push(ffi_projection(&chains.projection, &free_index)?);
                projections.push(chains.projection);
                projections.len() - 1
            }
        };
        let first_step = count(out.steps.len(), "steps")?;
        for step in chains.camera.steps().iter().chain(chains.board.steps()) {
            out.steps.push(ffi_step(step, &free_index)?);
        }
        let first_vertex = count(out.pixels.len() / 2, "vertices")?;
        for o in &term.observations {
            out.points.extend_from_slice(&o.point);
            out.pixels.extend_from_slice(&o.pixel);
        }
        let (first_weight, whitening_rank) = match &term.whitening {
            None => (-1, -1),
            Some(w) => {
                let k = term.residual_count();
                if w.size() != k || !w.is_well_formed() {
                    return Err(backend_error(format!(
                        "capture {}: the whitening matrix is not a finite {k}×{k} matrix",
                        term.capture
                    )));
                }
                let first = out.weights.len() as i64;
                match w {
                    Whitening::Dense(w) => {
                        out.weights
                            .extend((0..k).flat_map(|i| (0..k).map(move |j| w[(i, j)])));
                        (first, -1)
                    }
                    Whitening::LowRank { u, shrink, scale } => {
                        let q = u.ncols();
                        out.weights.push(*scale);
                        out.weights
                            .extend((0..k).flat_map(|i| (0..q).map(move |c| u[(i, c)])));
                        out.weights.extend(shrink.iter());
                        (
                            first,
                            i32::try_from(q).map_err(|_| {
                                backend_error(String::from("too many whitening directions"))
                            })?,
                        )
                    }
                }
            }
        };
        out.captures.push(ffi::FfiCapture {
            first_step,
            camera_steps: count(chains.camera.steps().len(), "steps")?,
            board_steps: count(chains.board.steps().len(), "steps")?,
            projection: count(projection, "projections")?,
            first_vertex,
            vertex_count: count(term.observations.len(), "vertices")?,
            first_weight,
            whitening_rank,
        });
    }
    Ok(out)
}
