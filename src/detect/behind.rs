//! The vertices the robot's own body hides, as the body model predicts them: a vertex whose
//! refinement window (the squares around it, to half a square either way) is not in plain
//! sight of the camera past every part of the body (docs/BODY.md) is dropped and named,
//! whatever the image shows there. The image test of a clean saddle ([`super::saddle`])
//! sees an edge that crosses a square; this sees a part that stands over the window
//! before it pulls a vertex by less than the image can tell.
//!
//! The prediction itself is the body model's ([`crate::body::sight`]), the one the
//! planner makes its captures by.

use super::saddle::{Dropped, Why};
use super::{DetectOptions, Outcome};
use crate::body::BodyModel;
pub use crate::body::sight::{GROW_OTHER, GROW_OWN, Hidden};
use crate::dataset::{Capture, Dataset};
use crate::model::{Model, PARAMETER_COUNT};

/// The vertices of `capture`'s board that `body` hides from its camera, predicted with the
/// parameters `params` (the logged angles plus their offsets pose the body).
pub fn hidden(
    model: &Model,
    body: &BodyModel,
    capture: &Capture,
    params: &[f64; PARAMETER_COUNT],
) -> Vec<Hidden> {
    crate::body::sight::hidden(
        model,
        body,
        capture.camera,
        capture.side,
        &capture.joints,
        params,
        crate::body::sight::Growth::FOR_OFFSETS,
    )
}

/// The vertices of `capture`'s board the body model puts behind a part of the robot
/// ([`hidden`]) posed with [`DetectOptions::body_prediction`]; none without the model
/// (`use_model`) or a body ([`DetectOptions::body`]).
pub(super) fn predicted(
    dataset: &Dataset,
    capture: &Capture,
    options: &DetectOptions,
) -> Vec<Hidden> {
    match &options.body {
        Some(body) if options.use_model => {
            hidden(&dataset.model, body, capture, &options.body_prediction())
        }
        _ => Vec::new(),
    }
}

/// `outcome` without the vertices `hidden` ([`predicted`]), each named among the dropped;
/// rejected when fewer than [`super::guided::MIN_VERTICES`] are left.
pub(super) fn drop_hidden(hidden: &[Hidden], outcome: Outcome) -> Outcome {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::body::Kind;
    use crate::model::{CameraId, Joint, JointAngles, Side, Vertex};

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
