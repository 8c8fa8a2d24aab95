//! Solving the calibration: the [`Problem`], the backends, and the [`Solution`] with its
//! uncertainty.
//!
//! Every backend turns a [`Problem`] into a [`BackendResult`]; [`solve`] then adds what
//! does not depend on the backend (residual statistics, scaled covariance, std), so that the
//! report sees a solution, not a solver.

#[cfg(feature = "ceres")]
pub mod ceres;
pub mod compare;
pub mod covariance;
pub mod jacobian;
pub mod lm;
pub mod noise;
pub mod problem;
pub mod tiny;
pub mod uncertainty;

use std::time::Instant;

use nalgebra::DMatrix;

use crate::model::{FixedSet, PARAMETER_COUNT, Param};
pub use problem::{CaptureTerm, Loss, Observation, Problem, Tolerances, Whitening};

/// Why a solve could not be done.
#[derive(Debug, thiserror::Error)]
pub enum SolveError {
    /// The problem cannot be solved as posed (checked before any backend runs).
    #[error("{0}")]
    Invalid(String),
    /// The backend itself failed (a C++ exception, a numerical failure).
    #[error("{solver} failed: {message}")]
    Backend {
        /// Which backend.
        solver: String,
        /// What it said.
        message: String,
    },
}

/// The optimiser's account of a run.
#[derive(Debug, Clone, PartialEq)]
pub struct Summary {
    /// Backend name (`ceres`, …).
    pub solver: String,
    /// Whether the backend reports convergence.
    pub converged: bool,
    /// Iterations taken.
    pub iterations: usize,
    /// `½‖r‖²` at the start (weighted residuals, robust loss applied).
    pub initial_cost: f64,
    /// `½‖r‖²` at the end.
    pub final_cost: f64,
    /// The backend's termination reason, in its words.
    pub termination: String,
    /// Wall time of the optimisation and covariance [s].
    pub seconds: f64,
}

/// What a backend returns.
#[derive(Debug, Clone, PartialEq)]
pub struct BackendResult {
    /// Final values of the free parameters (order of [`Problem::free`]), internal units.
    pub free_values: Vec<f64>,
    /// `(JᵀJ)⁻¹` (pseudo-inverse) of the weighted problem over the free parameters, not yet
    /// scaled by the residual variance; `None` when it could not be computed.
    pub covariance: Option<DMatrix<f64>>,
    /// The run's summary.
    pub summary: Summary,
}

/// A least-squares solver that can run a [`Problem`].
pub trait Backend {
    /// Short name, as in `--solver` and the result JSON.
    fn name(&self) -> &'static str;
    /// Solves the problem from its initial values.
    fn solve(&self, problem: &Problem) -> Result<BackendResult, SolveError>;
    /// Like [`Backend::solve`], but the covariance may be left out (`None`): for fits whose
    /// uncertainty nobody reads (the first fits before the noise model, bootstrap refits).
    fn solve_values(&self, problem: &Problem) -> Result<BackendResult, SolveError> {
        self.solve(problem)
    }
}

/// Names of the available backends, the default first.
pub fn backend_names() -> Vec<&'static str> {
    let mut names = Vec::new();
    if cfg!(feature = "ceres") {
        names.push("ceres");
    }
    names.extend(["lm", "tiny"]);
    names
}

/// The backend called `name` (see [`backend_names`]); `verbose` lets it log progress.
pub fn backend(name: &str, verbose: bool) -> Option<Box<dyn Backend>> {
    let _ = verbose;
    match name {
        #[cfg(feature = "ceres")]
        "ceres" => Some(Box::new(ceres::Ceres { verbose })),
        "lm" => Some(Box::new(lm::MinpackLm)),
        "tiny" => Some(Box::new(tiny::Tiny)),
        _ => None,
    }
}

/// A calibration result: parameters with their uncertainty, and how well the model fits.
#[derive(Debug, Clone, PartialEq)]
pub struct Solution {
    /// The optimiser's summary.
    pub summary: Summary,
    /// All parameter values, internal units (rad / mm).
    pub values: [f64; PARAMETER_COUNT],
    /// One-sigma uncertainty of every parameter, internal units; 0 for held parameters.
    pub std: [f64; PARAMETER_COUNT],
    /// Covariance of all parameters (PARAMETER_COUNT²), internal units; zero rows and
    /// columns for held parameters.
    pub covariance: DMatrix<f64>,
    /// Which parameters were held fixed.
    pub fixed: FixedSet,
    /// RMS of the unweighted residuals in u and v [px] at the solution.
    pub rms_px: [f64; 2],
    /// RMS in u and v at the start values [px].
    pub initial_rms_px: [f64; 2],
    /// Number of observed vertices.
    pub observations: usize,
    /// Number of captures with at least one vertex.
    pub captures: usize,
    /// Estimated residual variance `σ̂² = 2·cost / (m − n)` of the weighted residuals.
    pub residual_variance: f64,
    /// Wall time of the whole solve including the statistics [s].
    pub seconds: f64,
    /// Every observed vertex's residual (projection − observation) before and after.
    pub residuals: Vec<VertexResidual>,
    /// The noise levels the uncertainty is based on (estimated or given); `None` when the
    /// plain `σ̂²(JᵀJ)⁻¹` was used.
    pub noise: Option<noise::NoiseLevels>,
    /// One-sigma from the capture-clustered sandwich (internal units), beside `std`.
    pub sandwich_std: Option<[f64; PARAMETER_COUNT]>,
    /// One-sigma from the capture bootstrap, when asked for.
    pub bootstrap: Option<BootstrapStd>,
    /// What the data determine, and what not.
    pub identifiability: uncertainty::Identifiability,
    /// Vertices the robust first fit flagged as outliers and left out (with `--loss`).
    pub outliers: Vec<Outlier>,
}

/// A vertex whose residual after the robust fit is far beyond the noise.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Outlier {
    /// The capture id.
    pub capture: u64,
    /// Which vertex.
    pub vertex: crate::model::Vertex,
    /// Its `(u, v)` residual at the robust fit [px].
    pub residual: [f64; 2],
}

/// Residual norms beyond this many robust standard deviations mark an outlier.
pub const OUTLIER_SIGMAS: f64 = 5.0;

/// The capture bootstrap's one-sigma.
#[derive(Debug, Clone, PartialEq)]
pub struct BootstrapStd {
    /// One-sigma of every parameter, internal units.
    pub std: [f64; PARAMETER_COUNT],
    /// Refits done.
    pub replicates: usize,
    /// Refits that failed or did not converge (left out).
    pub failed: usize,
}

impl Solution {
    /// Whether the data determine `p` (a held parameter counts as determined).
    pub fn is_determined(&self, p: Param) -> bool {
        self.identifiability
            .determined
            .get(p.index())
            .copied()
            .unwrap_or(true)
    }
}

/// The residual of one observed vertex at the start values and at the solution [px].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VertexResidual {
    /// The capture id.
    pub capture: u64,
    /// Which vertex.
    pub vertex: crate::model::Vertex,
    /// `(u, v)` residual at the start values.
    pub initial: [f64; 2],
    /// `(u, v)` residual at the solution.
    pub solved: [f64; 2],
}

impl Solution {
    /// Value of one parameter in report units (deg / mm).
    pub fn report_value(&self, p: Param) -> f64 {
        p.unit().to_report(self.values[p.index()])
    }

    /// One-sigma of one parameter in report units (deg / mm).
    pub fn report_std(&self, p: Param) -> f64 {
        p.unit().to_report(self.std[p.index()])
    }
}

/// Lets the C allocator keep freed memory for reuse instead of handing it back to the
/// operating system: every fit allocates and frees the same large buffers (Ceres' dense
/// Jacobian and factorisation, the Rust Jacobians), and mapping them afresh each time costs
/// page faults worth ~20% of a solve (backend bench 12.2 → 9.6 ms). Affects the whole
/// process, which keeps up to 256 MB of freed memory; the CLI calls it at start, and a
/// program that solves many problems may too. Does nothing outside glibc.
pub fn retain_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only changes glibc malloc's tuning; it may be called at any time.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 64 << 20);
        libc::mallopt(libc::M_TRIM_THRESHOLD, 256 << 20);
    }
}

/// Checks that a problem can be handed to a backend: enough residuals for the free
/// parameters, every vertex in front of the camera at the start values, sane numbers.
pub fn validate(problem: &Problem) -> Result<(), SolveError> {
    let free = problem.free().len();
    if free == 0 {
        return Err(SolveError::Invalid(
            "every parameter is held fixed: nothing to solve".into(),
        ));
    }
    let m = problem.residual_count();
    if m <= free {
        return Err(SolveError::Invalid(format!(
            "too few corners: {} vertices give {m} residuals, but {free} parameters are free \
             (need more than {free} residuals)",
            problem.observation_count()
        )));
    }
    if problem.initial.iter().any(|v| !v.is_finite()) {
        return Err(SolveError::Invalid(
            "a start value is not a finite number".into(),
        ));
    }
    for c in &problem.captures {
        if c.observations
            .iter()
            .any(|o| o.pixel.iter().chain(&o.point).any(|x| !x.is_finite()))
        {
            return Err(SolveError::Invalid(format!(
                "capture {}: an observation is not a finite number",
                c.capture
            )));
        }
        if c.residuals(&problem.camera, &problem.initial).is_none() {
            return Err(SolveError::Invalid(format!(
                "capture {}: a vertex of the {} lies behind the camera at the start values; \
                 check the joint angles and the board column of this capture",
                c.capture, "board"
            )));
        }
        if let Some(w) = &c.whitening
            && (w.size() != c.residual_count() || !w.is_well_formed())
        {
            return Err(SolveError::Invalid(format!(
                "capture {}: the whitening matrix is not a finite {}×{} matrix",
                c.capture,
                c.residual_count(),
                c.residual_count()
            )));
        }
    }
    Ok(())
}

/// Solves `problem` with `backend` and derives the statistics of the result.
pub fn solve(problem: &Problem, backend: &dyn Backend) -> Result<Solution, SolveError> {
    let mut solution = optimise(problem, backend)?;
    add_statistics(problem, problem, &mut solution);
    Ok(solution)
}

/// The fit alone: values, summary, RMS at the solution and the scaled covariance, without
/// the per-vertex residuals, the RMS at the start, the identifiability report and the
/// sandwich (see [`add_statistics`]).
/// Intermediate fits and bootstrap refits need no more.
pub fn optimise(problem: &Problem, backend: &dyn Backend) -> Result<Solution, SolveError> {
    optimise_with(problem, backend, true)
}

/// [`optimise`], with the covariance only if `covariance` (else zero `std`).
fn optimise_with(
    problem: &Problem,
    backend: &dyn Backend,
    covariance: bool,
) -> Result<Solution, SolveError> {
    let start = Instant::now();
    validate(problem)?;
    let result = if covariance {
        backend.solve(problem)?
    } else {
        backend.solve_values(problem)?
    };
    let free = problem.free();
    if result.free_values.len() != free.len() {
        return Err(SolveError::Backend {
            solver: backend.name().into(),
            message: format!(
                "returned {} values for {} free parameters",
                result.free_values.len(),
                free.len()
            ),
        });
    }
    let values = problem.expand(&result.free_values);
    let rms_px = problem.rms(&values).ok_or_else(|| SolveError::Backend {
        solver: backend.name().into(),
        message: "the solution puts a vertex behind the camera".into(),
    })?;
    let dof = problem.residual_count().saturating_sub(free.len()).max(1);
    let residual_variance = 2.0 * result.summary.final_cost / dof as f64;
    let covariance = covariance::embed(
        &free,
        &result
            .covariance
            .clone()
            .unwrap_or_else(|| DMatrix::zeros(free.len(), free.len())),
        residual_variance,
    );
    let std = std::array::from_fn(|i| covariance[(i, i)].max(0.0).sqrt());
    Ok(Solution {
        summary: result.summary,
        values,
        std,
        covariance,
        fixed: problem.fixed.clone(),
        rms_px,
        initial_rms_px: [f64::NAN; 2],
        observations: problem.observation_count(),
        captures: problem.captures.len(),
        residual_variance,
        seconds: start.elapsed().as_secs_f64(),
        residuals: Vec::new(),
        noise: None,
        sandwich_std: None,
        bootstrap: None,
        identifiability: uncertainty::Identifiability::default(),
        outliers: Vec::new(),
    })
}

/// Adds to a fit of `fitted` (the problem as solved, perhaps whitened) the statistics that
/// do not depend on the backend: the identifiability report and the sandwich covariance
/// (from one Jacobian of `fitted`), and every vertex's residual before (at `original`'s
/// start values) and after.
pub fn add_statistics(fitted: &Problem, original: &Problem, solution: &mut Solution) {
    let start = Instant::now();
    let free_values: Vec<f64> = fitted
        .free()
        .iter()
        .map(|p| solution.values[p.index()])
        .collect();
    let (identifiability, sandwich) =
        uncertainty::statistics(fitted, &free_values, &solution.covariance);
    solution.identifiability = identifiability;
    solution.sandwich_std = sandwich.map(|c| std::array::from_fn(|i| c[(i, i)].max(0.0).sqrt()));
    solution.residuals = vertex_residuals(original, &solution.values);
    solution.initial_rms_px = initial_rms(&solution.residuals);
    solution.seconds += start.elapsed().as_secs_f64();
}

/// Rounds of (estimate the noise, whitened refit) after the first fit.
const NOISE_ROUNDS: usize = 2;

/// How [`calibrate`] arrives at the reported uncertainty.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UncertaintyOptions {
    /// Whiten each capture with the pixel + joint noise model (SPEC section 8). When off,
    /// the plain `σ̂²(JᵀJ)⁻¹` is reported, which is over-confident under joint noise.
    pub noise_model: bool,
    /// Given noise levels; missing ones are estimated from the residuals.
    pub noise: noise::NoiseOptions,
    /// Capture-bootstrap refits (0: none).
    pub bootstrap: usize,
    /// Seed of the bootstrap's resampling.
    pub seed: u64,
}

impl Default for UncertaintyOptions {
    fn default() -> Self {
        UncertaintyOptions {
            noise_model: true,
            noise: noise::NoiseOptions::default(),
            bootstrap: 0,
            seed: 1,
        }
    }
}

/// The whole identification phase: a first least-squares fit from the start values, then
/// (with the noise model) the noise levels from its residuals, and a second fit whitened
/// by each capture's residual covariance, whose covariance is the reported uncertainty.
pub fn calibrate(
    problem: &Problem,
    backend: &dyn Backend,
    options: &UncertaintyOptions,
) -> Result<Solution, SolveError> {
    if problem.loss != Loss::Squared {
        return calibrate_robust(problem, backend, options);
    }
    let (mut solution, last) = fit(problem, backend, options)?;
    if options.bootstrap > 0 {
        let (std, failed) = uncertainty::bootstrap(
            last.as_ref().unwrap_or(problem),
            &solution,
            backend,
            options.bootstrap,
            options.seed,
        )?;
        solution.bootstrap = Some(BootstrapStd {
            std,
            replicates: options.bootstrap,
            failed,
        });
    }
    Ok(solution)
}

/// With a robust loss: a robust fit, then the vertices far beyond the robust residual scale
/// are flagged as outliers and left out, and the rest is calibrated as usual (noise model,
/// whitening), so the reported uncertainty stays that of a least-squares fit to inliers.
fn calibrate_robust(
    problem: &Problem,
    backend: &dyn Backend,
    options: &UncertaintyOptions,
) -> Result<Solution, SolveError> {
    let mut robust = optimise(problem, backend)?;
    robust.residuals = vertex_residuals(problem, &robust.values);
    let mut coords: Vec<f64> = robust
        .residuals
        .iter()
        .flat_map(|r| r.solved.map(f64::abs))
        .collect();
    coords.sort_by(f64::total_cmp);
    let sigma = 1.4826 * coords.get(coords.len() / 2).copied().unwrap_or(0.0);
    let limit = OUTLIER_SIGMAS * sigma;
    let outliers: Vec<Outlier> = robust
        .residuals
        .iter()
        .filter(|r| r.solved[0].hypot(r.solved[1]) > limit)
        .map(|r| Outlier {
            capture: r.capture,
            vertex: r.vertex,
            residual: r.solved,
        })
        .collect();
    let mut inliers = problem.clone();
    inliers.loss = Loss::Squared;
    inliers.initial = robust.values;
    for term in &mut inliers.captures {
        let id = term.capture;
        term.observations.retain(|o| {
            !outliers
                .iter()
                .any(|x| x.capture == id && x.vertex == o.vertex)
        });
    }
    inliers.captures.retain(|t| !t.observations.is_empty());
    let mut solution = calibrate(&inliers, backend, options)?;
    solution.initial_rms_px = initial_rms(&robust.residuals);
    solution.summary.iterations += robust.summary.iterations;
    solution.summary.seconds += robust.summary.seconds;
    solution.outliers = outliers;
    Ok(solution)
}

/// The fits of [`calibrate`]; also returns the last whitened problem, if any.
fn fit(
    problem: &Problem,
    backend: &dyn Backend,
    options: &UncertaintyOptions,
) -> Result<(Solution, Option<Problem>), SolveError> {
    let start = Instant::now();
    let plain = !options.noise_model || problem.loss != Loss::Squared;
    let mut first = optimise_with(problem, backend, plain)?;
    if plain {
        add_statistics(problem, problem, &mut first);
        return Ok((first, None));
    }
    // The first (unweighted) fit is inefficient under joint noise, and its error looks like
    // joint noise in every capture; so estimate, refit whitened, and estimate once more at
    // the better fit before the final whitened fit.
    let fitted = problem.free().len();
    let mut current = first.clone();
    let mut levels = None;
    let mut last: Option<Problem> = None;
    let mut iterations = first.summary.iterations;
    let mut seconds = first.summary.seconds;
    for round in 0..NOISE_ROUNDS {
        let (estimate, captures) = noise::estimate(problem, &current.values, fitted, options.noise)
            .ok_or_else(|| SolveError::Backend {
                solver: backend.name().into(),
                message: "a fit puts a vertex behind the camera".into(),
            })?;
        if estimate.px <= 0.0 || !estimate.px.is_finite() {
            // A perfect fit (noise-free data): nothing to weight by. Its covariance was
            // skipped; a refit from the solution gives it in an iteration or two.
            let fitted = last.as_ref().unwrap_or(problem);
            let mut at = fitted.clone();
            at.initial = current.values;
            let refit = optimise(&at, backend)?;
            current.covariance = refit.covariance;
            current.std = refit.std;
            current.residual_variance = refit.residual_variance;
            add_statistics(fitted, problem, &mut current);
            return Ok((
                Solution {
                    noise: Some(estimate),
                    ..current
                },
                None,
            ));
        }
        let mut weighted = problem.clone();
        weighted.initial = current.values;
        for (term, cn) in weighted.captures.iter_mut().zip(&captures) {
            term.whitening = Some(cn.whitening(estimate));
        }
        current = optimise_with(&weighted, backend, round + 1 == NOISE_ROUNDS)?;
        last = Some(weighted);
        iterations += current.summary.iterations;
        seconds += current.summary.seconds;
        levels = Some(estimate);
    }
    let mut second = current;
    add_statistics(last.as_ref().unwrap_or(problem), problem, &mut second);
    let estimated = options.noise.px.is_none() || options.noise.joint.is_none();
    if !estimated {
        // Both noise levels given: trust them, do not rescale by the residuals.
        let scale = 1.0 / second.residual_variance;
        second.covariance *= scale;
        second.std = std::array::from_fn(|i| second.covariance[(i, i)].max(0.0).sqrt());
    }
    second.summary.iterations = iterations;
    // Costs as plain least squares (unweighted), like the RMS.
    second.summary.initial_cost = first.summary.initial_cost;
    second.summary.final_cost = 0.5
        * problem
            .residuals(&second.values)
            .map_or(f64::NAN, |r| r.iter().map(|x| x * x).sum::<f64>());
    second.summary.seconds = seconds;
    second.noise = levels;
    second.seconds = start.elapsed().as_secs_f64();
    Ok((second, last))
}

/// RMS in u and v of the residuals at the start values [px] (NaN where undefined).
fn initial_rms(residuals: &[VertexResidual]) -> [f64; 2] {
    let n = residuals.len().max(1) as f64;
    std::array::from_fn(|k| {
        (residuals.iter().map(|r| r.initial[k].powi(2)).sum::<f64>() / n).sqrt()
    })
}

/// Per-vertex residuals at the start values and at `values` (NaN where a vertex is behind
/// the camera, which [`validate`] rules out at the start).
fn vertex_residuals(problem: &Problem, values: &[f64]) -> Vec<VertexResidual> {
    let mut out = Vec::with_capacity(problem.observation_count());
    for term in &problem.captures {
        let before = term.residuals(&problem.camera, &problem.initial);
        let after = term.residuals(&problem.camera, values);
        for (k, obs) in term.observations.iter().enumerate() {
            let pick = |r: &Option<Vec<f64>>| {
                r.as_ref()
                    .map_or([f64::NAN; 2], |r| [r[2 * k], r[2 * k + 1]])
            };
            out.push(VertexResidual {
                capture: term.capture,
                vertex: obs.vertex,
                initial: pick(&before),
                solved: pick(&after),
            });
        }
    }
    out
}
