//! The vertices the robot's own body hides, as the body model predicts them: a vertex whose
//! refinement window (the squares around it, to half a square either way) is not in plain
//! sight of the camera past every part of the body (docs/BODY.md) is dropped and named,
//! whatever the image shows there. The image test of a clean saddle ([`super::saddle`])
//! sees an edge that crosses a square; this sees a part that stands over the window
//! before it pulls a vertex by less than the image can tell.
//!
//! The lines of sight are those of the model at the prediction's parameters, the body
//! grown for what the parameters may be off by: 3 mm for the board's own foot and toe
//! (rigid with the board; only the camera's place moves against them) and for the torso,
//! pelvis and arms (rigid with the head but for its two joints), 10 mm for the legs'
//! other parts. A part whose grown solid holds the camera is taken as it is.

use super::saddle::{Dropped, Why};
use super::{DetectOptions, Outcome};
use crate::body::{BodyModel, Kind, Part, first_blocking};
use crate::dataset::{Capture, Dataset};
use crate::model::{Board, JointAngles, Model, PARAMETER_COUNT, Side, Vertex};

/// How much the board's own foot and toe, the torso, pelvis and arms are grown (mm).
pub const GROW_OWN: f64 = 3.0;
/// How much the legs' other parts are grown (mm).
pub const GROW_OTHER: f64 = 10.0;

/// A vertex the body hides, with the part in front of it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hidden {
    /// Which vertex.
    pub vertex: Vertex,
    /// The part of the body in front of its window.
    pub kind: Kind,
    /// Its side, for a part of a leg or an arm.
    pub side: Option<Side>,
}

/// The points of `v`'s refinement window in the board frame: the vertex and the eight
/// points half a square from it.
fn window(board: &Board, v: Vertex) -> impl Iterator<Item = [f64; 3]> {
    let [x, y, _] = board.vertex_position(v);
    let h = board.square / 2.0;
    (-1..=1).flat_map(move |i| (-1..=1).map(move |j| [x + i as f64 * h, y + j as f64 * h, 0.0]))
}

/// The vertices of `capture`'s board that `body` hides from its camera, predicted with the
/// parameters `params` (the logged angles plus their offsets pose the body).
pub fn hidden(
    model: &Model,
    body: &BodyModel,
    capture: &Capture,
    params: &[f64; PARAMETER_COUNT],
) -> Vec<Hidden> {
    let joints = JointAngles::from_fn(|j| capture.joints.get(j) + params[j.offset().index()]);
    let chains = model.chains_for(capture.camera, capture.side, &capture.joints);
    let eye = chains.camera.eval(params).translation;
    let board = chains.board.eval(params);
    let posed = body.pose(&model.robot, &model.board, &joints);
    let side = capture.side;
    let grow = |p: &Part| {
        let g = if own_foot(p, side) || !p.kind.is_leg() {
            GROW_OWN
        } else {
            GROW_OTHER
        };
        if p.shape.distance(eye) <= g { 0.0 } else { g }
    };
    let carrier = |p: &Part| p.kind == Kind::Sandal && p.side == Some(side);
    model
        .board
        .vertices()
        .filter_map(|v| {
            let targets: Vec<[f64; 3]> = window(&model.board, v).map(|p| board.apply(&p)).collect();
            first_blocking(&posed, eye, &targets, grow, carrier).map(|part| Hidden {
                vertex: v,
                kind: part.kind,
                side: part.side,
            })
        })
        .collect()
}

/// `outcome` without the vertices the body model puts behind a part of the robot
/// ([`hidden`]), each named among the dropped; rejected when fewer than
/// [`super::guided::MIN_VERTICES`] are left. Only with the model (`use_model`) and a body
/// ([`DetectOptions::body`]).
pub(super) fn drop_hidden(
    dataset: &Dataset,
    capture: &Capture,
    options: &DetectOptions,
    outcome: Outcome,
) -> Outcome {
    let Outcome::Found {
        mut corners,
        order,
        whole_image,
        numbered,
        mut dropped,
    } = outcome
    else {
        return outcome;
    };
    let hidden = match &options.body {
        Some(body) if options.use_model => {
            hidden(&dataset.model, body, capture, &options.prediction())
        }
        _ => Vec::new(),
    };
    let before = corners.len();
    corners.retain(|c| {
        let Some(h) = hidden.iter().find(|h| h.vertex == c.vertex) else {
            return true;
        };
        dropped.push(Dropped {
            vertex: c.vertex,
            pixel: c.pixel,
            why: Why::Behind {
                kind: h.kind,
                side: h.side,
            },
        });
        false
    });
    if corners.len() < super::guided::MIN_VERTICES && corners.len() < before {
        return Outcome::Rejected {
            reason: format!(
                "{} of the {before} vertices found lie behind the robot's body (body model)",
                before - corners.len()
            ),
        };
    }
    dropped.sort_by_key(|d| d.vertex);
    Outcome::Found {
        corners,
        order,
        whole_image,
        numbered,
        dropped,
    }
}

/// Whether `p` is the foot or toe of the leg on `side`.
fn own_foot(p: &Part, side: Side) -> bool {
    p.side == Some(side) && matches!(p.kind, Kind::Foot | Kind::Toe)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{CameraId, Joint};

    fn capture(joints: JointAngles) -> Capture {
        Capture {
            id: 0,
            side: Side::Left,
            camera: CameraId::Lower,
            image: None,
            joints,
            line: 0,
        }
    }

    #[test]
    fn the_toe_hides_the_first_column_of_the_papers_board_and_the_chest_a_head_pitched_down() {
        let model = Model::default();
        let body = BodyModel::default();
        let zero = [0.0; PARAMETER_COUNT];
        let raised = crate::body::raised_left();
        let toe = |model: &Model| -> Vec<Vertex> {
            hidden(model, &body, &capture(raised), &zero)
                .into_iter()
                .filter(|h| h.kind == Kind::Toe)
                .map(|h| {
                    assert_eq!(h.side, Some(Side::Left), "{h:?}");
                    h.vertex
                })
                .collect()
        };
        // The paper's board begins under the toe: the toe hides vertices of its first
        // column, none of the others.
        let under = toe(&model);
        assert!(!under.is_empty());
        assert!(under.iter().all(|v| v.col == 0), "{under:?}");
        // A board 9 cm farther out clears the toe.
        let mut far = model;
        far.board.mount_origin[0] = 260.0;
        assert_eq!(toe(&far), Vec::<Vertex>::new());
        // The camera looking down at its chest: the torso hides the board's near rows.
        let all = hidden(&model, &body, &capture(raised), &zero);
        assert!(all.iter().any(|h| h.kind == Kind::Torso), "{all:?}");
        let mut up = raised;
        up.set(Joint::HeadPitch, -0.2);
        let fewer = hidden(&model, &body, &capture(up), &zero);
        assert!(
            fewer.iter().filter(|h| h.kind == Kind::Torso).count()
                < all.iter().filter(|h| h.kind == Kind::Torso).count(),
            "{fewer:?}"
        );
    }
}
