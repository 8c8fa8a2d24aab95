//! Stage 5: the noise model's rounds, and whether the noise model is kept or set aside
//! (docs/MODEL.md §9, "The noise model" and "When the noise model is set aside").

use super::screening::Screened;
use super::{Point, Points, UncertaintyOptions};
use crate::solve::backend::fit;
use crate::solve::{Backend, Misfit, Problem, SolveError, misfit, noise};

/// The whitened fit may not end with an RMS (u and v together) beyond this multiple of the
/// plain fit's: the noise model weights noise and must not trade the fit for it. A safety
/// net behind the misfit tests, which set the noise model aside first (docs/MODEL.md §9).
const WHITENED_RMS_LIMIT: f64 = 1.25;

/// When the misfit tests flag the residuals, the whitened fit may not end with an RMS
/// beyond this multiple of the plain fit's, or the noise model is set aside.
const MISFIT_RMS_LIMIT: f64 = 1.1;

/// When the misfit tests flag the residuals, each whitened round may take this many
/// iterations (a well-posed fit from the plain fit takes a few); one that has not
/// converged by then is wandering after structure it takes for joint noise, and the noise
/// model is set aside.
const MISFIT_NOISE_ITERATIONS: usize = 10;

/// What the weighting stage hands on.
pub(super) struct Weighted {
    /// The fit whose values are reported: the noise model's when it is kept, else the
    /// plain fit.
    pub last: Point,
    /// With the noise model kept: the problem whitened as fitted, and the noise levels.
    pub kept: Option<(Problem, noise::NoiseLevels)>,
    /// Whether the model explains the data, judged with the noise model's joint level.
    pub verdict: Misfit,
    /// Iterations of the noise model's fit (0 without one).
    pub iterations: usize,
    /// Its optimiser time (s).
    pub seconds: f64,
}

/// One round of the noise model, as [`noise_model`] ends it.
struct Round {
    /// The whitened fit.
    point: Point,
    /// The problem whitened by the levels estimated at that fit (or the first levels, when
    /// it stopped early or stayed at the plain fit), and those levels.
    whitened: Problem,
    levels: noise::NoiseLevels,
}

/// The weighting stage after the plain fit `plain` and the misfit tests `screened`: the
/// final fit is whitened by the noise model unless that makes the fit worse. When the tests
/// flag a misfit, the noise model gets a well-posed fit's iterations and must keep the
/// plain fit's RMS within [`MISFIT_RMS_LIMIT`]; a false alarm under real joint noise then
/// keeps the efficient fit, while structure that the noise model would take for joint
/// noise sets it aside.
pub(super) fn weigh(
    points: &Points,
    plain: &Point,
    screened: Screened,
    backend: &dyn Backend,
    options: &UncertaintyOptions,
) -> Result<Weighted, SolveError> {
    let Screened {
        tests,
        whitened,
        weighted,
    } = screened;
    let plain_rms = plain.at.rms();
    let mut verdict = misfit::verdict(tests.clone(), plain_rms, None);
    let flagged = verdict.detected;
    let implausible = misfit::implausible_rms(plain_rms);
    let start = match whitened {
        Some(w) => Some(w),
        None if options.noise_model && flagged && !implausible => {
            noise::whiten(points.problem, &plain.at, options.noise)
        }
        None => None,
    };
    let mut kept = None;
    let (mut iterations, mut seconds) = (0, 0.0);
    match start {
        Some(start) if !implausible => {
            let budget = flagged.then_some(MISFIT_NOISE_ITERATIONS);
            let round = noise_model(points, plain, start, weighted, backend, options, budget)?;
            iterations = round.point.fit.summary.iterations;
            seconds = round.point.fit.summary.seconds;
            // The joint noise is judged at the whitened fit: a plain fit under joint noise
            // is inefficient, and its residuals overstate the joint noise.
            let joint_deg = options
                .noise
                .joint
                .is_none()
                .then(|| round.levels.joint.to_degrees());
            verdict = misfit::verdict(tests, plain_rms, joint_deg);
            if keep_noise_model(&mut verdict, flagged, plain_rms, &round, joint_deg) {
                kept = Some(round);
            }
        }
        _ if options.noise_model && verdict.detected => verdict.noise_model_set_aside = true,
        _ => {}
    }
    let (last, kept) = match kept {
        Some(round) => (round.point, Some((round.whitened, round.levels))),
        None => (plain.clone(), None),
    };
    Ok(Weighted {
        last,
        kept,
        verdict,
        iterations,
        seconds,
    })
}

/// Whether the noise model's `round` is kept: not when the joint noise is implausible,
/// when a `flagged` misfit's round did not converge or fit as well as the plain fit, nor
/// when it moved the fit beyond [`WHITENED_RMS_LIMIT`] × the plain fit's RMS (which is a
/// misfit of its own). Marks `verdict` when it is set aside.
fn keep_noise_model(
    verdict: &mut Misfit,
    flagged: bool,
    plain_rms: [f64; 2],
    round: &Round,
    joint_deg: Option<f64>,
) -> bool {
    let both = |r: [f64; 2]| ((r[0] * r[0] + r[1] * r[1]) / 2.0).sqrt();
    let rms = round.point.at.rms();
    let noisy = misfit::implausible_joint_noise(joint_deg);
    let limit = if flagged {
        MISFIT_RMS_LIMIT
    } else {
        WHITENED_RMS_LIMIT
    };
    let worse = both(rms) > limit * both(plain_rms) + misfit::ROUNDING_RMS_PX;
    if noisy || (flagged && (worse || !round.point.fit.summary.converged)) {
        verdict.noise_model_set_aside = true;
        false
    } else if worse {
        verdict.detected = true;
        verdict.message = format!(
            "misfit: weighting by the noise model moves the fit to {:.2} px RMS, beyond \
             {WHITENED_RMS_LIMIT}× the plain fit's {:.2} px: the residuals are not joint noise",
            both(rms),
            both(plain_rms)
        );
        verdict.noise_model_set_aside = true;
        false
    } else {
        true
    }
}

/// The noise model from the first whitening (estimated at the plain fit): the whitened fit
/// (`done` when made already; with a `budget`, within that many iterations), then the
/// levels estimated again at that efficient fit — a plain fit under joint noise is
/// inefficient and its residuals overstate the joint noise. The result is that fit's values
/// with the second levels' whitening; it is not refitted with them (docs/MODEL.md §9).
fn noise_model(
    points: &Points,
    plain: &Point,
    first: (Problem, noise::NoiseLevels),
    done: Option<Point>,
    backend: &dyn Backend,
    options: &UncertaintyOptions,
    budget: Option<usize>,
) -> Result<Round, SolveError> {
    let (mut whitened, levels) = first;
    if let Some(b) = budget {
        whitened.tolerances.max_iterations = whitened.tolerances.max_iterations.min(b);
    }
    let point = match done {
        Some(p) => p,
        None => points.linearise(fit(&whitened, backend)?, Some(plain))?,
    };
    if budget.is_some() && !point.fit.summary.converged {
        return Ok(Round {
            point,
            whitened,
            levels,
        });
    }
    if point.fit.values == whitened.initial {
        // The whitened fit stayed at the plain fit (see `screening::whitened_fit`): the
        // levels estimated there are the first ones.
        whitened.tolerances = points.problem.tolerances;
        return Ok(Round {
            point,
            whitened,
            levels,
        });
    }
    Ok(
        match noise::whiten(points.problem, &point.at, options.noise) {
            Some((next, levels)) => Round {
                point,
                whitened: next,
                levels,
            },
            // The whitened fit leaves no residual: keep its weights.
            None => Round {
                point,
                whitened,
                levels,
            },
        },
    )
}
