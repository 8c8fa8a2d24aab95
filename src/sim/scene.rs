//! What stands in front of a simulated camera: the board in view and the robot's own body
//! (legs, feet on their sandals, torso, arms), posed by the true model, in the camera frame.
//! The renderer asks the scene, ray by ray, which solid of the body a line of sight meets
//! first and how it is shaded.

use crate::body::{BodyModel, Kind, PosedBody};
use crate::model::{CameraId, Joint, JointAngles, Model, PARAMETER_COUNT, Pose, Side};

/// The body seen from the camera: its solids in the camera frame, with the bounds of each
/// in normalised image coordinates for a quick rejection.
#[derive(Debug, Clone)]
pub struct BodyView {
    body: PosedBody,
    /// Per part: `[a_min, a_max, b_min, b_max]` of its bounding sphere's image in
    /// normalised coordinates, or `None` when it reaches behind the camera (always tested).
    bounds: Vec<Option<[f64; 4]>>,
}

/// Grey level of the body's plastic facing the camera square on, and in grazing light.
const LIT: f64 = 185.0;
/// The grey of a surface seen edge on.
const DIM: f64 = 95.0;

impl BodyView {
    /// The view of `body` (posed in `O`) from a camera at `T_OC` = `camera`.
    pub fn new(body: &PosedBody, camera: &Pose<f64>) -> BodyView {
        let to_camera = camera.inverse_then(&Pose::identity());
        let body = body.moved(&to_camera);
        let bounds = body
            .parts
            .iter()
            .map(|p| {
                let (c, r) = p.shape.bounds();
                if c[0] - r <= 1.0 {
                    return None;
                }
                // The sphere's image lies within the images of its bounding cube's corners
                // (all in front of the camera).
                let mut out = [
                    f64::INFINITY,
                    f64::NEG_INFINITY,
                    f64::INFINITY,
                    f64::NEG_INFINITY,
                ];
                for n in 0..8 {
                    let s = |k: usize| if n >> k & 1 == 1 { r } else { -r };
                    let p = [c[0] + s(0), c[1] + s(1), c[2] + s(2)];
                    let (a, b) = (-p[1] / p[0], -p[2] / p[0]);
                    out = [out[0].min(a), out[1].max(a), out[2].min(b), out[3].max(b)];
                }
                Some(out)
            })
            .collect();
        BodyView { body, bounds }
    }

    /// The body part that the ray through normalised point `(a, b)` meets first, nearer
    /// than `limit` (mm along the ray from the camera), with its grey level there: the
    /// part's index and the grey level.
    pub fn hit(&self, a: f64, b: f64, limit: f64) -> Option<(usize, f64)> {
        let len = (1.0 + a * a + b * b).sqrt();
        let dir = [1.0 / len, -a / len, -b / len];
        let mut best: Option<(usize, f64, [f64; 3])> = None;
        for (k, part) in self.body.parts.iter().enumerate() {
            if let Some([a0, a1, b0, b1]) = self.bounds[k]
                && (a < a0 || a > a1 || b < b0 || b > b1)
            {
                continue;
            }
            if let Some((t, n)) = part.shape.ray([0.0; 3], dir, 0.0)
                && t < limit
                && best.is_none_or(|(_, bt, _)| t < bt)
            {
                best = Some((k, t, n));
            }
        }
        best.map(|(k, _, n)| {
            // Lambert's law with the light at the camera: bright where the surface faces
            // it, dimmer towards the silhouette; each kind of part a little apart.
            let facing = -(n[0] * dir[0] + n[1] * dir[1] + n[2] * dir[2]);
            let tint = match self.body.parts[k].kind {
                Kind::Foot | Kind::Toe | Kind::Tibia | Kind::Thigh => 0.0,
                Kind::Sandal => -25.0,
                _ => -12.0,
            };
            (k, DIM + (LIT - DIM) * facing.clamp(0.0, 1.0) + tint)
        })
    }

    /// Whether the view has no part at all.
    pub fn is_empty(&self) -> bool {
        self.body.parts.is_empty()
    }
}

/// The body as the camera `camera` sees it in the capture of the board of `side` with the
/// logged angles `joints`, on the robot with the true parameters `params`: the legs at
/// their true angles, each foot on its sole as the true model places it (so that it stands
/// exactly on its sandal), the arms where `body` holds them. The sandal carrying the board
/// in view is left out (the board is drawn with its plate); so is the head.
pub fn body_view(
    model: &Model,
    body: &BodyModel,
    camera: CameraId,
    side: Side,
    joints: &JointAngles,
    params: &[f64],
) -> BodyView {
    let mut truth = [0.0; PARAMETER_COUNT];
    for (t, p) in truth.iter_mut().zip(params) {
        *t = *p;
    }
    let true_joints = JointAngles::from_fn(|j: Joint| joints.get(j) + truth[j.offset().index()]);
    let soles = Side::BOTH.map(|s| {
        // T_OS = T_OB · (Rz(α_RotZ) · T(α_TransX, α_TransY, 0) · T_SB)⁻¹.
        let board = model.chains_for(camera, s, joints).board.eval(&truth);
        let [rot, tx, ty] = s.board_params().map(|p| truth[p.index()]);
        let mount = Pose::rotation(crate::model::Axis::Z, rot)
            .compose(&Pose::translation(tx, ty, 0.0))
            .compose(&model.board.mount());
        board.compose(&mount.inverse_then(&Pose::identity()))
    });
    let mut posed = body.pose_with_soles(&model.robot, &model.board, &true_joints, &soles);
    posed
        .parts
        .retain(|p| p.kind != Kind::Head && !(p.kind == Kind::Sandal && p.side == Some(side)));
    let eye = model.chains_for(camera, side, joints).camera.eval(&truth);
    BodyView::new(&posed, &eye)
}
