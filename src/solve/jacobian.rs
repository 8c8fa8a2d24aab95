//! Residuals and their exact Jacobian in Rust, by forward-mode dual numbers through the same
//! generic model: what the pure-Rust backends and the Rust covariance use.
//!
//! The Jacobian is exact but not computed by brute force. Per capture, the derivative of the
//! board pose in the camera frame `T_CB` with respect to each free parameter comes from the
//! chains' structure (see `pose_derivatives`): each step is a rotation or translation by
//! an amount affine in the parameters, so one pass of prefix poses in `f64` gives every
//! step's derivative, and a parameter's is the sum over the steps it enters. Per vertex,
//! the chain rule then carries these derivatives through `p_C = R·p_B + t` (a constant
//! `p_B`) and through the generic camera model evaluated on 3-lane duals of the point. This
//! is the derivative the all-dual evaluation of the model gives (the tests compare them),
//! at a fraction of its cost.
//!
//! A robust loss is honoured by rescaling each vertex's residual pair `r` to
//! `r·√(ρ(s)/s)` with `s = ‖r‖²`, so that `½‖r̃‖² = ½ρ(s)` (see [`robust_weight`]); the
//! rescaling is differentiated exactly too, and any plain least-squares solver on `r̃`
//! minimises the robust cost `½Σρ(‖r_v‖²)`, as Ceres does with its loss functions.

use std::marker::PhantomData;

use nalgebra::{Const, DMatrix, DVector, U1};
use num_dual::{Derivative, Dual64, DualSVec64};

use super::problem::{Loss, Problem, Whitening};
use crate::model::{PARAMETER_COUNT, Param, Projection, Scalar, StanceChains, Step};

type Dual3 = DualSVec64<3>;
/// The point's three lanes, then the projection's six coefficients.
type Dual9 = DualSVec64<9>;

/// The message of every backend that refuses a robust loss together with whitening.
pub const LOSS_WITH_WHITENING: &str = "a whitening matrix cannot be combined with a robust loss";

/// `w(s) = √(ρ(s)/s)` for the squared residual norm `s` of one vertex: scaling the vertex's
/// residuals by `w` turns their squared norm into `ρ(s)`. Ceres' conventions: Huber with
/// scale `a` is `ρ(s) = s` for `s ≤ a²` and `2a√s − a²` beyond; Cauchy is
/// `ρ(s) = a²·ln(1 + s/a²)`. Generic over the scalar so that dual numbers differentiate it;
/// near `s = 0` a series keeps it finite and smooth.
pub fn robust_weight<T: Scalar>(loss: Loss, s: T) -> T {
    match loss {
        Loss::Squared => T::from(1.0),
        Loss::Huber(a) => {
            if s.re() <= a * a {
                T::from(1.0)
            } else {
                // ρ/s = 2a/√s − a²/s
                (s.sqrt().recip() * (2.0 * a) - s.recip() * (a * a)).sqrt()
            }
        }
        Loss::Cauchy(a) => {
            let x = s * (1.0 / (a * a));
            // ρ/s = ln(1 + x)/x
            let ratio = if x.re() < 1e-4 {
                // 1 − x/2 + x²/3 − x³/4 + x⁴/5: error below 1e-20 for x < 1e-4.
                T::from(1.0)
                    - x.clone()
                        * (T::from(0.5)
                            - x.clone()
                                * (T::from(1.0 / 3.0)
                                    - x.clone() * (T::from(0.25) - x.clone() * 0.2)))
            } else {
                x.ln_1p() / x
            };
            ratio.sqrt()
        }
    }
}

/// `w(s)` and `dw/ds` (see [`robust_weight`]).
fn weight_and_slope(loss: Loss, s: f64) -> (f64, f64) {
    let w = robust_weight(loss, Dual64::new(s, 1.0));
    (w.re, w.eps)
}

/// One capture, prepared for fast evaluation.
#[derive(Debug, Clone)]
struct Term {
    /// Chains with the held parameters frozen.
    chains: StanceChains,
    /// Free parameters this capture depends on: those of its chains, then those of the
    /// projection.
    used: Vec<Param>,
    /// How many of `used` are the chains'.
    chain_count: usize,
    /// Per free parameter of the capture's projection (the rest of `used`): its
    /// coefficient in fx, fy, cx, cy, k1, k2.
    projection_scales: Vec<(Param, [f64; 6])>,
    /// Their Jacobian columns.
    columns: Vec<usize>,
    /// First residual row of this capture.
    row: usize,
    /// Board-frame vertex positions.
    points: Vec<[f64; 3]>,
    /// Observed pixels.
    pixels: Vec<[f64; 2]>,
    /// Optional whitening.
    whitening: Option<Whitening>,
}

impl Term {
    fn residual_count(&self) -> usize {
        2 * self.points.len()
    }
}

/// Precomputed data to evaluate a problem quickly: chains with held parameters frozen, and
/// the column of each free parameter.
///
/// It copies what it needs from the problem, so it may outlive it (`Evaluator<'static>`);
/// the lifetime parameter only keeps the type's signature stable.
#[derive(Debug, Clone)]
pub struct Evaluator<'a> {
    loss: Loss,
    initial: [f64; PARAMETER_COUNT],
    terms: Vec<Term>,
    free: Vec<Param>,
    residual_count: usize,
    _problem: PhantomData<&'a Problem>,
}

/// The residuals of one capture and their Jacobian with respect to the free parameters
/// that capture depends on (see [`Evaluator::capture`]).
#[derive(Debug, Clone, PartialEq)]
pub struct CaptureJacobian {
    /// The weighted residuals, `u₀, v₀, u₁, v₁, …` (whitened or robustly rescaled).
    pub residuals: Vec<f64>,
    /// Row-major `residuals.len() × columns.len()` Jacobian.
    pub jacobian: Vec<f64>,
    /// The global Jacobian column (index into [`Evaluator::free`]) of each local column.
    pub columns: Vec<usize>,
}

/// Per free parameter of `projection` (those with a `column`): its coefficient in fx, fy,
/// cx, cy, k1, k2.
fn projection_scales(
    projection: &Projection,
    column: &[Option<usize>; PARAMETER_COUNT],
) -> Vec<(Param, [f64; 6])> {
    projection
        .params()
        .into_iter()
        .filter(|p| column[p.index()].is_some())
        .map(|p| {
            let scales = projection
                .coefficients()
                .map(|a| a.terms().filter(|(q, _)| *q == p).map(|(_, s)| s).sum());
            (p, scales)
        })
        .collect()
}

impl<'a> Evaluator<'a> {
    /// Prepares `problem` for evaluation.
    pub fn new(problem: &Problem) -> Self {
        Self::over(problem, problem.free(), &problem.initial, true)
    }

    /// Prepares `problem` for evaluation over the parameters `free` instead of its own free
    /// ones, every other parameter held at its value in `values`; with its weights
    /// (whitening, loss) if `weighted`, else plain least squares.
    pub fn over(
        problem: &Problem,
        free: Vec<Param>,
        values: &[f64; PARAMETER_COUNT],
        weighted: bool,
    ) -> Self {
        let mut column = [None; PARAMETER_COUNT];
        let mut held = [true; PARAMETER_COUNT];
        for (k, p) in free.iter().enumerate() {
            column[p.index()] = Some(k);
            held[p.index()] = false;
        }
        let mut row = 0;
        let terms = problem
            .captures
            .iter()
            .map(|term| {
                let chains = term.chains.freeze(&held, values);
                let mut used = chains.camera.params();
                for p in chains.board.params() {
                    if !used.contains(&p) {
                        used.push(p);
                    }
                }
                used.retain(|p| column[p.index()].is_some());
                let chain_count = used.len();
                let projection_scales = projection_scales(&chains.projection, &column);
                used.extend(projection_scales.iter().map(|(p, _)| *p));
                let columns = used
                    .iter()
                    .map(|p| column[p.index()].expect("free"))
                    .collect();
                let t = Term {
                    chains,
                    used,
                    chain_count,
                    projection_scales,
                    columns,
                    row,
                    points: term.observations.iter().map(|o| o.point).collect(),
                    pixels: term.observations.iter().map(|o| o.pixel).collect(),
                    whitening: if weighted {
                        term.whitening.clone()
                    } else {
                        None
                    },
                };
                row += t.residual_count();
                t
            })
            .collect();
        Evaluator {
            loss: if weighted {
                problem.loss
            } else {
                Loss::Squared
            },
            initial: *values,
            terms,
            free,
            residual_count: row,
            _problem: PhantomData,
        }
    }

    /// The free parameters (the Jacobian's columns).
    pub fn free(&self) -> &[Param] {
        &self.free
    }

    /// Number of residuals (rows of the Jacobian).
    pub fn residual_count(&self) -> usize {
        self.residual_count
    }

    /// Number of captures (the problem's capture order).
    pub fn capture_count(&self) -> usize {
        self.terms.len()
    }

    /// Whether the problem combines a robust loss with whitening, which no backend supports
    /// (Ceres refuses it; so do the pure-Rust backends, with [`LOSS_WITH_WHITENING`]).
    pub fn loss_with_whitening(&self) -> bool {
        self.loss != Loss::Squared && self.terms.iter().any(|t| t.whitening.is_some())
    }

    /// Weighted residuals at the free values `x`, or `None` if a vertex falls behind the
    /// camera. With a robust loss, `½‖r‖²` is the robust cost.
    pub fn residuals(&self, x: &[f64]) -> Option<DVector<f64>> {
        let params = self.expand(x);
        let mut out = DVector::zeros(self.residual_count);
        for term in &self.terms {
            let r = &mut out.as_mut_slice()[term.row..term.row + term.residual_count()];
            self.term_values(term, &params, r)?;
        }
        Some(out)
    }

    /// The full parameter vector with the free parameters set to `x`.
    pub fn expand(&self, x: &[f64]) -> [f64; PARAMETER_COUNT] {
        let mut all = self.initial;
        for (p, v) in self.free.iter().zip(x) {
            all[p.index()] = *v;
        }
        all
    }

    /// `½‖r‖²` of the weighted residuals (the robust cost with a loss), or `None`.
    pub fn cost(&self, x: &[f64]) -> Option<f64> {
        self.residuals(x).map(|r| 0.5 * r.norm_squared())
    }

    /// Weighted residuals and the dense Jacobian (m × free) at the free values `x`.
    pub fn residuals_and_jacobian(&self, x: &[f64]) -> Option<(DVector<f64>, DMatrix<f64>)> {
        let params = self.expand(x);
        let mut r = DVector::zeros(self.residual_count);
        let mut jac = DMatrix::zeros(self.residual_count, self.free.len());
        for term in &self.terms {
            let local = self.term_jacobian(term, &params)?;
            let rows = term.residual_count();
            let k = term.columns.len();
            r.rows_mut(term.row, rows)
                .copy_from_slice(&local.residuals[..rows]);
            for (c, &col) in term.columns.iter().enumerate() {
                let mut column = jac.column_mut(col);
                for i in 0..rows {
                    column[term.row + i] = local.jacobian[i * k + c];
                }
            }
        }
        Some((r, jac))
    }

    /// The weighted residuals of capture `index` (problem order) and their Jacobian with
    /// respect to the free parameters it depends on, at the free values `x`.
    pub fn capture(&self, index: usize, x: &[f64]) -> Option<CaptureJacobian> {
        self.capture_at(index, &self.expand(x))
    }

    /// [`Evaluator::capture`] at the full parameter vector `params` (internal units).
    pub fn capture_at(
        &self,
        index: usize,
        params: &[f64; PARAMETER_COUNT],
    ) -> Option<CaptureJacobian> {
        self.term_jacobian(&self.terms[index], params)
    }

    /// The weighted residuals of capture `index` at the full parameter vector `params`, or
    /// `None` when a vertex falls behind the camera.
    pub fn capture_residuals_at(
        &self,
        index: usize,
        params: &[f64; PARAMETER_COUNT],
    ) -> Option<Vec<f64>> {
        let term = &self.terms[index];
        let mut r = vec![0.0; term.residual_count()];
        self.term_values(term, params, &mut r)?;
        Some(r)
    }

    /// The free parameters capture `index` depends on (its local Jacobian columns).
    pub fn capture_parameters(&self, index: usize) -> &[Param] {
        &self.terms[index].used
    }

    /// Weighted residuals of one capture into `r`.
    fn term_values(
        &self,
        term: &Term,
        params: &[f64; PARAMETER_COUNT],
        r: &mut [f64],
    ) -> Option<()> {
        let pose = term.chains.camera_to_board::<f64>(params);
        let coefficients = term.chains.projection.coefficients_at(params);
        for (k, (p, px)) in term.points.iter().zip(&term.pixels).enumerate() {
            let [u, v] = term
                .chains
                .projection
                .project_with(&coefficients, &pose.apply(p))?;
            r[2 * k] = u - px[0];
            r[2 * k + 1] = v - px[1];
        }
        self.weigh_values(term, r);
        Some(())
    }

    /// Residuals and local Jacobian of one capture at the full parameter vector `params`.
    fn term_jacobian(
        &self,
        term: &Term,
        params: &[f64; PARAMETER_COUNT],
    ) -> Option<CaptureJacobian> {
        let k = term.used.len();
        let kc = term.chain_count;
        let (pose, dpose) = pose_derivatives(&term.chains, params, &term.used[..kc]);
        let rows = term.residual_count();
        let mut residuals = vec![0.0; rows];
        let mut jacobian = vec![0.0; rows * k];
        let mut dp = vec![[0.0; 3]; kc];
        let projection = &term.chains.projection;
        let coefficients = projection.coefficients().map(|a| a.eval(params));
        for (v, (p, px)) in term.points.iter().zip(&term.pixels).enumerate() {
            // The point in the camera frame and its derivative with respect to each
            // parameter: d(R·p + t) = dR·p + dt.
            let pc = pose.apply(p);
            for (d, dp) in dpose.iter().zip(dp.iter_mut()) {
                *dp = std::array::from_fn(|i| {
                    d[3 * i] * p[0] + d[3 * i + 1] * p[1] + d[3 * i + 2] * p[2] + d[9 + i]
                });
            }
            // The projection and its gradient with respect to the point (and, when the
            // projection has free parameters, its six coefficients).
            let (uv, grads): ([f64; 2], [[f64; 9]; 2]) = if term.projection_scales.is_empty() {
                let seeded: [Dual3; 3] = std::array::from_fn(|i| {
                    Dual3::new(pc[i], Derivative::derivative_generic(Const::<3>, U1, i))
                });
                let [u, w] = projection.project_with(&coefficients.map(Dual3::from), &seeded)?;
                let g = |d: &Dual3| {
                    let e = d.eps.unwrap_generic(Const::<3>, U1);
                    std::array::from_fn(|i| if i < 3 { e[i] } else { 0.0 })
                };
                ([u.re, w.re], [g(&u), g(&w)])
            } else {
                let lane = |value: f64, i: usize| {
                    Dual9::new(value, Derivative::derivative_generic(Const::<9>, U1, i))
                };
                let seeded: [Dual9; 3] = std::array::from_fn(|i| lane(pc[i], i));
                let coefficients: [Dual9; 6] =
                    std::array::from_fn(|c| lane(coefficients[c], 3 + c));
                let [u, w] = projection.project_with(&coefficients, &seeded)?;
                let g = |d: &Dual9| {
                    let e = d.eps.unwrap_generic(Const::<9>, U1);
                    std::array::from_fn(|i| e[i])
                };
                ([u.re, w.re], [g(&u), g(&w)])
            };
            residuals[2 * v] = uv[0] - px[0];
            residuals[2 * v + 1] = uv[1] - px[1];
            for (row, g) in grads.iter().enumerate() {
                let out = &mut jacobian[(2 * v + row) * k..(2 * v + row + 1) * k];
                for (o, dp) in out.iter_mut().zip(&dp) {
                    *o = g[0] * dp[0] + g[1] * dp[1] + g[2] * dp[2];
                }
                for (o, (_, scales)) in out[kc..].iter_mut().zip(&term.projection_scales) {
                    *o = (0..6).map(|c| g[3 + c] * scales[c]).sum();
                }
            }
        }
        self.weigh(term, &mut residuals, &mut jacobian, k);
        Some(CaptureJacobian {
            residuals,
            jacobian,
            columns: term.columns.clone(),
        })
    }

    /// Applies the whitening or the robust rescaling to a capture's residuals.
    fn weigh_values(&self, term: &Term, r: &mut [f64]) {
        if let Some(w) = &term.whitening {
            w.apply_in_place(r, 1);
        } else if self.loss != Loss::Squared {
            for pair in r.chunks_exact_mut(2) {
                let (w, _) = weight_and_slope(self.loss, pair[0] * pair[0] + pair[1] * pair[1]);
                pair[0] *= w;
                pair[1] *= w;
            }
        }
    }

    /// Applies the whitening or the robust rescaling to a capture's residuals and their
    /// row-major Jacobian with `k` columns.
    fn weigh(&self, term: &Term, r: &mut [f64], jac: &mut [f64], k: usize) {
        if let Some(w) = &term.whitening {
            w.apply_in_place(r, 1);
            w.apply_in_place(jac, k);
        } else if self.loss != Loss::Squared {
            // r̃ = w(s)·r, s = ‖r‖²: dr̃ = w·dr + 2·w'(s)·r·(rᵀ·dr).
            for (v, pair) in r.chunks_exact_mut(2).enumerate() {
                let (a, b) = (pair[0], pair[1]);
                let (w, slope) = weight_and_slope(self.loss, a * a + b * b);
                let rows = &mut jac[2 * v * k..(2 * v + 2) * k];
                let (ju, jv) = rows.split_at_mut(k);
                for (du, dv) in ju.iter_mut().zip(jv.iter_mut()) {
                    let ds = 2.0 * slope * (a * *du + b * *dv);
                    *du = w * *du + a * ds;
                    *dv = w * *dv + b * ds;
                }
                pair[0] = w * a;
                pair[1] = w * b;
            }
        }
    }
}

/// `T_CB = T_OC⁻¹·T_OB` at `params` and its derivatives with respect to each parameter of
/// `used`, each as 12 numbers: the row-major rotation, then the translation.
///
/// A chain is `T = S_1⋯S_n`; a step `S_k` rotates about or moves along a local axis `e` by
/// an amount `a_k`, so `∂T/∂a_k = P_k·Ĝ·Q_k` with the prefix `P_k = S_1⋯S_k`, the rest
/// `Q_k = S_(k+1)⋯S_n` and the generator `Ĝ` (`[e]×` for a rotation, the direction `e` for a
/// translation). For `T_CB`, a board step gives `+M·Ĝ·N` and a camera step `−M·Ĝ·N` (from
/// `∂(T⁻¹) = −T⁻¹·∂T·T⁻¹`), with `M = T_OC⁻¹·P_k` and `N = P_k⁻¹·T_OB` in both cases. A
/// parameter's derivative is the sum over the steps its amount enters, times its
/// coefficient there.
fn pose_derivatives(
    chains: &StanceChains,
    params: &[f64; PARAMETER_COUNT],
    used: &[Param],
) -> (crate::model::Pose<f64>, Vec<[f64; 12]>) {
    let mut slot = [None; PARAMETER_COUNT];
    for (i, p) in used.iter().enumerate() {
        slot[p.index()] = Some(i);
    }
    let camera = prefixes(&chains.camera, params);
    let board = prefixes(&chains.board, params);
    let t_oc = camera.last().expect("a prefix per step and the start");
    let t_ob = board.last().expect("a prefix per step and the start");
    let mut derivatives = vec![[0.0; 12]; used.len()];
    let chains_and_signs = [
        (&chains.camera, &camera, -1.0),
        (&chains.board, &board, 1.0),
    ];
    for (chain, prefix, sign) in chains_and_signs {
        for (k, step) in chain.steps().iter().enumerate() {
            let (axis, amount, rotation) = match step {
                Step::Rotate(axis, a) => (*axis, a, true),
                Step::Translate(axis, a) => (*axis, a, false),
                Step::Fixed(_) => continue,
            };
            if !amount.terms().any(|(p, _)| slot[p.index()].is_some()) {
                continue;
            }
            let after = &prefix[k + 1];
            let m = t_oc.inverse_then(after);
            let e = axis.index();
            let mut d = [0.0; 12];
            if rotation {
                let n = after.inverse_then(t_ob);
                // ∂R = R_M·[e]×·R_N, ∂t = R_M·(e × t_N); `[e]×·v = e × v`.
                let cross = |v: [f64; 3]| {
                    let mut out = [0.0; 3];
                    let (a, b) = ((e + 1) % 3, (e + 2) % 3);
                    out[a] = -v[b];
                    out[b] = v[a];
                    out
                };
                let column = |j: usize| cross(std::array::from_fn(|i| n.rotation[i][j]));
                let columns = [column(0), column(1), column(2), cross(n.translation)];
                for (j, c) in columns.iter().enumerate() {
                    for i in 0..3 {
                        let v = m.rotation[i][0] * c[0]
                            + m.rotation[i][1] * c[1]
                            + m.rotation[i][2] * c[2];
                        if j < 3 {
                            d[3 * i + j] = sign * v;
                        } else {
                            d[9 + i] = sign * v;
                        }
                    }
                }
            } else {
                // ∂R = 0, ∂t = R_M·e.
                for i in 0..3 {
                    d[9 + i] = sign * m.rotation[i][e];
                }
            }
            for (p, c) in amount.terms() {
                if let Some(i) = slot[p.index()] {
                    for (o, v) in derivatives[i].iter_mut().zip(&d) {
                        *o += c * v;
                    }
                }
            }
        }
    }
    (t_oc.inverse_then(t_ob), derivatives)
}

/// The poses `S_1⋯S_k` of a chain for `k = 0…n` (the identity first), at `params`.
fn prefixes(
    chain: &crate::model::chain::Chain,
    params: &[f64; PARAMETER_COUNT],
) -> Vec<crate::model::Pose<f64>> {
    let mut out = Vec::with_capacity(chain.steps().len() + 1);
    let mut pose = crate::model::Pose::identity();
    out.push(pose.clone());
    for step in chain.steps() {
        match step {
            Step::Fixed(p) => pose = pose.then_fixed(p),
            Step::Rotate(axis, a) => pose.rotate(*axis, &a.eval(params)),
            Step::Translate(axis, a) => pose.translate(*axis, &a.eval(params)),
        }
        out.push(pose.clone());
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn robust_weight_squares_to_rho() {
        for s in [0.0, 1e-12, 1e-6, 0.3, 1.0, 4.0, 17.0, 1e4] {
            let huber = robust_weight(Loss::Huber(2.0), s);
            let rho = if s <= 4.0 { s } else { 4.0 * s.sqrt() - 4.0 };
            assert!(
                (huber * huber * s - rho).abs() <= 1e-12 * rho.max(1.0),
                "huber {s}"
            );
            let cauchy = robust_weight(Loss::Cauchy(2.0), s);
            let rho = 4.0 * (s / 4.0).ln_1p();
            assert!(
                (cauchy * cauchy * s - rho).abs() <= 1e-14 * rho.max(1e-30),
                "cauchy {s}"
            );
        }
        // The series and the closed form meet smoothly.
        let a = weight_and_slope(Loss::Cauchy(1.0), 1e-4 * (1.0 - 1e-9));
        let b = weight_and_slope(Loss::Cauchy(1.0), 1e-4 * (1.0 + 1e-9));
        assert!((a.0 - b.0).abs() < 1e-12, "{a:?} {b:?}");
        assert!((a.1 - b.1).abs() < 1e-8, "{a:?} {b:?}");
        assert_eq!(weight_and_slope(Loss::Squared, 3.0), (1.0, 0.0));
    }
}
