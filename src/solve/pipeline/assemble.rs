//! Stage 6: the statistics from one Jacobian of the problem as fitted — the covariance, the
//! SVD report and the sandwich — and the [`Solution`] built once from what the stages
//! produced, with the optional capture bootstrap (docs/MODEL.md §9, §10 "The SVD report",
//! §11 "The pipeline", steps 5–6).

use super::robust::Robust;
use super::weighting::Weighted;
use super::{Point, UncertaintyOptions};
use crate::solve::{
    Backend, BootstrapStd, Problem, Solution, SolveError, Summary, Undetermined, VertexResidual,
    uncertainty,
};

/// The solution of `problem` from the stages' results: the values of the last fit, `std`
/// from the covariance of the problem as fitted (the capture-clustered sandwich when the
/// residuals may not be noise), the residuals before and after, and the optimiser's effort
/// summed over the fits; then, when asked for, the capture bootstrap.
pub(super) fn solution(
    problem: &Problem,
    undetermined: Vec<Undetermined>,
    robust: &Robust,
    plain: &Point,
    weighted: Weighted,
    backend: &dyn Backend,
    options: &UncertaintyOptions,
) -> Result<Solution, SolveError> {
    let last = &weighted.last;
    let verdict = weighted.verdict;
    let (fitted, levels) = match &weighted.kept {
        Some((whitened, levels)) => (whitened, Some(*levels)),
        None => (&robust.inliers, None),
    };
    // Both noise levels given: trust them, do not rescale by the residuals.
    let both_given = options.noise.px.is_some() && options.noise.joint.is_some();
    let variance = (levels.is_some() && both_given).then_some(1.0);
    let uncertainty::Statistics {
        mut covariance,
        identifiability,
        sandwich,
        residual_variance,
    } = uncertainty::statistics(fitted, &last.at, variance)?;
    if verdict.noise_model_set_aside || (levels.is_some() && verdict.detected) {
        // Residuals that may not be noise: the capture-clustered sandwich holds whatever
        // their correlation within a capture.
        covariance = sandwich.clone();
    }
    let std = std::array::from_fn(|i| covariance[(i, i)].max(0.0).sqrt());
    let residuals = problem.vertex_residuals(&last.fit.values);
    let robust_fit = robust.fit.as_ref().map(|f| &f.summary);
    let mut iterations = 0;
    let mut seconds = 0.0;
    for s in robust_fit.into_iter().chain([&plain.fit.summary]) {
        iterations += s.iterations;
        seconds += s.seconds;
    }
    let summary = Summary {
        iterations: iterations + weighted.iterations,
        initial_cost: robust_fit.map_or(plain.fit.summary.initial_cost, |s| s.initial_cost),
        final_cost: last.at.cost(),
        seconds: seconds + weighted.seconds,
        ..last.fit.summary.clone()
    };
    let mut solution = Solution {
        summary,
        values: last.fit.values,
        std,
        covariance,
        fixed: problem.fixed.clone(),
        rms_px: last.at.rms(),
        initial_rms_px: initial_rms(&residuals),
        observations: robust.inliers.observation_count(),
        captures: robust.inliers.captures.len(),
        residual_variance,
        seconds: 0.0,
        residuals,
        noise: levels,
        sandwich_std: Some(std::array::from_fn(|i| sandwich[(i, i)].max(0.0).sqrt())),
        bootstrap: None,
        identifiability,
        outliers: robust.outliers.clone(),
        families: robust.inliers.fixed.families(),
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
    Ok(solution)
}

/// RMS in u and v of the residuals at the start values (px) (NaN where undefined).
fn initial_rms(residuals: &[VertexResidual]) -> [f64; 2] {
    let n = residuals.len().max(1) as f64;
    std::array::from_fn(|k| {
        (residuals.iter().map(|r| r.initial[k].powi(2)).sum::<f64>() / n).sqrt()
    })
}
