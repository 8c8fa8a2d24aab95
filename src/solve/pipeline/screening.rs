//! Stage 4: whether the plain fit's residuals are noise — the misfit tests on its plain
//! residuals and, with the noise model on, on the whitened residuals at the whitened fit
//! (the noise model's first round, which [`super::weighting`] reuses) (docs/MODEL.md §11,
//! "Two weightings" and "When the plain test already decides").

use super::{Point, Points, UncertaintyOptions};
use crate::model::PARAMETER_COUNT;
use crate::solve::backend::{Fit, fit};
use crate::solve::{Backend, FamilyTest, Problem, SolveError, Summary, misfit, noise, uncertainty};

/// A whitened fit whose Gauss–Newton step from the plain fit is at most this many standard
/// deviations long (every parameter within this fraction of its σ) is the plain fit: see
/// [`whitened_fit`].
const WHITENED_STEP_SIGMAS: f64 = 1e-3;

/// The misfit tests with what the noise rounds reuse.
pub(super) struct Screened {
    /// The tests (combined over the two weightings when both were made).
    pub tests: Vec<FamilyTest>,
    /// The problem whitened by the levels estimated at the plain fit, and those levels;
    /// `None` when no whitening was made.
    pub whitened: Option<(Problem, noise::NoiseLevels)>,
    /// The fit of that whitened problem.
    pub weighted: Option<Point>,
}

/// The misfit tests after the plain fit `plain` of `points`' problem: on its plain
/// residuals there, and with the noise model on, on the residuals whitened by the levels
/// estimated there, at the fit of that whitened problem (see [`misfit::combined_tests`]).
/// Each score test runs at the estimate for the weights it uses.
///
/// When the plain tests alone (their p-values doubled, as [`misfit::combined_tests`] counts
/// them) already decide what the caller decides — `settled` — no whitening is made: a
/// noise model fitted to residuals that hold structure takes it for joint noise, and its
/// whitened fit then wanders.
pub(super) fn misfit_tests(
    points: &Points,
    plain: &Point,
    held: &[bool; PARAMETER_COUNT],
    backend: &dyn Backend,
    options: &UncertaintyOptions,
    settled: &dyn Fn(&[FamilyTest]) -> bool,
) -> Result<Screened, SolveError> {
    let rms = plain.at.rms();
    let rounding = rms[0].max(rms[1]) < misfit::ROUNDING_RMS_PX;
    let plain_tests = if rounding {
        // Residuals of rounding size hold nothing to test (their structure is the
        // optimiser's last step, not the data's).
        Vec::new()
    } else {
        misfit::family_tests_at(points.problem, &plain.at, held)
    };
    if options.noise_model {
        let alone = misfit::combined_tests(plain_tests.clone(), Vec::new());
        if settled(&alone) {
            return Ok(Screened {
                tests: alone,
                whitened: None,
                weighted: None,
            });
        }
    }
    let whitened = if options.noise_model {
        noise::whiten(points.problem, &plain.at, options.noise)
    } else {
        None
    };
    let Some((w, _)) = &whitened else {
        return Ok(Screened {
            tests: plain_tests,
            whitened: None,
            weighted: None,
        });
    };
    let (weighted, whitened_tests) = whitened_fit(points, w, plain, held, backend)?;
    Ok(Screened {
        tests: misfit::combined_tests(plain_tests, whitened_tests),
        whitened,
        weighted: Some(weighted),
    })
}

/// The fit of `whitened` (the problem weighted by the noise model estimated at the plain
/// fit `plain`, started there) and the whitened misfit tests at it. When the Gauss–Newton
/// step of the whitened problem from the plain fit is at most [`WHITENED_STEP_SIGMAS`]
/// standard deviations long, the plain fit is the whitened fit's optimum to that
/// precision, and the backend is not called (docs/MODEL.md §9).
fn whitened_fit(
    points: &Points,
    whitened: &Problem,
    plain: &Point,
    held: &[bool; PARAMETER_COUNT],
    backend: &dyn Backend,
) -> Result<(Point, Vec<FamilyTest>), SolveError> {
    if let Some(step) = uncertainty::gauss_newton_step(whitened, &plain.at)
        && step.sigmas <= WHITENED_STEP_SIGMAS
    {
        let summary = Summary {
            iterations: 0,
            initial_cost: step.cost,
            final_cost: step.cost,
            seconds: 0.0,
            ..plain.fit.summary.clone()
        };
        let stayed = Point {
            fit: Fit {
                values: plain.fit.values,
                summary,
            },
            at: plain.at.clone(),
        };
        let tests = misfit::family_tests_at(whitened, &stayed.at, held);
        return Ok((stayed, tests));
    }
    let weighted = points.linearise(fit(whitened, backend)?, Some(plain))?;
    let tests = misfit::family_tests_at(whitened, &weighted.at, held);
    Ok((weighted, tests))
}
