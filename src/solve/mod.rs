//! Solving the calibration: the [`Problem`], the backends, and the [`Solution`] with its
//! uncertainty and diagnosis.
//!
//! Every backend turns a [`Problem`] into a [`BackendResult`]. [`calibrate`] is the one
//! pipeline: it holds undetermined parameters, fits (robustly first with a loss), tests
//! whether the model fits ([`misfit`]), weights by the noise model when the residuals are
//! noise, and builds the [`Solution`] once from what the fits produced. With
//! [`ModelChoice::Auto`] it first chooses the families the data support.

#[cfg(feature = "ceres")]
pub mod ceres;
pub mod compare;
pub mod covariance;
pub mod identify;
pub mod jacobian;
pub mod lm;
pub mod misfit;
pub mod noise;
pub mod problem;
pub mod tiny;
pub mod uncertainty;

use std::cell::RefCell;
use std::rc::Rc;
use std::time::Instant;

use nalgebra::DMatrix;

use jacobian::Linearisation;

use crate::model::{Family, FixedSet, PARAMETER_COUNT, Param};
pub use identify::Undetermined;
pub use misfit::{FamilyTest, Misfit};
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
    /// Wall time of the optimisation and covariance (s).
    pub seconds: f64,
}

/// What a backend returns.
#[derive(Debug, Clone, PartialEq)]
pub struct BackendResult {
    /// Final values of the free parameters (order of [`Problem::free`]), internal units.
    pub free_values: Vec<f64>,
    /// The run's summary.
    pub summary: Summary,
}

/// A least-squares solver that can run a [`Problem`].
pub trait Backend {
    /// Short name, as in `--solver` and the result JSON.
    fn name(&self) -> &'static str;
    /// Solves the problem from its initial values: the values and the run's summary. The
    /// uncertainty is not the backend's: [`calibrate`] computes it from the Jacobian at the
    /// final fit, the same for every backend.
    fn solve(&self, problem: &Problem) -> Result<BackendResult, SolveError>;
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
    /// RMS of the unweighted residuals in u and v (px) at the solution.
    pub rms_px: [f64; 2],
    /// RMS in u and v at the start values (px).
    pub initial_rms_px: [f64; 2],
    /// Number of observed vertices.
    pub observations: usize,
    /// Number of captures with at least one vertex.
    pub captures: usize,
    /// Estimated residual variance `σ̂² = 2·cost / (m − n)` of the weighted residuals.
    pub residual_variance: f64,
    /// Wall time of the whole solve including the statistics (s).
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
    /// The families with free parameters in this fit.
    pub families: Vec<Family>,
    /// Free parameters the data cannot tell apart from others: held at their nominal value
    /// (zero std, `undetermined` in the JSON), with the combination they form.
    pub undetermined: Vec<Undetermined>,
    /// Whether the model explains the data, and what to free if not.
    pub misfit: Misfit,
    /// With [`ModelChoice::Auto`]: the tests of the families that were freed, in the order
    /// they were chosen.
    pub chosen: Vec<FamilyTest>,
}

/// A vertex whose residual after the robust fit is far beyond the noise.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Outlier {
    /// The capture id.
    pub capture: u64,
    /// Which vertex.
    pub vertex: crate::model::Vertex,
    /// Its `(u, v)` residual at the robust fit (px).
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
        !self.undetermined.iter().any(|u| u.param == p)
            && self
                .identifiability
                .determined
                .get(p.index())
                .copied()
                .unwrap_or(true)
    }

    /// Whether this is a calibration one may use: the optimiser converged to finite
    /// values within the physical bounds ([`Solution::out_of_bounds`]) and the residuals
    /// are within any plausible noise ([`misfit::IMPLAUSIBLE_RMS_PX`]).
    pub fn is_calibration(&self) -> bool {
        self.summary.converged
            && self.values.iter().all(|v| v.is_finite())
            && self.rms_px.iter().all(|r| *r <= misfit::IMPLAUSIBLE_RMS_PX)
            && self.out_of_bounds().is_empty()
    }

    /// The parameters whose value is outside its physical bound
    /// ([`crate::model::bounds`]): such a fit is no calibration, whatever its residuals.
    pub fn out_of_bounds(&self) -> Vec<crate::model::bounds::Violation> {
        crate::model::bounds::violations_internal(&self.values, Some(&self.std), Param::ALL)
    }
}

/// The residual of one observed vertex at the start values and at the solution (px).
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

/// The whitened fit may not end with an RMS (u and v together) beyond this multiple of the
/// plain fit's: the noise model weights noise and must not trade the fit for it. Under real
/// joint noise a whitened fit of few captures legitimately costs up to about 10 % RMS (the
/// bundled sample: 9 %), so this is a safety net behind the misfit tests, which set the
/// noise model aside first.
const WHITENED_RMS_LIMIT: f64 = 1.25;

/// When the misfit tests flag the residuals, the whitened fit may not end with an RMS
/// beyond this multiple of the plain fit's, or the noise model is set aside.
const MISFIT_RMS_LIMIT: f64 = 1.1;

/// When the misfit tests flag the residuals, each whitened round may take this many
/// iterations (a well-posed fit from the plain fit takes 1–6); one that has not converged
/// by then is wandering after structure it takes for joint noise, and the noise model is
/// set aside (measured on misfitting robots without this cap: 37–101 iterations).
const MISFIT_NOISE_ITERATIONS: usize = 10;

/// Which families are fitted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ModelChoice {
    /// Exactly the problem's free parameters (`--model paper` and `--free`/`--fix`).
    #[default]
    Given,
    /// Start from the problem's free parameters and free, one at a time, the significant
    /// family of the misfit test that explains most of the residuals, until none is
    /// significant (`--model auto`).
    Auto,
}

/// How [`calibrate`] arrives at the model and the reported uncertainty.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UncertaintyOptions {
    /// Whiten each capture with the pixel + joint noise model (docs/MODEL.md). When off,
    /// the plain `σ̂²(JᵀJ)⁻¹` is reported, which is over-confident under joint noise.
    pub noise_model: bool,
    /// Given noise levels; missing ones are estimated from the residuals.
    pub noise: noise::NoiseOptions,
    /// Capture-bootstrap refits (0: none).
    pub bootstrap: usize,
    /// Seed of the bootstrap's resampling.
    pub seed: u64,
    /// Which families are fitted.
    pub model: ModelChoice,
}

impl Default for UncertaintyOptions {
    fn default() -> Self {
        UncertaintyOptions {
            noise_model: true,
            noise: noise::NoiseOptions::default(),
            bootstrap: 0,
            seed: 1,
            model: ModelChoice::Given,
        }
    }
}

impl UncertaintyOptions {
    /// One plain least-squares fit with the textbook `σ̂²(JᵀJ)⁻¹` (`--plain-std`).
    pub fn plain() -> Self {
        UncertaintyOptions {
            noise_model: false,
            ..Default::default()
        }
    }
}

/// One optimiser run, as the pipeline's steps pass it on.
#[derive(Debug, Clone)]
struct Fit {
    /// All parameter values, internal units.
    values: [f64; PARAMETER_COUNT],
    /// The backend's summary.
    summary: Summary,
}

/// Runs `backend` on `problem`: the values; [`calibrate`] computes the covariance once,
/// from the Jacobian its statistics evaluate at the final fit.
fn fit(problem: &Problem, backend: &dyn Backend) -> Result<Fit, SolveError> {
    validate(problem)?;
    let result = backend.solve(problem)?;
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
    let mut summary = result.summary;
    if values.iter().any(|v| !v.is_finite()) {
        // Nothing downstream (residuals, covariance, tests) means anything there, and an
        // eigen-decomposition of non-finite numbers does not end.
        return Err(SolveError::Backend {
            solver: backend.name().into(),
            message: "the fit diverged to non-finite parameter values".into(),
        });
    }
    // A NaN gradient can end a search "converged" at a non-finite cost.
    summary.converged &= summary.final_cost.is_finite();
    Ok(Fit { values, summary })
}

/// The whole identification phase (the one public entry point): see the module docs.
pub fn calibrate(
    problem: &Problem,
    backend: &dyn Backend,
    options: &UncertaintyOptions,
) -> Result<Solution, SolveError> {
    match options.model {
        ModelChoice::Given => calibrate_given(problem, backend, options),
        ModelChoice::Auto => select_model(problem, backend, options),
    }
}

/// [`ModelChoice::Auto`]: frees the family explaining most of the residuals while one's
/// test is significant at [`misfit::AUTO_ALPHA`], then reports the last calibration with
/// the families chosen and why.
fn select_model(
    problem: &Problem,
    backend: &dyn Backend,
    options: &UncertaintyOptions,
) -> Result<Solution, SolveError> {
    let start = Instant::now();
    let mut current = problem.clone();
    let mut chosen: Vec<FamilyTest> = Vec::new();
    // Families whose fit left the physical bounds (crate::model::bounds): not freed.
    let mut rejected: Vec<Family> = Vec::new();
    // Screening: a plain fit (warm-started at the last one) and the tests, per step.
    let Screening {
        mut tests,
        values: mut warm,
        ..
    } = screen(&current, &problem.initial, backend, options, &chosen)?;
    let auto = Family::auto();
    while chosen.len() < auto.len() {
        let Some(test) = next_family(&tests, &chosen, &rejected).cloned() else {
            break;
        };
        let mut trial = current.clone();
        for p in test.family.params() {
            trial.fixed.set(p, false);
        }
        let mut trial_chosen = chosen.clone();
        trial_chosen.push(test.clone());
        // A family is not freed when its screening fit leaves the physical bounds by more
        // than 3 σ (the larger of the plain and the sandwich σ at that fit: a compliance
        // the data cannot pin down before play is free may lie far out and be noise);
        // the final calibration is held to the bounds themselves.
        // A screening fit that fails (diverges) frees nothing either.
        let within = match screen(&trial, &warm, backend, options, &trial_chosen) {
            Ok(Screening { tests, values, std })
                if crate::model::bounds::violations_at_screening(&values, &std, trial.free())
                    .is_empty() =>
            {
                Some((tests, values))
            }
            _ => None,
        };
        match within {
            Some((t, v)) => {
                current = trial;
                chosen = trial_chosen;
                tests = t;
                warm = v;
            }
            None => rejected.push(test.family),
        }
    }
    let solution = calibrate_given(&current, backend, options)?;
    Ok(Solution {
        chosen,
        seconds: start.elapsed().as_secs_f64(),
        ..solution
    })
}

/// What one screening step of [`ModelChoice::Auto`] finds.
struct Screening {
    /// The misfit tests at the screening fit.
    tests: Vec<FamilyTest>,
    /// The screening fit's values.
    values: [f64; PARAMETER_COUNT],
    /// Their σ there: the larger of the plain and the capture-clustered sandwich σ.
    std: [f64; PARAMETER_COUNT],
}

/// One screening step of [`ModelChoice::Auto`]: the plain fit of `problem` (undetermined
/// parameters held, outliers left out with a loss) started at `warm`, the misfit tests
/// at it — with the noise model on, also on the whitened residuals at the whitened fit —
/// and the fit's σ.
fn screen(
    problem: &Problem,
    warm: &[f64; PARAMETER_COUNT],
    backend: &dyn Backend,
    options: &UncertaintyOptions,
    chosen: &[FamilyTest],
) -> Result<Screening, SolveError> {
    let undetermined = identify::undetermined(problem)?;
    let held = identify::mask(&undetermined);
    let mut posed = identify::hold(problem, &undetermined);
    if posed.loss != Loss::Squared {
        posed = robust_stage(&posed, backend)?.0;
    }
    posed.initial = *warm;
    for u in &undetermined {
        posed.initial[u.param.index()] = problem.initial[u.param.index()];
    }
    let first = fit(&posed, backend)?;
    let settled = |tests: &[FamilyTest]| next_family(tests, chosen, &[]).is_some();
    let points = Linearisations::new(&posed, &held);
    let tests = misfit_tests(&points, &first, &held, backend, options, &settled)?.tests;
    let stats = uncertainty::statistics(&posed, &*points.at(&first.values)?, None)?;
    let std = std::array::from_fn(|i| {
        stats.covariance[(i, i)]
            .max(stats.sandwich[(i, i)])
            .max(0.0)
            .sqrt()
    });
    Ok(Screening {
        tests,
        values: first.values,
        std,
    })
}

/// The family [`ModelChoice::Auto`] frees next: of those not `chosen` (nor `rejected` for
/// a fit beyond the physical bounds) whose test is
/// significant at [`misfit::AUTO_ALPHA`] (Bonferroni over the tests), the one explaining
/// most of the residuals.
fn next_family<'t>(
    tests: &'t [FamilyTest],
    chosen: &[FamilyTest],
    rejected: &[Family],
) -> Option<&'t FamilyTest> {
    let level = misfit::AUTO_ALPHA / tests.len().max(1) as f64;
    tests
        .iter()
        .filter(|t| {
            t.p_value < level
                && t.family.info().auto
                && !chosen.iter().any(|c| c.family == t.family)
                && !rejected.contains(&t.family)
        })
        .max_by(|a, b| a.explained_px2.total_cmp(&b.explained_px2))
}

/// The misfit tests after the plain fit `values` of `posed`: on its plain residuals there,
/// and with the noise model on, on the residuals whitened by the levels estimated there, at
/// the fit of that whitened problem (see [`misfit::combined_tests`]). Each score test runs
/// at the estimate for the weights it uses: at the plain fit, which joint noise makes
/// inefficient, the whitened residuals kept a nonlinear remainder of its error that the
/// play test took for play in one run in four from planned stances (README, planning
/// section). Returns the tests, the whitening and the whitened fit (the noise model's first
/// round, for [`noise_model`] to reuse).
///
/// When the plain tests alone (their p-values doubled, as [`misfit::combined_tests`] counts
/// them) already decide what the caller decides — `settled` — no whitening is made: a
/// noise model fitted to residuals that hold structure takes it for joint noise, and its
/// whitened fit then wanders (measured: 37–101 iterations, 0.3–0.6 s per screening step
/// of `--model auto` on a realistic robot, against 5–8 for the plain fit).
fn misfit_tests(
    points: &Linearisations,
    first: &Fit,
    held: &[bool; PARAMETER_COUNT],
    backend: &dyn Backend,
    options: &UncertaintyOptions,
    settled: &dyn Fn(&[FamilyTest]) -> bool,
) -> Result<Screened, SolveError> {
    let posed = points.problem;
    let values = &first.values;
    let at = points.at(values)?;
    let rms = at.rms();
    let rounding = rms[0].max(rms[1]) < misfit::ROUNDING_RMS_PX;
    let plain = if rounding {
        // Residuals of rounding size hold nothing to test (their structure is the
        // optimiser's last step, not the data's).
        Vec::new()
    } else {
        misfit::family_tests_at(posed, &at, held)
    };
    if options.noise_model {
        let alone = misfit::combined_tests(plain.clone(), Vec::new());
        if settled(&alone) {
            return Ok(Screened {
                tests: alone,
                whitened: None,
                weighted: None,
            });
        }
    }
    let whitened = if options.noise_model {
        whiten(points, values, options)?
    } else {
        None
    };
    let Some((w, _)) = &whitened else {
        return Ok(Screened {
            tests: plain,
            whitened: None,
            weighted: None,
        });
    };
    let (weighted, whitened_tests) = whitened_fit(points, w, first, held, backend)?;
    let tests = misfit::combined_tests(plain, whitened_tests);
    Ok(Screened {
        tests,
        whitened,
        weighted: Some(weighted),
    })
}

/// The fit of `whitened` (the problem weighted by the noise model estimated at the plain
/// fit `plain`, started there) and the whitened misfit tests at it. When the Gauss–Newton
/// step of the whitened problem from the plain fit is at most [`WHITENED_STEP_SIGMAS`]
/// standard deviations long, the plain fit is the whitened fit's optimum to that
/// precision, and the backend is not called. (On data without joint noise the whitened
/// problem is the plain one up to a scale, and a backend run from its optimum took one
/// iteration that changed nothing.)
fn whitened_fit(
    points: &Linearisations,
    whitened: &Problem,
    plain: &Fit,
    held: &[bool; PARAMETER_COUNT],
    backend: &dyn Backend,
) -> Result<(Fit, Vec<FamilyTest>), SolveError> {
    let at = points.at(&plain.values)?;
    if let Some(step) = uncertainty::gauss_newton_step(whitened, &at)
        && step.sigmas <= WHITENED_STEP_SIGMAS
    {
        let summary = Summary {
            iterations: 0,
            initial_cost: step.cost,
            final_cost: step.cost,
            seconds: 0.0,
            ..plain.summary.clone()
        };
        let fit = Fit {
            values: plain.values,
            summary,
        };
        return Ok((fit, misfit::family_tests_at(whitened, &at, held)));
    }
    let weighted = fit(whitened, backend)?;
    let at = points.at(&weighted.values)?;
    Ok((weighted, misfit::family_tests_at(whitened, &at, held)))
}

/// A whitened fit whose Gauss–Newton step from the plain fit is at most this many standard
/// deviations long (every parameter within this fraction of its σ) is the plain fit: see
/// [`whitened_fit`].
const WHITENED_STEP_SIGMAS: f64 = 1e-3;

/// The misfit tests with what the noise rounds reuse (see [`misfit_tests`]).
struct Screened {
    tests: Vec<FamilyTest>,
    /// The problem whitened by the levels estimated at the plain fit, and those levels.
    whitened: Option<(Problem, noise::NoiseLevels)>,
    /// The fit of that whitened problem.
    weighted: Option<Fit>,
}

/// The robust first fit (with `--loss`): flags vertices beyond [`OUTLIER_SIGMAS`] robust
/// standard deviations and returns the problem without them, plain least squares, started
/// at the robust solution.
fn robust_stage(
    problem: &Problem,
    backend: &dyn Backend,
) -> Result<(Problem, Vec<Outlier>, Fit), SolveError> {
    let robust = fit(problem, backend)?;
    let residuals = vertex_residuals(problem, &robust.values);
    let mut coords: Vec<f64> = residuals
        .iter()
        .flat_map(|r| r.solved.map(f64::abs))
        .collect();
    coords.sort_by(f64::total_cmp);
    let sigma = 1.4826 * coords.get(coords.len() / 2).copied().unwrap_or(0.0);
    let limit = OUTLIER_SIGMAS * sigma;
    let outliers: Vec<Outlier> = residuals
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
    Ok((inliers, outliers, robust))
}

/// `problem` whitened by the noise model estimated from its residuals at `values`, started
/// there, with the levels; `None` when the residuals are zero (a noise-free fit has
/// nothing to weight by).
fn whiten(
    points: &Linearisations,
    values: &[f64; PARAMETER_COUNT],
    options: &UncertaintyOptions,
) -> Result<Option<(Problem, noise::NoiseLevels)>, SolveError> {
    let problem = points.problem;
    let fitted = problem.free().len();
    let (levels, captures) = noise::estimate_from(&*points.at(values)?, fitted, options.noise);
    if !(levels.px > 0.0 && levels.px.is_finite()) {
        return Ok(None);
    }
    let mut weighted = problem.clone();
    weighted.initial = *values;
    for (term, cn) in weighted.captures.iter_mut().zip(&captures) {
        term.whitening = Some(cn.whitening(levels));
    }
    Ok(Some((weighted, levels)))
}

/// The noise model from the first whitening (estimated at the plain fit): the whitened fit
/// (`done` when made already; with a `budget`, within that many iterations), then the
/// levels estimated again at that efficient fit — a plain fit under joint noise is
/// inefficient and its residuals overstate the joint noise. The result is that fit's values
/// with the second levels' whitening. (Refitting with the
/// second levels, as earlier versions did, moved the estimates by a small fraction of σ:
/// the uncertainty example's σ/scatter ratios stayed within 0.84–1.14 without it, and the
/// default calibration saves a third of its optimiser time.) Returns the fit, its whitened
/// problem, the levels and the iterations.
fn noise_model(
    points: &Linearisations,
    first: (Problem, noise::NoiseLevels),
    done: Option<Fit>,
    backend: &dyn Backend,
    options: &UncertaintyOptions,
    budget: Option<usize>,
) -> Result<(Fit, Problem, noise::NoiseLevels, usize), SolveError> {
    let (mut weighted, levels) = first;
    if let Some(b) = budget {
        weighted.tolerances.max_iterations = weighted.tolerances.max_iterations.min(b);
    }
    let f = match done {
        Some(f) => f,
        None => fit(&weighted, backend)?,
    };
    let iterations = f.summary.iterations;
    if budget.is_some() && !f.summary.converged {
        return Ok((f, weighted, levels, iterations));
    }
    if f.values == weighted.initial {
        // The whitened fit stayed at the plain fit (see [`whitened_fit`]): the levels
        // estimated there are the first ones.
        weighted.tolerances = points.problem.tolerances;
        return Ok((f, weighted, levels, iterations));
    }
    match whiten(points, &f.values, options)? {
        Some((next, levels)) => Ok((f, next, levels, iterations)),
        // The whitened fit leaves no residual: keep its weights.
        None => Ok((f, weighted, levels, iterations)),
    }
}

/// The linearisations of one posed problem at the points a calibration visits (the plain
/// fit, the whitened fit): each point is evaluated once, over every parameter that the
/// misfit tests, the noise estimate and the statistics need, and shared by them — each
/// applies its own weights.
struct Linearisations<'p> {
    problem: &'p Problem,
    columns: Vec<Param>,
    done: RefCell<Vec<Rc<Linearisation>>>,
}

impl<'p> Linearisations<'p> {
    /// For `problem` with the undetermined parameters `held`.
    fn new(problem: &'p Problem, held: &[bool; PARAMETER_COUNT]) -> Self {
        let mut columns = misfit::tested_columns(problem, held);
        for p in noise::joint_offsets() {
            if !columns.contains(&p) {
                columns.push(p);
            }
        }
        Linearisations {
            problem,
            columns,
            done: RefCell::new(Vec::new()),
        }
    }

    /// The linearisation at `values` (full parameter vector), evaluated on first use.
    fn at(&self, values: &[f64; PARAMETER_COUNT]) -> Result<Rc<Linearisation>, SolveError> {
        if let Some(done) = self.done.borrow().iter().find(|l| l.values() == values) {
            return Ok(done.clone());
        }
        let at = Linearisation::at(self.problem, self.columns.clone(), values)
            .map(Rc::new)
            .ok_or_else(|| SolveError::Invalid("a fit puts a vertex behind the camera".into()))?;
        self.done.borrow_mut().push(at.clone());
        Ok(at)
    }
}

/// [`ModelChoice::Given`]: the calibration of the problem's free parameters.
fn calibrate_given(
    problem: &Problem,
    backend: &dyn Backend,
    options: &UncertaintyOptions,
) -> Result<Solution, SolveError> {
    let start = Instant::now();
    validate(problem)?;
    let undetermined = identify::undetermined(problem)?;
    let held = identify::mask(&undetermined);
    let posed = identify::hold(problem, &undetermined);
    let mut iterations = 0;
    let mut optimiser_seconds = 0.0;
    let (posed, outliers, robust) = if posed.loss != Loss::Squared {
        let (inliers, outliers, robust) = robust_stage(&posed, backend)?;
        iterations += robust.summary.iterations;
        optimiser_seconds += robust.summary.seconds;
        (inliers, outliers, Some(robust))
    } else {
        (posed, Vec::new(), None)
    };
    let initial_cost = robust.as_ref().map(|r| r.summary.initial_cost);

    // The plain least-squares fit, and whether its residuals are noise.
    let first = fit(&posed, backend)?;
    iterations += first.summary.iterations;
    optimiser_seconds += first.summary.seconds;
    let points = Linearisations::new(&posed, &held);
    let plain_rms = points.at(&first.values)?.rms();
    let Screened {
        tests,
        whitened,
        weighted: weighted_first,
    } = misfit_tests(&points, &first, &held, backend, options, &|tests| {
        tests.iter().any(|t| t.significant)
    })?;
    let mut verdict = misfit::verdict(tests.clone(), plain_rms, None);

    // The final fit: whitened by the noise model unless that makes the fit worse. When the
    // tests flag a misfit, the noise model gets a well-posed fit's iterations and must keep
    // the plain fit's RMS within MISFIT_RMS_LIMIT; a false alarm under real joint noise
    // then keeps the efficient fit, while structure that the noise model would take for
    // joint noise sets it aside (docs/MODEL.md §9).
    let flagged = verdict.detected;
    let implausible = misfit::implausible_rms(plain_rms);
    let noise_start = match whitened {
        Some(w) => Some(w),
        None if options.noise_model && flagged && !implausible => {
            whiten(&points, &first.values, options)?
        }
        None => None,
    };
    let mut weighted: Option<Problem> = None;
    let mut levels = None;
    let mut last = first.clone();
    match noise_start {
        Some(start) if !implausible => {
            let budget = flagged.then_some(MISFIT_NOISE_ITERATIONS);
            let (f, w, l, its) =
                noise_model(&points, start, weighted_first, backend, options, budget)?;
            iterations += its;
            optimiser_seconds += f.summary.seconds;
            let rms = points.at(&f.values)?.rms();
            let both = |r: [f64; 2]| ((r[0] * r[0] + r[1] * r[1]) / 2.0).sqrt();
            // The joint noise is judged at the whitened fit: a plain fit under joint noise
            // is inefficient, and its residuals overstate the joint noise.
            let joint_deg = options.noise.joint.is_none().then(|| l.joint.to_degrees());
            verdict = misfit::verdict(tests, plain_rms, joint_deg);
            let noisy = misfit::implausible_joint_noise(joint_deg);
            let limit = if flagged {
                MISFIT_RMS_LIMIT
            } else {
                WHITENED_RMS_LIMIT
            };
            let worse = both(rms) > limit * both(plain_rms) + misfit::ROUNDING_RMS_PX;
            if noisy || (flagged && (worse || !f.summary.converged)) {
                verdict.noise_model_set_aside = true;
            } else if worse {
                verdict.detected = true;
                verdict.message = format!(
                    "misfit: weighting by the noise model moves the fit to {:.2} px RMS, \
                     beyond {WHITENED_RMS_LIMIT}× the plain fit's {:.2} px: the residuals \
                     are not joint noise",
                    both(rms),
                    both(plain_rms)
                );
                verdict.noise_model_set_aside = true;
            } else {
                last = f;
                weighted = Some(w);
                levels = Some(l);
            }
        }
        _ if options.noise_model && verdict.detected => verdict.noise_model_set_aside = true,
        _ => {}
    }

    // The covariance and the statistics from one Jacobian of the problem as fitted.
    let sandwich_reported = verdict.noise_model_set_aside || (levels.is_some() && verdict.detected);
    let fitted = weighted.as_ref().unwrap_or(&posed);
    let both_given = options.noise.px.is_some() && options.noise.joint.is_some();
    // Both noise levels given: trust them, do not rescale by the residuals.
    let variance = (levels.is_some() && both_given).then_some(1.0);
    let at_last = points.at(&last.values)?;
    let uncertainty::Statistics {
        mut covariance,
        identifiability,
        sandwich,
        residual_variance,
    } = uncertainty::statistics(fitted, &at_last, variance)?;
    if sandwich_reported {
        // Residuals that may not be noise: the capture-clustered sandwich holds whatever
        // their correlation within a capture.
        covariance = sandwich.clone();
    }
    let std = std::array::from_fn(|i| covariance[(i, i)].max(0.0).sqrt());
    let residuals = vertex_residuals(problem, &last.values);
    let initial_rms_px = initial_rms(&residuals);
    let rms_px = at_last.rms();
    let final_cost = at_last.cost();
    let summary = Summary {
        iterations,
        initial_cost: initial_cost.unwrap_or(first.summary.initial_cost),
        final_cost,
        seconds: optimiser_seconds,
        ..last.summary.clone()
    };
    let mut solution = Solution {
        summary,
        values: last.values,
        std,
        covariance,
        fixed: problem.fixed.clone(),
        rms_px,
        initial_rms_px,
        observations: posed.observation_count(),
        captures: posed.captures.len(),
        residual_variance,
        seconds: 0.0,
        residuals,
        noise: levels,
        sandwich_std: Some(std::array::from_fn(|i| sandwich[(i, i)].max(0.0).sqrt())),
        bootstrap: None,
        identifiability,
        outliers,
        families: posed.fixed.families(),
        undetermined,
        misfit: verdict,
        chosen: Vec::new(),
    };
    if options.bootstrap > 0 {
        let (std, failed) = uncertainty::bootstrap(
            fitted,
            &solution.values,
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
    solution.seconds = start.elapsed().as_secs_f64();
    Ok(solution)
}

/// RMS in u and v of the residuals at the start values (px) (NaN where undefined).
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
