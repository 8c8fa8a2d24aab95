//! Stage 3: the plain least-squares fit of the problem as posed (undetermined parameters
//! held, outliers left out), linearised once for the stages after it (docs/MODEL.md §11,
//! "The pipeline", step 3).

use super::{Point, Points};
use crate::solve::backend::fit;
use crate::solve::{Backend, SolveError};

/// The plain fit of `points`' problem from its start values, with its linearisation.
pub(super) fn plain_fit(points: &Points, backend: &dyn Backend) -> Result<Point, SolveError> {
    points.linearise(fit(points.problem, backend)?, None)
}
