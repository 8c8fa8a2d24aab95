//! The NAO's geometry, its measured joints, and the head→camera and hip→sole chains
//! (docs/MODEL.md §2).

use std::f64::consts::FRAC_PI_4;

use super::camera::CameraId;
use super::chain::{Affine, Chain};
use super::joint::{Joint, JointAngles};
use super::parameters::Param;
use super::pose::Axis;

/// A leg, and so the sandal (board) strapped to its foot.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Side {
    /// The left leg (`s = +1`).
    Left,
    /// The right leg (`s = −1`).
    Right,
}

impl Side {
    /// Both sides, left first.
    pub const BOTH: [Side; 2] = [Side::Left, Side::Right];

    /// The mirror sign `s` of docs/MODEL.md §2.
    pub fn sign(self) -> f64 {
        match self {
            Side::Left => 1.0,
            Side::Right => -1.0,
        }
    }

    /// `left` or `right`, as in `captures.csv`.
    pub fn name(self) -> &'static str {
        match self {
            Side::Left => "left",
            Side::Right => "right",
        }
    }

    /// Parses `left` / `right`.
    pub fn from_name(name: &str) -> Option<Side> {
        match name {
            "left" => Some(Side::Left),
            "right" => Some(Side::Right),
            _ => None,
        }
    }

    /// The six joints of this leg, hip to ankle.
    pub fn leg_joints(self) -> [Joint; 6] {
        use Joint::*;
        match self {
            Side::Left => [
                LHipYawPitch,
                LHipRoll,
                LHipPitch,
                LKneePitch,
                LAnklePitch,
                LAnkleRoll,
            ],
            Side::Right => [
                RHipYawPitch,
                RHipRoll,
                RHipPitch,
                RKneePitch,
                RAnklePitch,
                RAnkleRoll,
            ],
        }
    }

    /// The board mounting parameters (RotZ, TransX, TransY) of this side's sandal.
    pub fn board_params(self) -> [Param; 3] {
        match self {
            Side::Left => [Param::LBoardRotZ, Param::LBoardTransX, Param::LBoardTransY],
            Side::Right => [Param::RBoardRotZ, Param::RBoardTransX, Param::RBoardTransY],
        }
    }
}

/// The link lengths and fixed angles of the head and leg chains (docs/MODEL.md §2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RobotGeometry {
    /// Lateral distance of each hip joint from the origin (mm).
    pub hip_offset_y: f64,
    /// Height of the HeadYaw joint above the origin (mm).
    pub hip_to_neck_z: f64,
    /// Hip to knee (mm).
    pub thigh: f64,
    /// Knee to ankle (mm).
    pub tibia: f64,
    /// Ankle to sole (mm).
    pub foot_height: f64,
    /// Lower camera position in the HeadPitch frame (mm).
    pub lower_camera_offset: [f64; 3],
    /// Lower camera tilt about y, looking down (rad).
    pub lower_camera_tilt: f64,
    /// Upper camera position in the HeadPitch frame (mm).
    pub upper_camera_offset: [f64; 3],
    /// Upper camera tilt about y, looking down (rad).
    pub upper_camera_tilt: f64,
    /// Direction of gravity in the origin frame `O`, a unit vector (lying on its back:
    /// `(−1, 0, 0)`); it sets the gravity torques of compliance and play.
    pub gravity: [f64; 3],
}

impl Default for RobotGeometry {
    /// NAO H25 V4, V5 and V6.
    fn default() -> Self {
        RobotGeometry {
            hip_offset_y: 50.0,
            hip_to_neck_z: 211.5,
            thigh: 100.0,
            tibia: 102.9,
            foot_height: 45.19,
            lower_camera_offset: [50.71, 0.0, 17.74],
            lower_camera_tilt: 39.7f64.to_radians(),
            upper_camera_offset: [58.71, 0.0, 63.64],
            upper_camera_tilt: 1.2f64.to_radians(),
            gravity: [-1.0, 0.0, 0.0],
        }
    }
}

impl RobotGeometry {
    /// `T_OC`: origin → lower camera, with the head joint offsets, the neck and camera
    /// position corrections and the camera rotation offsets as parameters.
    pub fn camera_chain(&self, joints: &JointAngles) -> Chain {
        let [x, y, z] = self.lower_camera_offset;
        let length = |value: f64, param: Param| Affine::constant(value).plus(param, 1.0);
        self.head_chain(joints)
            .translate(Axis::X, length(x, Param::CamX))
            .translate(Axis::Y, length(y, Param::CamY))
            .translate(Axis::Z, length(z, Param::CamZ))
            .rotate(Axis::Y, Affine::constant(self.lower_camera_tilt))
            .rotate(Axis::Y, Affine::param(Param::CamPitch))
            .rotate(Axis::X, Affine::param(Param::CamRoll))
            .rotate(Axis::Z, Affine::param(Param::CamYaw))
    }

    /// Origin → upper camera: the head chain of [`RobotGeometry::camera_chain`], then the
    /// upper camera's mount `T(upper_camera_offset) · Ry(upper_camera_tilt)` and its rotation
    /// offsets `Ry(α_UpperCamPitch) · Rx(α_UpperCamRoll) · Rz(α_UpperCamYaw)` (docs/MODEL.md).
    pub fn upper_camera_chain(&self, joints: &JointAngles) -> Chain {
        let [x, y, z] = self.upper_camera_offset;
        self.head_chain(joints)
            .translate(Axis::X, Affine::constant(x))
            .translate(Axis::Y, Affine::constant(y))
            .translate(Axis::Z, Affine::constant(z))
            .rotate(Axis::Y, Affine::constant(self.upper_camera_tilt))
            .rotate(Axis::Y, Affine::param(Param::UpperCamPitch))
            .rotate(Axis::X, Affine::param(Param::UpperCamRoll))
            .rotate(Axis::Z, Affine::param(Param::UpperCamYaw))
    }

    /// Origin → the camera `camera`.
    pub fn camera_chain_of(&self, camera: CameraId, joints: &JointAngles) -> Chain {
        match camera {
            CameraId::Lower => self.camera_chain(joints),
            CameraId::Upper => self.upper_camera_chain(joints),
        }
    }

    /// Origin → HeadPitch frame: the neck and the two head joints with their offsets.
    fn head_chain(&self, joints: &JointAngles) -> Chain {
        let length = |value: f64, param: Param| Affine::constant(value).plus(param, 1.0);
        Chain::new()
            .translate(Axis::Z, length(self.hip_to_neck_z, Param::NeckZ))
            .rotate(
                Axis::Z,
                Affine::joint(1.0, joints.get(Joint::HeadYaw), Param::HeadYaw),
            )
            .rotate(
                Axis::Y,
                Affine::joint(1.0, joints.get(Joint::HeadPitch), Param::HeadPitch),
            )
    }

    /// `T_OS`: origin → sole of one leg, with the joint offsets, link corrections,
    /// compliance and play as parameters. `torques` are the capture's gravity torques about
    /// the six joints (see [`super::gravity::leg_torques`]): each joint turns by
    /// `q = θ + α + κ·τ + (π/2)·sign(τ)`.
    pub fn sole_chain(&self, side: Side, joints: &JointAngles, torques: &[f64; 6]) -> Chain {
        let s = side.sign();
        let [thigh, tibia, foot] = match side {
            Side::Left => [Param::LThigh, Param::LTibia, Param::LFoot],
            Side::Right => [Param::RThigh, Param::RTibia, Param::RFoot],
        };
        let angle = |k: usize, sign: f64| {
            let joint = side.leg_joints()[k];
            let tau = torques[k];
            let half_sign = if tau > 0.0 {
                0.5
            } else if tau < 0.0 {
                -0.5
            } else {
                0.0
            };
            Affine::joint(sign, joints.get(joint), joint.offset())
                .plus(joint.compliance().expect("a leg joint"), sign * tau)
                .plus(joint.play().expect("a leg joint"), sign * half_sign)
        };
        let down = |value: f64, param: Param| Affine::constant(-value).plus(param, -1.0);
        Chain::new()
            .translate(
                Axis::Y,
                Affine::constant(s * self.hip_offset_y).plus(Param::HipOffsetY, s),
            )
            .rotate(Axis::X, Affine::constant(s * FRAC_PI_4))
            .rotate(Axis::Z, angle(0, -s))
            .rotate(Axis::X, Affine::constant(-s * FRAC_PI_4))
            .rotate(Axis::X, angle(1, 1.0))
            .rotate(Axis::Y, angle(2, 1.0))
            .translate(Axis::Z, down(self.thigh, thigh))
            .rotate(Axis::Y, angle(3, 1.0))
            .translate(Axis::Z, down(self.tibia, tibia))
            .rotate(Axis::Y, angle(4, 1.0))
            .rotate(Axis::X, angle(5, 1.0))
            .translate(Axis::Z, down(self.foot_height, foot))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn compliance_and_play_follow_the_leg_joints() {
        for j in Joint::ALL {
            match j.leg_index() {
                None => assert!(j.compliance().is_none() && j.play().is_none()),
                Some(_) => {
                    assert_eq!(
                        j.compliance().unwrap().name(),
                        format!("{}Compliance", j.name())
                    );
                    assert_eq!(j.play().unwrap().name(), format!("{}Play", j.name()));
                }
            }
        }
    }

    #[test]
    fn joint_angles_map_zip_and_lerp_joint_by_joint_in_order() {
        let mut order = Vec::new();
        let a = JointAngles::from_fn(|j| {
            order.push(j);
            0.1 * j.index() as f64 - 0.5
        });
        assert_eq!(order, Joint::ALL);
        assert_eq!(a.get(Joint::HeadPitch), 0.1 - 0.5);
        let b = a.map(|q| -2.0 * q + 0.3);
        let sum = a + b;
        let difference = b - a;
        let scaled = a * 3.0;
        for (j, q) in a.iter() {
            assert_eq!(b.get(j), -2.0 * q + 0.3);
            assert_eq!(sum.get(j), q + b.get(j));
            assert_eq!(difference.get(j), b.get(j) - q);
            assert_eq!(scaled.get(j), q * 3.0);
            assert_eq!(a.zip_with(&b, f64::max).get(j), q.max(b.get(j)));
        }
        // lerp is a + t·(b − a), bit for bit: the moves of capture and the collision
        // checks of the planner interpolate the same postures.
        for t in [0.0, 0.25, 1.0 / 3.0, 0.9] {
            let between = a.lerp(&b, t);
            for (j, q) in a.iter() {
                assert_eq!(between.get(j).to_bits(), (q + t * (b.get(j) - q)).to_bits());
            }
        }
        assert_eq!(a.lerp(&b, 0.0), a);
        assert!((a.lerp(&b, 1.0) - b).iter().all(|(_, d)| d.abs() < 1e-15));
        assert_eq!(
            JointAngles::fill(0.5)
                .iter()
                .filter(|&(_, q)| q == 0.5)
                .count(),
            14
        );
    }

    #[test]
    fn joints_are_found_by_name() {
        for j in Joint::ALL {
            assert_eq!(Joint::from_name(j.name()), Some(j));
        }
        assert_eq!(Joint::from_name("LKnee"), None);
        assert_eq!(Joint::from_name("lkneepitch"), None);
    }
}
