//! What a capture tells: the Fisher information each capture carries about the free
//! parameters under the per-capture noise model (pixel noise plus joint noise shared by a
//! capture's vertices), the problem `solve` would pose for the captures, and the sums of
//! such information that [`super::design`] selects by.

use nalgebra::DMatrix;

use crate::body::BodyModel;
use crate::model::{
    CameraId, FixedSet, JointAngles, Model, PARAMETER_COUNT, Side, StanceChains, Vertex,
};
use crate::solve::jacobian::Evaluator;
use crate::solve::noise::{self, NoiseLevels, NoiseOptions};
use crate::solve::{CaptureTerm, Loss, Observation, Problem, Tolerances};

/// The information one capture carries: `M_c = Gᵀ·G` on a few of the free parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct CaptureInformation {
    /// Indices into the free parameters of `G`'s columns.
    pub columns: Vec<usize>,
    /// `k × columns.len()` factor with `k` the rank of the capture's information.
    pub factor: DMatrix<f64>,
}

/// The body the camera sees the boards past, and the parameters its lines of sight are
/// predicted at: only the vertices it leaves in plain sight inform
/// ([`crate::body::sight::in_sight`]).
#[derive(Debug, Clone, Copy)]
pub struct PastBody<'a> {
    /// The body model.
    pub body: &'a BodyModel,
    /// The parameters (internal units) the lines of sight are predicted at.
    pub params: &'a [f64; PARAMETER_COUNT],
}

impl PastBody<'_> {
    /// Whether at least `need` vertices of the board of leg `side` are in plain sight of
    /// the camera of `chains` (the stance's, [`Model::chains_for`]) at `joints` (the count
    /// stops once it decides).
    pub fn at_least_in_sight(
        &self,
        model: &Model,
        side: Side,
        joints: &JointAngles,
        chains: &StanceChains,
        need: usize,
    ) -> bool {
        crate::body::sight::Sightlines::with_chains(
            model,
            self.body,
            side,
            joints,
            chains,
            self.params,
            crate::body::sight::Growth::FOR_OFFSETS,
        )
        .at_least_in_sight(need)
    }

    /// The vertices of the board of leg `side` in plain sight of `camera` at `joints`.
    pub fn in_sight(
        &self,
        model: &Model,
        camera: CameraId,
        side: Side,
        joints: &JointAngles,
    ) -> Vec<Vertex> {
        crate::body::sight::in_sight(model, self.body, camera, side, joints, self.params)
    }
}

/// The Fisher information of each capture `(side, joints)` about the parameters left free
/// by `fixed`, at the nominal model (all offsets zero), under the noise model with
/// `levels`: pixel noise on every vertex plus joint noise shared by the capture's vertices.
/// `None` for a capture whose board is (partly) behind the camera.
pub fn capture_information(
    model: &Model,
    captures: &[(Side, JointAngles)],
    fixed: &FixedSet,
    levels: NoiseLevels,
) -> Vec<Option<CaptureInformation>> {
    let lower: Vec<(CameraId, Side, JointAngles)> = captures
        .iter()
        .map(|(side, joints)| (CameraId::Lower, *side, *joints))
        .collect();
    capture_information_for(model, &lower, fixed, levels, None)
}

/// [`capture_information`] of captures `(camera, side, joints)`, each through its camera,
/// of the vertices `past` leaves in plain sight (all when `None`).
pub fn capture_information_for(
    model: &Model,
    captures: &[(CameraId, Side, JointAngles)],
    fixed: &FixedSet,
    levels: NoiseLevels,
    past: Option<PastBody>,
) -> Vec<Option<CaptureInformation>> {
    let zero = [0.0; PARAMETER_COUNT];
    let (mut problem, index) = problem_of(model, captures, fixed, past);
    // The noise model's whitening at the given levels (nothing is estimated when both are
    // given; the residuals are zero here).
    let given = NoiseOptions {
        px: Some(levels.px),
        joint: Some(levels.joint),
    };
    if let Some((levels, noise)) = noise::estimate(&problem, &zero, 0, given) {
        for (term, n) in problem.captures.iter_mut().zip(&noise) {
            term.whitening = Some(n.whitening(levels));
        }
    }
    let evaluator = Evaluator::new(&problem);
    index
        .into_iter()
        .map(|k| {
            let k = k?;
            let cj = evaluator.capture_at(k, &zero)?;
            let cols = cj.columns.len();
            let rows = cj.residuals.len();
            let jac = DMatrix::from_row_slice(rows, cols, &cj.jacobian);
            let info = jac.transpose() * &jac;
            let eigen = info.symmetric_eigen();
            let max = eigen.eigenvalues.iter().copied().fold(0.0, f64::max);
            let keep: Vec<usize> = (0..cols)
                .filter(|&i| eigen.eigenvalues[i] > 1e-12 * max && eigen.eigenvalues[i] > 0.0)
                .collect();
            let mut factor = DMatrix::zeros(keep.len(), cols);
            for (r, &i) in keep.iter().enumerate() {
                let s = eigen.eigenvalues[i].sqrt();
                for c in 0..cols {
                    factor[(r, c)] = s * eigen.eigenvectors[(c, i)];
                }
            }
            Some(CaptureInformation {
                columns: cj.columns,
                factor,
            })
        })
        .collect()
}

/// The least-squares problem `solve` poses for the captures `(camera, side, joints)` at
/// the nominal model (every offset zero), the pixels those it predicts, without noise
/// model, of the vertices `past` leaves in plain sight (all when `None`); and for each
/// capture its index among the problem's (`None` for a board (partly) behind the camera,
/// or wholly behind the body).
fn problem_of(
    model: &Model,
    captures: &[(CameraId, Side, JointAngles)],
    fixed: &FixedSet,
    past: Option<PastBody>,
) -> (Problem, Vec<Option<usize>>) {
    let zero = [0.0; PARAMETER_COUNT];
    let all: Vec<Vertex> = model.board.vertices().collect();
    let mut terms = Vec::with_capacity(captures.len());
    let mut index = Vec::with_capacity(captures.len());
    for (camera, side, joints) in captures {
        let sighted;
        let vertices: &[Vertex] = match past {
            Some(past) => {
                sighted = past.in_sight(model, *camera, *side, joints);
                &sighted
            }
            None => &all,
        };
        if vertices.is_empty() {
            index.push(None);
            continue;
        }
        let chains = model.chains_for(*camera, *side, joints);
        let Some(pixels) = model
            .project(&chains, &zero, vertices)
            .into_iter()
            .collect::<Option<Vec<_>>>()
        else {
            index.push(None);
            continue;
        };
        let term = CaptureTerm {
            capture: terms.len() as u64,
            chains,
            observations: vertices
                .iter()
                .zip(&pixels)
                .map(|(v, uv)| Observation {
                    vertex: *v,
                    point: model.board.vertex_position(*v),
                    pixel: *uv,
                })
                .collect(),
            whitening: None,
        };
        index.push(Some(terms.len()));
        terms.push(term);
    }
    let problem = Problem {
        camera: model.camera,
        captures: terms,
        initial: zero,
        fixed: fixed.clone(),
        loss: Loss::Squared,
        tolerances: Tolerances::default(),
    };
    (problem, index)
}

/// The free parameters `solve` would hold at their nominal value for a dataset of these
/// captures ([`crate::solve::identify::undetermined`]: an extended parameter whose
/// Jacobian column the parameters before it nearly produce, as the principal point and the
/// camera rotation do when every board is seen near the image centre), with the
/// combination each forms.
pub fn held_by_solve(
    model: &Model,
    captures: &[(CameraId, Side, JointAngles)],
    fixed: &FixedSet,
    past: Option<PastBody>,
) -> Vec<crate::solve::identify::Undetermined> {
    let (problem, _) = problem_of(model, captures, fixed, past);
    crate::solve::identify::undetermined(&problem).unwrap_or_default()
}

/// Adds `sign · M_c` to the information `m`.
pub fn accumulate(m: &mut DMatrix<f64>, info: &CaptureInformation, sign: f64) {
    let local = info.factor.transpose() * &info.factor;
    for (a, &i) in info.columns.iter().enumerate() {
        for (b, &j) in info.columns.iter().enumerate() {
            m[(i, j)] += sign * local[(a, b)];
        }
    }
}

/// The information of a set of captures.
pub fn information(n: usize, infos: &[&CaptureInformation]) -> DMatrix<f64> {
    let mut m = DMatrix::zeros(n, n);
    for info in infos {
        accumulate(&mut m, info, 1.0);
    }
    m
}
