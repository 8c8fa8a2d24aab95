//! Self-collision of the legs, feet and sandals with each other, with the body and with the
//! floor, for a NAO lying on its back.
//!
//! The model is deliberately simple and errs on the safe side:
//! - thighs (hip → knee) and tibias (knee → ankle) are capsules (a segment swept by a
//!   sphere);
//! - each foot and each sandal is a box in its sole frame;
//! - the torso is a box from above the hips to the neck;
//! - the floor is the plane `x_O = floor_x` under the robot's back.
//!
//! Checked: the two legs against each other (capsules, boxes), each sandal and foot against
//! its own thigh, every tibia, foot and sandal against the torso, and everything against
//! the floor. A box is tested against a capsule through spheres spaced along the capsule's
//! segment (at most a few millimetres closer than the exact test), box against box with the
//! separating-axis test.

pub use crate::body::shapes::{Capsule, OrientedBox};
use crate::body::shapes::{norm, point_segment_distance, segment_distance};
use crate::model::{JointAngles, Pose, RobotGeometry, Side};

/// Sizes of the collision model (mm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyModel {
    /// Radius of the thigh capsules.
    pub thigh_radius: f64,
    /// Radius of the tibia capsules.
    pub tibia_radius: f64,
    /// Foot box in the sole frame: low corner.
    pub foot_lo: [f64; 3],
    /// Foot box in the sole frame: high corner.
    pub foot_hi: [f64; 3],
    /// Sandal box (plate with the pattern) in the sole frame: low corner.
    pub sandal_lo: [f64; 3],
    /// Sandal box in the sole frame: high corner.
    pub sandal_hi: [f64; 3],
    /// Torso box in `O`: low corner.
    pub torso_lo: [f64; 3],
    /// Torso box in `O`: high corner.
    pub torso_hi: [f64; 3],
    /// The floor under the robot's back: nothing may reach below this `x_O`.
    pub floor_x: f64,
}

impl Default for BodyModel {
    /// A NAO H25 with the default sandals (pattern 17 cm ahead of the ankle, 7 × 5 squares of
    /// 25 mm), a little larger than the real parts.
    fn default() -> Self {
        BodyModel {
            thigh_radius: 32.0,
            tibia_radius: 30.0,
            foot_lo: [-55.0, -45.0, 0.0],
            foot_hi: [110.0, 45.0, 50.0],
            sandal_lo: [-55.0, -70.0, -8.0],
            sandal_hi: [265.0, 70.0, 0.0],
            torso_lo: [-60.0, -80.0, 50.0],
            torso_hi: [60.0, 80.0, 200.0],
            floor_x: -60.0,
        }
    }
}

/// The collision shapes of one leg.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LegShapes {
    /// Hip → knee.
    pub thigh: Capsule,
    /// Knee → ankle.
    pub tibia: Capsule,
    /// The foot.
    pub foot: OrientedBox,
    /// The sandal.
    pub sandal: OrientedBox,
}

/// The shapes of the leg on `side` at the angles `joints` (nominal geometry).
pub fn leg_shapes(
    robot: &RobotGeometry,
    body: &BodyModel,
    side: Side,
    joints: &JointAngles,
) -> LegShapes {
    let s = side.sign();
    let crate::body::LegFrames {
        hip,
        knee,
        ankle,
        sole,
    } = crate::body::leg_frames(robot, side, joints);
    let mirror = |p: [f64; 3]| [p[0], s * p[1], p[2]];
    let (foot_lo, foot_hi) = (mirror(body.foot_lo), mirror(body.foot_hi));
    LegShapes {
        thigh: Capsule {
            a: hip.translation,
            b: knee.translation,
            radius: body.thigh_radius,
        },
        tibia: Capsule {
            a: knee.translation,
            b: ankle.translation,
            radius: body.tibia_radius,
        },
        foot: OrientedBox::in_frame(&sole, foot_lo, foot_hi),
        sandal: OrientedBox::in_frame(&sole, body.sandal_lo, body.sandal_hi),
    }
}

/// The first collision found at the angles `joints`, named (`"left sandal / torso"`), or
/// `None` when the stance is free of collisions.
pub fn collision(robot: &RobotGeometry, body: &BodyModel, joints: &JointAngles) -> Option<String> {
    let legs = Side::BOTH.map(|side| leg_shapes(robot, body, side, joints));
    let torso = OrientedBox::in_frame(&Pose::identity(), body.torso_lo, body.torso_hi);
    let name = |k: usize| Side::BOTH[k].name();
    let hit = |what: String| Some(what);

    for (k, leg) in legs.iter().enumerate() {
        let capsules = [("thigh", &leg.thigh), ("tibia", &leg.tibia)];
        let boxes = [("foot", &leg.foot), ("sandal", &leg.sandal)];
        // The floor.
        for (part, c) in capsules {
            if c.a[0] - c.radius < body.floor_x || c.b[0] - c.radius < body.floor_x {
                return hit(format!("{} {part} / floor", name(k)));
            }
        }
        for (part, b) in boxes {
            if b.corners().iter().any(|p| p[0] < body.floor_x) {
                return hit(format!("{} {part} / floor", name(k)));
            }
        }
        // The torso (the thigh starts at the hip, below the torso box).
        for (part, c) in capsules {
            if c.hits_box(&torso) {
                return hit(format!("{} {part} / torso", name(k)));
            }
        }
        for (part, b) in boxes {
            if b.overlaps(&torso) {
                return hit(format!("{} {part} / torso", name(k)));
            }
            // The foot and the sandal against the leg's own thigh.
            if leg.thigh.hits_box(b) {
                return hit(format!("{} {part} / {} thigh", name(k), name(k)));
            }
        }
    }
    // The legs against each other.
    let [l, r] = &legs;
    let capsules = |leg: &LegShapes| [("thigh", leg.thigh), ("tibia", leg.tibia)];
    let boxes = |leg: &LegShapes| [("foot", leg.foot), ("sandal", leg.sandal)];
    for (pl, cl) in capsules(l) {
        for (pr, cr) in capsules(r) {
            if cl.hits(&cr) {
                return hit(format!("left {pl} / right {pr}"));
            }
        }
        for (pr, br) in boxes(r) {
            if cl.hits_box(&br) {
                return hit(format!("left {pl} / right {pr}"));
            }
        }
    }
    for (pl, bl) in boxes(l) {
        for (pr, cr) in capsules(r) {
            if cr.hits_box(&bl) {
                return hit(format!("left {pl} / right {pr}"));
            }
        }
        for (pr, br) in boxes(r) {
            if bl.overlaps(&br) {
                return hit(format!("left {pl} / right {pr}"));
            }
        }
    }
    None
}

/// The first part of the leg on `side` that blocks the line of sight from `eye` to one of
/// `targets` (points in `O`, mm), named (`"right thigh"`), or `None` when every target is
/// in plain sight of it. Thighs and tibias are tested exactly, the foot and sandal boxes at
/// points 5 mm apart along each line.
pub fn sight_blocked(
    robot: &RobotGeometry,
    body: &BodyModel,
    joints: &JointAngles,
    side: Side,
    eye: [f64; 3],
    targets: &[[f64; 3]],
) -> Option<String> {
    let leg = leg_shapes(robot, body, side, joints);
    let name = side.name();
    for &t in targets {
        for (part, c) in [("thigh", &leg.thigh), ("tibia", &leg.tibia)] {
            if segment_distance(eye, t, c.a, c.b) < c.radius {
                return Some(format!("{name} {part}"));
            }
        }
        let line = Capsule {
            a: eye,
            b: t,
            radius: 0.0,
        };
        for (part, b) in [("foot", &leg.foot), ("sandal", &leg.sandal)] {
            // A line farther from the box's centre than its corners (a micrometre spared
            // for rounding) has no point in it.
            let clear = point_segment_distance(b.centre, eye, t) > norm(b.half) + 1e-3;
            if !clear && line.samples(5.0).any(|p| b.distance(p) <= 0.0) {
                return Some(format!("{name} {part}"));
            }
        }
    }
    None
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

    #[test]
    fn a_sight_line_through_a_thigh_or_sandal_is_blocked_and_one_beside_it_is_not() {
        let robot = RobotGeometry::default();
        let body = BodyModel::default();
        let joints = pose(&[(Joint::RHipPitch, -0.5), (Joint::RKneePitch, 1.0)]);
        let leg = leg_shapes(&robot, &body, Side::Right, &joints);
        let mid: [f64; 3] = std::array::from_fn(|i| 0.5 * (leg.thigh.a[i] + leg.thigh.b[i]));
        // A line across the thigh's middle, perpendicular to it in the y direction.
        let across = |dy: f64| {
            (
                [mid[0], mid[1] - 300.0 + dy, mid[2]],
                [mid[0], mid[1] + 300.0 + dy, mid[2]],
            )
        };
        let (eye, target) = across(0.0);
        assert_eq!(
            sight_blocked(&robot, &body, &joints, Side::Right, eye, &[target]).as_deref(),
            Some("right thigh")
        );
        // Well above the leg (towards the ceiling, +x when lying on the back).
        let (eye, target) = across(0.0);
        let lift = |p: [f64; 3]| [p[0] + 400.0, p[1], p[2]];
        assert_eq!(
            sight_blocked(
                &robot,
                &body,
                &joints,
                Side::Right,
                lift(eye),
                &[lift(target)]
            ),
            None
        );
        // Straight through the sandal's centre.
        let c = leg.sandal.centre;
        let through = [c[0] - 1.0, c[1], c[2] + 1.0];
        let far = [c[0] + 1.0, c[1], c[2] - 1.0];
        assert!(sight_blocked(&robot, &body, &joints, Side::Right, far, &[through]).is_some());
    }

    #[test]
    fn lying_spread_is_free_and_known_collisions_are_found() {
        let robot = RobotGeometry::default();
        let body = BodyModel::default();
        use Joint::*;
        // Lying with the legs slightly spread (as the resting leg is parked) is free; with the
        // legs parallel the 14 cm wide sandals overlap the other foot.
        let spread = pose(&[(LHipRoll, 0.15), (RHipRoll, -0.15)]);
        assert_eq!(collision(&robot, &body, &spread), None);
        assert!(collision(&robot, &body, &JointAngles::default()).is_some());
        // Both hips rolled inward as far as they go: the knees and feet meet.
        let crossed = pose(&[(LHipRoll, -0.37), (RHipRoll, 0.37)]);
        let what = collision(&robot, &body, &crossed).expect("legs collide");
        assert!(what.contains("left") && what.contains("right"), "{what}");
        // A straight leg pushed backwards goes through the floor.
        let floor = pose(&[(LHipPitch, 0.48)]);
        assert!(
            collision(&robot, &body, &floor)
                .expect("floor")
                .contains("floor")
        );
        // Hip and knee fully bent bring the sandal into the torso or the own thigh.
        let folded = pose(&[(LHipPitch, -1.5), (LKneePitch, 2.1), (LAnklePitch, 0.9)]);
        assert!(collision(&robot, &body, &folded).is_some());
    }
}
