//! Stage 2: with a robust loss (`--loss`), the robust first fit; the vertices it leaves far
//! beyond the noise are listed as outliers and left out of every later fit (docs/MODEL.md
//! §11, "The pipeline", step 2).

use crate::solve::backend::{Fit, fit};
use crate::solve::{Backend, Loss, Outlier, Problem, SolveError};

/// Residual norms beyond this many robust standard deviations mark an outlier.
pub const OUTLIER_SIGMAS: f64 = 5.0;

/// What the robust stage hands on.
pub(super) struct Robust {
    /// The problem the later stages fit: plain least squares, without the outliers, started
    /// at the robust solution (the posed problem itself without a loss).
    pub inliers: Problem,
    /// The vertices left out.
    pub outliers: Vec<Outlier>,
    /// The robust fit, when one was made.
    pub fit: Option<Fit>,
}

/// The robust stage of `posed`: nothing to do without a loss; with one, the robust fit,
/// outliers beyond [`OUTLIER_SIGMAS`] robust standard deviations
/// (`σ = 1.4826 · median |coordinate|`) and the problem without them.
pub(super) fn robust_stage(posed: Problem, backend: &dyn Backend) -> Result<Robust, SolveError> {
    if posed.loss == Loss::Squared {
        return Ok(Robust {
            inliers: posed,
            outliers: Vec::new(),
            fit: None,
        });
    }
    let robust = fit(&posed, backend)?;
    let residuals = posed.vertex_residuals(&robust.values);
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
    let mut inliers = posed;
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
    Ok(Robust {
        inliers,
        outliers,
        fit: Some(robust),
    })
}
