//! The optimal choice of captures: the Fisher information each candidate capture adds
//! under the per-capture noise model, and a greedy selection refined by exchange passes.
//! The information itself is computed in [`super::information`] (re-exported here).
//!
//! Criterion: `Φ = Σ_i (w_i·var_i)^q` over the free parameters, with `var = diag(M⁻¹)`,
//! `M = Σ_c J_cᵀ Σ_c⁻¹ J_c` (the Fisher information under the per-capture noise model) and
//! `q = 16`, so that the worst weighted variance decides (`q → ∞` is minimax). The weights
//! `w_i` are the average information one pool capture carries about parameter `i`
//! (column scaling: unit-free, comparable across degrees, millimetres and compliances),
//! except that the 15 angle offsets (camera rotation and leg joints), the parameters the
//! calibration is judged by, share one weight: for them the criterion is the worst
//! predicted σ itself. The greedy start is A-optimal (`q = 1`), since a high power only
//! sees the worst parameter while most are still undetermined.

use nalgebra::{DMatrix, DVector};

pub use super::information::{
    CaptureInformation, accumulate, capture_information, capture_information_for, held_by_solve,
    information,
};
use crate::model::Param;

/// The design criterion of a variance vector: `Σ (w_i·var_i)^q`.
fn criterion(var: impl Iterator<Item = f64>, weights: &[f64], power: f64) -> f64 {
    var.zip(weights)
        .map(|(v, w)| {
            let x = (v * w).max(0.0);
            if power == 1.0 { x } else { x.powf(power) }
        })
        .sum()
}

/// Work space of [`criterion_with`], kept from candidate to candidate.
#[derive(Debug, Default)]
struct Scratch {
    /// `A = C[:, cols]·Gᵀ`, column `r` at `r·n`; solved in place into `L⁻¹·Aᵀ`.
    a: Vec<f64>,
    /// `S = I + G·A[cols, :]` (column-major), factorised in place.
    s: Vec<f64>,
    /// The eight partial sums of each parameter's squared norm.
    acc: Vec<f64>,
    /// The variances after the addition.
    var: Vec<f64>,
}

/// The criterion after adding capture `info` to the design with covariance `cov`
/// (Woodbury: `(M + GᵀG)⁻¹ = C − C·Gᵀ·(I + G·C·Gᵀ)⁻¹·G·C`, only its diagonal).
///
/// Every parameter's arithmetic is that of the plain matrix expressions (nalgebra's
/// Cholesky factorisation, triangular solve and dot product, operation for operation), done
/// for all parameters at once in work space that is reused, so that a design is the same
/// number for number as with those expressions.
fn criterion_with(
    cov: &DMatrix<f64>,
    info: &CaptureInformation,
    weights: &[f64],
    power: f64,
    w: &mut Scratch,
) -> f64 {
    let n = cov.nrows();
    let k = info.factor.nrows();
    let cov = cov.as_slice();
    let g = info.factor.as_slice();
    // A = C[:, cols]·Gᵀ  (n × k), accumulated over the columns in order.
    w.a.clear();
    w.a.resize(n * k, 0.0);
    for (c, &col) in info.columns.iter().enumerate() {
        let from = &cov[col * n..col * n + n];
        for r in 0..k {
            let gv = g[r + c * k];
            if gv != 0.0 {
                for (a, x) in w.a[r * n..r * n + n].iter_mut().zip(from) {
                    *a += *x * gv;
                }
            }
        }
    }
    // S = I + G·A[cols, :]
    w.s.clear();
    w.s.resize(k * k, 0.0);
    for r in 0..k {
        w.s[r + r * k] = 1.0;
    }
    for r in 0..k {
        for (c, &col) in info.columns.iter().enumerate() {
            let gv = g[r + c * k];
            for q in 0..k {
                w.s[r + q * k] += gv * w.a[q * n + col];
            }
        }
    }
    // Cholesky S = L·Lᵀ in place (the lower triangle), column by column.
    let s = &mut w.s;
    for j in 0..k {
        for m in 0..j {
            let factor = -s[j + m * k];
            for p in j..k {
                s[p + j * k] += factor * s[p + m * k];
            }
        }
        let diag = s[j + j * k];
        // Not positive definite (or not a number): the capture adds nothing usable.
        if diag.is_nan() || diag <= 0.0 {
            return f64::INFINITY;
        }
        let denom = diag.sqrt();
        s[j + j * k] = denom;
        for p in j + 1..k {
            s[p + j * k] /= denom;
        }
    }
    // L⁻¹·Aᵀ: forward substitution, every parameter's column at once.
    for r in 0..k {
        let d = s[r + r * k];
        let (done, rest) = w.a.split_at_mut((r + 1) * n);
        let row = &mut done[r * n..];
        for x in row.iter_mut() {
            *x /= d;
        }
        for p in r + 1..k {
            let l = s[p + r * k];
            let target = &mut rest[(p - r - 1) * n..(p - r) * n];
            for (y, x) in target.iter_mut().zip(row.iter()) {
                *y += -*x * l;
            }
        }
    }
    // diag(A·S⁻¹·Aᵀ): each parameter's squared norm, summed as nalgebra's dot product sums
    // (eight partial sums over whole blocks of eight, then the rest).
    let blocks = k / 8 * 8;
    w.acc.clear();
    w.acc.resize(8 * n, 0.0);
    for b in (0..blocks).step_by(8) {
        for m in 0..8 {
            let row = &w.a[(b + m) * n..(b + m + 1) * n];
            for (acc, x) in w.acc[m * n..(m + 1) * n].iter_mut().zip(row) {
                *acc += *x * *x;
            }
        }
    }
    w.var.clear();
    w.var.extend((0..n).map(|i| {
        let acc = |m: usize| w.acc[m * n + i];
        let mut res = 0.0;
        res += acc(0) + acc(4);
        res += acc(1) + acc(5);
        res += acc(2) + acc(6);
        res += acc(3) + acc(7);
        for t in blocks..k {
            let x = w.a[t * n + i];
            res += x * x;
        }
        cov[i * n + i] - res
    }));
    criterion(w.var.iter().copied(), weights, power)
}

/// Whether the criterion after adding capture `info` is surely at least `limit`: a lower
/// bound of it reaches `limit`. The variance of a parameter `i` falls by
/// `a_iᵀ·S⁻¹·a_i ≤ |a_i|²` (`S ⪰ I`, `a_i = G·C[cols, i]`, see [`criterion_with`]), so
/// `Σ (w_i·(C_ii − |a_i|²))^q`, summed over the parameters `order` gives in turn (the
/// largest terms first), bounds the criterion below and can stop as soon as it reaches
/// `limit` — for most captures after a few parameters, at a fraction of the criterion's
/// cost. The bound is lowered a little against rounding, so that a capture whose
/// criterion is below `limit` is never passed over.
fn surely_at_least(
    cov: &DMatrix<f64>,
    info: &CaptureInformation,
    weights: &[f64],
    power: f64,
    order: &[usize],
    limit: f64,
    w: &mut Scratch,
) -> bool {
    let n = cov.nrows();
    let k = info.factor.nrows();
    let cov = cov.as_slice();
    let g = info.factor.as_slice();
    w.acc.clear();
    w.acc.resize(k, 0.0);
    let integer = power.fract() == 0.0 && (1.0..=64.0).contains(&power);
    let mut low = 0.0;
    for &i in order {
        let column = &cov[i * n..i * n + n];
        w.acc.fill(0.0);
        for (c, &col) in info.columns.iter().enumerate() {
            let x = column[col];
            for (a, gv) in w.acc.iter_mut().zip(&g[c * k..c * k + k]) {
                *a += *gv * x;
            }
        }
        let most: f64 = w.acc.iter().map(|a| a * a).sum();
        let cii = column[i];
        let x = ((cii - most - 1e-12 * cii.abs()) * weights[i]).max(0.0);
        low += if integer {
            x.powi(power as i32)
        } else {
            x.powf(power)
        };
        if low * (1.0 - 1e-6) >= limit {
            return true;
        }
    }
    false
}

/// The unused capture of `pool` whose addition to the design with covariance `cov` gives
/// the smallest criterion (of equal ones the first), with that criterion, among those whose
/// criterion is below `below` (`None` when there is none; every capture when `below` is
/// infinite): the pool's two halves searched
/// on two threads, each capture first by [`surely_at_least`] against the best found so
/// far (and `below`), and exactly by [`criterion_with`] only when that leaves it in the
/// running.
fn best_addition(
    pool: &[&CaptureInformation],
    used: &[bool],
    cov: &DMatrix<f64>,
    weights: &[f64],
    power: f64,
    below: f64,
) -> Option<(usize, f64)> {
    // The parameters by their weighted variance, the largest first: the bound's terms in
    // the order that reaches a limit soonest.
    let n = cov.nrows();
    let mut order: Vec<usize> = (0..n).collect();
    let key = |i: usize| cov[(i, i)] * weights[i];
    order.sort_by(|a, b| key(*b).total_cmp(&key(*a)));
    let order = &order;
    let search = |range: std::ops::Range<usize>| {
        let mut w = Scratch::default();
        let mut best: Option<(usize, f64)> = None;
        for c in range.filter(|c| !used[*c]) {
            let limit = best.map_or(below, |(_, v)| v.min(below));
            if limit.is_finite()
                && surely_at_least(cov, pool[c], weights, power, order, limit, &mut w)
            {
                continue;
            }
            let v = criterion_with(cov, pool[c], weights, power, &mut w);
            // Without a bound every capture competes (as an infinite criterion does).
            let admitted = below == f64::INFINITY || v < below;
            if admitted && best.is_none_or(|(_, b)| v.total_cmp(&b).is_lt()) {
                best = Some((c, v));
            }
        }
        best
    };
    let half = pool.len() / 2;
    let (first, second) = std::thread::scope(|scope| {
        let first = scope.spawn(|| search(0..half));
        let second = search(half..pool.len());
        (first.join().expect("design thread"), second)
    });
    match (first, second) {
        (Some(a), Some(b)) if b.1.total_cmp(&a.1).is_lt() => Some(b),
        (Some(a), _) => Some(a),
        (None, b) => b,
    }
}

/// Inverse of a symmetric positive definite matrix (with a tiny ridge when needed).
fn inverse(m: &DMatrix<f64>) -> DMatrix<f64> {
    let n = m.nrows();
    if let Some(c) = m.clone().cholesky() {
        return c.inverse();
    }
    let ridge = 1e-12 * m.diagonal().max().max(1e-300);
    (m + DMatrix::identity(n, n) * ridge)
        .cholesky()
        .map(|c| c.inverse())
        .unwrap_or_else(|| DMatrix::identity(n, n) / ridge)
}

/// How the selection runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DesignOptions {
    /// Exponent `q` of the criterion `Σ (w_i·var_i)^q` in the exchange passes: 1 is
    /// A-optimality, larger leans towards the worst-determined parameter (`q → ∞` is
    /// minimax). The greedy start uses `q = 1`.
    pub power: f64,
    /// Most exchange passes after the greedy selection (they stop when a pass changes
    /// nothing).
    pub exchange_passes: usize,
}

impl Default for DesignOptions {
    /// `q = 16`: the criterion is then within 20 % of the worst weighted variance alone
    /// for up to 21 parameters (`21^(1/16) = 1.21`) and smooth enough to steer the exchange.
    fn default() -> Self {
        DesignOptions {
            power: 16.0,
            exchange_passes: 1,
        }
    }
}

/// The weights `w_i` of the criterion for `n` free parameters: the average information one
/// pool capture carries about each (column scaling, so that `w_i·var_i` is unit-free), and
/// among the `focus` parameters (those with a positive factor, all in the same unit) one
/// common weight, their mean, times the parameter's factor, so that the criterion compares
/// their plain variances: its worst term is the largest σ of the focus parameters (a
/// factor `1/r²` asks for a σ `r` times the others').
pub fn weights(pool: &[&CaptureInformation], n: usize, focus: &[f64]) -> Vec<f64> {
    let total = information(n, pool);
    let mut w: Vec<f64> = (0..n)
        .map(|i| (total[(i, i)] / pool.len().max(1) as f64).max(1e-300))
        .collect();
    let focused: Vec<usize> = (0..n)
        .filter(|&i| focus.get(i).is_some_and(|f| *f > 0.0))
        .collect();
    if !focused.is_empty() {
        let mean = focused.iter().map(|&i| w[i]).sum::<f64>() / focused.len() as f64;
        for &i in &focused {
            w[i] = mean * focus[i];
        }
    }
    w
}

/// Picks `count` captures from `pool` (a capture may be picked once) that minimise the
/// criterion `Σ (w_i·var_i)^q` with the [`weights`] for `focus` (`n` free parameters):
/// from `start` (indices into `pool`, e.g. an earlier design), filled up greedily
/// (A-optimal, `q = 1`), each step adding the capture that lowers it most (exactly, by a
/// rank-k update), then exchange passes with the options' `q` that swap each picked
/// capture for the best one of the pool while that lowers the criterion. Returns the
/// indices into `pool`.
pub fn select(
    pool: &[&CaptureInformation],
    n: usize,
    focus: &[f64],
    count: usize,
    start: &[usize],
    options: &DesignOptions,
) -> Vec<usize> {
    let column = weights(pool, n, focus);
    let weights = &column;
    // A weak prior (as much as a thousandth of one capture's) keeps M invertible at the start.
    let prior = DMatrix::from_diagonal(&DVector::from_iterator(n, column.iter().map(|w| w * 1e-3)));
    let mut m = prior.clone();
    let mut chosen: Vec<usize> = Vec::with_capacity(count);
    let mut used = vec![false; pool.len()];
    for &c in start.iter().take(count) {
        if c < pool.len() && !used[c] {
            used[c] = true;
            chosen.push(c);
            accumulate(&mut m, pool[c], 1.0);
        }
    }
    while chosen.len() < count.min(pool.len()) {
        let cov = inverse(&m);
        let Some((c, _)) = best_addition(pool, &used, &cov, weights, 1.0, f64::INFINITY) else {
            break;
        };
        used[c] = true;
        chosen.push(c);
        accumulate(&mut m, pool[c], 1.0);
    }
    // The exchange criterion is scaled by the greedy design's largest weighted variance,
    // so that a high power stays within the range of floating point.
    let scale = inverse(&m)
        .diagonal()
        .iter()
        .zip(weights)
        .map(|(v, w)| v * w)
        .fold(0.0, f64::max)
        .max(1e-300);
    let scaled: Vec<f64> = weights.iter().map(|w| w / scale).collect();
    for _ in 0..options.exchange_passes {
        let mut improved = false;
        for slot in chosen.iter_mut() {
            let current = *slot;
            let cov_all = inverse(&m);
            let now = criterion(cov_all.diagonal().iter().copied(), &scaled, options.power);
            accumulate(&mut m, pool[current], -1.0);
            used[current] = false;
            let cov = inverse(&m);
            // Only a capture that lowers the criterion below what it was is taken.
            let below = now * (1.0 - 1e-9);
            let pick = match best_addition(pool, &used, &cov, &scaled, options.power, below) {
                Some((c, _)) => {
                    improved |= c != current;
                    c
                }
                None => current,
            };
            used[pick] = true;
            *slot = pick;
            accumulate(&mut m, pool[pick], 1.0);
        }
        if !improved {
            break;
        }
    }
    chosen
}

/// The predicted uncertainty of a design.
#[derive(Debug, Clone, PartialEq)]
pub struct Prediction {
    /// The free parameters.
    pub free: Vec<Param>,
    /// Predicted one-sigma of each free parameter, internal units (radians, mm, …);
    /// infinite for a parameter the captures cannot determine.
    pub std: Vec<f64>,
    /// Rank of the column-scaled information (as `solve` counts it).
    pub rank: usize,
    /// Combinations of parameters the captures cannot determine, described.
    pub undetermined: Vec<String>,
}

impl Prediction {
    /// Predicted σ of `p` in internal units, if it is free.
    pub fn std_of(&self, p: Param) -> Option<f64> {
        self.free.iter().position(|q| *q == p).map(|k| self.std[k])
    }

    /// Every free parameter the design leaves undetermined (an infinite σ: no capture
    /// sees it, or it lies on an undetermined direction), in registry order.
    pub fn undetermined_params(&self) -> Vec<Param> {
        self.free
            .iter()
            .zip(&self.std)
            .filter(|(_, s)| !s.is_finite())
            .map(|(p, _)| *p)
            .collect()
    }
}

/// Predicted σ = sqrt(diag(M⁻¹)) of a set of captures, with the identifiability analysis
/// `solve` applies to a fit (the same rank threshold and named undetermined directions).
pub fn predict(free: &[Param], infos: &[&CaptureInformation]) -> Prediction {
    let n = free.len();
    // Stack the factors: a "Jacobian" whose Gram matrix is M.
    let rows: usize = infos.iter().map(|i| i.factor.nrows()).sum();
    // At least as many rows as parameters (zero rows change nothing): the analysis then
    // sees every direction the captures leave undetermined, not only those of the
    // singular values a short matrix has.
    let mut stacked = DMatrix::zeros(rows.max(n).max(1), n);
    let mut r0 = 0;
    for info in infos {
        for r in 0..info.factor.nrows() {
            for (c, &col) in info.columns.iter().enumerate() {
                stacked[(r0 + r, col)] = info.factor[(r, c)];
            }
        }
        r0 += info.factor.nrows();
    }
    let m = stacked.transpose() * &stacked;
    let (cov, _) = crate::solve::covariance::from_jacobian(&stacked);
    let full = crate::solve::covariance::embed(free, &cov, 1.0);
    let report = crate::solve::uncertainty::identifiability_of(free, &stacked, &full);
    let std = free
        .iter()
        .enumerate()
        .map(|(k, p)| {
            if report.determined[p.index()] && m[(k, k)] > 0.0 {
                cov[(k, k)].max(0.0).sqrt()
            } else {
                f64::INFINITY
            }
        })
        .collect();
    Prediction {
        free: free.to_vec(),
        std,
        rank: report.rank,
        undetermined: report.undetermined.iter().map(|d| d.describe()).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// [`criterion_with`] in plain matrix expressions.
    fn criterion_with_matrices(
        cov: &DMatrix<f64>,
        info: &CaptureInformation,
        weights: &[f64],
        power: f64,
    ) -> f64 {
        let n = cov.nrows();
        let k = info.factor.nrows();
        let mut a: DMatrix<f64> = DMatrix::zeros(n, k);
        for (c, &col) in info.columns.iter().enumerate() {
            for r in 0..k {
                let g = info.factor[(r, c)];
                if g != 0.0 {
                    for i in 0..n {
                        a[(i, r)] += cov[(i, col)] * g;
                    }
                }
            }
        }
        let mut s: DMatrix<f64> = DMatrix::identity(k, k);
        for r in 0..k {
            for (c, &col) in info.columns.iter().enumerate() {
                let g = info.factor[(r, c)];
                for q in 0..k {
                    s[(r, q)] += g * a[(col, q)];
                }
            }
        }
        let Some(chol) = s.cholesky() else {
            return f64::INFINITY;
        };
        let y = chol
            .l()
            .solve_lower_triangular(&a.transpose())
            .unwrap_or_else(|| a.transpose());
        let var = (0..n).map(|i| cov[(i, i)] - y.column(i).norm_squared());
        criterion(var, weights, power)
    }

    /// A random capture's information on `rank` rows over some of `n` parameters.
    fn random_information(rng: &mut impl Rng, n: usize, rank: usize) -> CaptureInformation {
        let mut columns: Vec<usize> = (0..n).filter(|_| rng.random_bool(0.5)).collect();
        if columns.is_empty() {
            columns.push(rng.random_range(0..n));
        }
        let factor = DMatrix::from_fn(rank, columns.len(), |_, _| {
            if rng.random_bool(0.1) {
                0.0
            } else {
                rng.random_range(-3.0..3.0)
            }
        });
        CaptureInformation { columns, factor }
    }

    #[test]
    fn the_criterion_after_an_addition_is_that_of_the_matrix_expressions_bit_for_bit() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        for (n, rank) in [
            (1, 1),
            (5, 3),
            (21, 7),
            (21, 8),
            (32, 14),
            (32, 16),
            (40, 17),
        ] {
            let pool: Vec<CaptureInformation> = (0..3 * n)
                .map(|_| random_information(&mut rng, n, rank))
                .collect();
            let m =
                information(n, &pool.iter().collect::<Vec<_>>()) + DMatrix::identity(n, n) * 1e-3;
            let cov = inverse(&m);
            let weights: Vec<f64> = (0..n).map(|_| rng.random_range(0.1..2.0)).collect();
            let mut w = Scratch::default();
            for info in &pool {
                for power in [1.0, 16.0] {
                    let fast = criterion_with(&cov, info, &weights, power, &mut w);
                    let plain = criterion_with_matrices(&cov, info, &weights, power);
                    assert_eq!(fast.to_bits(), plain.to_bits(), "n {n}, rank {rank}");
                }
            }
            // A covariance that is not positive definite is refused alike.
            let bad = -cov.clone();
            let info = &pool[0];
            assert_eq!(
                criterion_with(&bad, info, &weights, 1.0, &mut w),
                criterion_with_matrices(&bad, info, &weights, 1.0)
            );
        }
    }

    #[test]
    fn the_best_addition_is_the_first_of_the_smallest() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(4);
        let n = 12;
        let mut pool: Vec<CaptureInformation> = (0..41)
            .map(|_| random_information(&mut rng, n, 5))
            .collect();
        // Equal captures in both halves: the first of them wins.
        pool[30] = pool[3].clone();
        pool[35] = pool[3].clone();
        let refs: Vec<&CaptureInformation> = pool.iter().collect();
        let cov = inverse(&(information(n, &refs) + DMatrix::identity(n, n)));
        let weights = vec![1.0; n];
        let mut used = vec![false; pool.len()];
        used[7] = true;
        for power in [1.0, 16.0] {
            let values: Vec<(usize, f64)> = refs
                .iter()
                .enumerate()
                .filter(|(c, _)| !used[*c])
                .map(|(c, info)| (c, criterion_with_matrices(&cov, info, &weights, power)))
                .collect();
            let serial = values.iter().copied().min_by(|a, b| a.1.total_cmp(&b.1));
            let found = best_addition(&refs, &used, &cov, &weights, power, f64::INFINITY);
            assert_eq!(found, serial);
            // Below a bound: the best below it, or none.
            let (_, best) = serial.unwrap();
            let mut sorted: Vec<f64> = values.iter().map(|v| v.1).collect();
            sorted.sort_by(f64::total_cmp);
            assert_eq!(
                best_addition(&refs, &used, &cov, &weights, power, sorted[5]),
                serial
            );
            assert_eq!(
                best_addition(&refs, &used, &cov, &weights, power, best),
                None
            );
        }
        // The best made equal to one in the second half: still the first.
        let (best, _) = best_addition(&refs, &used, &cov, &weights, 16.0, f64::INFINITY).unwrap();
        pool[40] = pool[best].clone();
        let refs: Vec<&CaptureInformation> = pool.iter().collect();
        assert_eq!(
            best_addition(&refs, &used, &cov, &weights, 16.0, f64::INFINITY).map(|b| b.0),
            Some(best.min(40))
        );
        assert_eq!(
            best_addition(&refs, &[true; 41], &cov, &weights, 1.0, f64::INFINITY),
            None
        );
    }

    #[test]
    fn the_bound_never_passes_over_a_capture_below_the_limit_and_spares_most_above() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(6);
        let n = 32;
        let pool: Vec<CaptureInformation> = (0..400)
            .map(|_| random_information(&mut rng, n, 14))
            .collect();
        let refs: Vec<&CaptureInformation> = pool.iter().collect();
        let cov = inverse(&(information(n, &refs) + DMatrix::identity(n, n) * 1e-3));
        let weights: Vec<f64> = (0..n).map(|_| rng.random_range(0.1..2.0)).collect();
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by(|a, b| {
            (cov[(*b, *b)] * weights[*b]).total_cmp(&(cov[(*a, *a)] * weights[*a]))
        });
        let mut w = Scratch::default();
        for power in [1.0, 16.0] {
            let values: Vec<f64> = pool
                .iter()
                .map(|info| criterion_with(&cov, info, &weights, power, &mut w))
                .collect();
            let mut sorted = values.clone();
            sorted.sort_by(f64::total_cmp);
            // The tenth best as the limit: every capture below it is kept, most above are
            // spared their criterion.
            let limit = sorted[10];
            let mut spared = 0;
            for (info, v) in pool.iter().zip(&values) {
                let sure = surely_at_least(&cov, info, &weights, power, &order, limit, &mut w);
                assert!(!(sure && *v < limit), "passed over {v} < {limit}");
                spared += sure as usize;
            }
            assert!(spared > 200, "{spared} of 400 spared at q = {power}");
        }
    }
}
