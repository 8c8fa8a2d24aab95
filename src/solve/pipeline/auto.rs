//! `--model auto` ([`ModelChoice::Auto`](super::ModelChoice::Auto)): forward selection of the families the data
//! support, one screening step per family, then the pipeline on the chosen model
//! (docs/MODEL.md §11, "`--model auto`").

use std::time::Instant;

use super::{Points, UncertaintyOptions, calibrate_given, hold, plain, robust, screening};
use crate::model::{Family, PARAMETER_COUNT};
use crate::solve::{Backend, FamilyTest, Problem, Solution, SolveError, misfit, uncertainty};

/// [`ModelChoice::Auto`](super::ModelChoice::Auto): frees the family explaining most of the residuals while one's
/// test is significant at [`misfit::AUTO_ALPHA`], then reports the last calibration with
/// the families chosen and why.
pub(super) fn select_model(
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

/// What one screening step of [`ModelChoice::Auto`](super::ModelChoice::Auto) finds.
struct Screening {
    /// The misfit tests at the screening fit.
    tests: Vec<FamilyTest>,
    /// The screening fit's values.
    values: [f64; PARAMETER_COUNT],
    /// Their σ there: the larger of the plain and the capture-clustered sandwich σ.
    std: [f64; PARAMETER_COUNT],
}

/// One screening step of [`ModelChoice::Auto`](super::ModelChoice::Auto): the plain fit of `problem` (undetermined
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
    let hold::Posed {
        problem: posed,
        undetermined,
        held,
    } = hold::hold_undetermined(problem)?;
    let mut inliers = robust::robust_stage(posed, backend)?.inliers;
    inliers.initial = *warm;
    for u in &undetermined {
        inliers.initial[u.param.index()] = problem.initial[u.param.index()];
    }
    let points = Points::new(&inliers, &held);
    let plain = plain::plain_fit(&points, backend)?;
    let settled = |tests: &[FamilyTest]| next_family(tests, chosen, &[]).is_some();
    let tests = screening::misfit_tests(&points, &plain, &held, backend, options, &settled)?.tests;
    let stats = uncertainty::statistics(&inliers, &plain.at, None)?;
    let std = std::array::from_fn(|i| {
        stats.covariance[(i, i)]
            .max(stats.sandwich[(i, i)])
            .max(0.0)
            .sqrt()
    });
    Ok(Screening {
        tests,
        values: plain.fit.values,
        std,
    })
}

/// The family [`ModelChoice::Auto`](super::ModelChoice::Auto) frees next: of those not `chosen` (nor `rejected` for
/// a fit beyond the physical bounds) whose test is significant at [`misfit::AUTO_ALPHA`]
/// (Bonferroni over the tests), the one explaining most of the residuals.
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
