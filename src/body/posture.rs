//! The arms: their five joints each, the posture capture puts them in, and their solids.
//!
//! The arm chain is the official URDF's (ros-naoqi `nao_robot`): for the left arm
//! `T(0, 98, 185) · Ry(ShoulderPitch) · Rz(ShoulderRoll) · T(105, 15, 0) · Rx(ElbowYaw) ·
//! Rz(ElbowRoll) · T(55.95, 0, 0) · Rx(WristYaw)` in `O` (the torso frame 85 mm above `O`),
//! the right arm mirrored in y. The joint limits are the V6's (Aldebaran's joint tables, as
//! LoLA enforces them).

use super::{BodyModel, Capsule, Kind, Part, Shape, Sphere};
use std::f64::consts::FRAC_PI_2;

use crate::model::{Axis, Pose, Side};

/// The arm joints in LoLA's names and the plan's column order: left arm, then right.
pub const ARM_JOINTS: [&str; 10] = [
    "LShoulderPitch",
    "LShoulderRoll",
    "LElbowYaw",
    "LElbowRoll",
    "LWristYaw",
    "RShoulderPitch",
    "RShoulderRoll",
    "RElbowYaw",
    "RElbowRoll",
    "RWristYaw",
];

/// The limits (rad) of the arm joints, in [`ARM_JOINTS`] order.
pub const ARM_LIMITS: [(f64, f64); 10] = [
    (-2.0857, 2.0857),
    (-0.3142, 1.3265),
    (-2.0857, 2.0857),
    (-1.5446, -0.0349),
    (-1.8238, 1.8238),
    (-2.0857, 2.0857),
    (-1.3265, 0.3142),
    (-2.0857, 2.0857),
    (0.0349, 1.5446),
    (-1.8238, 1.8238),
];

/// The angles (rad) of both arms' joints, in [`ARM_JOINTS`] order.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArmPosture(pub [f64; 10]);

impl ArmPosture {
    /// Arms lying beside the body, as the robot is laid down (shoulders pitched 90°, the
    /// arms along the body toward the feet, slightly out).
    pub const BESIDE_BODY: ArmPosture = ArmPosture([
        FRAC_PI_2, 0.15, 0.0, -0.1, 0.0, //
        FRAC_PI_2, -0.15, 0.0, 0.1, 0.0,
    ]);

    /// Where capture puts the arms for the whole run: above the head, lying on the floor
    /// beyond it (shoulders pitched −90°, so that the arms point away from the feet, rolled
    /// 26° out to clear the head, elbows nearly straight). Behind every camera that looks at
    /// the sandals and out of every leg's reach (`naocalib plan` checks both against the body
    /// model and prints the clearance).
    pub const CAPTURE: ArmPosture = ArmPosture([
        -FRAC_PI_2, 0.45, 0.0, -0.05, 0.0, //
        -FRAC_PI_2, -0.45, 0.0, 0.05, 0.0,
    ]);

    /// The five angles of the arm on `side` (ShoulderPitch, ShoulderRoll, ElbowYaw,
    /// ElbowRoll, WristYaw).
    pub fn arm(&self, side: Side) -> [f64; 5] {
        let k = match side {
            Side::Left => 0,
            Side::Right => 5,
        };
        std::array::from_fn(|i| self.0[k + i])
    }

    /// The first joint outside its limits, named with its angle and limits.
    pub fn check(&self) -> Result<(), String> {
        for ((name, (lo, hi)), q) in ARM_JOINTS.iter().zip(ARM_LIMITS).zip(self.0) {
            if !q.is_finite() || q < lo || q > hi {
                return Err(format!(
                    "{name} = {q:.4} rad is outside its limits {lo:.4} … {hi:.4} rad"
                ));
            }
        }
        Ok(())
    }
}

/// The frames of the arm on `side`: the shoulder (after ShoulderRoll), the elbow (after
/// ElbowRoll) and the wrist (after WristYaw), in `O`.
pub fn arm_frames(side: Side, arms: &ArmPosture) -> [Pose<f64>; 3] {
    let s = side.sign();
    let q = arms.arm(side);
    let [x, y, z] = BodyModel::SHOULDER;
    let shoulder = Pose::translation(x, s * y, z)
        .compose(&Pose::rotation(Axis::Y, q[0]))
        .compose(&Pose::rotation(Axis::Z, q[1]));
    let [ex, ey, ez] = BodyModel::ELBOW;
    let elbow = shoulder
        .compose(&Pose::translation(ex, s * ey, ez))
        .compose(&Pose::rotation(Axis::X, q[2]))
        .compose(&Pose::rotation(Axis::Z, q[3]));
    let [wx, wy, wz] = BodyModel::WRIST;
    let wrist = elbow
        .compose(&Pose::translation(wx, wy, wz))
        .compose(&Pose::rotation(Axis::X, q[4]));
    [shoulder, elbow, wrist]
}

/// The solids of the arm on `side`: the shoulder's sphere, the upper arm, the forearm
/// with the hand.
pub fn arm_parts(body: &BodyModel, side: Side, arms: &ArmPosture) -> [Part; 3] {
    let [shoulder, elbow, _] = arm_frames(side, arms);
    let along = |frame: &Pose<f64>, x: f64| frame.apply(&[x, 0.0, 0.0]);
    let part = |kind, shape| Part {
        kind,
        side: Some(side),
        shape,
    };
    [
        part(
            Kind::Shoulder,
            Shape::Sphere(Sphere {
                centre: shoulder.translation,
                radius: body.shoulder_radius,
            }),
        ),
        part(
            Kind::UpperArm,
            Shape::Capsule(Capsule {
                a: along(&shoulder, body.upper_arm[0]),
                b: along(&shoulder, body.upper_arm[1]),
                radius: body.upper_arm_radius,
            }),
        ),
        part(
            Kind::Forearm,
            Shape::Capsule(Capsule {
                a: along(&elbow, body.forearm[0]),
                b: along(&elbow, body.forearm[1]),
                radius: body.forearm_radius,
            }),
        ),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_postures_are_within_the_limits_and_a_wrong_one_is_named() {
        ArmPosture::CAPTURE.check().unwrap();
        ArmPosture::BESIDE_BODY.check().unwrap();
        let mut bad = ArmPosture::CAPTURE;
        bad.0[6] = 0.5;
        let e = bad.check().unwrap_err();
        assert!(e.starts_with("RShoulderRoll = 0.5000 rad"), "{e}");
    }

    #[test]
    fn arms_beside_the_body_point_to_the_feet_and_captures_arms_lie_beyond_the_head() {
        for side in Side::BOTH {
            let [shoulder, _, wrist] = arm_frames(side, &ArmPosture::BESIDE_BODY);
            let d: [f64; 3] =
                std::array::from_fn(|i| wrist.translation[i] - shoulder.translation[i]);
            // Toward the feet (−z), beside the torso (|y| beyond the shoulder's 98 mm).
            assert!(d[2] < -140.0, "{side:?} {d:?}");
            assert!(side.sign() * wrist.translation[1] > 98.0, "{d:?}");
            let [shoulder, _, wrist] = arm_frames(side, &ArmPosture::CAPTURE);
            let d: [f64; 3] =
                std::array::from_fn(|i| wrist.translation[i] - shoulder.translation[i]);
            // Beyond the head (+z), a little out, in the plane of the shoulders.
            assert!(d[2] > 120.0, "{side:?} {d:?}");
            assert!(side.sign() * d[1] > 30.0, "{side:?} {d:?}");
            assert!(d[0].abs() < 20.0, "{d:?}");
        }
    }

    #[test]
    fn the_arms_way_beyond_the_head_and_back_clears_the_head_and_the_floor() {
        // Capture moves the arms in a straight line of the joint angles, the head at rest.
        let body = BodyModel::default();
        let head = [body.head_centre[0], 0.0, 211.5 + body.head_centre[2]];
        let (from, to) = (ArmPosture::BESIDE_BODY.0, ArmPosture::CAPTURE.0);
        let mut least = f64::INFINITY;
        for k in 0..=100 {
            let t = k as f64 / 100.0;
            let at = ArmPosture(std::array::from_fn(|i| from[i] + t * (to[i] - from[i])));
            for side in Side::BOTH {
                for part in arm_parts(&body, side, &at) {
                    // Each solid is at least MARGIN larger than its part: the parts are
                    // apart while the solids overlap by less than both margins.
                    let gap = part.shape.distance(head) - body.head_radius;
                    least = least.min(gap);
                    assert!(
                        gap > -2.0 * BodyModel::MARGIN,
                        "{} meets the head at t = {t} ({gap:.1} mm)",
                        part.name()
                    );
                    // Nothing of the arm below the floor under the back.
                    if let Shape::Capsule(cap) = &part.shape {
                        let low = cap.a[0].min(cap.b[0]) - cap.radius;
                        assert!(low > body.floor_x, "{} at t = {t}: {low}", part.name());
                    }
                }
            }
        }
        // The closest the arms come to the head on the way, in the solids' terms.
        assert!(least < 0.0, "{least}");
    }
}
