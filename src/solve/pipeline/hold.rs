//! Stage 1: the undetermined parameters, found at the start values and held for every fit of
//! the run (docs/MODEL.md §10).

use crate::model::PARAMETER_COUNT;
use crate::solve::{Problem, SolveError, Undetermined, identify};

/// The problem as it is posed to the fits: the undetermined parameters held.
pub(super) struct Posed {
    /// The problem with the undetermined parameters held at their start values.
    pub problem: Problem,
    /// The undetermined parameters, with the combination each forms.
    pub undetermined: Vec<Undetermined>,
    /// Their mask, indexed by [`crate::model::Param::index`].
    pub held: [bool; PARAMETER_COUNT],
}

/// Finds the undetermined free parameters of `problem` ([`identify::undetermined`]) and
/// holds them.
pub(super) fn hold_undetermined(problem: &Problem) -> Result<Posed, SolveError> {
    let undetermined = identify::undetermined(problem)?;
    Ok(Posed {
        problem: identify::hold(problem, &undetermined),
        held: identify::mask(&undetermined),
        undetermined,
    })
}
