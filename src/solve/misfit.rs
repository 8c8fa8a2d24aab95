//! Does the fitted model explain the data? A cluster-robust score (Lagrange-multiplier)
//! test of every family that was not fitted, at the least-squares solution, with no refit
//! (docs/MODEL.md, "Misfit").
//!
//! For a family `F` held at zero, the score is `g = J̃_Fᵀ r`, with `J̃_F` the family's
//! Jacobian columns with the fitted parameters' columns projected out and `r` the residuals.
//! Each capture contributes `s_c = J̃_F,cᵀ r_c`; since a capture's residuals share its joint
//! noise, the captures, not the vertices, are the independent units: Hotelling's
//! `T² = C·s̄ᵀ S⁺ s̄` over the `C` capture scores (mean `s̄`, sample covariance `S`), which
//! holds for any correlation within a capture, is referred to `F(q, C − q)` as
//! `(C − q)/(q (C − 1)) · T²` with `q` directions tested. A family is significant when its p-value is below
//! [`FAMILY_ALPHA`] divided by the number of families tested (Bonferroni), so a dataset
//! that the model fits is flagged in about [`FAMILY_ALPHA`] of the cases or fewer.
//!
//! Beside the families, the residuals themselves are checked for plausibility: an RMS
//! beyond [`IMPLAUSIBLE_RMS_PX`] is not a calibration, and a joint noise that the noise
//! model would need beyond [`IMPLAUSIBLE_JOINT_NOISE_DEG`] is structure, not noise.

use nalgebra::{DMatrix, DVector};
use statrs::distribution::{ContinuousCDF, FisherSnedecor};

use super::identify::threshold;
use super::linearisation::Linearisation;
use super::problem::Problem;
use crate::model::{Family, PARAMETER_COUNT, Param};

/// Family-wise false-alarm rate of the misfit verdict (nominal; docs/MODEL.md §11, step 6
/// of the statistic).
pub const FAMILY_ALPHA: f64 = 0.01;
/// Family-wise level at which `--model auto` frees a family (Bonferroni over the families
/// tested, like [`FAMILY_ALPHA`]). More liberal than the misfit verdict on purpose: freeing
/// a family the data do not need costs a little σ, honestly reported; leaving out one they
/// need biases the estimates by many σ (docs/MODEL.md §11, "`--model auto`").
pub const AUTO_ALPHA: f64 = 0.10;
/// A residual RMS (either coordinate) beyond this is not a calibration (px).
pub const IMPLAUSIBLE_RMS_PX: f64 = 10.0;
/// Joint noise beyond this per joint and capture is not what a NAO's encoders give (deg).
pub const IMPLAUSIBLE_JOINT_NOISE_DEG: f64 = 0.5;
/// A residual RMS (both coordinates) below this is rounding: the model explains the data
/// exactly (a noise-free simulation), nothing is tested, and RMS comparisons treat
/// differences this small as equal (px).
pub const ROUNDING_RMS_PX: f64 = 1e-6;

/// The score test of one family.
#[derive(Debug, Clone, PartialEq)]
pub struct FamilyTest {
    /// The family tested.
    pub family: Family,
    /// Its parameters that entered the test (those the fitted ones do not already
    /// produce).
    pub params: Vec<Param>,
    /// Directions tested (`q`).
    pub df: usize,
    /// The F statistic `(C − q)/(q (C − 1)) · T`.
    pub statistic: f64,
    /// Its p-value under "the family is not needed".
    pub p_value: f64,
    /// Whether it is significant at the Bonferroni level.
    pub significant: bool,
    /// How much of the residual sum of squares freeing the family would explain, to first
    /// order (`gᵀ (J̃_Fᵀ J̃_F)⁺ g`) (px²): what ranks the suggestions.
    pub explained_px2: f64,
}

/// The verdict on a fit.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Misfit {
    /// Whether the residuals hold more than the measurement noise explains.
    pub detected: bool,
    /// Families the data support freeing, the one explaining most of the residuals first.
    pub suggest: Vec<Family>,
    /// One plain sentence: what is wrong and what to try (or that nothing is).
    pub message: String,
    /// Every family's test.
    pub tests: Vec<FamilyTest>,
    /// Whether the noise model was set aside because of the misfit (the reported σ is then
    /// the capture-clustered sandwich).
    pub noise_model_set_aside: bool,
}

/// Score tests of every family not (fully) free in `problem`, at the full parameter vector
/// `values`, on the residuals as `problem` weighs them (whitened where a capture has a
/// whitening). `held` marks parameters held because they are undetermined (never tested).
pub fn family_tests(
    problem: &Problem,
    values: &[f64; PARAMETER_COUNT],
    held: &[bool; PARAMETER_COUNT],
) -> Vec<FamilyTest> {
    Linearisation::at(problem, tested_columns(problem, held), values)
        .map_or_else(Vec::new, |at| family_tests_at(problem, &at, held))
}

/// [`family_tests`] from a linearisation of `problem`'s captures at the solution that
/// differentiates (at least) by [`tested_columns`].
pub fn family_tests_at(
    problem: &Problem,
    at: &Linearisation,
    held: &[bool; PARAMETER_COUNT],
) -> Vec<FamilyTest> {
    Scores::at(problem, at, held).map_or_else(Vec::new, |s| s.tests())
}

/// The parameters the tests differentiate by: the fitted ones and every candidate (fixed,
/// not `held`).
pub fn tested_columns(problem: &Problem, held: &[bool; PARAMETER_COUNT]) -> Vec<Param> {
    Param::ALL
        .into_iter()
        .filter(|p| problem.fixed.can_free(*p))
        .filter(|p| !problem.fixed.is_fixed(*p) || !held[p.index()])
        .collect()
}

/// What the score tests need, over the fitted parameters and every candidate (the columns
/// `free`): the Gram matrix `JᵀJ` of the Jacobian and each capture's gradient `J_cᵀ r_c`.
/// Both are summed capture by capture from the captures' own Jacobians, so the tall
/// Jacobian is never formed: the projections the tests need are small products of these.
struct Scores {
    candidates: Vec<(Family, Vec<Param>)>,
    fitted: Vec<Param>,
    free: Vec<Param>,
    /// `JᵀJ` over `free`.
    gram: DMatrix<f64>,
    /// One row per capture: `J_cᵀ r_c` over `free`.
    gradients: DMatrix<f64>,
}

impl Scores {
    /// `None` when there is nothing to test.
    fn at(problem: &Problem, at: &Linearisation, held: &[bool; PARAMETER_COUNT]) -> Option<Scores> {
        let fitted = problem.free();
        let candidates: Vec<(Family, Vec<Param>)> = Family::ALL
            .into_iter()
            .map(|f| {
                let params: Vec<Param> = f
                    .params()
                    .filter(|p| problem.fixed.can_free(*p))
                    .filter(|p| problem.fixed.is_fixed(*p) && !held[p.index()])
                    .collect();
                (f, params)
            })
            .filter(|(_, params)| !params.is_empty())
            .collect();
        if candidates.is_empty() {
            return None;
        }
        // The fitted parameters and every candidate.
        let free = tested_columns(problem, held);
        let sums = at.normal_sums(problem, &free);
        Some(Scores {
            candidates,
            fitted,
            free,
            gram: sums.gram,
            gradients: sums.gradients,
        })
    }

    /// The tests. With `A` the fitted columns scaled to unit norm and `J_K` the candidate
    /// columns, the candidates with `A`'s span projected out are `J̃ = J_K − A·B`,
    /// `B = (AᵀA)⁺AᵀJ_K` (directions of `AᵀA` below 1e-10 of its largest eigenvalue left
    /// out); their Gram matrix is `J_KᵀJ_K − (AᵀJ_K)ᵀB` and capture `c`'s scores are
    /// `J̃_cᵀr_c = J_K,cᵀr_c − Bᵀ·A_cᵀr_c`.
    fn tests(&self) -> Vec<FamilyTest> {
        let free = &self.free;
        let column = |p: Param| free.iter().position(|q| *q == p).expect("free");
        let fitted: Vec<usize> = self.fitted.iter().map(|p| column(*p)).collect();
        let candidate_params: Vec<Param> = self
            .candidates
            .iter()
            .flat_map(|(_, ps)| ps.iter().copied())
            .collect();
        let targets: Vec<usize> = candidate_params.iter().map(|p| column(*p)).collect();
        let captures = self.gradients.nrows();
        let sub = |rows: &[usize], cols: &[usize]| {
            DMatrix::from_fn(rows.len(), cols.len(), |i, j| self.gram[(rows[i], cols[j])])
        };
        let mut projected_gram = sub(&targets, &targets);
        let mut capture_scores = self.gradients.select_columns(&targets);
        if !fitted.is_empty() {
            let scale: DVector<f64> = DVector::from_iterator(
                fitted.len(),
                fitted.iter().map(|&f| {
                    let d = self.gram[(f, f)].sqrt();
                    if d > 0.0 { 1.0 / d } else { 1.0 }
                }),
            );
            let scaled_gram = DMatrix::from_fn(fitted.len(), fitted.len(), |i, j| {
                self.gram[(fitted[i], fitted[j])] * scale[i] * scale[j]
            });
            // AᵀJ_K
            let mut cross = sub(&fitted, &targets);
            for (i, mut row) in cross.row_iter_mut().enumerate() {
                row *= scale[i];
            }
            if let Ok(inverse) = scaled_gram.pseudo_inverse(1e-10) {
                let b = inverse * &cross;
                projected_gram -= cross.transpose() * &b;
                projected_gram = (&projected_gram + projected_gram.transpose()) * 0.5;
                // Rows A_cᵀr_c of every capture.
                let mut a_r = self.gradients.select_columns(&fitted);
                for (j, mut col) in a_r.column_iter_mut().enumerate() {
                    col *= scale[j];
                }
                capture_scores -= a_r * b;
            }
        }
        let position = |p: Param| {
            candidate_params
                .iter()
                .position(|q| *q == p)
                .expect("candidate")
        };
        let tests = self.candidates.len().max(1) as f64;
        self.candidates
            .iter()
            .filter_map(|(family, params)| {
                let mut kept = Vec::new();
                let mut norms = Vec::new();
                for &p in params {
                    let norm = self.gram[(column(p), column(p))].sqrt();
                    if norm == 0.0 {
                        continue;
                    }
                    let i = position(p);
                    let projected = projected_gram[(i, i)].max(0.0).sqrt();
                    if projected / norm >= threshold(p) {
                        kept.push(p);
                        norms.push(norm);
                    }
                }
                let k = kept.len();
                if k == 0 || captures <= k + 1 {
                    return None;
                }
                let at: Vec<usize> = kept.iter().map(|p| position(*p)).collect();
                // The kept columns' capture scores and Gram matrix, scaled to the columns'
                // norms before projection.
                let mut scores = DMatrix::zeros(captures, k);
                for (i, (&a, norm)) in at.iter().zip(&norms).enumerate() {
                    scores.set_column(i, &(capture_scores.column(a) / *norm));
                }
                let gram = DMatrix::from_fn(k, k, |i, j| {
                    projected_gram[(at[i], at[j])] / (norms[i] * norms[j])
                });
                let g: DVector<f64> = scores.row_sum().transpose();
                let v = scores.transpose() * &scores;
                // Hotelling's T² of the capture scores: the sample covariance is centred.
                let captures_f = captures as f64;
                let v = v - &g * g.transpose() / captures_f;
                let eigen = v.symmetric_eigen();
                let max = eigen.eigenvalues.max();
                if max <= 0.0 {
                    return None;
                }
                let mut t = 0.0;
                let mut df = 0;
                for (i, &l) in eigen.eigenvalues.iter().enumerate() {
                    if l > 1e-10 * max {
                        let z = eigen.eigenvectors.column(i).dot(&g);
                        t += z * z / l;
                        df += 1;
                    }
                }
                t *= (captures_f - 1.0) / captures_f;
                let explained_px2 = gram
                    .pseudo_inverse(1e-10)
                    .map(|p| g.dot(&(p * &g)))
                    .unwrap_or(f64::NAN);
                let c = captures as f64;
                let dfq = df as f64;
                let statistic = (c - dfq) / (dfq * (c - 1.0)) * t;
                let p_value = FisherSnedecor::new(dfq, c - dfq)
                    .map(|f| f.sf(statistic))
                    .unwrap_or(f64::NAN);
                Some(FamilyTest {
                    family: *family,
                    params: kept,
                    df,
                    statistic,
                    p_value,
                    significant: p_value < FAMILY_ALPHA / tests,
                    explained_px2,
                })
            })
            .collect()
    }
}

/// The family tests under two weightings, as one test per family: `plain` on the
/// residuals in pixels, `whitened` on the residuals whitened by the noise model. Whitening
/// gives power against small effects under real joint noise; but a noise model estimated
/// at a misfitting solution takes the structure for joint noise and whitens the leg-angle
/// directions — where head, link, compliance and play effects live — away (docs/MODEL.md
/// §11, "Two weightings"). The smaller p-value
/// counts, doubled (Bonferroni over the two weightings), so the false-alarm rate stays
/// within [`FAMILY_ALPHA`]; the suggestions are ranked by the plain test's px².
pub fn combined_tests(plain: Vec<FamilyTest>, whitened: Vec<FamilyTest>) -> Vec<FamilyTest> {
    let tests = plain.len().max(1) as f64;
    plain
        .into_iter()
        .map(|p| {
            let w = whitened.iter().find(|w| w.family == p.family);
            let best = match w {
                Some(w) if w.p_value < p.p_value => w,
                _ => &p,
            };
            let p_value = (2.0 * best.p_value).min(1.0);
            FamilyTest {
                df: best.df,
                statistic: best.statistic,
                params: best.params.clone(),
                p_value,
                significant: p_value < FAMILY_ALPHA / tests,
                ..p
            }
        })
        .collect()
}

/// Whether a residual RMS (u, v; px) is beyond any plausible noise (or undefined): not a
/// calibration.
pub fn implausible_rms(rms_px: [f64; 2]) -> bool {
    let rms = rms_px[0].max(rms_px[1]);
    rms.is_nan() || rms > IMPLAUSIBLE_RMS_PX
}

/// Whether an estimated joint noise level (deg; `None` when it was given) is more than a
/// NAO's encoders give: structure, not noise.
pub fn implausible_joint_noise(joint_noise_deg: Option<f64>) -> bool {
    joint_noise_deg.is_some_and(|j| j > IMPLAUSIBLE_JOINT_NOISE_DEG)
}

/// The verdict from the family tests, the RMS and (if estimated) the joint noise level.
pub fn verdict(tests: Vec<FamilyTest>, rms_px: [f64; 2], joint_noise_deg: Option<f64>) -> Misfit {
    let mut significant: Vec<&FamilyTest> = tests.iter().filter(|t| t.significant).collect();
    significant.sort_by(|a, b| b.explained_px2.total_cmp(&a.explained_px2));
    let suggest: Vec<Family> = significant.iter().map(|t| t.family).collect();
    let rms = rms_px[0].max(rms_px[1]);
    let implausible = implausible_rms(rms_px);
    let noisy = implausible_joint_noise(joint_noise_deg);
    let detected = !suggest.is_empty() || implausible || noisy;
    let names: Vec<&str> = suggest.iter().map(|f| f.name()).collect();
    let message = if implausible {
        format!(
            "not a calibration: the residuals are {rms:.1} px RMS, beyond any plausible noise \
             ({IMPLAUSIBLE_RMS_PX} px); check the corners, the board column and the joint \
             angles"
        )
    } else if !suggest.is_empty() {
        let auto = if suggest.iter().any(|f| f.info().auto) {
            " (or --model auto)"
        } else {
            ""
        };
        format!(
            "misfit: the residuals hold structure the fitted model cannot produce; the data \
             point to {} — try --free {}{auto}",
            names.join(", "),
            names.join(",")
        )
    } else if noisy {
        format!(
            "misfit: the residuals look like {:.2}° of joint noise per capture, more than a \
             NAO's encoders give ({IMPLAUSIBLE_JOINT_NOISE_DEG}°); no family of the extended \
             model explains it — check the joint angles' timing and the images",
            joint_noise_deg.unwrap_or(f64::NAN)
        )
    } else if rms < ROUNDING_RMS_PX {
        format!(
            "the model explains the data to rounding (RMS below {ROUNDING_RMS_PX} px): nothing \
             to test"
        )
    } else {
        "the model explains the data: no family's test is significant".to_string()
    };
    Misfit {
        detected,
        suggest,
        message,
        tests,
        noise_model_set_aside: false,
    }
}
