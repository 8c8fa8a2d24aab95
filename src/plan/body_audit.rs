//! The plan held against the body model (docs/BODY.md): for every capture, the whole body
//! posed with the arms where capture puts them, its smallest clearance (between parts the
//! model checks, or from the floor), any contact, and which planned vertices a part of the
//! body hides from the camera; and every move of the plan (the ways the planner's own
//! collision model lets through) walked in the body model. What `naocalib plan` prints
//! beside the rules its captures were chosen by.

use std::collections::BTreeMap;

use crate::body::{self, BodyModel, Clearance, move_contact};
use crate::model::{JointAngles, Model, PARAMETER_COUNT};

use super::PlannedCapture;
use super::route::NoRoute;

/// A board whose pattern the body hides in part.
#[derive(Debug, Clone, PartialEq)]
pub struct HiddenBoard {
    /// The capture's index in the plan.
    pub capture: usize,
    /// The inner vertices hidden.
    pub vertices: usize,
    /// The part that hides the first of them ("left toe").
    pub by: String,
}

/// The plan's captures held against the body model.
#[derive(Debug, Clone, PartialEq)]
pub struct BodyAudit {
    /// The smallest clearance over all captures, with the capture's index.
    pub clearance: Option<(usize, Clearance)>,
    /// The captures in which two parts touch, or a part the floor, named.
    pub contacts: Vec<(usize, String)>,
    /// The boards with hidden vertices.
    pub hidden: Vec<HiddenBoard>,
    /// Inner vertices over all captures.
    pub vertices: usize,
    /// The vertices whose refinement window the body leaves in plain sight, its parts grown
    /// for the offsets ([`body::sight`]; what `detect --body` keeps), over all captures.
    pub planned: usize,
    /// The moves checked: from rest to every capture with a way, and back.
    pub moves: usize,
    /// The moves that bring two parts into contact between postures free of it
    /// ([`body::move_contact`]), by the capture they lead to (`None`: the return to rest),
    /// named.
    pub moves_through_contact: Vec<(Option<usize>, String)>,
}

impl BodyAudit {
    /// The hidden vertices over all captures.
    pub fn hidden_vertices(&self) -> usize {
        self.hidden.iter().map(|h| h.vertices).sum()
    }

    /// Vertices and boards hidden by each part, the most first: `(part, vertices, boards)`.
    pub fn by_part(&self) -> Vec<(String, usize, usize)> {
        let mut tally: BTreeMap<&str, (usize, usize)> = BTreeMap::new();
        for h in &self.hidden {
            let t = tally.entry(&h.by).or_default();
            t.0 += h.vertices;
            t.1 += 1;
        }
        let mut out: Vec<(String, usize, usize)> = tally
            .into_iter()
            .map(|(part, (v, b))| (part.to_string(), v, b))
            .collect();
        out.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
        out
    }
}

/// Holds every capture of `captures` against `body` (nominal model at the offsets
/// `centre`): clearance, contact and the line of sight from the camera to each inner vertex
/// (every part but the sandal that carries the pattern); and the moves `ways` (the
/// planner's [`super::route::moves`] from `rest`) walked in the body model.
pub fn audit(
    model: &Model,
    body: &BodyModel,
    captures: &[PlannedCapture],
    centre: &[f64; PARAMETER_COUNT],
    rest: &JointAngles,
    ways: &[Result<Vec<JointAngles>, NoRoute>],
) -> BodyAudit {
    let mut out = BodyAudit {
        clearance: None,
        contacts: Vec::new(),
        hidden: Vec::new(),
        vertices: 0,
        planned: 0,
        moves: 0,
        moves_through_contact: Vec::new(),
    };
    let mut at = *rest;
    for (k, way) in ways.iter().enumerate() {
        let Ok(way) = way else { continue };
        out.moves += 1;
        let mut touched = None;
        for next in way {
            touched = touched.or_else(|| move_contact(model, body, &at, next));
            at = *next;
        }
        if let Some(what) = touched {
            out.moves_through_contact
                .push(((k < captures.len()).then_some(k), what));
        }
    }
    for (k, c) in captures.iter().enumerate() {
        let posed = body.pose(&model.robot, &model.board, &c.joints);
        if let Some(what) = body::any_contact(&posed, body.floor_x) {
            out.contacts.push((k, what));
        }
        let clear = body::clearance(&posed, body.floor_x);
        if out.clearance.as_ref().is_none_or(|(_, b)| clear.mm < b.mm) {
            out.clearance = Some((k, clear));
        }
        out.planned +=
            body::sight::in_sight(model, body, c.camera, c.side, &c.joints, centre).len();
        let chains = model.chains_for(c.camera, c.side, &c.joints);
        let eye = chains.camera.eval(centre).translation;
        let board = chains.board.eval(centre);
        let mut hidden = 0;
        let mut first = None;
        for v in model.board.vertices() {
            out.vertices += 1;
            let p = board.apply(&model.board.vertex_position(v));
            if let Some(part) = body::sight_blocked(&posed, c.side, eye, &[p], 0.0) {
                hidden += 1;
                first.get_or_insert(part);
            }
        }
        if let Some(by) = first {
            out.hidden.push(HiddenBoard {
                capture: k,
                vertices: hidden,
                by,
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{CameraId, Joint, JointAngles, Side};

    fn capture(joints: JointAngles) -> PlannedCapture {
        PlannedCapture {
            camera: CameraId::Lower,
            side: Side::Left,
            joints,
        }
    }

    #[test]
    fn hidden_vertices_agree_with_points_along_each_line_and_a_leg_in_the_floor_is_a_contact() {
        let model = Model::default();
        let body = BodyModel::default();
        let centre = [0.0; PARAMETER_COUNT];
        let raised = crate::body::raised_left();
        // The same with the right leg raised too.
        let mut both = raised;
        both.set(Joint::RHipPitch, -1.3);
        // The left leg pushed down through the floor.
        let mut low = crate::plan::route::rest_posture();
        low.set(Joint::LHipPitch, 0.45);
        let captures = [capture(raised), capture(both), capture(low)];
        let rest = crate::plan::route::rest_posture();
        let a = audit(&model, &body, &captures, &centre, &rest, &[]);
        assert_eq!(a.vertices, 3 * 24);
        assert!(
            a.contacts
                .iter()
                .any(|(k, what)| *k == 2 && what.contains("floor")),
            "{:?}",
            a.contacts
        );
        assert!(a.contacts.iter().all(|(k, _)| *k != 0), "{:?}", a.contacts);
        // Each line of sight walked in 0.5 mm steps: hidden where a step lies inside a part
        // other than the pattern's own sandal.
        for (k, c) in captures.iter().enumerate() {
            let posed = body.pose(&model.robot, &model.board, &c.joints);
            let chains = model.chains_for(c.camera, c.side, &c.joints);
            let eye = chains.camera.eval(&centre).translation;
            let board = chains.board.eval(&centre);
            let walked = model
                .board
                .vertices()
                .filter(|v| {
                    let p = board.apply(&model.board.vertex_position(*v));
                    let n = 2000;
                    (1..n).any(|i| {
                        let t = i as f64 / n as f64;
                        let q: [f64; 3] = std::array::from_fn(|d| eye[d] + t * (p[d] - eye[d]));
                        posed.parts.iter().any(|part| {
                            part.kind != body::Kind::Head
                                && !(part.kind == body::Kind::Sandal && part.side == Some(c.side))
                                && part.shape.distance(q) == 0.0
                        })
                    })
                })
                .count();
            let found = a
                .hidden
                .iter()
                .find(|h| h.capture == k)
                .map_or(0, |h| h.vertices);
            assert_eq!(found, walked, "capture {k}");
        }
        assert!(a.hidden_vertices() > 0, "{:?}", a.hidden);
        let (_, c) = a.clearance.as_ref().unwrap();
        assert_eq!(c.mm, 0.0);
        assert_eq!(
            a.by_part().iter().map(|p| p.1).sum::<usize>(),
            a.hidden_vertices()
        );
    }

    #[test]
    fn a_move_between_postures_free_of_contact_is_walked_and_its_contact_named() {
        let model = Model::default();
        let body = BodyModel::default();
        let rest = crate::plan::route::rest_posture();
        let touch = |a: &JointAngles| {
            body::any_contact(&body.pose(&model.robot, &model.board, a), body.floor_x)
        };
        // The left leg raised or not, rolled from out to in, its knee straight or bent;
        // the right leg at rest.
        let mut postures = Vec::new();
        for pitch in [0.0, -0.6, -1.2] {
            for roll in [-0.3, -0.1, 0.15, 0.4] {
                for knee in [0.0, 1.2] {
                    let mut p = rest;
                    p.set(Joint::LHipPitch, pitch);
                    p.set(Joint::LHipRoll, roll);
                    p.set(Joint::LKneePitch, knee);
                    if touch(&p).is_none() {
                        postures.push(p);
                    }
                }
            }
        }
        // Every pair of them: a contact the audit names is one a walk in a third of its
        // steps finds too, and most moves such a walk finds in contact the audit names.
        let (mut through, mut finer) = (0, 0);
        for a in &postures {
            for b in &postures {
                let named = move_contact(&model, &body, a, b);
                let widest = (*b - *a).iter().map(|(_, d)| d.abs()).fold(0.0, f64::max);
                let n = 3 * (widest / body::MOVE_STEP).ceil() as usize;
                let walked = (1..n).any(|k| touch(&a.lerp(b, k as f64 / n as f64)).is_some());
                assert!(named.is_none() || walked, "{named:?}");
                through += named.is_some() as usize;
                finer += walked as usize;
            }
        }
        assert!(postures.len() >= 6, "{} free postures", postures.len());
        assert!(
            through > 0,
            "no move between free postures passes through contact"
        );
        assert!(10 * through >= 9 * finer, "{through} of {finer} named");
        // The audit counts the moves with a way and names those through contact by the
        // capture they lead to.
        let captures: Vec<PlannedCapture> = postures.iter().map(|p| capture(*p)).collect();
        let ways: Vec<Result<Vec<JointAngles>, NoRoute>> = postures
            .iter()
            .map(|p| Ok(vec![*p]))
            .chain([Err(NoRoute), Ok(vec![rest])])
            .collect();
        let a = audit(
            &model,
            &body,
            &captures,
            &[0.0; PARAMETER_COUNT],
            &rest,
            &ways,
        );
        assert_eq!(a.moves, postures.len() + 1);
        let mut at = rest;
        let expected: Vec<usize> = (0..=postures.len() + 1)
            .filter(|&k| {
                let to = if k < postures.len() {
                    postures[k]
                } else if k == postures.len() {
                    return false;
                } else {
                    rest
                };
                let hit = move_contact(&model, &body, &at, &to).is_some();
                at = to;
                hit
            })
            .collect();
        let got: Vec<usize> = a
            .moves_through_contact
            .iter()
            .map(|m| m.0.unwrap_or(postures.len() + 1))
            .collect();
        assert_eq!(got, expected);
    }
}
