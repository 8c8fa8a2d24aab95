//! Whether a problem can be handed to a backend: the one check behind
//! [`super::Problem::from_dataset`] (which names the dataset's file and line) and
//! [`validate`] (which every fit runs), each condition in one wording.

use super::{Problem, SolveError};
use crate::dataset::Dataset;

/// Checks that a problem can be handed to a backend: something free, more residuals than
/// free parameters, finite start values and observations, every vertex in front of the
/// camera at the start values, well-formed whitening matrices.
pub fn validate(problem: &Problem) -> Result<(), SolveError> {
    check(problem, None)
}

/// [`validate`], naming `dataset`'s files and lines when the problem was made from it.
pub(crate) fn check(problem: &Problem, dataset: Option<&Dataset>) -> Result<(), SolveError> {
    let invalid = |message: String| Err(SolveError::Invalid(message));
    let free = problem.free().len();
    if free == 0 {
        return invalid("every parameter is held fixed: nothing to solve".into());
    }
    let residuals = problem.residual_count();
    if residuals <= free {
        let file = dataset.map_or_else(String::new, |d| {
            format!("{}: ", d.dir.join("corners.csv").display())
        });
        return invalid(format!(
            "{file}too few corners to calibrate: {} vertices give {residuals} residuals, but \
             {free} parameters are free (hold some fixed with --fix, or add captures)",
            problem.observation_count()
        ));
    }
    if problem.initial.iter().any(|v| !v.is_finite()) {
        return invalid("a start value is not a finite number".into());
    }
    for c in &problem.captures {
        // The dataset's row of this capture, when there is a dataset.
        let row = || dataset.and_then(|d| d.captures.iter().find(|k| k.id == c.capture));
        // "DIR/captures.csv line 3, capture 7", or "capture 7" without a dataset.
        let place = || match (dataset, row()) {
            (Some(d), Some(k)) => format!(
                "{} line {}, capture {}",
                d.dir.join("captures.csv").display(),
                k.line,
                c.capture
            ),
            _ => format!("capture {}", c.capture),
        };
        if c.observations
            .iter()
            .any(|o| o.pixel.iter().chain(&o.point).any(|x| !x.is_finite()))
        {
            return invalid(format!(
                "{}: an observation is not a finite number",
                place()
            ));
        }
        if let Some(k) = c.behind_camera(&problem.camera, &problem.initial) {
            let board = row().map_or("board".into(), |k| format!("{} board", k.side.name()));
            let vertex = c.observations[k].vertex;
            return invalid(format!(
                "{}: vertex ({}, {}) of the {board} lies behind the camera at the start values; \
                 check the joint angles and the board column",
                place(),
                vertex.row,
                vertex.col,
            ));
        }
        if let Some(w) = &c.whitening
            && (w.size() != c.residual_count() || !w.is_well_formed())
        {
            let n = c.residual_count();
            return invalid(format!(
                "{}: the whitening matrix is not a finite {n}×{n} matrix",
                place()
            ));
        }
    }
    Ok(())
}
