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

/// `(JᵀJ)⁺` of a Jacobian and its numerical rank. Columns are scaled to unit norm first,
/// so that units do not decide the rank; directions whose relative singular value (after
/// scaling) is below [`RELATIVE_RANK_THRESHOLD`] count as not determined and are left out
/// of the pseudo-inverse, so a rank-deficient problem gives a finite covariance, never NaN.
///
/// Fast path: the eigen-decomposition of the column-scaled `JᵀJ` (n × n), whose
/// eigenvalues are the squared singular values. Squaring loses precision only for the
/// smallest singular values; when one of them lies near the threshold, where that could
/// change the rank, the routine falls back to the SVD of the scaled `J` itself.
pub fn from_jacobian(jacobian: &DMatrix<f64>) -> (DMatrix<f64>, usize) {
    let n = jacobian.ncols();
    if n == 0 {
        return (DMatrix::zeros(0, 0), 0);
    }
    let norms: Vec<f64> = (0..n).map(|j| jacobian.column(j).norm()).collect();
    let scale: Vec<f64> = norms
        .iter()
        .map(|&norm| if norm > 0.0 { 1.0 / norm } else { 1.0 })
        .collect();
    let mut normal = DMatrix::zeros(n, n);
    for i in 0..n {
        for j in i..n {
            let value = jacobian.column(i).dot(&jacobian.column(j)) * scale[i] * scale[j];
            normal[(i, j)] = value;
            normal[(j, i)] = value;
        }
    }
    let eigen = normal.symmetric_eigen();
    let max = eigen.eigenvalues.max();
    let threshold = max * RELATIVE_RANK_THRESHOLD * RELATIVE_RANK_THRESHOLD;
    // Eigenvalues of JᵀJ are accurate to about n·ε·max in absolute terms: within a factor
    // of 100 of the threshold the rank is better decided on J itself.
    if eigen
        .eigenvalues
        .iter()
        .any(|&l| l > threshold * 1e-2 && l < threshold * 1e2)
    {
        return from_scaled_svd(jacobian, &scale);
    }
    let mut cov = DMatrix::zeros(n, n);
    let mut rank = 0;
    for (k, &l) in eigen.eigenvalues.iter().enumerate() {
        if l > threshold && l > 0.0 {
            rank += 1;
            let v = eigen.eigenvectors.column(k);
            cov.ger(1.0 / l, &v, &v, 1.0);
        }
    }
    unscale(&mut cov, &scale);
    (cov, rank)
}

/// [`from_jacobian`] through the SVD of the column-scaled Jacobian (slower, but free of the
/// squaring of `JᵀJ`).
fn from_scaled_svd(jacobian: &DMatrix<f64>, scale: &[f64]) -> (DMatrix<f64>, usize) {
    let n = jacobian.ncols();
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
            cov.ger(1.0 / (s * s), &v, &v, 1.0);
        }
    }
    unscale(&mut cov, scale);
    (cov, rank)
}

/// `D·C·D` for the column scaling `D`.
fn unscale(cov: &mut DMatrix<f64>, scale: &[f64]) {
    let n = cov.ncols();
    for j in 0..n {
        for i in 0..n {
            cov[(i, j)] *= scale[i] * scale[j];
        }
    }
}

/// The numerical rank of a covariance matrix (a pseudo-inverse `(JᵀJ)⁺`, for example from
/// Ceres, which does not report its rank): the number of eigenvalues of the
/// diagonally-scaled matrix `S·C·S` (`S = diag(C)^(-1/2)` over the nonzero diagonal) above
/// `1e-9` of the largest. The pseudo-inverse leaves dropped directions exactly out, so
/// they show up as eigenvalues at rounding level, far below this.
pub fn rank_of_covariance(cov: &DMatrix<f64>) -> usize {
    let keep: Vec<usize> = (0..cov.nrows()).filter(|&i| cov[(i, i)] > 0.0).collect();
    if keep.is_empty() {
        return 0;
    }
    let d = keep.len();
    let scaled = DMatrix::from_fn(d, d, |a, b| {
        let (i, j) = (keep[a], keep[b]);
        cov[(i, j)] / (cov[(i, i)] * cov[(j, j)]).sqrt()
    });
    let values = scaled.symmetric_eigenvalues();
    let max = values.max();
    values.iter().filter(|&&l| l > max * 1e-9).count()
}

/// Singular values below this fraction of the largest (after column scaling) count as zero.
pub const RELATIVE_RANK_THRESHOLD: f64 = 1e-7;
