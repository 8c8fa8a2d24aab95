//! The calibration pipeline ([`calibrate`]) as a sequence of named stages, each in its own
//! file and each handing the next a small value (docs/MODEL.md §11, "The pipeline"):
//!
//! 1. [`hold`]: find the undetermined parameters and hold them (§10) → [`hold::Posed`];
//! 2. [`robust`]: with a robust loss, the robust fit and its outliers left out (§11, step 2)
//!    → [`robust::Robust`];
//! 3. [`plain`]: the plain least-squares fit, linearised once → [`Point`];
//! 4. [`screening`]: the misfit tests at it, and with the noise model on the whitened fit
//!    and its tests (§11) → [`screening::Screened`];
//! 5. [`weighting`]: the noise model's rounds and whether the noise model is kept (§9)
//!    → [`weighting::Weighted`];
//! 6. [`assemble`]: the statistics from one Jacobian at the final point, the [`Solution`]
//!    and the optional bootstrap (§9).
//!
//! [`auto`] chooses the families for [`ModelChoice::Auto`] (§11, `--model auto`) and then
//! runs the same stages.

mod assemble;
mod auto;
mod hold;
mod plain;
mod robust;
mod screening;
mod weighting;

use std::rc::Rc;
use std::time::Instant;

pub use robust::OUTLIER_SIGMAS;

use super::backend::Fit;
use super::linearisation::Linearisation;
use super::{Backend, FamilyTest, Problem, Solution, SolveError, misfit, noise};
use crate::model::{PARAMETER_COUNT, Param};

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

/// The whole identification phase (the one public entry point): validates the problem,
/// holds undetermined parameters, fits (robustly first with a loss), tests whether the
/// model fits ([`misfit`]), weights by the noise model when the residuals are noise, and
/// builds the [`Solution`] once from what the fits produced. With [`ModelChoice::Auto`] it
/// first chooses the families the data support.
pub fn calibrate(
    problem: &Problem,
    backend: &dyn Backend,
    options: &UncertaintyOptions,
) -> Result<Solution, SolveError> {
    match options.model {
        ModelChoice::Given => calibrate_given(problem, backend, options),
        ModelChoice::Auto => auto::select_model(problem, backend, options),
    }
}

/// [`ModelChoice::Given`]: the calibration of the problem's free parameters, stage by stage.
fn calibrate_given(
    problem: &Problem,
    backend: &dyn Backend,
    options: &UncertaintyOptions,
) -> Result<Solution, SolveError> {
    let start = Instant::now();
    super::validate(problem)?;
    // 1–3: the posed problem, outliers left out, its plain fit.
    let hold::Posed {
        problem: posed,
        undetermined,
        held,
    } = hold::hold_undetermined(problem)?;
    let robust = robust::robust_stage(posed, backend)?;
    let points = Points::new(&robust.inliers, &held);
    let plain = plain::plain_fit(&points, backend)?;
    // 4–5: are the residuals noise, and is the noise model kept?
    let any_significant = |tests: &[FamilyTest]| tests.iter().any(|t| t.significant);
    let screened =
        screening::misfit_tests(&points, &plain, &held, backend, options, &any_significant)?;
    let weighted = weighting::weigh(&points, &plain, screened, backend, options)?;
    // 6: statistics at the final point, the solution, the bootstrap.
    let mut solution = assemble::solution(
        problem,
        undetermined,
        &robust,
        &plain,
        weighted,
        backend,
        options,
    )?;
    solution.seconds = start.elapsed().as_secs_f64();
    Ok(solution)
}

/// A fit and the linearisation of the posed problem at its values: what the stages after
/// a fit read (the tests, the noise estimate, the RMS, the statistics), evaluated once.
#[derive(Debug, Clone)]
struct Point {
    fit: Fit,
    /// Shared where two fits are at the same values: a whitened fit that stayed at the
    /// plain fit has the plain fit's linearisation.
    at: Rc<Linearisation>,
}

/// How the posed problem is linearised at the points the pipeline visits: over the fitted
/// parameters, the candidates of the misfit tests and the joint offsets (the noise model's
/// columns), so that one evaluation per point serves every stage.
struct Points<'p> {
    /// The problem as fitted by the plain stage (undetermined parameters held, outliers
    /// left out).
    problem: &'p Problem,
    columns: Vec<Param>,
}

impl<'p> Points<'p> {
    /// For `problem` with the undetermined parameters `held`.
    fn new(problem: &'p Problem, held: &[bool; PARAMETER_COUNT]) -> Self {
        let mut columns = misfit::tested_columns(problem, held);
        for p in noise::joint_offsets() {
            if !columns.contains(&p) {
                columns.push(p);
            }
        }
        Points { problem, columns }
    }

    /// `fit` with its linearisation, evaluated here unless `near` (a point already
    /// linearised) is at the same values.
    fn linearise(&self, fit: Fit, near: Option<&Point>) -> Result<Point, SolveError> {
        if let Some(p) = near
            && p.at.values() == &fit.values
        {
            return Ok(Point {
                fit,
                at: p.at.clone(),
            });
        }
        let at = Linearisation::at(self.problem, self.columns.clone(), &fit.values)
            .ok_or_else(|| SolveError::Invalid("a fit puts a vertex behind the camera".into()))?;
        Ok(Point {
            fit,
            at: Rc::new(at),
        })
    }
}
