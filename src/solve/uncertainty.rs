//! Checks on the reported uncertainty and on what the data can determine: the
//! capture-clustered sandwich, the capture bootstrap, and the identifiability report
//! (singular values, correlations, weakly or not observable parameter combinations).

use nalgebra::{DMatrix, DVector};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::covariance::{self, Spectrum};
use super::linearisation::{self, Linearisation, NormalSums, OwnSlice};
use super::{Backend, Problem, SolveError};
use crate::model::{PARAMETER_COUNT, Param};

/// Relative singular value (column-scaled Jacobian) below which a direction counts as not
/// determined by the data.
pub const UNDETERMINED: f64 = covariance::RELATIVE_RANK_THRESHOLD;
/// Relative singular value below which a direction counts as weakly determined.
pub const WEAK: f64 = 1e-3;
/// Correlations at least this strong are listed.
pub const HIGH_CORRELATION: f64 = 0.9;

/// A direction in parameter space, as a named combination (coefficients of the
/// column-scaled, unit-free parameters; unit norm).
#[derive(Debug, Clone, PartialEq)]
pub struct Direction {
    /// Singular value relative to the largest one.
    pub relative_singular_value: f64,
    /// `(parameter, coefficient)`, largest first, coefficients below 0.1 left out.
    pub terms: Vec<(Param, f64)>,
}

impl Direction {
    /// "0.71·LHipPitch − 0.70·LKneePitch" (terms below 0.05 of the largest left out).
    pub fn describe(&self) -> String {
        let mut out = String::new();
        let max = self.terms.iter().map(|t| t.1.abs()).fold(0.0, f64::max);
        let shown = self.terms.iter().filter(|t| t.1.abs() >= 0.05 * max);
        for (k, (p, c)) in shown.enumerate() {
            let sign = if *c < 0.0 {
                "−"
            } else if k > 0 {
                "+"
            } else {
                ""
            };
            if k > 0 {
                out.push(' ');
            }
            out.push_str(sign);
            if k > 0 {
                out.push(' ');
            }
            out.push_str(&format!("{:.2}·{}", c.abs(), p.name()));
        }
        out
    }
}

/// What the data can and cannot determine.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Identifiability {
    /// Singular values of the column-scaled (weighted) Jacobian, largest first.
    pub singular_values: Vec<f64>,
    /// Largest over smallest non-zero singular value (∞ is reported as `None`).
    pub condition_number: Option<f64>,
    /// Numerical rank (directions above [`UNDETERMINED`]).
    pub rank: usize,
    /// Free parameters.
    pub free: usize,
    /// Pairs of parameters correlated at least [`HIGH_CORRELATION`], strongest first.
    pub correlated: Vec<(Param, Param, f64)>,
    /// Directions below [`WEAK`] but above [`UNDETERMINED`].
    pub weak: Vec<Direction>,
    /// Directions the data do not determine at all.
    pub undetermined: Vec<Direction>,
    /// Parameters that no capture observes (zero Jacobian column).
    pub unobserved: Vec<Param>,
    /// A set of parameters whose holding fixed would make the problem determined.
    pub suggest_fix: Vec<Param>,
    /// Whether each parameter is determined (fixed ones count as determined).
    pub determined: Vec<bool>,
}

/// The correlation matrix of a covariance (zero where a variance is zero).
pub fn correlation(cov: &DMatrix<f64>) -> DMatrix<f64> {
    let n = cov.nrows();
    DMatrix::from_fn(n, n, |i, j| {
        let d = (cov[(i, i)] * cov[(j, j)]).sqrt();
        if d > 0.0 {
            cov[(i, j)] / d
        } else if i == j {
            1.0
        } else {
            0.0
        }
    })
}

/// What [`super::calibrate`] reports beside the fit, from one evaluation of the Jacobian.
#[derive(Debug, Clone)]
pub struct Statistics {
    /// `σ̂²·(JᵀJ)⁺`, full PARAMETER_COUNT² matrix (zero rows and columns for fixed
    /// parameters).
    pub covariance: DMatrix<f64>,
    /// What the data determine.
    pub identifiability: Identifiability,
    /// The capture-clustered sandwich covariance, full PARAMETER_COUNT² matrix.
    pub sandwich: DMatrix<f64>,
    /// `σ̂² = ‖r‖²/(m − n)` of the (weighted) residuals there.
    pub residual_variance: f64,
}

/// The residual variance, the covariance (`(JᵀJ)⁺` as [`covariance::from_jacobian`]
/// computes it, scaled by `variance`, or by the residual variance when that is `None`), the
/// identifiability report and the sandwich covariance of `problem` at the solution, from
/// `at`: a linearisation of its captures there that differentiates (at least) by its free
/// parameters, weighted here by each capture's whitening. The problem's loss must be plain
/// least squares (a robust loss is not applied: the calibration fits its final problem
/// without one).
pub fn statistics(
    problem: &Problem,
    at: &Linearisation,
    variance: Option<f64>,
) -> Result<Statistics, super::SolveError> {
    debug_assert_eq!(problem.loss, super::Loss::Squared);
    let free = problem.free();
    let n = free.len();
    // Each capture over its own free parameters (a dozen of the free ones at most).
    let slices = at.own_slices(problem, &free);
    let mut gram = DMatrix::zeros(n, n);
    let mut rss = 0.0;
    let mut rows = 0;
    for own in &slices {
        linearisation::add_block(
            &mut gram,
            &own.columns,
            &covariance::gram(&own.slice.jacobian),
        );
        rss += own.slice.residuals.norm_squared();
        rows += own.slice.residuals.len();
    }
    if n == 0 {
        return Err(super::SolveError::Invalid(
            "no parameter is free at the final fit: no covariance to compute".into(),
        ));
    }
    if !(rss.is_finite() && gram.iter().all(|v| v.is_finite())) {
        // An eigen-decomposition of non-finite numbers does not end.
        return Err(super::SolveError::Invalid(
            "the fit reached non-finite residuals or derivatives: no covariance can be \
             computed (the data or the start values are degenerate)"
                .into(),
        ));
    }
    let spectrum = Spectrum::of_gram(&gram).unwrap_or_else(|| {
        // Near the rank threshold: decide on the stacked Jacobian itself.
        let mut jac = DMatrix::zeros(rows, n);
        let mut row = 0;
        for own in &slices {
            let m = own.slice.residuals.len();
            for (a, &ca) in own.columns.iter().enumerate() {
                jac.view_mut((row, ca), (m, 1))
                    .copy_from(&own.slice.jacobian.column(a));
            }
            row += m;
        }
        Spectrum::of_jacobian(&jac)
    });
    let dof = rows.saturating_sub(n).max(1);
    let residual_variance = rss / dof as f64;
    let (unscaled, _) = spectrum.pseudo_inverse();
    let covariance = covariance::embed(&free, &unscaled, variance.unwrap_or(residual_variance));
    Ok(Statistics {
        identifiability: identifiability_from(&free, &spectrum, &covariance),
        sandwich: sandwich_of(&free, &slices, &unscaled),
        covariance,
        residual_variance,
    })
}

/// How far a point is from the optimum of a least-squares problem, to first order.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GaussNewtonStep {
    /// The length of the Gauss–Newton step of the free parameters, in standard deviations
    /// of the estimate: `√(gᵀ(JᵀJ)⁺g / σ̂²)` with `g = Jᵀr` and `σ̂² = ‖r‖²/(m − n)`. No
    /// parameter is more than this many of its σ from where the step leads
    /// (Cauchy–Schwarz).
    pub sigmas: f64,
    /// `½‖r‖²` at the point.
    pub cost: f64,
}

/// The [`GaussNewtonStep`] of `problem` (residuals weighted by each capture's whitening,
/// plain least squares) from the point of `at`, a linearisation that differentiates by (at
/// least) its free parameters; `None` when nothing is free, no degree of freedom is left or
/// the step is not finite.
pub fn gauss_newton_step(problem: &Problem, at: &Linearisation) -> Option<GaussNewtonStep> {
    let free = problem.free();
    let n = free.len();
    let NormalSums {
        gram,
        gradients,
        rss,
        rows,
    } = at.normal_sums(problem, &free);
    let gradient = gradients.row_sum().transpose();
    if n == 0 || rows <= n {
        return None;
    }
    // Columns scaled to unit norm: gᵀ(JᵀJ)⁺g = (Sg)ᵀ(S·JᵀJ·S)⁺(Sg).
    let scale = DVector::from_fn(n, |i, _| {
        let d = gram[(i, i)].sqrt();
        if d > 0.0 { 1.0 / d } else { 1.0 }
    });
    let scaled = DMatrix::from_fn(n, n, |i, j| gram[(i, j)] * scale[i] * scale[j]);
    let g = gradient.component_mul(&scale);
    let q = g.dot(&(scaled.pseudo_inverse(1e-10).ok()? * &g)).max(0.0);
    let sigmas = (q / (rss / (rows - n) as f64)).sqrt();
    sigmas.is_finite().then_some(GaussNewtonStep {
        sigmas,
        cost: 0.5 * rss,
    })
}

/// The report before any analysis: every parameter determined, nothing flagged.
fn unanalysed(free: &[Param]) -> Identifiability {
    Identifiability {
        free: free.len(),
        determined: vec![true; PARAMETER_COUNT],
        ..Default::default()
    }
}

/// The identifiability report from the (weighted) Jacobian `jac` over the `free` parameters.
pub fn identifiability_of(
    free: &[Param],
    jac: &DMatrix<f64>,
    cov: &DMatrix<f64>,
) -> Identifiability {
    identifiability_from(free, &Spectrum::of_jacobian(jac), cov)
}

/// The identifiability report from the spectrum of the (weighted) Jacobian over the `free`
/// parameters and the covariance `cov` (full PARAMETER_COUNT² matrix).
pub fn identifiability_from(
    free: &[Param],
    spectrum: &Spectrum,
    cov: &DMatrix<f64>,
) -> Identifiability {
    let mut report = unanalysed(free);
    let n = free.len();
    let observed = &spectrum.observed;
    // Unobserved parameters are reported by name; the spectrum is the observed ones'.
    report.unobserved = (0..n)
        .filter(|j| !observed.contains(j))
        .map(|j| free[j])
        .collect();
    let max = spectrum.singular_values.first().copied().unwrap_or(0.0);
    report.singular_values = spectrum.singular_values.clone();
    let mut suggested: Vec<Param> = report.unobserved.clone();
    // The undetermined directions with the components of the parameters already suggested
    // eliminated (Gaussian elimination with pivoting on the largest component): each
    // suggestion then removes a direction the earlier ones left, so holding them all leaves
    // the rest determined. (Taking each direction's largest component instead can suggest a
    // set that misses a direction, when the null space has several.)
    let mut pivots: Vec<(usize, DVector<f64>)> = Vec::new();
    for p in &report.unobserved {
        report.determined[p.index()] = false;
    }
    for (k, &value) in spectrum.singular_values.iter().enumerate() {
        let rel = if max > 0.0 { value / max } else { 0.0 };
        if rel > UNDETERMINED {
            report.rank += 1;
        }
        if rel >= WEAK {
            continue;
        }
        let v = spectrum.vectors.column(k);
        let mut terms: Vec<(Param, f64)> = observed
            .iter()
            .enumerate()
            .map(|(k, &j)| (free[j], v[k]))
            .filter(|(_, c)| c.abs() >= 0.1)
            .collect();
        terms.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()));
        if terms.first().is_some_and(|t| t.1 < 0.0) {
            terms.iter_mut().for_each(|t| t.1 = -t.1);
        }
        let direction = Direction {
            relative_singular_value: rel,
            terms,
        };
        if rel > UNDETERMINED {
            report.weak.push(direction);
        } else {
            for (p, _) in &direction.terms {
                report.determined[p.index()] = false;
            }
            let mut rest = v.into_owned();
            for (j, pivot) in &pivots {
                let f = rest[*j] / pivot[*j];
                rest -= pivot * f;
            }
            let pick = (0..rest.len())
                .filter(|&i| !suggested.contains(&free[observed[i]]))
                .max_by(|&a, &b| rest[a].abs().total_cmp(&rest[b].abs()));
            if let Some(i) = pick {
                suggested.push(free[observed[i]]);
                pivots.push((i, rest));
            }
            report.undetermined.push(direction);
        }
    }
    report.suggest_fix = suggested;
    let smallest = report
        .singular_values
        .iter()
        .copied()
        .filter(|s| *s > max * UNDETERMINED);
    report.condition_number = smallest.fold(None, |_, s| Some(max / s));
    if report.rank < n {
        report.condition_number = None;
    }
    let corr = correlation(cov);
    for (a, pa) in free.iter().enumerate() {
        for pb in &free[a + 1..] {
            let r = corr[(pa.index(), pb.index())];
            if r.abs() >= HIGH_CORRELATION
                && report.determined[pa.index()]
                && report.determined[pb.index()]
            {
                report.correlated.push((*pa, *pb, r));
            }
        }
    }
    report
        .correlated
        .sort_by(|a, b| b.2.abs().total_cmp(&a.2.abs()));
    report
}

/// The capture-clustered sandwich covariance `H⁺ (Σ_c g_c g_cᵀ) H⁺` of the (weighted)
/// problem from each capture's residuals and Jacobian over the `free` parameters and
/// `h_inv = (JᵀJ)⁺` ([`covariance::from_jacobian`]), with
/// `H = JᵀJ` and `g_c = J_cᵀ (I − H_cc)^{-1/2} r_c` (the "CR2" leverage correction,
/// `H_cc = J_c H⁺ J_cᵀ`, since a fitted capture's residuals are smaller than its errors):
/// robust to any correlation of the residuals within a capture. Full PARAMETER_COUNT²
/// matrix.
pub fn sandwich_of(free: &[Param], captures: &[OwnSlice], h_inv: &DMatrix<f64>) -> DMatrix<f64> {
    let n = free.len();
    let mut meat = DMatrix::zeros(n, n);
    for own in captures {
        let j_c = &own.slice.jacobian;
        // The columns the capture's residuals move with (a parameter it depends on may
        // still have a zero derivative).
        let local: Vec<usize> = (0..j_c.ncols())
            .filter(|&j| j_c.column(j).iter().any(|v| *v != 0.0))
            .collect();
        if local.is_empty() {
            // The capture does not depend on any free parameter: it adds nothing (and an
            // empty matrix has no eigen-decomposition).
            continue;
        }
        let cols: Vec<usize> = local.iter().map(|&j| own.columns[j]).collect();
        let b = j_c.select_columns(&local);
        let p = DMatrix::from_fn(cols.len(), cols.len(), |i, j| h_inv[(cols[i], cols[j])]);
        let r_c = leverage_corrected(&b, &p, &own.slice.residuals);
        let g: DVector<f64> = b.tr_mul(&r_c);
        for (a, &ia) in cols.iter().enumerate() {
            for (c, &ic) in cols.iter().enumerate() {
                meat[(ia, ic)] += g[a] * g[c];
            }
        }
    }
    let cov = h_inv * meat * h_inv;
    covariance::embed(free, &cov, 1.0)
}

/// `(I − H_cc)^{-1/2} r_c` with the leverage `H_cc = B P Bᵀ` of one capture (`B` its
/// Jacobian on its own columns, `P` their block of `H⁺`), leverages capped at 0.99.
///
/// `H_cc` (2k × 2k) has rank at most `B`'s column count, so its eigenpairs come from the
/// small `M = Sᵀ BᵀB S` with `P = S Sᵀ`: `M v = λ v` gives `H_cc u = λ u` for
/// `u = B S v / √λ`.
fn leverage_corrected(b: &DMatrix<f64>, p: &DMatrix<f64>, r_c: &DVector<f64>) -> DVector<f64> {
    if b.ncols() == 0 || b.nrows() == 0 {
        return r_c.clone();
    }
    // Any factor `P = S Sᵀ` will do: the Cholesky factor, or (P only semi-definite, for a
    // rank-deficient problem) the symmetric square root.
    let s = p.clone().cholesky().map(|c| c.unpack()).unwrap_or_else(|| {
        let pe = p.clone().symmetric_eigen();
        let root = pe.eigenvalues.map(|l| l.max(0.0).sqrt());
        &pe.eigenvectors * DMatrix::from_diagonal(&root) * pe.eigenvectors.transpose()
    });
    let bs = b * s;
    let m = covariance::gram(&bs);
    let me = m.symmetric_eigen();
    let mut out = r_c.clone();
    for (k, &l) in me.eigenvalues.iter().enumerate() {
        if l <= 1e-12 {
            continue;
        }
        let u = &bs * me.eigenvectors.column(k) / l.sqrt();
        let factor = 1.0 / (1.0 - l.min(0.99)).sqrt() - 1.0;
        out.axpy(factor * u.dot(r_c), &u, 1.0);
    }
    out
}

/// A hook told `(done, total)` after each bootstrap refit.
pub type ProgressHook = Box<dyn Fn(usize, usize)>;

thread_local! {
    static BOOTSTRAP_PROGRESS: std::cell::RefCell<Option<ProgressHook>> =
        const { std::cell::RefCell::new(None) };
}

/// Runs `f` with `hook` told `(done, total)` after every bootstrap refit that [`bootstrap`]
/// makes on this thread meanwhile (a long `--bootstrap` shows progress with it).
pub fn with_bootstrap_progress<R>(hook: Box<dyn Fn(usize, usize)>, f: impl FnOnce() -> R) -> R {
    let previous = BOOTSTRAP_PROGRESS.with(|p| p.replace(Some(hook)));
    let result = f();
    BOOTSTRAP_PROGRESS.with(|p| *p.borrow_mut() = previous);
    result
}

fn bootstrap_progress(done: usize, total: usize) {
    BOOTSTRAP_PROGRESS.with(|p| {
        if let Some(hook) = p.borrow().as_ref() {
            hook(done, total);
        }
    });
}

/// The capture bootstrap: `n` refits on captures drawn with replacement (each keeping its
/// whitening), started from the solution. Returns the standard deviation of the estimates
/// (internal units) and how many refits failed.
pub fn bootstrap(
    problem: &Problem,
    values: &[f64; PARAMETER_COUNT],
    backend: &dyn Backend,
    n: usize,
    seed: u64,
) -> Result<([f64; PARAMETER_COUNT], usize), SolveError> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut sum = [0.0; PARAMETER_COUNT];
    let mut sum2 = [0.0; PARAMETER_COUNT];
    let mut ok = 0usize;
    let mut failed = 0usize;
    let count = problem.captures.len();
    for _ in 0..n {
        let mut sample = problem.clone();
        sample.initial = *values;
        sample.captures = (0..count)
            .map(|_| problem.captures[rng.random_range(0..count)].clone())
            .collect();
        match super::fit(&sample, backend) {
            Ok(s) if s.summary.converged => {
                ok += 1;
                for i in 0..PARAMETER_COUNT {
                    sum[i] += s.values[i];
                    sum2[i] += s.values[i] * s.values[i];
                }
            }
            _ => failed += 1,
        }
        bootstrap_progress(ok + failed, n);
    }
    if ok < 2 {
        return Err(SolveError::Invalid(format!(
            "bootstrap: only {ok} of {n} refits succeeded"
        )));
    }
    let k = ok as f64;
    let std = std::array::from_fn(|i| {
        let mean = sum[i] / k;
        ((sum2[i] - k * mean * mean) / (k - 1.0)).max(0.0).sqrt()
    });
    Ok((std, failed))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The small-eigenproblem leverage correction equals the direct one on the full
    /// `H_cc = B P Bᵀ` (2k × 2k).
    #[test]
    fn leverage_correction_matches_direct_eigendecomposition() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let (rows, cols) = (48, 11);
        let b = DMatrix::from_fn(rows, cols, |_, _| rng.random_range(-1.0..1.0));
        let a = DMatrix::from_fn(cols, cols, |_, _| rng.random_range(-1.0..1.0));
        // A positive definite P scaled so that some leverages exceed the 0.99 cap.
        let p = (&a * a.transpose() + DMatrix::identity(cols, cols)) * 0.02;
        let r = DVector::from_fn(rows, |_, _| rng.random_range(-1.0..1.0));

        let h = &b * &p * b.transpose();
        let eig = h.symmetric_eigen();
        assert!(eig.eigenvalues.iter().any(|&l| l > 0.99));
        let scale = eig
            .eigenvalues
            .map(|l: f64| 1.0 / (1.0 - l.clamp(0.0, 0.99)).sqrt());
        let v = &eig.eigenvectors;
        let direct = v * DMatrix::from_diagonal(&scale) * (v.transpose() * &r);

        let fast = leverage_corrected(&b, &p, &r);
        let err = (&fast - &direct).norm() / direct.norm();
        assert!(err < 1e-10, "relative difference {err:e}");
    }
}
