//! The NAO's geometry, its measured joints, and the head→camera and hip→sole chains
//! (docs/MODEL.md §2).

use std::f64::consts::FRAC_PI_4;

use super::camera::CameraId;
use super::chain::{Affine, Chain};
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

macro_rules! joints {
    ($($name:ident),* $(,)?) => {
        /// A measured joint, named as in NAOqi and the `captures.csv` header.
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
        #[repr(usize)]
        pub enum Joint { $(#[doc = concat!("Joint `", stringify!($name), "`.")] $name,)* }

        impl Joint {
            /// Every measured joint, in `captures.csv` order.
            pub const ALL: [Joint; [$(Joint::$name),*].len()] = [$(Joint::$name),*];

            /// The joint's name (NAOqi).
            pub fn name(self) -> &'static str {
                match self { $(Joint::$name => stringify!($name),)* }
            }

            /// The joint named `name` (NAOqi), if any.
            pub fn from_name(name: &str) -> Option<Joint> {
                match name { $(stringify!($name) => Some(Joint::$name),)* _ => None }
            }

            /// The calibration parameter that offsets this joint (`q = θ + α`).
            pub fn offset(self) -> Param {
                match self { $(Joint::$name => Param::$name,)* }
            }
        }
    };
}

joints!(
    HeadYaw,
    HeadPitch,
    LHipYawPitch,
    LHipRoll,
    LHipPitch,
    LKneePitch,
    LAnklePitch,
    LAnkleRoll,
    RHipYawPitch,
    RHipRoll,
    RHipPitch,
    RKneePitch,
    RAnklePitch,
    RAnkleRoll,
);

/// Number of measured joints.
pub const JOINT_COUNT: usize = Joint::ALL.len();

impl Joint {
    /// Index into [`JointAngles`].
    pub fn index(self) -> usize {
        self as usize
    }

    /// Position among the twelve leg joints (left then right, hip to ankle); `None` for
    /// the head joints.
    pub fn leg_index(self) -> Option<usize> {
        self.index().checked_sub(2)
    }

    /// The joint's compliance parameter (leg joints only), from the parameter registry.
    pub fn compliance(self) -> Option<Param> {
        Param::of_joint(super::Family::Compliance, self)
    }

    /// The joint's play parameter (leg joints only), from the parameter registry.
    pub fn play(self) -> Option<Param> {
        Param::of_joint(super::Family::Play, self)
    }

    /// The joint's mechanical range in radians (NAO H25 documentation).
    pub fn limits(self) -> (f64, f64) {
        use Joint::*;
        match self {
            HeadYaw => (-2.0857, 2.0857),
            HeadPitch => (-0.6720, 0.5149),
            LHipYawPitch | RHipYawPitch => (-1.145303, 0.740810),
            LHipRoll => (-0.379472, 0.790477),
            RHipRoll => (-0.790477, 0.379472),
            LHipPitch | RHipPitch => (-1.535889, 0.484090),
            LKneePitch => (-0.092346, 2.112528),
            RKneePitch => (-0.103083, 2.120198),
            LAnklePitch => (-1.189516, 0.922747),
            RAnklePitch => (-1.186448, 0.932056),
            LAnkleRoll => (-0.397880, 0.769001),
            RAnkleRoll => (-0.768992, 0.397935),
        }
    }
}

/// The NAO documentation's head anti-collision limits: HeadPitch range (deg) by HeadYaw
/// (deg) (the head must not hit the shoulders), interpolated linearly between rows. The
/// same table, in radians, is B-Human's `Config/Robots/Default/headLimits.cfg` lines 2–4
/// (`intervals`, `lowerBounds`, `upperBounds`; BHumanCodeRelease d89d603f), which
/// `HeadLimits::getTiltBound` (`Src/Representations/Configuration/HeadLimits.cpp` lines
/// 15–42) interpolates linearly between rows as here.
const HEAD_PITCH_BY_YAW: [(f64, f64, f64); 13] = [
    (-119.52, -25.73, 18.91),
    (-87.49, -18.91, 11.46),
    (-62.45, -24.64, 17.19),
    (-51.74, -27.50, 18.91),
    (-43.32, -31.40, 21.20),
    (-27.85, -38.50, 24.18),
    (0.0, -38.50, 29.51),
    (27.85, -38.50, 24.18),
    (43.32, -31.40, 21.20),
    (51.74, -27.50, 18.91),
    (62.45, -24.64, 17.19),
    (87.49, -18.91, 11.46),
    (119.52, -25.73, 18.91),
];

/// The HeadPitch range (rad) allowed at HeadYaw `yaw` (rad).
pub fn head_pitch_limits(yaw: f64) -> (f64, f64) {
    let y = yaw.to_degrees().clamp(-119.52, 119.52);
    let k = HEAD_PITCH_BY_YAW
        .windows(2)
        .position(|w| y <= w[1].0)
        .unwrap_or(HEAD_PITCH_BY_YAW.len() - 2);
    let (a, b) = (HEAD_PITCH_BY_YAW[k], HEAD_PITCH_BY_YAW[k + 1]);
    let t = (y - a.0) / (b.0 - a.0);
    (
        (a.1 + t * (b.1 - a.1)).to_radians(),
        (a.2 + t * (b.2 - a.2)).to_radians(),
    )
}

/// The measured angles of every joint of one capture, in radians.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct JointAngles(pub [f64; JOINT_COUNT]);

impl JointAngles {
    /// The angle of every joint from `f(joint)`, called in [`Joint::ALL`] order.
    pub fn from_fn(mut f: impl FnMut(Joint) -> f64) -> JointAngles {
        JointAngles(Joint::ALL.map(&mut f))
    }

    /// Every joint at `angle`.
    pub fn fill(angle: f64) -> JointAngles {
        JointAngles([angle; JOINT_COUNT])
    }

    /// The measured angle of `joint`.
    pub fn get(&self, joint: Joint) -> f64 {
        self.0[joint.index()]
    }

    /// Sets the measured angle of `joint`.
    pub fn set(&mut self, joint: Joint, angle: f64) {
        self.0[joint.index()] = angle;
    }

    /// Each joint with its angle, in [`Joint::ALL`] order.
    pub fn iter(&self) -> impl Iterator<Item = (Joint, f64)> + '_ {
        Joint::ALL.into_iter().zip(self.0)
    }

    /// `f` of every angle, called in [`Joint::ALL`] order.
    pub fn map(&self, f: impl FnMut(f64) -> f64) -> JointAngles {
        JointAngles(self.0.map(f))
    }

    /// `f(self, other)` joint by joint, called in [`Joint::ALL`] order.
    pub fn zip_with(&self, other: &JointAngles, mut f: impl FnMut(f64, f64) -> f64) -> JointAngles {
        JointAngles::from_fn(|j| f(self.get(j), other.get(j)))
    }

    /// The posture a fraction `t` of the straight way from `self` to `to`: every joint at
    /// `a + t·(b − a)` (`self` at `t = 0`; `to` at `t = 1` up to rounding).
    pub fn lerp(&self, to: &JointAngles, t: f64) -> JointAngles {
        self.zip_with(to, |a, b| a + t * (b - a))
    }
}

impl std::ops::Add for JointAngles {
    type Output = JointAngles;

    /// Joint by joint `self + other`.
    fn add(self, other: JointAngles) -> JointAngles {
        self.zip_with(&other, |a, b| a + b)
    }
}

impl std::ops::Sub for JointAngles {
    type Output = JointAngles;

    /// Joint by joint `self − other`.
    fn sub(self, other: JointAngles) -> JointAngles {
        self.zip_with(&other, |a, b| a - b)
    }
}

impl std::ops::Mul<f64> for JointAngles {
    type Output = JointAngles;

    /// Every angle times `factor`.
    fn mul(self, factor: f64) -> JointAngles {
        self.map(|a| a * factor)
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
