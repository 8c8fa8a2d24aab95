//! Covariance of the estimate, shared by every backend.

use nalgebra::DMatrix;

use crate::model::{PARAMETER_COUNT, Param};

/// Embeds a covariance over the `free` parameters into the full PARAMETER_COUNT² matrix,
/// scaled by `variance`; held parameters get zero rows and columns.
pub fn embed(free: &[Param], cov: &DMatrix<f64>, variance: f64) -> DMatrix<f64> {
    let mut full = DMatrix::zeros(PARAMETER_COUNT, PARAMETER_COUNT);
    for (a, pa) in free.iter().enumerate() {
        for (b, pb) in free.iter().enumerate() {
            full[(pa.index(), pb.index())] = cov[(a, b)] * variance;
        }
    }
    full
}
