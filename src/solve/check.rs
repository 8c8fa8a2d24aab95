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
        if let Some(k) = c.behind_camera(&problem.initial) {
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

#[cfg(test)]
mod tests {
    use crate::model::{FixedSet, Joint, Model, Param};
    use crate::sim::{SimOptions, simulate};
    use crate::solve::{Problem, SolveError, validate};

    fn message(e: SolveError) -> String {
        e.to_string()
    }

    /// A vertex behind the camera and too few corners are told in one wording, with the
    /// dataset's file and line from `from_dataset` and by capture id from `validate`.
    #[test]
    fn from_dataset_and_validate_word_each_error_alike() {
        let options = SimOptions {
            stances: 3,
            heads: 2,
            ..SimOptions::default()
        };
        let mut dataset = simulate(&Model::default(), &options).unwrap();
        let problem = Problem::from_dataset(&dataset, FixedSet::default()).unwrap();
        assert!(validate(&problem).is_ok());

        // The head turned round and up: its capture's board lies behind the camera.
        let turned = dataset.captures[1].clone();
        let mut joints = turned.joints;
        joints.set(Joint::HeadYaw, 3.1);
        joints.set(Joint::HeadPitch, -1.5);
        dataset.captures[1].joints = joints;
        let e = message(Problem::from_dataset(&dataset, FixedSet::default()).unwrap_err());
        let tail = "lies behind the camera at the start values; check the joint angles and \
                    the board column";
        assert!(e.contains("captures.csv line "), "{e}");
        assert!(
            e.contains(&format!(", capture {}: vertex (", turned.id)),
            "{e}"
        );
        assert!(
            e.contains(&format!("of the {} board {tail}", turned.side.name())),
            "{e}"
        );
        // The same problem built without the check, as a library user might: `validate`.
        dataset.captures[1] = turned.clone();
        let mut bad = Problem::from_dataset(&dataset, FixedSet::default()).unwrap();
        bad.captures[1].chains = dataset.model.chains(turned.side, &joints);
        let e = message(validate(&bad).unwrap_err());
        assert!(
            e.starts_with(&format!("capture {}: vertex (", turned.id)),
            "{e}"
        );
        assert!(e.ends_with(&format!("of the board {tail}")), "{e}");

        // Too few corners: the same sentence, with corners.csv named from a dataset.
        let keep = 10;
        dataset.corners.truncate(keep);
        let e = message(Problem::from_dataset(&dataset, FixedSet::default()).unwrap_err());
        let few = format!(
            "too few corners to calibrate: {keep} vertices give {} residuals, but 21 \
             parameters are free",
            2 * keep
        );
        assert!(e.contains("corners.csv: ") && e.contains(&few), "{e}");
        let mut small = problem.clone();
        small.captures.truncate(1);
        small.captures[0].observations.truncate(keep);
        let e = message(validate(&small).unwrap_err());
        assert!(e.starts_with(&few), "{e}");

        // Nothing free.
        let mut held = problem;
        for p in Param::ALL {
            held.fixed.set(p, true);
        }
        let e = message(validate(&held).unwrap_err());
        assert_eq!(e, "every parameter is held fixed: nothing to solve");
    }
}
