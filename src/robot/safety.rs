//! Watching the motors: temperatures and currents that LoLA reports every cycle
//! (docs/CAPTURE.md §3).

use crate::model::Joint;

use super::body::{BodyLimits, worst_status};
use super::lola::{self, SensorMessage};
use super::plausible::Plausibility;

/// The limits on what the motors report.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SafetyLimits {
    /// At this temperature (°C) of a head or leg motor the legs go to rest and wait …
    pub pause_temperature: f64,
    /// … until every one is at or below this (°C) …
    pub resume_temperature: f64,
    /// … for at most this many cycles; then the run stops.
    pub max_pause_cycles: u32,
    /// At this temperature (°C) the run stops at once (rest, stiffness ramped down).
    pub stop_temperature: f64,
    /// A head or leg motor drawing more than this (A) …
    pub max_current: f64,
    /// … for this many cycles in a row stops the run.
    pub current_cycles: u32,
    /// A message that does not come within this many cycles stops the run.
    pub silent_cycles: u32,
    /// Which joint readings are believed ([`super::plausible`]).
    pub readings: Plausibility,
    /// How the robot lies, its chest button, its motors' status, its battery
    /// ([`super::body`]).
    pub body: BodyLimits,
}

impl Default for SafetyLimits {
    /// Pause at 70 °C until 60 °C (at most 10 minutes), stop at 80 °C (the V6 reports
    /// temperature status 1 "hot" from about 70 °C and cuts motor power near 90 °C),
    /// stop on more than 2.5 A for 50 cycles (0.6 s: a stalled motor, the leg pushing
    /// against something), and on 25 cycles (0.3 s) without a message; readings as
    /// [`Plausibility::default`], the robot as a whole as [`BodyLimits::default`].
    fn default() -> Self {
        SafetyLimits {
            pause_temperature: 70.0,
            resume_temperature: 60.0,
            max_pause_cycles: 50_000,
            stop_temperature: 80.0,
            max_current: 2.5,
            current_cycles: 50,
            silent_cycles: 25,
            readings: Plausibility::default(),
            body: BodyLimits::default(),
        }
    }
}

/// What the watch concludes from one message, the motor named by `M`: the head's or a
/// leg's [`Joint`], or a LoLA index for the arms.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Verdict<M = Joint> {
    /// Everything within the limits.
    Fine,
    /// A motor is hot: pause at rest until it cools (the motor, °C).
    Hot(M, f64),
    /// A motor's status says the firmware starts reducing its stiffness (status 1, nao_lola
    /// `JointStatuses.msg` line 3): pause at rest until it is 0 (the motor, its status, its
    /// temperature in °C, which may well be low).
    Status(M, i32, f64),
    /// Stop the run: too hot (the motor, °C).
    Overheated(M, f64),
    /// Stop the run: a motor drew too much current for too long (the motor, A).
    Overcurrent(M, f64),
    /// Stop the run: a motor's temperature or current is not a number, so the limits
    /// above cannot be checked (the motor, `temperature` or `current`, the value).
    Unreadable(M, &'static str, f64),
}

impl<M: Copy> Verdict<M> {
    /// The verdict with its motor renamed by `f`.
    pub fn map<N>(self, f: impl Fn(M) -> N) -> Verdict<N> {
        match self {
            Verdict::Fine => Verdict::Fine,
            Verdict::Hot(m, t) => Verdict::Hot(f(m), t),
            Verdict::Status(m, s, t) => Verdict::Status(f(m), s, t),
            Verdict::Overheated(m, t) => Verdict::Overheated(f(m), t),
            Verdict::Overcurrent(m, a) => Verdict::Overcurrent(f(m), a),
            Verdict::Unreadable(m, what, v) => Verdict::Unreadable(f(m), what, v),
        }
    }

    /// Why the run stops, the motor named by `name`, or `None` when the verdict does not
    /// stop it (fine, or a pause).
    pub fn stops(&self, limits: &SafetyLimits, name: impl Fn(M) -> String) -> Option<String> {
        match *self {
            Verdict::Overheated(m, t) => Some(format!(
                "{} reached {t:.1} °C (limit {:.0} °C)",
                name(m),
                limits.stop_temperature
            )),
            Verdict::Overcurrent(m, a) => Some(format!(
                "{} drew {a:.2} A for {} cycles (limit {:.2} A)",
                name(m),
                limits.current_cycles,
                limits.max_current
            )),
            Verdict::Unreadable(m, what, value) => Some(format!(
                "{} reports a {what} of {value}: its limits cannot be watched",
                name(m)
            )),
            Verdict::Fine | Verdict::Hot(..) | Verdict::Status(..) => None,
        }
    }
}

/// The motor watch, one message per cycle.
#[derive(Debug, Clone, Default)]
pub struct Watch {
    over_current: u32,
}

impl SafetyLimits {
    /// Checks the limits' order; the message names the limit.
    pub fn validate(&self) -> Result<(), String> {
        if !(self.resume_temperature < self.pause_temperature
            && self.pause_temperature <= self.stop_temperature)
        {
            return Err("temperatures must be resume < pause ≤ stop".into());
        }
        if self.max_current.is_nan()
            || self.max_current <= 0.0
            || self.current_cycles == 0
            || self.silent_cycles == 0
        {
            return Err("the current limit and the cycle counts must be above 0".into());
        }
        let r = &self.readings;
        if !(r.range_tolerance >= 0.0 && r.jump_slack >= 0.0) {
            return Err("the readings' range tolerance and jump slack must be at least 0".into());
        }
        self.body.validate()
    }

    /// Whether the head and leg motors are cool enough to go on: every one at or below the
    /// resume temperature, none with a status above 0.
    pub fn cooled(&self, message: &SensorMessage) -> bool {
        SafetyLimits::hottest(message).1 <= self.resume_temperature && worst_status(message).1 < 1
    }

    /// The hottest head or leg motor and its temperature (°C).
    pub fn hottest(message: &SensorMessage) -> (Joint, f64) {
        lola::to_joint_angles(&message.temperature).iter().fold(
            (Joint::HeadYaw, f64::NEG_INFINITY),
            |a, b| {
                if b.1 > a.1 { b } else { a }
            },
        )
    }
}

impl Watch {
    /// Checks one message's head and leg motors against `limits`.
    pub fn check(&mut self, limits: &SafetyLimits, message: &SensorMessage) -> Verdict {
        let motors = Joint::ALL.map(lola::index);
        self.check_motors(limits, message, &motors).map(|k| {
            Joint::ALL
                .into_iter()
                .find(|&j| lola::index(j) == k)
                .expect("a head or leg motor")
        })
    }

    /// Checks one message's `motors` (LoLA indices) against `limits`: a reading that is not
    /// a number, then the hottest, a current over the limit for its cycles, a motor hot
    /// enough to pause, the worst status.
    pub fn check_motors(
        &mut self,
        limits: &SafetyLimits,
        message: &SensorMessage,
        motors: &[usize],
    ) -> Verdict<usize> {
        if motors.is_empty() {
            return Verdict::Fine;
        }
        let reading = |values: &[f32; lola::JOINTS], k: usize| f64::from(values[k]);
        for &k in motors {
            for (what, values) in [
                ("temperature", &message.temperature),
                ("current", &message.current),
            ] {
                let value = reading(values, k);
                if !value.is_finite() {
                    return Verdict::Unreadable(k, what, value);
                }
            }
        }
        let most = |value: &dyn Fn(usize) -> f64| {
            motors
                .iter()
                .map(|&k| (k, value(k)))
                .fold((motors[0], f64::NEG_INFINITY), |a, b| {
                    if b.1 > a.1 { b } else { a }
                })
        };
        let (hottest, temperature) = most(&|k| reading(&message.temperature, k));
        if temperature >= limits.stop_temperature {
            return Verdict::Overheated(hottest, temperature);
        }
        let (pulling, current) = most(&|k| reading(&message.current, k).abs());
        if current > limits.max_current {
            self.over_current += 1;
            if self.over_current >= limits.current_cycles {
                return Verdict::Overcurrent(pulling, current);
            }
        } else {
            self.over_current = 0;
        }
        if temperature >= limits.pause_temperature {
            return Verdict::Hot(hottest, temperature);
        }
        let (worst, status) = most(&|k| f64::from(message.status[k]));
        if status >= 1.0 {
            return Verdict::Status(worst, status as i32, reading(&message.temperature, worst));
        }
        Verdict::Fine
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::lola::JOINTS;

    fn message(temperature: f32, current: f32) -> SensorMessage {
        SensorMessage {
            temperature: [40.0; JOINTS],
            current: [0.1; JOINTS],
            ..SensorMessage::on_back([0.0; JOINTS])
        }
        .with(10, temperature, current)
    }

    impl SensorMessage {
        fn with(mut self, k: usize, temperature: f32, current: f32) -> Self {
            self.temperature[k] = temperature;
            self.current[k] = current;
            self
        }
    }

    #[test]
    fn temperatures_pause_then_stop() {
        let limits = SafetyLimits::default();
        let mut w = Watch::default();
        assert_eq!(w.check(&limits, &message(50.0, 0.1)), Verdict::Fine);
        assert_eq!(
            w.check(&limits, &message(72.0, 0.1)),
            Verdict::Hot(Joint::LKneePitch, 72.0)
        );
        assert_eq!(
            w.check(&limits, &message(81.0, 0.1)),
            Verdict::Overheated(Joint::LKneePitch, 81.0)
        );
        // An arm's temperature is not watched (its stiffness stays 0).
        let arm = message(40.0, 0.1).with(3, 95.0, 0.1);
        assert_eq!(w.check(&limits, &arm), Verdict::Fine);
    }

    #[test]
    fn a_status_of_1_rests_as_when_hot_until_it_clears() {
        let limits = SafetyLimits::default();
        let mut w = Watch::default();
        let mut m = message(50.0, 0.1);
        m.status[lola::index(Joint::RHipPitch)] = 1;
        assert_eq!(
            w.check(&limits, &m),
            Verdict::Status(Joint::RHipPitch, 1, 40.0)
        );
        let mut cool = message(40.0, 0.1);
        assert!(limits.cooled(&cool));
        cool.status[lola::index(Joint::RHipPitch)] = 1;
        assert!(!limits.cooled(&cool), "cool but still reported hot");
        // An arm's status is not watched.
        let mut arm = message(40.0, 0.1);
        arm.status[3] = 1;
        assert_eq!(w.check(&limits, &arm), Verdict::Fine);
        assert!(limits.cooled(&arm));
    }

    #[test]
    fn a_temperature_or_current_that_is_not_a_number_stops_at_once() {
        let limits = SafetyLimits::default();
        let mut w = Watch::default();
        assert!(matches!(
            w.check(&limits, &message(f32::NAN, 0.1)),
            Verdict::Unreadable(Joint::LKneePitch, "temperature", t) if t.is_nan()
        ));
        assert!(matches!(
            w.check(&limits, &message(40.0, f32::INFINITY)),
            Verdict::Unreadable(Joint::LKneePitch, "current", _)
        ));
        // Arms are not watched.
        let arm = message(40.0, 0.1).with(3, f32::NAN, f32::NAN);
        assert_eq!(w.check(&limits, &arm), Verdict::Fine);
    }

    #[test]
    fn currents_stop_only_when_they_last() {
        let limits = SafetyLimits::default();
        let mut w = Watch::default();
        for _ in 0..limits.current_cycles - 1 {
            assert_eq!(w.check(&limits, &message(40.0, 3.0)), Verdict::Fine);
        }
        assert_eq!(w.check(&limits, &message(40.0, 0.5)), Verdict::Fine);
        for _ in 0..limits.current_cycles - 1 {
            assert_eq!(w.check(&limits, &message(40.0, 3.0)), Verdict::Fine);
        }
        assert!(matches!(
            w.check(&limits, &message(40.0, 3.0)),
            Verdict::Overcurrent(Joint::LKneePitch, _)
        ));
    }
}
