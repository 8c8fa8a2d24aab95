//! The two hypotheses' fit: a camera's boards ([`Seen`]) as taken or turned back by 180°
//! about the image centre ([`turn_back`]), their residuals against the model, and the
//! camera's rotation and the legs' joint offsets fitted to them from the prediction
//! (Levenberg–Marquardt, [`fit`]).

use nalgebra::{DMatrix, DVector};

use crate::model::{CameraId, Model, PARAMETER_COUNT, Param, ParamGroup, StanceChains, Vertex};

/// One board found: the chains of its capture and its vertices.
pub(super) struct Seen {
    /// The chains of its capture.
    pub(super) chains: StanceChains,
    /// Its vertices and the pixels they were found at.
    pub(super) vertices: Vec<(Vertex, [f64; 2])>,
}

/// The board `seen` in a picture of `camera` turned back by 180° about the image centre:
/// every pixel mirrored through it; when the pattern looks the same turned by 180°, of
/// the two numberings the image allows, the one the prediction `params` puts nearer.
pub(super) fn turn_back(model: &Model, camera: CameraId, seen: &Seen, params: &[f64]) -> Seen {
    let c = model.intrinsics(camera);
    let (w, h) = (f64::from(c.width) - 1.0, f64::from(c.height) - 1.0);
    let mirrored: Vec<(Vertex, [f64; 2])> = seen
        .vertices
        .iter()
        .map(|&(v, p)| (v, [w - p[0], h - p[1]]))
        .collect();
    let b = &model.board;
    let chains = seen.chains.clone();
    // The pattern's colours turned by 180° are its own when its squares along both sides
    // add up to an even number (7 × 5: black corners all round).
    if (b.squares_x + b.squares_y).is_multiple_of(2) {
        let reversed: Vec<(Vertex, [f64; 2])> = mirrored
            .iter()
            .map(|&(v, p)| {
                let v = Vertex {
                    row: b.rows() - 1 - v.row,
                    col: b.cols() - 1 - v.col,
                };
                (v, p)
            })
            .collect();
        if rms(&residuals(model, &chains, &reversed, params))
            < rms(&residuals(model, &chains, &mirrored, params))
        {
            return Seen {
                chains,
                vertices: reversed,
            };
        }
    }
    Seen {
        chains,
        vertices: mirrored,
    }
}

/// How far off (px) a vertex the model puts behind the camera counts.
const BEHIND_PX: f64 = 1000.0;

/// Residuals (px) of `vertices` against the model at `params`, u and v per vertex.
pub(super) fn residuals(
    model: &Model,
    chains: &StanceChains,
    vertices: &[(Vertex, [f64; 2])],
    params: &[f64],
) -> Vec<f64> {
    let which: Vec<Vertex> = vertices.iter().map(|(v, _)| *v).collect();
    model
        .project(chains, params, &which)
        .into_iter()
        .zip(vertices)
        .flat_map(|(p, (_, seen))| match p {
            Some(p) => [p[0] - seen[0], p[1] - seen[1]],
            None => [BEHIND_PX; 2],
        })
        .collect()
}

/// Root mean square of `r`.
pub(super) fn rms(r: &[f64]) -> f64 {
    (r.iter().map(|x| x * x).sum::<f64>() / r.len().max(1) as f64).sqrt()
}

/// Every residual of `boards` at `params`.
fn all_residuals(model: &Model, boards: &[Seen], params: &[f64]) -> Vec<f64> {
    boards
        .iter()
        .flat_map(|b| residuals(model, &b.chains, &b.vertices, params))
        .collect()
}

/// The parameters a hypothesis's fit frees for `camera`: its three rotation offsets
/// (first), and both legs' joint offsets.
fn free_params(camera: CameraId) -> Vec<usize> {
    camera
        .rotation_params()
        .into_iter()
        .chain(
            Param::ALL
                .into_iter()
                .filter(|p| matches!(p.group(), ParamGroup::LeftLeg | ParamGroup::RightLeg)),
        )
        .map(Param::index)
        .collect()
}

/// Most iterations of a hypothesis's fit (Levenberg–Marquardt).
const ITERATIONS: usize = 30;

/// The RMS (px per coordinate) of `boards` (of `camera`) against the model fitted from
/// `params` ([`free_params`] free, the rest held there), and how far (deg) the fit turned
/// the camera.
pub(super) fn fit(
    model: &Model,
    camera: CameraId,
    boards: &[Seen],
    params: &[f64; PARAMETER_COUNT],
) -> (f64, f64) {
    let (rms, turn, _) = fit_params(model, camera, boards, params);
    (rms, turn)
}

/// [`fit`], and the fitted parameters.
pub(super) fn fit_params(
    model: &Model,
    camera: CameraId,
    boards: &[Seen],
    params: &[f64; PARAMETER_COUNT],
) -> (f64, f64, [f64; PARAMETER_COUNT]) {
    let free = free_params(camera);
    let n = free.len();
    let at = |x: &DVector<f64>| {
        let mut p = *params;
        for (k, &i) in free.iter().enumerate() {
            p[i] += x[k];
        }
        p
    };
    let cost = |r: &[f64]| r.iter().map(|x| x * x).sum::<f64>();
    let mut x = DVector::zeros(n);
    let mut r = all_residuals(model, boards, &at(&x));
    let mut lambda = 1e-3;
    for _ in 0..ITERATIONS {
        // The Jacobian by forward differences.
        const STEP: f64 = 1e-7;
        let mut jac = DMatrix::zeros(r.len(), n);
        for k in 0..n {
            let mut hi = x.clone();
            hi[k] += STEP;
            let a = all_residuals(model, boards, &at(&hi));
            for (row, (a, b)) in a.iter().zip(&r).enumerate() {
                jac[(row, k)] = (a - b) / STEP;
            }
        }
        let jtj = jac.transpose() * &jac;
        let jtr = jac.transpose() * DVector::from_column_slice(&r);
        let mut improved = false;
        for _ in 0..10 {
            let mut damped = jtj.clone();
            for k in 0..n {
                // A parameter no board depends on (a leg without boards) stays put.
                damped[(k, k)] = damped[(k, k)] * (1.0 + lambda) + 1e-9;
            }
            let Some(step) = damped.lu().solve(&(-&jtr)) else {
                break;
            };
            let next = &x + &step;
            let rn = all_residuals(model, boards, &at(&next));
            if cost(&rn) < cost(&r) {
                improved = step.norm() > 1e-10;
                x = next;
                r = rn;
                lambda = (lambda / 10.0).max(1e-9);
                break;
            }
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
    }
    let turn = x.rows(0, 3).norm().to_degrees();
    (rms(&r), turn, at(&x))
}
