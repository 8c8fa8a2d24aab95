//! Contact between the body's parts and with the floor, lines of sight past the body, and
//! the smallest clearance of a posture, for a NAO lying on its back.
//!
//! Which pairs are checked: each leg's parts against the other leg's, against the torso and
//! the pelvis (not the thighs, whose boxes hold the round housing at the hip, nor the
//! tibias, which the pelvis box swept over the hip angles would meet at any turned hip), the head and
//! both arms; the foot,
//! toe and sandal against their own thigh; every leg part against the floor. Parts joined
//! by a joint (thigh–tibia, tibia–foot, arm–torso) are not checked against each other.
//! A box is tested against a capsule through spheres spaced at most 5 mm along the
//! capsule's segment (at most a few millimetres closer than the exact test), box against
//! box with the separating-axis test.

use super::shapes::{Shape, norm, point_segment_distance, segment_distance, sub};
use super::{BodyModel, Kind, Part, PosedBody};
use crate::model::{Board, JointAngles, Model, RobotGeometry, Side};

/// Whether two solids touch.
fn touch(a: &Shape, b: &Shape) -> bool {
    use Shape::*;
    match (a, b) {
        (Capsule(p), Capsule(q)) => p.hits(q),
        (Capsule(c), Box(b)) | (Box(b), Capsule(c)) => c.hits_box(b),
        (Box(p), Box(q)) => p.overlaps(q),
        (Sphere(s), other) | (other, Sphere(s)) => other.distance(s.centre) < s.radius,
    }
}

/// The distance between two solids (0 when they touch), to within the 2 mm steps at which
/// a box's edges and a capsule's segment are sampled against a box.
fn gap(a: &Shape, b: &Shape) -> f64 {
    use Shape::*;
    match (a, b) {
        (Capsule(p), Capsule(q)) => {
            (segment_distance(p.a, p.b, q.a, q.b) - p.radius - q.radius).max(0.0)
        }
        (Sphere(s), other) | (other, Sphere(s)) => (other.distance(s.centre) - s.radius).max(0.0),
        (Capsule(c), Box(b)) | (Box(b), Capsule(c)) => c
            .samples(2.0)
            .map(|p| (b.distance(p) - c.radius).max(0.0))
            .fold(f64::INFINITY, f64::min),
        (Box(p), Box(q)) => {
            if p.overlaps(q) {
                return 0.0;
            }
            let edges = |from: &super::OrientedBox, to: &super::OrientedBox| {
                box_edges(from)
                    .flat_map(|(a, b)| {
                        super::Capsule { a, b, radius: 0.0 }
                            .samples(2.0)
                            .collect::<Vec<_>>()
                    })
                    .map(|p| to.distance(p))
                    .fold(f64::INFINITY, f64::min)
            };
            edges(p, q).min(edges(q, p))
        }
    }
}

/// The twelve edges of a box.
fn box_edges(b: &super::OrientedBox) -> impl Iterator<Item = ([f64; 3], [f64; 3])> + '_ {
    let corners = b.corners();
    (0..8).flat_map(move |n| {
        (0..3)
            .filter(move |k| n >> k & 1 == 0)
            .map(move |k| (corners[n], corners[n | 1 << k]))
    })
}

/// How far the lowest point of a solid lies above the floor plane `x_O = floor_x`.
fn above_floor(shape: &Shape, floor_x: f64) -> f64 {
    match shape {
        Shape::Capsule(c) => c.a[0].min(c.b[0]) - c.radius - floor_x,
        Shape::Sphere(s) => s.centre[0] - s.radius - floor_x,
        Shape::Box(b) => {
            b.corners()
                .iter()
                .map(|p| p[0])
                .fold(f64::INFINITY, f64::min)
                - floor_x
        }
    }
}

/// Whether the pair of parts is one the model checks (see the module's doc).
fn checked(a: &Part, b: &Part) -> bool {
    let (leg, other) = match (a.kind.is_leg(), b.kind.is_leg()) {
        (true, true) => return a.side != b.side || own_thigh(a, b) || own_thigh(b, a),
        (true, false) => (a, b),
        (false, true) => (b, a),
        (false, false) => return false,
    };
    // A thigh's box holds its top, the HipPitch motor's housing, which is round about the
    // hip's axis: its corners would meet the waist and the pelvis at any raised thigh. The
    // pelvis box holds the hips' housings swept over every HipYawPitch and HipRoll, which
    // the legs' own knees reach whenever HipYawPitch turns them: a tibia is kept from the
    // waist by the torso's boxes and from the hips by its thigh.
    !((leg.kind == Kind::Thigh && matches!(other.kind, Kind::Pelvis | Kind::Torso))
        || (leg.kind == Kind::Tibia && other.kind == Kind::Pelvis))
}

/// The foot, toe or sandal `a` against its own leg's thigh `b`.
fn own_thigh(a: &Part, b: &Part) -> bool {
    matches!(a.kind, Kind::Foot | Kind::Toe | Kind::Sandal) && b.kind == Kind::Thigh
}

/// The pairs of parts the model checks.
fn pairs(body: &PosedBody) -> impl Iterator<Item = (&Part, &Part)> {
    let parts = &body.parts;
    (0..parts.len()).flat_map(move |i| {
        (i + 1..parts.len())
            .map(move |j| (&parts[i], &parts[j]))
            .filter(|(a, b)| checked(a, b))
    })
}

/// The first contact of the posed body, named (`"left sandal / torso"`,
/// `"right tibia / floor"`), or `None` when it is free of contact.
pub fn contact(posed: &PosedBody, floor_x: f64) -> Option<String> {
    for part in posed.parts.iter().filter(|p| p.kind.is_leg()) {
        if above_floor(&part.shape, floor_x) < 0.0 {
            return Some(format!("{} / floor", part.name()));
        }
    }
    pairs(posed)
        .find(|(a, b)| apart_bounds(a, b) <= 0.0 && touch(&a.shape, &b.shape))
        .map(|(a, b)| format!("{} / {}", a.name(), b.name()))
}

/// How far apart the bounding spheres of two parts are (negative where they overlap): a
/// lower bound of their distance.
fn apart_bounds(a: &Part, b: &Part) -> f64 {
    let ((ca, ra), (cb, rb)) = (a.shape.bounds(), b.shape.bounds());
    norm(sub(ca, cb)) - ra - rb
}

/// The first contact of the head with a leg part, named, or `None`.
pub fn head_contact(posed: &PosedBody) -> Option<String> {
    let head = posed.parts.iter().find(|p| p.kind == Kind::Head)?;
    posed
        .parts
        .iter()
        .filter(|p| p.kind.is_leg())
        .find(|p| touch(&head.shape, &p.shape))
        .map(|p| format!("{} / head", p.name()))
}

/// The first contact of any kind a plan is held against, named: two parts or a leg and
/// the floor ([`contact`]), the head and a leg ([`head_contact`]).
pub fn any_contact(posed: &PosedBody, floor_x: f64) -> Option<String> {
    contact(posed, floor_x).or_else(|| head_contact(posed))
}

/// Largest step of any joint between two postures checked along a move (rad).
pub const MOVE_STEP: f64 = 0.03;

/// The first posture strictly between `from` and `to` on the straight move (checked every
/// [`MOVE_STEP`]) that brings two parts of `body` into contact, named; `None` when the
/// move stays free, or when an end is in contact already (a contact of the posture itself).
pub fn move_contact(
    model: &Model,
    body: &BodyModel,
    from: &JointAngles,
    to: &JointAngles,
) -> Option<String> {
    let touch =
        |a: &JointAngles| any_contact(&body.pose(&model.robot, &model.board, a), body.floor_x);
    let widest = (*to - *from)
        .iter()
        .map(|(_, d)| d.abs())
        .fold(0.0, f64::max);
    let n = (widest / MOVE_STEP).ceil() as usize;
    if n < 2 || touch(from).is_some() || touch(to).is_some() {
        return None;
    }
    (1..n).find_map(|k| touch(&from.lerp(to, k as f64 / n as f64)))
}

/// The first collision of the robot at the leg and head angles `joints` (the arms where
/// `body` holds them) with the sandals of `board`, named, or `None` when the posture is free
/// of it.
pub fn collision(
    robot: &RobotGeometry,
    board: &Board,
    body: &BodyModel,
    joints: &JointAngles,
) -> Option<String> {
    contact(&body.pose(robot, board, joints), body.floor_x)
}

/// The smallest distance between two parts the model checks, or of a leg part from the
/// floor, and where it is.
#[derive(Debug, Clone, PartialEq)]
pub struct Clearance {
    /// The distance (mm); 0 when they touch.
    pub mm: f64,
    /// The two parts ("left toe / right sandal", "right tibia / floor").
    pub between: String,
}

/// The smallest clearance of the posed body.
pub fn clearance(posed: &PosedBody, floor_x: f64) -> Clearance {
    let mut best = Clearance {
        mm: f64::INFINITY,
        between: String::new(),
    };
    for part in posed.parts.iter().filter(|p| p.kind.is_leg()) {
        let d = above_floor(&part.shape, floor_x).max(0.0);
        if d < best.mm {
            best = Clearance {
                mm: d,
                between: format!("{} / floor", part.name()),
            };
        }
    }
    for (a, b) in pairs(posed) {
        // A pair farther apart than their bounding spheres allow cannot set the minimum.
        if apart_bounds(a, b) >= best.mm {
            continue;
        }
        let d = gap(&a.shape, &b.shape);
        if d < best.mm {
            best = Clearance {
                mm: d,
                between: format!("{} / {}", a.name(), b.name()),
            };
        }
    }
    best
}

/// The first part of the body (the head aside) that stands between `eye` and one of
/// `targets` (points in `O`, mm), grown by `grow` mm, named (`"right thigh"`), or `None`
/// when every target is in plain sight. Parts for which `skip` holds are left out (the
/// sandal that carries the targets).
pub fn sight_blocked_by_body(
    posed: &PosedBody,
    eye: [f64; 3],
    targets: &[[f64; 3]],
    grow: impl Fn(&Part) -> f64,
    skip: impl Fn(&Part) -> bool,
) -> Option<String> {
    first_blocking(posed, eye, targets, grow, skip).map(Part::name)
}

/// The part [`sight_blocked_by_body`] names.
pub fn first_blocking<'a>(
    posed: &'a PosedBody,
    eye: [f64; 3],
    targets: &[[f64; 3]],
    grow: impl Fn(&Part) -> f64,
    skip: impl Fn(&Part) -> bool,
) -> Option<&'a Part> {
    // Only parts whose bounding sphere reaches the cone of the lines of sight can block.
    let near: Vec<&Part> = posed
        .parts
        .iter()
        .filter(|p| p.kind != Kind::Head && !skip(p))
        .filter(|p| {
            let (c, r) = p.shape.bounds();
            targets
                .iter()
                .any(|&t| point_segment_distance(c, eye, t) < r + grow(p))
        })
        .collect();
    targets.iter().find_map(|&t| {
        near.iter()
            .find(|p| p.shape.blocks(eye, t, grow(p)))
            .copied()
    })
}

/// The first part of the body except the sandal on `side` (whose pattern the targets are)
/// that stands between `eye` and one of `targets`, grown by `grow` mm.
pub fn sight_blocked(
    posed: &PosedBody,
    side: Side,
    eye: [f64; 3],
    targets: &[[f64; 3]],
    grow: f64,
) -> Option<String> {
    sight_blocked_by_body(
        posed,
        eye,
        targets,
        |_| grow,
        |p| p.kind == Kind::Sandal && p.side == Some(side),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Joint;

    fn pose(pairs: &[(Joint, f64)]) -> JointAngles {
        let mut j = JointAngles::default();
        for (joint, v) in pairs {
            j.set(*joint, *v);
        }
        j
    }

    fn free(joints: &JointAngles) -> Option<String> {
        collision(
            &RobotGeometry::default(),
            &Board::default(),
            &BodyModel::default(),
            joints,
        )
    }

    #[test]
    fn lying_spread_is_free_and_known_collisions_are_found() {
        use Joint::*;
        // Lying with the legs spread (as the resting leg is parked) is free; with the legs
        // parallel the sandals overlap the other foot.
        let spread = pose(&[(LHipRoll, 0.2), (RHipRoll, -0.2)]);
        assert_eq!(free(&spread), None);
        assert!(free(&JointAngles::default()).is_some());
        // Both hips rolled inward as far as they go: the knees and feet meet.
        let crossed = pose(&[(LHipRoll, -0.37), (RHipRoll, 0.37)]);
        let what = free(&crossed).expect("legs collide");
        assert!(what.contains("left") && what.contains("right"), "{what}");
        // A straight leg pushed backwards goes through the floor.
        let floor = pose(&[(LHipPitch, 0.48), (RHipRoll, -0.2)]);
        assert!(free(&floor).expect("floor").contains("floor"));
        // Hip and knee fully bent bring the sandal into the torso or the own thigh.
        let folded = pose(&[(LHipPitch, -1.5), (LKneePitch, 2.1), (LAnklePitch, 0.9)]);
        assert!(free(&folded).is_some());
    }

    #[test]
    fn arms_beside_the_body_are_met_by_a_leg_spread_wide_and_spread_arms_are_not() {
        use Joint::*;
        let robot = RobotGeometry::default();
        let board = Board::default();
        let body = BodyModel::default();
        // The left leg raised and rolled out as far as it goes, the knee bent: its foot
        // swings over the place beside the body where the arm lies when the robot is laid.
        let wide = pose(&[
            (LHipRoll, 0.75),
            (LHipPitch, -1.2),
            (LKneePitch, 1.6),
            (RHipRoll, -0.35),
        ]);
        let laid = BodyModel {
            arms: crate::body::ArmPosture::BESIDE_BODY,
            ..body
        };
        let beside = collision(&robot, &board, &laid, &wide);
        let spread = collision(&robot, &board, &body, &wide);
        assert!(
            beside.as_deref().is_some_and(|w| w.contains("arm")),
            "{beside:?}"
        );
        assert!(
            spread.as_deref().is_none_or(|w| !w.contains("arm")),
            "{spread:?}"
        );
    }

    #[test]
    fn clearance_is_zero_exactly_where_there_is_contact() {
        use Joint::*;
        let robot = RobotGeometry::default();
        let board = Board::default();
        let body = BodyModel::default();
        let posed = |roll: f64| {
            // Both legs straight on the floor, spread by `roll`.
            let joints = pose(&[(LHipRoll, roll), (RHipRoll, -roll)]);
            body.pose(&robot, &board, &joints)
        };
        let touching = clearance(&posed(0.0), body.floor_x);
        assert_eq!(touching.mm, 0.0);
        assert!(
            touching.between.starts_with("left") && touching.between.contains("/ right"),
            "{touching:?}"
        );
        let mut free = 0;
        for k in 0..=40 {
            let p = posed(k as f64 * 0.01);
            let c = clearance(&p, body.floor_x);
            assert_eq!(c.mm == 0.0, contact(&p, body.floor_x).is_some(), "{c:?}");
            free += usize::from(c.mm > 0.0);
        }
        assert!(
            free > 5,
            "legs spread up to 0.4 rad are free of contact {free} times"
        );
    }

    #[test]
    fn a_sight_line_through_a_thigh_is_blocked_and_one_above_it_is_not() {
        let robot = RobotGeometry::default();
        let board = Board::default();
        let body = BodyModel::default();
        let joints = pose(&[(Joint::RHipPitch, -0.5), (Joint::RKneePitch, 1.0)]);
        let posed = body.pose(&robot, &board, &joints);
        let thigh = posed
            .parts
            .iter()
            .find(|p| p.kind == Kind::Thigh && p.side == Some(Side::Right))
            .unwrap();
        let (mid, _) = thigh.shape.bounds();
        // A line from above the thigh down through its middle, and one beside it (out of
        // the body, to the robot's right).
        let line = |dy: f64| {
            (
                [mid[0] + 300.0, mid[1] + dy, mid[2]],
                [mid[0] - 20.0, mid[1] + dy, mid[2]],
            )
        };
        let (eye, target) = line(0.0);
        let what = sight_blocked(&posed, Side::Left, eye, &[target], 0.0);
        assert_eq!(what.as_deref(), Some("right thigh"));
        let (eye, target) = line(-150.0);
        assert_eq!(sight_blocked(&posed, Side::Left, eye, &[target], 0.0), None);
        // Grown by the distance to its side, the thigh blocks the line beside it too.
        let what = sight_blocked(&posed, Side::Left, eye, &[target], 120.0);
        assert!(what.is_some());
    }
}
