//! Which joint readings to believe (docs/CAPTURE.md §3): a reading that is not finite, lies
//! outside the joint's range, or moved farther since the last believed reading than the
//! joint's motor can move it is implausible. One implausible reading of a joint is a
//! glitch: it is ignored (the last plausible reading stands) and nothing follows it; a
//! second one within [`Plausibility::glitch_cycles`] is a fault that stops the run.
//! Commands never depend on an implausible reading.

use crate::model::{JOINT_COUNT, Joint, JointAngles};

use super::lola::{self, CYCLE_S, JOINTS, SensorMessage};

/// The fastest each joint's motor turns it (rad/s): the NAO's published maximum joint
/// velocities (Aldebaran's joint tables, NAOqi `ALMotion.getLimits`): 8.26797 (HeadYaw),
/// 7.19407 (HeadPitch), 4.16174 (HipYawPitch, HipRoll, AnkleRoll), 6.40239 (HipPitch,
/// KneePitch, AnklePitch).
pub fn max_speed(joint: Joint) -> f64 {
    use Joint::*;
    match joint {
        HeadYaw => 8.26797,
        HeadPitch => 7.19407,
        LHipYawPitch | RHipYawPitch | LHipRoll | RHipRoll | LAnkleRoll | RAnkleRoll => 4.16174,
        LHipPitch | RHipPitch | LKneePitch | RKneePitch | LAnklePitch | RAnklePitch => 6.40239,
    }
}

/// The thresholds of plausible readings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plausibility {
    /// How far beyond the joint's published limits a reading may lie (rad).
    pub range_tolerance: f64,
    /// Added to a joint's motion per cycle ([`max_speed`] × 12 ms) before a change of its
    /// reading counts as a jump (rad): the encoder's flicker.
    pub jump_slack: f64,
    /// A second implausible reading of the same joint within this many cycles of the first
    /// is a fault.
    pub glitch_cycles: u32,
}

impl Default for Plausibility {
    /// 4° beyond the limits (leg offsets up to 2°, joint play up to 1.4° and a few encoder
    /// steps), a slack of 2 encoder steps (0.18°), a fault on a second glitch within 25
    /// cycles (0.3 s).
    fn default() -> Self {
        Plausibility {
            range_tolerance: 4f64.to_radians(),
            jump_slack: 2.0 * std::f64::consts::TAU / 4096.0,
            glitch_cycles: 25,
        }
    }
}

impl Plausibility {
    /// The most a reading of `joint` may change in one cycle (rad).
    pub fn max_step(&self, joint: Joint) -> f64 {
        max_speed(joint) * CYCLE_S + self.jump_slack
    }
}

/// What is wrong with a reading.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Implausible {
    /// Not a finite number.
    NotFinite,
    /// Outside the joint's limits (with the tolerance).
    OutOfRange,
    /// Changed more than the motor can move it since the last plausible reading (that
    /// reading, rad; the most it could have changed, rad).
    Jump(f64, f64),
    /// A stiffness outside 0 … 1 (or not finite).
    Stiffness,
}

/// An implausible reading that stops the run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{}", self.describe())]
pub struct ReadingFault {
    /// LoLA's name of the joint.
    pub joint: &'static str,
    /// The reading (rad; the stiffness for [`Implausible::Stiffness`]).
    pub value: f64,
    /// What is wrong with it.
    pub why: Implausible,
    /// Whether it repeats a glitch (a second implausible reading within the glitch window).
    pub repeated: bool,
}

impl ReadingFault {
    fn describe(&self) -> String {
        let deg = self.value.to_degrees();
        let what = match self.why {
            Implausible::NotFinite => format!("{} reads {}", self.joint, self.value),
            Implausible::OutOfRange => {
                let (lo, hi) =
                    Joint::from_name(self.joint).map_or((f64::NAN, f64::NAN), Joint::limits);
                format!(
                    "{} reads {deg:.1}°, outside its range {:.1}° … {:.1}°",
                    self.joint,
                    lo.to_degrees(),
                    hi.to_degrees()
                )
            }
            Implausible::Jump(from, most) => format!(
                "{} reads {deg:.1}° after {:.1}°: a jump its motor cannot make (at most \
                 {:.1}°)",
                self.joint,
                from.to_degrees(),
                most.to_degrees()
            ),
            Implausible::Stiffness => {
                format!("{} reports stiffness {}", self.joint, self.value)
            }
        };
        if self.repeated {
            format!("implausible joint reading, again: {what}")
        } else {
            format!("implausible joint reading: {what}")
        }
    }
}

/// The readings believed so far, cycle by cycle.
#[derive(Debug, Clone)]
pub struct Believed {
    limits: Plausibility,
    believed: JointAngles,
    /// Cycles since each joint's reading was last believed.
    since: [u32; JOINT_COUNT],
    /// The cycle of each joint's last glitch.
    glitch: [Option<u64>; JOINT_COUNT],
    /// Joints whose readings are no longer believed (after a fault).
    lost: [bool; JOINT_COUNT],
    cycle: u64,
    /// Whether every joint's reading of the last cycle was believed.
    all: bool,
}

/// Checks a measured joint's reading alone: finite and within its limits.
fn in_range(limits: &Plausibility, joint: Joint, value: f64) -> Result<(), Implausible> {
    if !value.is_finite() {
        return Err(Implausible::NotFinite);
    }
    let (lo, hi) = joint.limits();
    if value < lo - limits.range_tolerance || value > hi + limits.range_tolerance {
        return Err(Implausible::OutOfRange);
    }
    Ok(())
}

impl Believed {
    /// Starts from the robot's first message, which must be plausible throughout: every
    /// position and stiffness of the 25 joints finite, the stiffnesses within 0 … 1, the
    /// measured joints within their range. Nothing can be commanded otherwise.
    pub fn start(limits: Plausibility, first: &SensorMessage) -> Result<Believed, ReadingFault> {
        for k in 0..JOINTS {
            let name = lola::JOINT_NAMES[k];
            let q = first.position[k] as f64;
            if !q.is_finite() {
                return Err(ReadingFault {
                    joint: name,
                    value: q,
                    why: Implausible::NotFinite,
                    repeated: false,
                });
            }
            let s = first.stiffness[k] as f64;
            if !(0.0..=1.0).contains(&s) {
                return Err(ReadingFault {
                    joint: name,
                    value: s,
                    why: Implausible::Stiffness,
                    repeated: false,
                });
            }
        }
        let believed = first.joints();
        for (j, value) in believed.iter() {
            if let Err(why) = in_range(&limits, j, value) {
                return Err(ReadingFault {
                    joint: j.name(),
                    value,
                    why,
                    repeated: false,
                });
            }
        }
        Ok(Believed {
            limits,
            believed,
            since: [0; JOINT_COUNT],
            glitch: [None; JOINT_COUNT],
            lost: [false; JOINT_COUNT],
            cycle: 0,
            all: true,
        })
    }

    /// Checks the next message's readings: plausible ones are believed, a glitch is
    /// ignored, and a repeated one is a fault (the first such joint; the joint is no longer
    /// believed: [`Believed::lost`]).
    pub fn check(&mut self, message: &SensorMessage) -> Option<ReadingFault> {
        self.cycle += 1;
        self.all = true;
        let mut fault = None;
        for (j, value) in message.joints().iter() {
            let k = j.index();
            let from = self.believed.get(j);
            let most = self.limits.max_step(j) * (self.since[k] + 1) as f64;
            let verdict = in_range(&self.limits, j, value).and_then(|()| {
                if (value - from).abs() > most {
                    Err(Implausible::Jump(from, most))
                } else {
                    Ok(())
                }
            });
            match verdict {
                Ok(()) if !self.lost[k] => {
                    self.believed.set(j, value);
                    self.since[k] = 0;
                }
                Ok(()) => self.all = false,
                Err(why) => {
                    self.all = false;
                    self.since[k] += 1;
                    let repeated = self.glitch[k]
                        .is_some_and(|c| self.cycle - c <= self.limits.glitch_cycles as u64);
                    self.glitch[k] = Some(self.cycle);
                    if repeated {
                        self.lost[k] = true;
                        fault.get_or_insert(ReadingFault {
                            joint: j.name(),
                            value,
                            why,
                            repeated,
                        });
                    }
                }
            }
        }
        fault
    }

    /// The believed readings: each joint's last plausible one.
    pub fn readings(&self) -> JointAngles {
        self.believed
    }

    /// Whether every reading of the last message was believed.
    pub fn all_believed(&self) -> bool {
        self.all
    }

    /// Whether `joint`'s readings are no longer believed (a fault).
    pub fn lost(&self, joint: Joint) -> bool {
        self.lost[joint.index()]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn message(knee: f32) -> SensorMessage {
        let mut m = SensorMessage {
            temperature: [40.0; JOINTS],
            current: [0.1; JOINTS],
            ..SensorMessage::on_back([0.0; JOINTS])
        };
        m.position[lola::index(Joint::LKneePitch)] = knee;
        m
    }

    #[test]
    fn a_first_message_must_be_plausible() {
        let p = Plausibility::default();
        assert!(Believed::start(p, &message(0.5)).is_ok());
        let e = Believed::start(p, &message(f32::NAN)).unwrap_err();
        assert_eq!((e.joint, e.why), ("LKneePitch", Implausible::NotFinite));
        let e = Believed::start(p, &message(3.0)).unwrap_err();
        assert_eq!(e.why, Implausible::OutOfRange);
        assert!(e.to_string().contains("171.9°"), "{e}");
        let mut arm = message(0.5);
        arm.position[3] = f32::INFINITY;
        assert_eq!(Believed::start(p, &arm).unwrap_err().joint, "LShoulderRoll");
        let mut stiff = message(0.5);
        stiff.stiffness[10] = 1.5;
        assert_eq!(
            Believed::start(p, &stiff).unwrap_err().why,
            Implausible::Stiffness
        );
    }

    #[test]
    fn one_glitch_is_ignored_and_a_second_is_a_fault() {
        let p = Plausibility::default();
        let mut b = Believed::start(p, &message(0.5)).unwrap();
        let knee = |b: &Believed| b.readings().get(Joint::LKneePitch);
        // A legal move: 0.07 rad in a cycle (the knee's motor: 0.077 + slack).
        assert!(b.check(&message(0.57)).is_none());
        assert!((knee(&b) - 0.57).abs() < 1e-6);
        // A 28.6° glitch: ignored, not followed.
        assert!(b.check(&message(1.07)).is_none());
        assert!(!b.all_believed());
        assert!((knee(&b) - 0.57).abs() < 1e-6);
        for _ in 0..p.glitch_cycles {
            assert!(b.check(&message(0.57)).is_none());
        }
        assert!(b.all_believed());
        // Another glitch long after: ignored too; then one more at once: a fault.
        assert!(b.check(&message(f32::NAN)).is_none());
        let e = b.check(&message(1.07)).unwrap();
        assert!(e.repeated && matches!(e.why, Implausible::Jump(..)), "{e}");
        assert!(b.lost(Joint::LKneePitch));
        // A lost joint is not believed again.
        assert!(b.check(&message(0.57)).is_none());
        assert!(!b.all_believed());
    }

    #[test]
    fn after_a_glitch_the_allowed_change_grows_with_the_cycles() {
        let p = Plausibility::default();
        let mut b = Believed::start(p, &message(0.5)).unwrap();
        assert!(b.check(&message(f32::NAN)).is_none());
        // Two cycles of the knee's motor: 0.154 rad + slack.
        assert!(b.check(&message(0.64)).is_none());
        assert!(b.all_believed());
    }
}
