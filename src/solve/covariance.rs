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

/// `JᵀJ` of a capture's Jacobian over its own dozen or so columns: each product of two
/// columns once, by their dot product, and mirrored. Quicker there than nalgebra's general
/// product, which packs its operands first; over several dozen columns (the misfit tests'
/// candidates) the packed product is the quicker (docs/PERFORMANCE.md).
pub fn gram(jacobian: &DMatrix<f64>) -> DMatrix<f64> {
    let (m, n) = jacobian.shape();
    let mut out = DMatrix::zeros(n, n);
    if m == 0 {
        return out;
    }
    let columns: Vec<&[f64]> = jacobian.as_slice().chunks_exact(m).collect();
    for b in 0..n {
        for a in 0..=b {
            let v = dot(columns[a], columns[b]);
            out[(a, b)] = v;
            out[(b, a)] = v;
        }
    }
    out
}

/// `x·y`, summed in four lanes (which the compiler keeps in vector registers).
fn dot(x: &[f64], y: &[f64]) -> f64 {
    let mut lanes = [0.0; 4];
    let (xs, ys) = (x.chunks_exact(4), y.chunks_exact(4));
    let tail: f64 = xs
        .remainder()
        .iter()
        .zip(ys.remainder())
        .map(|(a, b)| a * b)
        .sum();
    for (a, b) in xs.zip(ys) {
        for k in 0..4 {
            lanes[k] += a[k] * b[k];
        }
    }
    (lanes[0] + lanes[1]) + (lanes[2] + lanes[3]) + tail
}

/// `(JᵀJ)⁺` of a Jacobian and its numerical rank. Columns are scaled to unit norm first,
/// so that units do not decide the rank; directions whose relative singular value (after
/// scaling) is below [`RELATIVE_RANK_THRESHOLD`] count as not determined and are left out
/// of the pseudo-inverse, so a rank-deficient problem gives a finite covariance, never NaN.
///
/// Fast path: the eigen-decomposition of the column-scaled `JᵀJ` (see
/// [`Spectrum::of_gram`]); near the threshold, the SVD of the scaled `J` itself.
pub fn from_jacobian(jacobian: &DMatrix<f64>) -> (DMatrix<f64>, usize) {
    Spectrum::of_gram(&(jacobian.transpose() * jacobian))
        .unwrap_or_else(|| Spectrum::of_jacobian(jacobian))
        .pseudo_inverse()
}

/// The singular values and right singular vectors of a Jacobian with its observed columns
/// scaled to unit norm: what the covariance ([`Spectrum::pseudo_inverse`]) and the
/// identifiability report are built from.
#[derive(Debug, Clone)]
pub struct Spectrum {
    /// Every column's norm (zero: a parameter no residual depends on).
    pub norms: Vec<f64>,
    /// The observed columns (non-zero norm), in order.
    pub observed: Vec<usize>,
    /// Singular values of the scaled observed columns, largest first.
    pub singular_values: Vec<f64>,
    /// The matching right singular vectors, one column each (over `observed`).
    pub vectors: DMatrix<f64>,
}

impl Spectrum {
    /// From the Gram matrix `JᵀJ`, by the eigen-decomposition of its scaled observed block
    /// (eigenvalues are the squared singular values). Squaring loses precision only for
    /// the smallest singular values: when a squared one lies within a factor of 100 of the
    /// squared rank threshold, where that could change the rank, `None` — decide on `J`
    /// itself ([`Spectrum::of_jacobian`]).
    pub fn of_gram(gram: &DMatrix<f64>) -> Option<Spectrum> {
        let norms: Vec<f64> = (0..gram.ncols())
            .map(|j| gram[(j, j)].max(0.0).sqrt())
            .collect();
        let observed: Vec<usize> = (0..norms.len()).filter(|&j| norms[j] > 0.0).collect();
        if observed.is_empty() {
            return Some(Spectrum::sorted(
                norms,
                observed,
                Vec::new(),
                DMatrix::zeros(0, 0),
            ));
        }
        let scaled = DMatrix::from_fn(observed.len(), observed.len(), |a, b| {
            let (i, j) = (observed[a], observed[b]);
            gram[(i, j)] / (norms[i] * norms[j])
        });
        let eigen = scaled.symmetric_eigen();
        let max = eigen.eigenvalues.max();
        let threshold = max * RELATIVE_RANK_THRESHOLD * RELATIVE_RANK_THRESHOLD;
        // Eigenvalues of JᵀJ are accurate to about n·ε·max in absolute terms.
        if eigen
            .eigenvalues
            .iter()
            .any(|&l| l > threshold * 1e-2 && l < threshold * 1e2)
        {
            return None;
        }
        let values: Vec<f64> = eigen
            .eigenvalues
            .iter()
            .map(|l| l.max(0.0).sqrt())
            .collect();
        Some(Spectrum::sorted(
            norms,
            observed,
            values,
            eigen.eigenvectors,
        ))
    }

    /// From the Jacobian itself: the SVD of the triangular factor of its scaled observed
    /// columns (same singular values and right vectors as the tall matrix's).
    pub fn of_jacobian(jacobian: &DMatrix<f64>) -> Spectrum {
        let norms: Vec<f64> = (0..jacobian.ncols())
            .map(|j| jacobian.column(j).norm())
            .collect();
        let observed: Vec<usize> = (0..norms.len()).filter(|&j| norms[j] > 0.0).collect();
        if observed.is_empty() || jacobian.nrows() == 0 {
            // Nothing observed (rank 0): no decomposition of an empty matrix.
            return Spectrum::sorted(norms, Vec::new(), Vec::new(), DMatrix::zeros(0, 0));
        }
        let mut scaled = DMatrix::zeros(jacobian.nrows(), observed.len());
        for (k, &j) in observed.iter().enumerate() {
            scaled.set_column(k, &(jacobian.column(j) / norms[j]));
        }
        let svd = scaled.qr().r().svd(false, true);
        let vectors = svd.v_t.expect("requested V").transpose();
        let values = svd.singular_values.iter().copied().collect();
        Spectrum::sorted(norms, observed, values, vectors)
    }

    fn sorted(
        norms: Vec<f64>,
        observed: Vec<usize>,
        values: Vec<f64>,
        vectors: DMatrix<f64>,
    ) -> Spectrum {
        let mut order: Vec<usize> = (0..values.len()).collect();
        order.sort_by(|a, b| values[*b].total_cmp(&values[*a]));
        Spectrum {
            singular_values: order.iter().map(|&k| values[k]).collect(),
            vectors: vectors.select_columns(&order),
            norms,
            observed,
        }
    }

    /// `(JᵀJ)⁺` over every column (zero rows and columns for unobserved ones), directions
    /// below [`RELATIVE_RANK_THRESHOLD`] left out, and the numerical rank.
    pub fn pseudo_inverse(&self) -> (DMatrix<f64>, usize) {
        let n = self.norms.len();
        let max = self.singular_values.first().copied().unwrap_or(0.0);
        let threshold = max * RELATIVE_RANK_THRESHOLD;
        let d = self.observed.len();
        let mut scaled = DMatrix::zeros(d, d);
        let mut rank = 0;
        for (k, &s) in self.singular_values.iter().enumerate() {
            if s > threshold && s > 0.0 {
                rank += 1;
                let v = self.vectors.column(k);
                scaled.ger(1.0 / (s * s), &v, &v, 1.0);
            }
        }
        let mut cov = DMatrix::zeros(n, n);
        for (a, &i) in self.observed.iter().enumerate() {
            for (b, &j) in self.observed.iter().enumerate() {
                cov[(i, j)] = scaled[(a, b)] / (self.norms[i] * self.norms[j]);
            }
        }
        (cov, rank)
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gram_is_the_product_of_the_transpose_with_the_jacobian() {
        // 47 rows: the four lanes and a remainder of three.
        let j = DMatrix::from_fn(47, 13, |r, c| {
            ((r * 7 + c * 11) % 17) as f64 - 8.0 + 0.01 * c as f64
        });
        let expected = j.transpose() * &j;
        let g = gram(&j);
        assert_eq!(g.shape(), (13, 13));
        for (a, b) in g.iter().zip(expected.iter()) {
            assert!((a - b).abs() <= 1e-12 * b.abs().max(1.0), "{a} vs {b}");
        }
        assert_eq!(g, g.transpose());
        assert_eq!(gram(&DMatrix::zeros(0, 3)), DMatrix::zeros(3, 3));
    }
}
