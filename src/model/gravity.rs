//! Gravity torques about the leg joints (compliance and play, docs/MODEL.md): each capture's
//! torques are computed once from the logged angles and the nominal geometry, with the NAO
//! H25 mass table and the sandal, and enter the model as per-capture coefficients.

use std::f64::consts::FRAC_PI_4;

use super::board::Board;
use super::joint::JointAngles;
use super::pose::{Axis, Pose};
use super::robot::{RobotGeometry, Side};

/// Standard gravity (m/s²).
pub const G: f64 = 9.81;

/// One link of a leg: its mass (g) and centre of mass (mm) in the frame after its joint
/// (left leg; the right leg mirrors y).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Link {
    /// Link name.
    pub name: &'static str,
    /// Mass (g).
    pub mass_g: f64,
    /// Centre of mass in the frame `F_i` after joint `i` (mm).
    pub com_mm: [f64; 3],
}

/// The NAO H25 leg links after each joint (HipYawPitch … AnkleRoll), the public mass table
/// SPL teams use.
pub const LEG_LINKS: [Link; 6] = [
    Link {
        name: "pelvis",
        mass_g: 69.81,
        com_mm: [-7.81, -11.14, 26.61],
    },
    Link {
        name: "hip",
        mass_g: 140.53,
        com_mm: [-15.49, 0.29, -5.15],
    },
    Link {
        name: "thigh",
        mass_g: 389.68,
        com_mm: [1.38, 2.21, -53.73],
    },
    Link {
        name: "tibia",
        mass_g: 301.42,
        com_mm: [4.53, 2.25, -49.36],
    },
    Link {
        name: "ankle",
        mass_g: 134.16,
        com_mm: [0.45, 0.29, 6.85],
    },
    Link {
        name: "foot",
        mass_g: 171.84,
        com_mm: [25.42, 3.30, -32.39],
    },
];

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn column(pose: &Pose<f64>, k: usize) -> [f64; 3] {
    [
        pose.rotation[0][k],
        pose.rotation[1][k],
        pose.rotation[2][k],
    ]
}

/// One leg's joint frames `F_0 … F_5` in `O`, the axes `u_j` about which a growing angle
/// turns and a point `o_j` on each (docs/MODEL.md §6).
struct LegFrames {
    frames: [Pose<f64>; 6],
    axes: [[f64; 3]; 6],
    points: [[f64; 3]; 6],
}

fn leg_frames(robot: &RobotGeometry, side: Side, joints: &JointAngles) -> LegFrames {
    let s = side.sign();
    let q = side.leg_joints().map(|j| joints.get(j));
    let base = Pose::translation(0.0, s * robot.hip_offset_y, 0.0)
        .compose(&Pose::rotation(Axis::X, s * FRAC_PI_4));
    let f0 = base
        .compose(&Pose::rotation(Axis::Z, -s * q[0]))
        .compose(&Pose::rotation(Axis::X, -s * FRAC_PI_4));
    let f1 = f0.compose(&Pose::rotation(Axis::X, q[1]));
    let f2 = f1.compose(&Pose::rotation(Axis::Y, q[2]));
    let f3 = f2
        .compose(&Pose::translation(0.0, 0.0, -robot.thigh))
        .compose(&Pose::rotation(Axis::Y, q[3]));
    let f4 = f3
        .compose(&Pose::translation(0.0, 0.0, -robot.tibia))
        .compose(&Pose::rotation(Axis::Y, q[4]));
    let f5 = f4.compose(&Pose::rotation(Axis::X, q[5]));

    let z0 = column(&base, 2);
    let axes = [
        z0.map(|x| -s * x),
        column(&f1, 0),
        column(&f2, 1),
        column(&f3, 1),
        column(&f4, 1),
        column(&f5, 0),
    ];
    let hip = f0.translation;
    let points = [
        hip,
        hip,
        hip,
        f3.translation,
        f4.translation,
        f4.translation,
    ];
    LegFrames {
        frames: [f0, f1, f2, f3, f4, f5],
        axes,
        points,
    }
}

/// `u_j · Σ (c − o_j) × (m·g·d)` (N·m) over `masses` (g, mm in `O`) for unit gravity `d`.
fn moment_about(axis: [f64; 3], point: [f64; 3], masses: &[(f64, [f64; 3])], d: [f64; 3]) -> f64 {
    let moment = masses.iter().fold([0.0; 3], |acc, (mass, c)| {
        let r = [0, 1, 2].map(|k| (c[k] - point[k]) / 1000.0);
        let force = d.map(|x| mass / 1000.0 * G * x);
        let m = cross(r, force);
        [acc[0] + m[0], acc[1] + m[1], acc[2] + m[2]]
    });
    dot(axis, moment)
}

/// The gravity torque (N·m) about each joint of one leg (HipYawPitch, HipRoll, HipPitch,
/// KneePitch, AnklePitch, AnkleRoll) at the logged angles, offsets left out:
/// `τ_j = u_j · Σ_{i ≥ j} (c_i − o_j) × (m_i·g·d)` with `u_j` the axis about which a growing
/// angle turns, `o_j` a point on it and `d` the unit gravity direction of `robot`.
pub fn leg_torques(
    robot: &RobotGeometry,
    board: &Board,
    side: Side,
    joints: &JointAngles,
) -> [f64; 6] {
    let s = side.sign();
    let LegFrames {
        frames,
        axes,
        points,
    } = leg_frames(robot, side, joints);
    let norm = dot(robot.gravity, robot.gravity).sqrt();
    let d = robot.gravity.map(|x| x / norm);
    let mirror = |c: [f64; 3]| [c[0], s * c[1], c[2]];
    // Every mass with its position in O [mm], in the order of the frames they hang from
    // (the sandal's from the last).
    let [cx, cy, cz] = mirror(board.com_mm);
    let masses: [(f64, [f64; 3]); 7] = std::array::from_fn(|i| match LEG_LINKS.get(i) {
        Some(link) => (link.mass_g, frames[i].apply(&mirror(link.com_mm))),
        None => (
            board.mass_g,
            frames[5].apply(&[cx, cy, cz - robot.foot_height]),
        ),
    });
    // The masses distal of joint j: the links from frame j on, and the sandal.
    std::array::from_fn(|j| moment_about(axes[j], points[j], &masses[j..], d))
}

/// naocalib's standard stand, the posture a robot plays in (deg), the same for both legs:
/// `HipYawPitch, HipRoll, HipPitch, KneePitch, AnklePitch, AnkleRoll`. Hip, knee and ankle
/// pitch sum to zero, so the soles lie flat and the torso is upright.
pub const STAND_DEG: [f64; 6] = [0.0, 0.0, -22.0, 44.0, -22.0, 0.0];

/// The upper body (torso, neck, head and both arms hanging down) of the NAO H25, the
/// public mass table: total mass (g) …
pub const UPPER_BODY_MASS_G: f64 = 2876.5;
/// … and its centre of mass in `O` (mm) with the torso upright and the arms down.
pub const UPPER_BODY_COM_MM: [f64; 3] = [-1.7, 0.0, 148.8];

/// The logged angles of the standard stand ([`STAND_DEG`], both legs, head and arms 0).
pub fn stand_joints() -> JointAngles {
    let mut joints = JointAngles::default();
    for side in [Side::Left, Side::Right] {
        for (j, deg) in side.leg_joints().into_iter().zip(STAND_DEG) {
            joints.set(j, deg.to_radians());
        }
    }
    joints
}

/// The gravity torque (N·m) about each joint of one leg of a robot **standing** at `joints`
/// (torso upright, gravity along −z of `O`, both soles on the ground): the leg supports
/// its own links above each joint and half the upper body ([`UPPER_BODY_MASS_G`] at
/// [`UPPER_BODY_COM_MM`]). The torque the joint transmits is minus the moment of those
/// loads about its axis, `τ_j = −u_j · Σ_{above j} (c − o_j) × (m·g·d)`, in the sign
/// convention of [`leg_torques`] (positive: the load turns the angle up). The lateral
/// forces between the two legs in double support are left out.
pub fn standing_leg_torques(robot: &RobotGeometry, side: Side, joints: &JointAngles) -> [f64; 6] {
    let s = side.sign();
    let LegFrames {
        frames,
        axes,
        points,
    } = leg_frames(robot, side, joints);
    let d = [0.0, 0.0, -1.0];
    let mirror = |c: [f64; 3]| [c[0], s * c[1], c[2]];
    std::array::from_fn(|j| {
        let mut above: Vec<(f64, [f64; 3])> = LEG_LINKS[..j]
            .iter()
            .enumerate()
            .map(|(i, link)| (link.mass_g, frames[i].apply(&mirror(link.com_mm))))
            .collect();
        above.push((UPPER_BODY_MASS_G / 2.0, UPPER_BODY_COM_MM));
        -moment_about(axes[j], points[j], &above, d)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Joint;

    /// The reference torques of docs/MODEL.md (pose A, default geometry, lying on its back).
    #[test]
    fn standing_torques_load_the_knees_and_mirror_between_legs() {
        let robot = RobotGeometry::default();
        let joints = stand_joints();
        let left = standing_leg_torques(&robot, Side::Left, &joints);
        let right = standing_leg_torques(&robot, Side::Right, &joints);
        // The bent knee carries the body: the load bends it further (turns the angle up).
        assert!(left[3] > 0.3, "{left:?}");
        for k in [2, 3, 4] {
            assert!(
                (left[k] - right[k]).abs() < 1e-9,
                "pitch {k}: {left:?} {right:?}"
            );
        }
        for k in [1, 5] {
            assert!(
                (left[k] + right[k]).abs() < 1e-9,
                "roll {k}: {left:?} {right:?}"
            );
        }
    }

    #[test]
    fn reference_torques_of_pose_a() {
        use Joint::*;
        let mut joints = JointAngles::default();
        for (j, v) in [
            (HeadYaw, 0.3),
            (HeadPitch, 0.2),
            (LHipYawPitch, -0.3),
            (LHipRoll, 0.1),
            (LHipPitch, -0.4),
            (LKneePitch, 0.8),
            (LAnklePitch, -0.35),
            (LAnkleRoll, -0.05),
            (RHipYawPitch, -0.3),
            (RHipRoll, -0.1),
            (RHipPitch, -0.5),
            (RKneePitch, 0.9),
            (RAnklePitch, -0.4),
            (RAnkleRoll, 0.07),
        ] {
            joints.set(j, v);
        }
        let robot = RobotGeometry::default();
        let board = Board::default();
        let left = leg_torques(&robot, &board, Side::Left, &joints);
        let right = leg_torques(&robot, &board, Side::Right, &joints);
        let want_left = [0.7861, 0.3455, 1.3550, 0.6162, 0.0647, 0.0247];
        let want_right = [0.7307, -0.3333, 1.2896, 0.6048, 0.0533, -0.0243];
        for k in 0..6 {
            assert!((left[k] - want_left[k]).abs() < 1e-4, "left {k}: {left:?}");
            assert!(
                (right[k] - want_right[k]).abs() < 1e-4,
                "right {k}: {right:?}"
            );
        }
    }
}
