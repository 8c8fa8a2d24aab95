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

/// `(JᵀJ)⁺` of a Jacobian and its numerical rank, through the SVD of `J` (columns scaled to
/// unit norm first, so that units do not decide the rank). Singular directions whose
/// relative singular value is below `1e-7` count as not determined and are left out of the
/// pseudo-inverse, so a rank-deficient problem gives a finite covariance, never NaN.
pub fn from_jacobian(jacobian: &DMatrix<f64>) -> (DMatrix<f64>, usize) {
    let n = jacobian.ncols();
    let scale: Vec<f64> = (0..n)
        .map(|j| {
            let norm = jacobian.column(j).norm();
            if norm > 0.0 { 1.0 / norm } else { 1.0 }
        })
        .collect();
    let mut scaled = jacobian.clone();
    for (j, s) in scale.iter().enumerate() {
        scaled.column_mut(j).scale_mut(*s);
    }
    let svd = scaled.svd(false, true);
    let v_t = svd.v_t.expect("requested V");
    let max = svd.singular_values.max();
    let threshold = max * RELATIVE_RANK_THRESHOLD;
    let mut cov = DMatrix::zeros(n, n);
    let mut rank = 0;
    for (k, s) in svd.singular_values.iter().enumerate() {
        if *s > threshold && *s > 0.0 {
            rank += 1;
            let v = v_t.row(k).transpose();
            cov += (&v * v.transpose()) / (s * s);
        }
    }
    for i in 0..n {
        for j in 0..n {
            cov[(i, j)] *= scale[i] * scale[j];
        }
    }
    (cov, rank)
}

/// Singular values below this fraction of the largest (after column scaling) count as zero.
pub const RELATIVE_RANK_THRESHOLD: f64 = 1e-7;
