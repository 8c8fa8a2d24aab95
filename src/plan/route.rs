//! Moves between postures: the way from one posture to the next that the collision model
//! lets through, and how long a measurement phase takes. The planner orders its captures by
//! these moves and `capture` drives them, so a plan runs as it was planned.
//!
//! A move interpolates all joints together in a straight line from one posture to the next
//! (as `capture` commands it), checked every [`CHECK_STEP`] rad against
//! [`collision::collision`], and, where both postures are free of contact in the whole body
//! model (docs/BODY.md; a plan made past the body, as `naocalib plan` makes it), every
//! [`crate::body::MOVE_STEP`] rad against it ([`move_is_clear`]). When the straight move
//! collides, [`route`] tries, in turn:
//! the HipYawPitch motor first or last; one leg (with the head) first; through the rest
//! posture; through both legs raised ([`tucked`]); through rest and then both legs raised.
//!
//! Timing model ([`Timing`]): a move takes as long as its slowest joint,
//! `max_j |Δθ_j| / ω_j`, with a cautious speed for the legs (which carry the sandals near the
//! body) and a faster one for the head; after each leg move the robot waits for the sandal
//! to settle (also at a route's intermediate postures), after a head-only move for the image
//! to settle; then it takes the picture and logs the joints. The phase starts and ends at
//! the rest posture.

use super::collision::{self, BodyModel};
use crate::model::head_pitch_limits;
use crate::model::{Joint, JointAngles, Model, Side};

/// Largest step of any joint between two collision checks along a move (rad).
pub const CHECK_STEP: f64 = 0.01;

/// Lying on its back, every head and leg joint at 0 but the hips rolled out by 0.15 rad
/// (as the plan's resting leg, so that the sandals do not touch): where a measurement
/// phase starts and ends.
pub fn rest_posture() -> JointAngles {
    let mut rest = JointAngles::default();
    rest.set(Joint::LHipRoll, 0.15);
    rest.set(Joint::RHipRoll, -0.15);
    rest
}

/// `rest` with both legs raised (hip pitch −0.8, knee 1.4, ankle pitch −0.6 rad): the
/// sandals lifted clear of each other and of the floor.
pub fn tucked(rest: &JointAngles) -> JointAngles {
    let mut tucked = *rest;
    for side in Side::BOTH {
        let [_, _, hip, knee, ankle, _] = side.leg_joints();
        tucked.set(hip, -0.8);
        tucked.set(knee, 1.4);
        tucked.set(ankle, -0.6);
    }
    tucked
}

/// Whether the straight move from `from` to `to` is free of collisions, checked every
/// [`CHECK_STEP`] rad. Parts that touch at the start (the feet of a robot put down with its
/// legs together) may go on touching until they part; after that nothing may, and they
/// must have parted by the end.
pub fn move_is_free(model: &Model, body: &BodyModel, from: &JointAngles, to: &JointAngles) -> bool {
    let n = steps(from, to);
    let at = |k: usize| from.lerp(to, k as f64 / n as f64);
    let free = |a: &JointAngles| collision::collision(&model.robot, body, a).is_none();
    if free(from) {
        // The common case: the end first, then the points between in coarse-to-fine order,
        // which finds a collision after few checks.
        if !free(to) {
            return false;
        }
        let mut stride = n.next_power_of_two();
        let mut seen = vec![false; n + 1];
        seen[0] = true;
        seen[n] = true;
        while stride > 1 {
            stride /= 2;
            let mut k = stride;
            while k < n {
                if !seen[k] {
                    seen[k] = true;
                    if !free(&at(k)) {
                        return false;
                    }
                }
                k += stride;
            }
        }
        return true;
    }
    let mut parted = false;
    (0..=n).all(|k| {
        let f = free(&at(k));
        parted |= f;
        f || !parted
    }) && parted
}

/// Whether the straight move from `from` to `to` is free of collisions
/// ([`move_is_free`]) and, between postures the whole body model (docs/BODY.md) finds free
/// of contact, free of contact in it too ([`crate::body::move_contact`]).
pub fn move_is_clear(
    model: &Model,
    body: &BodyModel,
    from: &JointAngles,
    to: &JointAngles,
) -> bool {
    move_is_free(model, body, from, to)
        && crate::body::move_contact(model, &crate::body::BodyModel::default(), from, to).is_none()
}

/// The number of checked steps of the move from `from` to `to` (at least 1).
fn steps(from: &JointAngles, to: &JointAngles) -> usize {
    (*to - *from)
        .iter()
        .map(|(_, d)| (d.abs() / CHECK_STEP).ceil() as usize)
        .max()
        .unwrap_or(0)
        .max(1)
}

/// Whether `joints` may be commanded: every joint within its limits, HeadPitch within its
/// HeadYaw-dependent range, one HipYawPitch angle (one motor).
fn within_limits(joints: &JointAngles) -> bool {
    let inside = joints.iter().all(|(j, q)| {
        let (lo, hi) = j.limits();
        (lo..=hi).contains(&q)
    });
    let (lo, hi) = head_pitch_limits(joints.get(Joint::HeadYaw));
    inside
        && (lo..=hi).contains(&joints.get(Joint::HeadPitch))
        && (joints.get(Joint::LHipYawPitch) - joints.get(Joint::RHipYawPitch)).abs() <= 1e-9
}

/// No collision-free way to a posture was found.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error(
    "no collision-free way there (directly, joint group by joint group, or through rest or \
     legs raised)"
)]
pub struct NoRoute;

/// A collision-free way from `from` to `to`: the postures to move through in turn, the
/// last one `to` (see the module documentation for the ways tried); `rest` is the rest
/// posture.
pub fn route(
    model: &Model,
    body: &BodyModel,
    from: &JointAngles,
    to: &JointAngles,
    rest: &JointAngles,
) -> Result<Vec<JointAngles>, NoRoute> {
    let tucked = tucked(rest);
    // `base` with the joints `joints` taken from `from`.
    let with = |base: &JointAngles, from: &JointAngles, joints: &[Joint]| {
        let mut a = *base;
        for &j in joints {
            a.set(j, from.get(j));
        }
        a
    };
    use Joint::{HeadPitch, HeadYaw, LHipYawPitch, RHipYawPitch};
    let hyp = [LHipYawPitch, RHipYawPitch];
    let leg = |side: Side| {
        let mut joints = side.leg_joints().to_vec();
        joints.extend([LHipYawPitch, RHipYawPitch, HeadYaw, HeadPitch]);
        joints
    };
    let ways: [Vec<JointAngles>; 8] = [
        vec![*to],
        vec![with(from, to, &hyp), *to],
        vec![with(to, from, &hyp), *to],
        vec![with(from, to, &leg(Side::Left)), *to],
        vec![with(from, to, &leg(Side::Right)), *to],
        vec![*rest, *to],
        vec![tucked, *to],
        vec![*rest, tucked, *to],
    ];
    ways.into_iter()
        .find(|way| {
            let mut at = *from;
            way.iter().all(|next| {
                let ok = within_limits(next) && move_is_clear(model, body, &at, next);
                at = *next;
                ok
            })
        })
        .ok_or(NoRoute)
}

/// The timing model's constants (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Timing {
    /// Leg joint speed [rad/s].
    pub leg_speed: f64,
    /// Head joint speed [rad/s].
    pub head_speed: f64,
    /// Wait after a move of any leg joint (s).
    pub leg_settle: f64,
    /// Wait after a head-only move (s).
    pub head_settle: f64,
    /// Taking the picture and logging the joints (s).
    pub capture: f64,
}

impl Default for Timing {
    /// Legs at 30°/s, head at 90°/s, 1 s settling after a leg move, 0.3 s after a head move,
    /// 0.2 s per picture.
    fn default() -> Self {
        Timing {
            leg_speed: 30f64.to_radians(),
            head_speed: 90f64.to_radians(),
            leg_settle: 1.0,
            head_settle: 0.3,
            capture: 0.2,
        }
    }
}

impl Timing {
    /// Time of the straight move from `a` to `b` (s), without settling.
    pub fn motion(&self, a: &JointAngles, b: &JointAngles) -> f64 {
        (*a - *b)
            .iter()
            .map(|(j, d)| {
                let speed = if j.leg_index().is_some() {
                    self.leg_speed
                } else {
                    self.head_speed
                };
                d.abs() / speed
            })
            .fold(0.0, f64::max)
    }

    /// Time of the straight move from `a` to `b` and the wait for it to settle (s).
    pub fn settled(&self, a: &JointAngles, b: &JointAngles) -> f64 {
        let legs_move = (*a - *b)
            .iter()
            .any(|(j, d)| j.leg_index().is_some() && d.abs() > 1e-9);
        let settle = if legs_move {
            self.leg_settle
        } else {
            self.head_settle
        };
        self.motion(a, b) + settle
    }

    /// Time from `a` to the picture at `b` moving straight (s): motion, settling and the
    /// capture.
    pub fn step(&self, a: &JointAngles, b: &JointAngles) -> f64 {
        self.settled(a, b) + self.capture
    }

    /// Time from `from` through the postures of `way` to the picture at its last one (s):
    /// each move with its settling, then the capture.
    pub fn way(&self, from: &JointAngles, way: &[JointAngles]) -> f64 {
        let mut at = from;
        let mut total = self.capture;
        for next in way {
            total += self.settled(at, next);
            at = next;
        }
        total
    }
}

/// The moves of executing `captures` in order from `rest` and back to it: the way to each
/// capture ([`route`], from where the previous move ended; the robot stays where it is
/// when there is none) and, last, the straight move back to rest (`Err` when it collides,
/// [`move_is_clear`]).
/// `n + 1` entries for `n` captures.
pub fn moves(
    model: &Model,
    body: &BodyModel,
    rest: &JointAngles,
    captures: &[JointAngles],
) -> Vec<Result<Vec<JointAngles>, NoRoute>> {
    let mut at = *rest;
    let mut out = Vec::with_capacity(captures.len() + 1);
    for c in captures {
        let way = route(model, body, &at, c, rest);
        if way.is_ok() {
            at = *c;
        }
        out.push(way);
    }
    out.push(if move_is_clear(model, body, &at, rest) {
        Ok(vec![*rest])
    } else {
        Err(NoRoute)
    });
    out
}

/// The predicted time of each move of [`moves`] (s): the way to each capture with its
/// picture (0 for a capture without a way: it is skipped), and last the return to rest.
pub fn step_times(
    model: &Model,
    body: &BodyModel,
    timing: &Timing,
    rest: &JointAngles,
    captures: &[JointAngles],
) -> Vec<f64> {
    step_times_of(timing, rest, captures, &moves(model, body, rest, captures))
}

/// [`step_times`] of the moves `moves` ([`moves`] of `captures` from `rest`).
pub fn step_times_of(
    timing: &Timing,
    rest: &JointAngles,
    captures: &[JointAngles],
    moves: &[Result<Vec<JointAngles>, NoRoute>],
) -> Vec<f64> {
    let mut at = *rest;
    let n = captures.len();
    moves
        .iter()
        .enumerate()
        .map(|(k, way)| match way {
            Ok(way) if k < n => {
                let t = timing.way(&at, way);
                at = captures[k];
                t
            }
            // The return to rest is a move without a picture.
            _ if k == n => timing.motion(&at, rest),
            _ => 0.0,
        })
        .collect()
}

/// The predicted duration of the measurement phase (s): the sum of [`step_times`].
pub fn duration(
    model: &Model,
    body: &BodyModel,
    timing: &Timing,
    rest: &JointAngles,
    captures: &[JointAngles],
) -> f64 {
    step_times(model, body, timing, rest, captures).iter().sum()
}

/// [`duration`] of the moves `moves` ([`moves`] of `captures` from `rest`).
pub fn duration_of(
    timing: &Timing,
    rest: &JointAngles,
    captures: &[JointAngles],
    moves: &[Result<Vec<JointAngles>, NoRoute>],
) -> f64 {
    step_times_of(timing, rest, captures, moves).iter().sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rest_and_tucked_are_free_and_a_straight_leg_swing_through_the_other_is_not() {
        let model = Model::default();
        let body = BodyModel::default();
        let rest = rest_posture();
        assert!(collision::collision(&model.robot, &body, &rest).is_none());
        assert!(move_is_free(&model, &body, &rest, &tucked(&rest)));
        // The left leg rolled inward into the right one collides.
        let mut low = rest;
        low.set(Joint::LHipRoll, -0.37);
        assert!(collision::collision(&model.robot, &body, &low).is_some());
        assert!(!move_is_free(&model, &body, &rest, &low));
        assert_eq!(route(&model, &body, &rest, &low, &rest), Err(NoRoute));
        let way = route(&model, &body, &rest, &tucked(&rest), &rest).expect("a way");
        assert_eq!(way, vec![tucked(&rest)]);
        // From the legs together (touching) the robot may part them.
        let together = JointAngles::default();
        assert!(collision::collision(&model.robot, &body, &together).is_some());
        assert!(move_is_free(&model, &body, &together, &rest));
        assert!(!move_is_free(&model, &body, &rest, &together));
    }

    #[test]
    fn the_time_of_a_way_adds_every_move_and_one_picture() {
        let timing = Timing::default();
        let rest = rest_posture();
        let up = tucked(&rest);
        let direct = timing.way(&rest, &[up]);
        assert!((direct - timing.step(&rest, &up)).abs() < 1e-12);
        let there_and_back = timing.way(&rest, &[up, rest]);
        assert!(
            (there_and_back
                - (2.0 * (timing.motion(&rest, &up) + timing.leg_settle) + timing.capture))
                .abs()
                < 1e-12
        );
    }
}
