//! The arms during a capture run: where LoLA reads them, where capture commands them, what
//! their motors may report, and how the dry run names where they are.
//!
//! The robot is laid down with its arms beside the body ([`ArmPosture::BESIDE_BODY`]),
//! where they are in the cameras' view and in the legs' reach. A run lifts them to the
//! plan's arm posture (beyond the head, [`ArmPosture::CAPTURE`]) once the robot is known to
//! lie on its back and its stiffness is ramped up, at [`MotionOptions::arm_speed`], holds
//! them there, and lays them back beside the body at a clean end before the stiffness
//! ramps down (docs/CAPTURE.md).
//!
//! The arm joints are LoLA's indices 2–6 (left) and 18–22 (right) (nao_lola
//! `lola_enums.hpp` lines 25–53, [`lola::JOINT_NAMES`]), commanded like the legs: one
//! `Position` and one `Stiffness` per joint in every answer, as B-Human's `NaoProvider`
//! fills all 25 (`NaoProvider.cpp` lines 421–443) and HULKs' `LolaControlFrame` carries
//! both arms' positions and stiffnesses (`hula_types/src/lola.rs` lines 5–28).

use crate::body::posture::ARM_LIMITS;
use crate::body::{ARM_JOINTS, ArmPosture};

use super::lola::{self, JOINTS, SensorMessage};
use super::motion::MotionOptions;
use super::safety::{SafetyLimits, Watch};

/// Within this (rad, 5°) of a named posture in every arm joint, the arms are said to be in
/// it ([`describe`]).
pub const NEAR: f64 = 5.0 * std::f64::consts::PI / 180.0;

/// LoLA's index of each arm joint, in [`ARM_JOINTS`] order.
pub fn indices() -> [usize; 10] {
    ARM_JOINTS.map(|name| {
        lola::JOINT_NAMES
            .iter()
            .position(|n| *n == name)
            .expect("every arm joint is a LoLA joint")
    })
}

/// The arm angles in one of LoLA's 25-value arrays.
pub fn read(values: &[f32; JOINTS]) -> ArmPosture {
    let at = indices();
    ArmPosture(std::array::from_fn(|k| f64::from(values[at[k]])))
}

/// `base`, one value per LoLA joint, with `f` of each arm angle of `arms` in its place.
pub fn put<T>(mut base: [T; JOINTS], arms: &ArmPosture, f: impl Fn(f64) -> T) -> [T; JOINTS] {
    for (k, q) in indices().into_iter().zip(arms.0) {
        base[k] = f(q);
    }
    base
}

/// The largest difference (rad) of an arm joint between `a` and `b` (infinite when one
/// is not a number).
pub fn distance(a: &ArmPosture, b: &ArmPosture) -> f64 {
    a.0.iter()
        .zip(b.0)
        .map(|(x, y)| {
            let d = (x - y).abs();
            if d.is_nan() { f64::INFINITY } else { d }
        })
        .fold(0.0, f64::max)
}

/// The postures with a name: how the robot is laid down, and capture's.
pub const NAMED: [(ArmPosture, &str); 2] = [
    (ArmPosture::BESIDE_BODY, "beside the body"),
    (ArmPosture::CAPTURE, "beyond the head"),
];

/// The name of the posture ([`NAMED`]) `arms` is within [`NEAR`] of, if any.
pub fn named(arms: &ArmPosture) -> Option<&'static str> {
    NAMED
        .into_iter()
        .find(|(p, _)| distance(arms, p) <= NEAR)
        .map(|(_, name)| name)
}

/// Where the arms are, in words: a named posture ([`named`]) with its largest difference,
/// else every joint's angle in degrees.
pub fn describe(arms: &ArmPosture) -> String {
    let posture = NAMED.into_iter().find(|(p, _)| distance(arms, p) <= NEAR);
    match posture {
        Some((p, name)) => format!(
            "{name} (every joint within {:.1}° of it)",
            distance(arms, &p).to_degrees()
        ),
        None => {
            let angles: Vec<String> = ARM_JOINTS
                .iter()
                .zip(arms.0)
                .map(|(n, q)| format!("{n} {:.1}°", q.to_degrees()))
                .collect();
            angles.join(", ")
        }
    }
}

/// The first arm joint of `arms` outside its limits ([`ARM_LIMITS`]): its index and what
/// is wrong.
pub fn outside_limits(arms: &ArmPosture) -> Option<(usize, String)> {
    arms.0
        .iter()
        .zip(ARM_LIMITS)
        .position(|(q, (lo, hi))| !(lo..=hi).contains(q))
        .map(|k| {
            let (lo, hi) = ARM_LIMITS[k];
            (
                k,
                format!(
                    "{:.2}° is outside the joint's limits {:.2}° … {:.2}°",
                    arms.0[k].to_degrees(),
                    lo.to_degrees(),
                    hi.to_degrees()
                ),
            )
        })
}

/// The watch on the arm motors while they are stiff: what would stop a run (a motor at
/// the stop temperature, a status at the stop level, a current above the limit for the
/// limit's cycles, a temperature or current that is not a number). The legs rest to cool;
/// the arms, holding their posture beyond the head with next to no load, have no such
/// pause: an arm motor that heats up stops the run.
#[derive(Debug, Clone, Default)]
pub struct ArmWatch {
    motors: Watch,
}

impl ArmWatch {
    /// Checks one message: why the run stops, naming the joint.
    pub fn check(&mut self, limits: &SafetyLimits, m: &SensorMessage) -> Result<(), String> {
        let arms = indices();
        let verdict = self.motors.check_motors(limits, m, &arms);
        let name = |k: usize| lola::JOINT_NAMES[k].to_string();
        if let Some(why) = verdict.stops(limits, name) {
            return Err(why);
        }
        // No pause for the arms, but a status at the stop level stops the run (a hot arm
        // motor above pauses nothing and hides no status).
        let (k, status) = arms
            .iter()
            .map(|&k| (k, m.status[k]))
            .fold((arms[0], i32::MIN), |a, b| if b.1 > a.1 { b } else { a });
        if status >= limits.body.stop_status {
            return Err(format!(
                "{} reports status {status} (the firmware reduces its stiffness)",
                name(k)
            ));
        }
        Ok(())
    }
}

/// How long (s) the arms take from `from` to `to` at `motion`'s arm speed.
pub fn move_seconds(motion: &MotionOptions, from: &ArmPosture, to: &ArmPosture) -> f64 {
    motion.arm_path(from, to).len() as f64 * lola::CYCLE_S
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arm_joints_sit_at_lolas_indices_and_read_back() {
        assert_eq!(indices(), [2, 3, 4, 5, 6, 18, 19, 20, 21, 22]);
        let values = put([0.0f32; JOINTS], &ArmPosture::CAPTURE, |q| q as f32);
        assert_eq!(values[7], 0.0, "HipYawPitch untouched");
        assert!(distance(&read(&values), &ArmPosture::CAPTURE) < 1e-6);
    }

    #[test]
    fn postures_are_named_within_a_few_degrees_else_given_as_angles() {
        assert_eq!(named(&ArmPosture::BESIDE_BODY), Some("beside the body"));
        assert_eq!(named(&ArmPosture::CAPTURE), Some("beyond the head"));
        let mut near = ArmPosture::BESIDE_BODY;
        near.0[0] -= 4f64.to_radians();
        assert!(describe(&near).starts_with("beside the body (every joint within 4.0°"));
        near.0[0] -= 2f64.to_radians();
        assert_eq!(named(&near), None);
        let words = describe(&near);
        assert!(
            words.starts_with("LShoulderPitch 84.0°, LShoulderRoll 8.6°"),
            "{words}"
        );
        assert!(words.ends_with("RWristYaw 0.0°"), "{words}");
        let mut nan = ArmPosture::CAPTURE;
        nan.0[9] = f64::NAN;
        assert_eq!(named(&nan), None);
    }

    #[test]
    fn an_arm_outside_its_limits_is_named() {
        assert_eq!(outside_limits(&ArmPosture::CAPTURE), None);
        let mut bad = ArmPosture::CAPTURE;
        bad.0[8] = -0.2;
        let (k, why) = outside_limits(&bad).unwrap();
        assert_eq!(ARM_JOINTS[k], "RElbowRoll");
        assert!(
            why.starts_with("-11.46° is outside the joint's limits 2.00°"),
            "{why}"
        );
    }

    #[test]
    fn the_arm_watch_stops_on_heat_status_and_a_lasting_current() {
        let limits = SafetyLimits::default();
        let mut w = ArmWatch::default();
        let calm = SensorMessage::on_back([0.0; JOINTS]);
        assert_eq!(w.check(&limits, &calm), Ok(()));
        let mut hot = calm.clone();
        hot.temperature[19] = 81.0;
        assert!(
            w.check(&limits, &hot)
                .unwrap_err()
                .starts_with("RShoulderRoll reached 81.0")
        );
        let mut status = calm.clone();
        status.status[2] = 2;
        assert!(
            w.check(&limits, &status)
                .unwrap_err()
                .starts_with("LShoulderPitch reports status 2")
        );
        let mut pulling = calm.clone();
        pulling.current[5] = 3.0;
        for _ in 1..limits.current_cycles {
            assert_eq!(w.check(&limits, &pulling), Ok(()));
        }
        assert!(
            w.check(&limits, &pulling)
                .unwrap_err()
                .contains("LElbowRoll drew 3.00 A")
        );
        // A current that drops resets the count.
        let mut w = ArmWatch::default();
        for _ in 0..3 * limits.current_cycles {
            assert_eq!(w.check(&limits, &pulling), Ok(()));
            assert_eq!(w.check(&limits, &calm), Ok(()));
        }
    }
}
