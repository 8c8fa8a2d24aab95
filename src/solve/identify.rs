//! Undetermined parameters of the extended model: free parameters whose effect on the
//! residuals the other free parameters already produce (CamPitch, HeadPitch, CamX and CamZ,
//! for one, trade against each other). They are held at their nominal value instead of
//! being fitted, and the combination they form is named (docs/MODEL.md, "Undetermined
//! directions"). The paper's 21 parameters are never held: a dataset that cannot determine
//! them is diagnosed by the identifiability report, which suggests what to `--fix`.
//!
//! The test is a Gram–Schmidt pass over the column-scaled Jacobian in registry order (the
//! paper's parameters first): a parameter whose column keeps less than [`threshold`] of its
//! length once the columns before it are projected out adds nothing the data can tell
//! apart, and is held.

use nalgebra::{DMatrix, DVector};

use super::jacobian::Evaluator;
use super::uncertainty::Direction;
use super::{Problem, SolveError};
use crate::model::{PARAMETER_COUNT, Param};

/// A parameter is undetermined when less than this fraction of its (column-scaled)
/// Jacobian column lies outside the span of the parameters before it: its σ would be
/// inflated more than 50-fold by the trade-off. (A stricter rule, 0.2 for the extended
/// families, was tried: holding parameters that are merely weak, such as the principal
/// point against the camera rotation, biased the others on noise-free data by up to
/// 1.8 deg/(N·m) and did not make `--model auto` more honest.)
pub const UNDETERMINED_RATIO: f64 = 0.02;

/// The threshold that applies to `p` (one for all parameters).
pub fn threshold(_p: Param) -> f64 {
    UNDETERMINED_RATIO
}

/// A parameter the data cannot tell apart from others, and the combination it forms.
#[derive(Debug, Clone, PartialEq)]
pub struct Undetermined {
    /// The parameter, held at its nominal value.
    pub param: Param,
    /// What is left of its column after the others are projected out (relative).
    pub ratio: f64,
    /// The direction in parameter space (report units, largest coefficient 1) along which
    /// the residuals do not change: the parameter with the ones it trades against.
    pub direction: Direction,
}

/// Finds the undetermined free parameters of `problem` at its start values. The paper's
/// parameters are never held, so a problem that frees only them needs no Jacobian.
pub fn undetermined(problem: &Problem) -> Result<Vec<Undetermined>, SolveError> {
    if problem
        .free()
        .iter()
        .all(|p| p.family() == crate::model::Family::Paper)
    {
        return Ok(Vec::new());
    }
    let eval = Evaluator::new(problem);
    let x: Vec<f64> = problem
        .free()
        .iter()
        .map(|p| problem.initial[p.index()])
        .collect();
    let (_, jac) = eval.residuals_and_jacobian(&x).ok_or_else(|| {
        SolveError::Invalid("a vertex lies behind the camera at the start values".into())
    })?;
    Ok(undetermined_of(eval.free(), &jac))
}

/// [`undetermined`] from the Jacobian `jac` over the `free` parameters.
pub fn undetermined_of(free: &[Param], jac: &DMatrix<f64>) -> Vec<Undetermined> {
    let mut basis: Vec<DVector<f64>> = Vec::new();
    // The kept columns' indices and their coefficients in the orthonormal basis (the
    // columns of the triangular factor R of the kept, scaled columns).
    let mut kept: Vec<usize> = Vec::new();
    let mut r_columns: Vec<DVector<f64>> = Vec::new();
    let mut out = Vec::new();
    for (j, &p) in free.iter().enumerate() {
        let paper = p.family() == crate::model::Family::Paper;
        let norm = jac.column(j).norm();
        if norm == 0.0 {
            // Unobserved: the identifiability report names a paper parameter; an
            // extended one is held.
            if !paper {
                out.push(Undetermined {
                    param: p,
                    ratio: 0.0,
                    direction: Direction {
                        relative_singular_value: 0.0,
                        terms: vec![(p, 1.0)],
                    },
                });
            }
            continue;
        }
        let column: DVector<f64> = jac.column(j) / norm;
        let mut v = column.clone();
        let mut coefficients = DVector::zeros(basis.len());
        for (k, q) in basis.iter().enumerate() {
            let d = q.dot(&v);
            coefficients[k] = d;
            v.axpy(-d, q, 1.0);
        }
        let ratio = v.norm();
        if ratio >= threshold(p) {
            let mut r = DVector::zeros(basis.len() + 1);
            r.rows_mut(0, basis.len()).copy_from(&coefficients);
            r[basis.len()] = ratio;
            basis.push(v / ratio);
            kept.push(j);
            r_columns.push(r);
            continue;
        }
        if paper {
            // The paper's model keeps its parameters: a rank-deficient dataset is
            // diagnosed by the identifiability report (with a suggestion to --fix).
            continue;
        }
        // column ≈ Σ c_k · (kept column k, scaled) with R·c = Qᵀ·column (R upper
        // triangular: the kept columns in the orthonormal basis).
        let n = kept.len();
        let mut r = DMatrix::zeros(n, n);
        for (k, rc) in r_columns.iter().enumerate() {
            r.view_mut((0, k), (k + 1, 1)).copy_from(rc);
        }
        let c = r
            .solve_upper_triangular(&coefficients)
            .unwrap_or_else(|| DVector::zeros(n));
        // Moving p by δ (scaled units) and each kept k by −c_k·δ leaves the residuals
        // (nearly) unchanged. In internal units: δp = 1/‖J_p‖, δk = −c_k/‖J_k‖.
        let mut terms: Vec<(Param, f64)> = vec![(p, p.unit().to_report(1.0 / norm))];
        for (k, &i) in kept.iter().enumerate() {
            let n = jac.column(i).norm();
            let q = free[i];
            terms.push((q, q.unit().to_report(-c[k] / n)));
        }
        let max = terms.iter().map(|t| t.1.abs()).fold(0.0, f64::max);
        terms.iter_mut().for_each(|t| t.1 /= max);
        terms.retain(|t| t.1.abs() >= 1e-9);
        terms.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()));
        if terms.first().is_some_and(|t| t.1 < 0.0) {
            terms.iter_mut().for_each(|t| t.1 = -t.1);
        }
        out.push(Undetermined {
            param: p,
            ratio,
            direction: Direction {
                relative_singular_value: ratio,
                terms,
            },
        });
    }
    out
}

/// `problem` with the `undetermined` parameters held at their start values.
pub fn hold(problem: &Problem, undetermined: &[Undetermined]) -> Problem {
    let mut held = problem.clone();
    for u in undetermined {
        held.fixed.set(u.param, true);
    }
    held
}

/// A mask of the undetermined parameters, indexed by [`Param::index`].
pub fn mask(undetermined: &[Undetermined]) -> [bool; PARAMETER_COUNT] {
    let mut m = [false; PARAMETER_COUNT];
    for u in undetermined {
        m[u.param.index()] = true;
    }
    m
}

/// `truth` moved along the `undetermined` directions to where a solution holds them (each
/// undetermined parameter at zero): what the data determine, and what a solution's
/// estimates are to be compared with (to first order).
pub fn determined_truth(
    undetermined: &[Undetermined],
    truth: &[f64; PARAMETER_COUNT],
) -> [f64; PARAMETER_COUNT] {
    let mut t = *truth;
    for u in undetermined {
        let Some(lead) = u.direction.terms.iter().find(|(p, _)| *p == u.param) else {
            continue;
        };
        let step = u.param.unit().to_report(t[u.param.index()]) / lead.1;
        for (p, c) in &u.direction.terms {
            let moved = p.unit().to_report(t[p.index()]) - step * c;
            t[p.index()] = p.unit().from_report(moved);
        }
    }
    t
}
