//! The measurement noise model: pixel noise on every vertex plus joint-angle noise shared by
//! all vertices of a capture (docs/MODEL.md §9).
//!
//! A capture's residuals `r_c` then have the covariance
//! `Σ_c = σ_px² I + J_θ,c diag(σ_θ²) J_θ,cᵀ`, where `J_θ,c = ∂r_c/∂θ` is the Jacobian with
//! respect to that capture's joint angles (head and the leg in view). The solve is whitened
//! by `W_c = Σ_c^{-1/2}`; the noise levels are estimated from the residuals unless given.

use nalgebra::{DMatrix, DVector};

use super::linearisation::{CaptureSlice, Linearisation};
use super::problem::{Problem, Whitening};
use crate::model::{Joint, PARAMETER_COUNT, Param};

/// Noise levels: given on the command line, or estimated from the residuals.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NoiseLevels {
    /// Pixel noise σ per coordinate (px).
    pub px: f64,
    /// Joint-angle noise σ per joint and capture (rad).
    pub joint: f64,
}

/// How the noise levels are chosen.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct NoiseOptions {
    /// Pixel noise σ (px); estimated from the residuals when `None`.
    pub px: Option<f64>,
    /// Joint-angle noise σ (rad); estimated from the residuals when `None`.
    pub joint: Option<f64>,
}

/// Per-capture quantities for the noise model.
#[derive(Debug, Clone)]
pub struct CaptureNoise {
    /// Left singular vectors of `J_θ,c` (2k × d).
    u: DMatrix<f64>,
    /// Its squared singular values (d).
    s2: DVector<f64>,
}

impl CaptureNoise {
    /// Decomposes `J_θ,c`, the Jacobian of capture `index` of `at` with respect to its
    /// joint angles (its joint offsets' columns: a joint's angle and its offset enter its
    /// step as one amount); also returns the capture's unweighted residuals.
    fn with_residuals(at: &Linearisation, index: usize) -> (CaptureNoise, DVector<f64>) {
        let joints: Vec<Param> = at
            .capture_params(index)
            .iter()
            .copied()
            .filter(|p| joint_offsets().any(|j| j == *p))
            .collect();
        let CaptureSlice {
            residuals: r,
            jacobian: jac,
        } = at.capture(index, &joints, None);
        // From the small d × d eigenproblem of JᵀJ: JᵀJ v = s² v, u = J v / s. Directions
        // with s² below 1e-12 of the largest carry no joint noise worth weighting and are
        // dropped (their u would not be accurate).
        let eigen = (jac.transpose() * &jac).symmetric_eigen();
        let max = eigen.eigenvalues.iter().copied().fold(0.0, f64::max);
        let keep: Vec<usize> = (0..eigen.eigenvalues.len())
            .filter(|&k| eigen.eigenvalues[k] > 1e-12 * max && eigen.eigenvalues[k] > 0.0)
            .collect();
        let mut u = DMatrix::zeros(jac.nrows(), keep.len());
        let mut s2 = DVector::zeros(keep.len());
        for (c, &k) in keep.iter().enumerate() {
            let l = eigen.eigenvalues[k];
            u.set_column(c, &(&jac * eigen.eigenvectors.column(k) / l.sqrt()));
            s2[c] = l;
        }
        (CaptureNoise { u, s2 }, r)
    }

    /// The whitening `Σ_c^{-1/2}` (symmetric, low rank plus identity) for the given noise
    /// levels.
    pub fn whitening(&self, levels: NoiseLevels) -> Whitening {
        self.clone().into_whitening(levels)
    }

    /// [`CaptureNoise::whitening`], keeping the decomposition's directions instead of a
    /// copy of them.
    pub fn into_whitening(self, levels: NoiseLevels) -> Whitening {
        let a = levels.px * levels.px;
        let b = levels.joint * levels.joint;
        // Σ = a·I + U·diag(b·s²)·Uᵀ ⇒ Σ^{-1/2} = (I − U·diag(1 − sqrt(a/(a + b·s²)))·Uᵀ)/√a.
        Whitening::LowRank {
            shrink: self.s2.map(|s2| 1.0 - (a / (a + b * s2)).sqrt()),
            u: self.u,
            scale: 1.0 / a.sqrt(),
        }
    }
}

/// Every joint's offset: what a [`Linearisation`] for [`estimate_from`] must differentiate by.
pub fn joint_offsets() -> impl Iterator<Item = Param> {
    Joint::ALL.into_iter().map(|j| j.offset())
}

/// Sufficient statistics of one capture's residual for the variance-component fit.
struct Components {
    /// Squares of the residual's coordinates along the joint directions.
    z2: Vec<f64>,
    /// The joint directions' squared singular values.
    s2: Vec<f64>,
    /// Energy of the residual outside the joint directions.
    rest: f64,
    /// Number of residuals.
    n: usize,
}

/// Estimates the noise levels from the residuals at a solution by maximum likelihood over
/// the two variance components (pixel, joint), with `fitted` parameters' worth of degrees
/// of freedom taken off the pixel part. Given levels are kept.
pub fn estimate(
    problem: &Problem,
    params: &[f64; PARAMETER_COUNT],
    fitted: usize,
    given: NoiseOptions,
) -> Option<(NoiseLevels, Vec<CaptureNoise>)> {
    let at = Linearisation::at(problem, joint_offsets().collect(), params)?;
    Some(estimate_from(&at, fitted, given))
}

/// `problem` whitened by the noise model estimated from its residuals at the point of `at`
/// (`given` levels taken as given), started there, with the levels; `None` when the
/// residuals are zero (a noise-free fit has nothing to weight by).
pub fn whiten(
    problem: &Problem,
    at: &Linearisation,
    given: NoiseOptions,
) -> Option<(Problem, NoiseLevels)> {
    let fitted = problem.free().len();
    let (levels, captures) = estimate_from(at, fitted, given);
    if !(levels.px > 0.0 && levels.px.is_finite()) {
        return None;
    }
    let mut weighted = problem.clone();
    weighted.initial = *at.values();
    for (term, cn) in weighted.captures.iter_mut().zip(captures) {
        term.whitening = Some(cn.into_whitening(levels));
    }
    Some((weighted, levels))
}

/// [`estimate`] from a linearisation at the solution that differentiates by every joint
/// offset ([`joint_offsets`]), among other parameters.
pub fn estimate_from(
    at: &Linearisation,
    fitted: usize,
    given: NoiseOptions,
) -> (NoiseLevels, Vec<CaptureNoise>) {
    let count = at.capture_count();
    let mut noise = Vec::with_capacity(count);
    let mut parts = Vec::with_capacity(count);
    for index in 0..count {
        let (cn, r) = CaptureNoise::with_residuals(at, index);
        let z = cn.u.transpose() * &r;
        let z2: Vec<f64> = z.iter().map(|x| x * x).collect();
        let rest = (r.norm_squared() - z2.iter().sum::<f64>()).max(0.0);
        parts.push(Components {
            z2,
            s2: cn.s2.iter().copied().collect(),
            rest,
            n: r.len(),
        });
        noise.push(cn);
    }
    let total: usize = parts.iter().map(|c| c.n).sum();
    let dof = total.saturating_sub(fitted).max(1) as f64;
    // For a ratio ρ = σ_θ²/σ_px², the best σ_px² is closed-form; profile over ρ.
    let px2_given = given.px.map(|p| p * p);
    let px2_for = |rho: f64| -> f64 {
        px2_given.unwrap_or_else(|| {
            parts
                .iter()
                .map(|c| {
                    c.rest
                        + c.z2
                            .iter()
                            .zip(&c.s2)
                            .map(|(z2, s2)| z2 / (1.0 + rho * s2))
                            .sum::<f64>()
                })
                .sum::<f64>()
                / dof
        })
    };
    // −2·log-likelihood up to a constant: Σ_c [n_c·ln a + rest_c/a
    //   + Σ_k (ln(1 + ρ s²_k) + z²_k / (a (1 + ρ s²_k)))].
    let neg_log_lik = |rho: f64| -> f64 {
        let a = px2_for(rho).max(1e-300);
        let mut v = total as f64 * a.ln();
        for c in &parts {
            v += c.rest / a;
            for (z2, s2) in c.z2.iter().zip(&c.s2) {
                let f = rho * s2;
                v += f.ln_1p() + z2 / (a * (1.0 + f));
            }
        }
        v
    };
    let rho = match (given.joint, px2_given) {
        (Some(j), Some(a)) => j * j / a,
        (Some(j), None) => {
            // σ_θ given, σ_px estimated: fixed point of σ_px² = px2_for(σ_θ² / σ_px²).
            let mut a = px2_for(0.0).max(1e-300);
            for _ in 0..100 {
                a = px2_for(j * j / a).max(1e-300);
            }
            j * j / a
        }
        (None, _) => {
            let best = golden_section(|l| neg_log_lik(l.exp()), -40.0, 20.0).exp();
            if neg_log_lik(0.0) <= neg_log_lik(best) {
                0.0
            } else {
                best
            }
        }
    };
    let px2 = px2_for(rho);
    let levels = NoiseLevels {
        px: px2.sqrt(),
        joint: (rho * px2).sqrt(),
    };
    (levels, noise)
}

/// Minimises a unimodal function on `[lo, hi]` by golden-section search.
fn golden_section(f: impl Fn(f64) -> f64, mut lo: f64, mut hi: f64) -> f64 {
    let g = (5f64.sqrt() - 1.0) / 2.0;
    let mut a = hi - g * (hi - lo);
    let mut b = lo + g * (hi - lo);
    let (mut fa, mut fb) = (f(a), f(b));
    for _ in 0..100 {
        if fa < fb {
            hi = b;
            b = a;
            fb = fa;
            a = hi - g * (hi - lo);
            fa = f(a);
        } else {
            lo = a;
            a = b;
            fa = fb;
            b = lo + g * (hi - lo);
            fb = f(b);
        }
        if hi - lo < 1e-6 {
            break;
        }
    }
    (lo + hi) / 2.0
}
