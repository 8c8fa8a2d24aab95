//! The NAO's measured joints (named as in NAOqi and `captures.csv`), their ranges, and
//! the angles of one capture. The parameters that belong to a joint (its offset, its
//! compliance, its play) are the registry's (`super::parameters`).

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
            pub const fn name(self) -> &'static str {
                match self { $(Joint::$name => stringify!($name),)* }
            }

            /// The joint named `name` (NAOqi), if any.
            pub fn from_name(name: &str) -> Option<Joint> {
                match name { $(stringify!($name) => Some(Joint::$name),)* _ => None }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{Family, Param};

    #[test]
    fn every_joint_is_offset_by_the_parameter_of_its_name() {
        for joint in Joint::ALL {
            let offset = joint.offset();
            assert_eq!(offset.name(), joint.name());
            assert!(matches!(offset.family(), Family::Paper | Family::Head));
            assert_eq!(Param::from_name(joint.name()), Some(offset));
        }
        assert_eq!(Joint::LKneePitch.offset(), Param::LKneePitch);
        assert_eq!(Joint::HeadYaw.compliance(), None);
        assert!(Joint::RAnkleRoll.play().is_some());
    }
}
