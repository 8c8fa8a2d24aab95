//! Moving safely, counted in LoLA cycles: stiffness ramps, bounded-speed interpolation,
//! settling and obstruction detection (docs/CAPTURE.md).

use crate::body::ArmPosture;
use crate::model::{Joint, JointAngles};

use super::lola::CYCLE_S;

/// How the robot is moved and when a stance counts as reached (docs/CAPTURE.md §2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotionOptions {
    /// Leg joint speed limit (rad/s); the plan's timing assumes the same.
    pub leg_speed: f64,
    /// Head joint speed limit (rad/s).
    pub head_speed: f64,
    /// Arm joint speed limit (rad/s): the arms' way to capture's posture and back.
    pub arm_speed: f64,
    /// Stiffness of the head and leg joints while measuring (0 … 1).
    pub stiffness: f64,
    /// Cycles of a stiffness ramp up or down (at least 84, i.e. 1 s).
    pub ramp_cycles: u32,
    /// A stance is reached when, over the last [`MotionOptions::settle_cycles`] readings,
    /// no joint's readings spread (max − min) more than this (rad) …
    pub settle_threshold: f64,
    /// … over this many cycles (at least 25, i.e. 0.3 s) …
    pub settle_cycles: u32,
    /// … within this many cycles after the commanded motion ended; else it is skipped.
    pub settle_timeout_cycles: u32,
    /// A joint farther than this from its command (rad) …
    pub obstruction: f64,
    /// … for this many cycles in a row is obstructed: the stance is skipped.
    pub obstruction_cycles: u32,
    /// Cycles between the trigger of the picture and the readings that belong to it (the
    /// sensor lag of LoLA's readings behind the joints).
    pub sensor_lag_cycles: u32,
    /// Fewest readings averaged into a capture's joint angles.
    pub window_cycles: u32,
}

impl Default for MotionOptions {
    /// Legs 30°/s, head 90°/s (as the plan's timing), arms 30°/s (the 180° of
    /// ShoulderPitch from beside the body to beyond the head in 6 s), stiffness 0.8, ramps of 100 cycles
    /// (1.2 s), settled when no joint's readings spread more than 0.3° (3 encoder steps:
    /// the readings of a joint at rest flicker by a step) over 30 cycles
    /// (0.36 s) within 250 cycles (3 s), obstructed when a joint stays more than 4° from
    /// its command for 25 cycles (0.3 s), readings taken 2 cycles behind the picture, at
    /// least 10 of them.
    fn default() -> Self {
        MotionOptions {
            leg_speed: 30f64.to_radians(),
            head_speed: 90f64.to_radians(),
            arm_speed: 30f64.to_radians(),
            stiffness: 0.8,
            ramp_cycles: 100,
            settle_threshold: 0.3f64.to_radians(),
            settle_cycles: 30,
            settle_timeout_cycles: 250,
            obstruction: 4f64.to_radians(),
            obstruction_cycles: 25,
            sensor_lag_cycles: 2,
            window_cycles: 10,
        }
    }
}

/// Fewest cycles of a stiffness ramp: 1 s of 12 ms cycles, rounded up.
pub const MIN_RAMP_CYCLES: u32 = 84;
/// Fewest cycles of the settling window: 0.3 s of 12 ms cycles, rounded up.
pub const MIN_SETTLE_CYCLES: u32 = 25;

impl MotionOptions {
    /// Checks the options against the safety rules; the message names the option.
    pub fn validate(&self) -> Result<(), String> {
        let speed = |v: f64, name: &str, max_deg: f64| {
            if v.is_finite() && v > 0.0 && v <= max_deg.to_radians() {
                Ok(())
            } else {
                Err(format!(
                    "{name} must be above 0 and at most {max_deg}°/s, got {:.1}°/s",
                    v.to_degrees()
                ))
            }
        };
        speed(self.leg_speed, "the leg speed", 60.0)?;
        speed(self.head_speed, "the head speed", 180.0)?;
        speed(self.arm_speed, "the arm speed", 60.0)?;
        if !(self.stiffness > 0.0 && self.stiffness <= 1.0) {
            return Err(format!(
                "the stiffness must be above 0 and at most 1, got {}",
                self.stiffness
            ));
        }
        if self.ramp_cycles < MIN_RAMP_CYCLES {
            return Err(format!(
                "a stiffness ramp must last at least {MIN_RAMP_CYCLES} cycles (1 s)"
            ));
        }
        if self.settle_cycles < MIN_SETTLE_CYCLES {
            return Err(format!(
                "the settling window must last at least {MIN_SETTLE_CYCLES} cycles (0.3 s)"
            ));
        }
        if !(self.settle_threshold > 0.0 && self.obstruction > self.settle_threshold) {
            return Err("the settling threshold must be above 0 and below the obstruction".into());
        }
        if self.window_cycles == 0 || self.obstruction_cycles == 0 {
            return Err("the reading window and obstruction cycles must be at least 1".into());
        }
        Ok(())
    }

    /// The speed limit of `joint` (rad/s).
    pub fn speed(&self, joint: Joint) -> f64 {
        if joint.leg_index().is_some() {
            self.leg_speed
        } else {
            self.head_speed
        }
    }

    /// The commanded positions of a move from `from` to `to`, one per cycle, ending at
    /// `to`: all joints interpolated together, each stepping at most its speed limit per
    /// cycle.
    pub fn path(&self, from: &JointAngles, to: &JointAngles) -> Vec<JointAngles> {
        let steps = bounded_steps((*to - *from).iter().map(|(j, d)| (d, self.speed(j))));
        interpolate(steps, to, |t| from.lerp(to, t))
    }

    /// The commanded arm postures of a move of the arms from `from` to `to`, one per
    /// cycle, ending at `to`: as [`MotionOptions::path`], every arm joint at most
    /// [`MotionOptions::arm_speed`].
    pub fn arm_path(&self, from: &ArmPosture, to: &ArmPosture) -> Vec<ArmPosture> {
        let steps = bounded_steps(
            from.0
                .iter()
                .zip(to.0)
                .map(|(a, b)| (b - a, self.arm_speed)),
        );
        interpolate(steps, to, |t| {
            ArmPosture(std::array::from_fn(|k| {
                from.0[k] + t * (to.0[k] - from.0[k])
            }))
        })
    }

    /// The stiffness in cycle `k` (0-based) of a ramp from `from` to `to` (cycle 0 is
    /// `from`; `to` from cycle [`MotionOptions::ramp_cycles`] on).
    pub fn ramp(&self, from: f64, to: f64, k: u32) -> f64 {
        from + (to - from) * (k.min(self.ramp_cycles) as f64 / self.ramp_cycles as f64)
    }

    /// The stiffness in cycle `k` (0-based) of a ramp down from `from` to 0.
    pub fn ramp_down(&self, from: f64, k: u32) -> f64 {
        from * (1.0 - (k + 1).min(self.ramp_cycles) as f64 / self.ramp_cycles as f64)
    }
}

/// The cycles of a move whose joints each go `delta` (rad) at most `speed` (rad/s): the
/// slowest joint's, rounded up.
fn bounded_steps(moves: impl Iterator<Item = (f64, f64)>) -> usize {
    moves
        .map(|(delta, speed)| (delta.abs() / (speed * CYCLE_S)).ceil())
        .fold(0.0, f64::max) as usize
}

/// `steps` postures, the `k`th `at(k / steps)`, the last exactly `to`.
fn interpolate<T: Copy>(steps: usize, to: &T, at: impl Fn(f64) -> T) -> Vec<T> {
    (1..=steps)
        .map(|k| {
            if k == steps {
                *to
            } else {
                at(k as f64 / steps as f64)
            }
        })
        .collect()
}

/// Watches the readings of a stance: settled (steady over a window), obstructed (a joint
/// far from its command for a while).
#[derive(Debug, Clone)]
pub struct Settle {
    window: std::collections::VecDeque<JointAngles>,
    far_cycles: u32,
    far_joint: Option<Joint>,
}

/// What [`Settle::push`] concludes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SettleState {
    /// Still moving or not yet long enough steady.
    Moving,
    /// Steady over the window and near the command.
    Settled,
    /// A joint has stayed far from its command: it, and how far (rad).
    Obstructed(Joint, f64),
}

impl Default for Settle {
    fn default() -> Self {
        Self::new()
    }
}

impl Settle {
    /// A fresh watch (at the start of a move).
    pub fn new() -> Self {
        Settle {
            window: std::collections::VecDeque::new(),
            far_cycles: 0,
            far_joint: None,
        }
    }

    /// Adds one cycle's `reading` under the `command` of that cycle.
    pub fn push(
        &mut self,
        options: &MotionOptions,
        command: &JointAngles,
        reading: &JointAngles,
    ) -> SettleState {
        let (worst, gap) = (*reading - *command)
            .iter()
            .map(|(j, d)| (j, d.abs()))
            .fold((Joint::HeadYaw, 0.0), |a, b| if b.1 > a.1 { b } else { a });
        if gap > options.obstruction {
            self.far_cycles += 1;
            self.far_joint = Some(worst);
            if self.far_cycles >= options.obstruction_cycles {
                return SettleState::Obstructed(worst, gap);
            }
        } else {
            self.far_cycles = 0;
            self.far_joint = None;
        }
        self.window.push_back(*reading);
        if self.window.len() > options.settle_cycles as usize {
            self.window.pop_front();
        }
        if self.window.len() < options.settle_cycles as usize || self.far_cycles > 0 {
            return SettleState::Moving;
        }
        let lo = (self.window.iter()).fold(JointAngles::fill(f64::INFINITY), |lo, r| {
            lo.zip_with(r, f64::min)
        });
        let hi = (self.window.iter()).fold(JointAngles::fill(f64::NEG_INFINITY), |hi, r| {
            hi.zip_with(r, f64::max)
        });
        let steady = (hi - lo)
            .iter()
            .all(|(_, spread)| spread <= options.settle_threshold);
        if steady {
            SettleState::Settled
        } else {
            SettleState::Moving
        }
    }

    /// The joint that is far from its command now, if any.
    pub fn far_joint(&self) -> Option<Joint> {
        self.far_joint
    }
}

/// Running mean and spread of the readings of a capture (Welford).
#[derive(Debug, Clone, Default)]
pub struct Readings {
    count: u32,
    mean: JointAngles,
    /// Sum of squared deviations from the mean, of every joint.
    m2: JointAngles,
}

impl Readings {
    /// Adds one cycle's readings.
    pub fn push(&mut self, reading: &JointAngles) {
        self.count += 1;
        let n = self.count as f64;
        let d = *reading - self.mean;
        self.mean = self.mean.zip_with(&d, |mean, d| mean + d / n);
        let d_after = *reading - self.mean;
        self.m2 = self.m2 + d.zip_with(&d_after, |d, e| d * e);
    }

    /// Readings added.
    pub fn count(&self) -> u32 {
        self.count
    }

    /// The mean of every joint (rad).
    pub fn mean(&self) -> JointAngles {
        self.mean
    }

    /// The largest standard deviation of a joint's readings (rad).
    pub fn spread(&self) -> f64 {
        if self.count < 2 {
            return 0.0;
        }
        self.m2
            .iter()
            .map(|(_, m)| (m / (self.count - 1) as f64).sqrt())
            .fold(0.0, f64::max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_keep_to_the_speed_limits_and_end_at_the_target() {
        let o = MotionOptions::default();
        let from = JointAngles::default();
        let mut to = JointAngles::default();
        to.set(Joint::LKneePitch, 1.2);
        to.set(Joint::HeadYaw, -0.9);
        to.set(Joint::RAnklePitch, 0.3);
        let path = o.path(&from, &to);
        assert_eq!(*path.last().unwrap(), to);
        // 1.2 rad at 30°/s: 2.29 s, 191 cycles.
        assert_eq!(path.len(), 191);
        let mut prev = from;
        for p in &path {
            for j in Joint::ALL {
                let step = (p.get(j) - prev.get(j)).abs();
                assert!(step <= o.speed(j) * CYCLE_S * (1.0 + 1e-9), "{j:?} {step}");
            }
            prev = *p;
        }
        assert!(o.path(&to, &to).is_empty());
    }

    #[test]
    fn arm_paths_keep_to_the_arm_speed_and_end_at_the_target() {
        let o = MotionOptions::default();
        let (from, to) = (ArmPosture::BESIDE_BODY, ArmPosture::CAPTURE);
        let path = o.arm_path(&from, &to);
        assert_eq!(*path.last().unwrap(), to);
        // ShoulderPitch turns by 180° at 30°/s: 6 s, 500 cycles (501 by rounding).
        assert!((500..=501).contains(&path.len()), "{}", path.len());
        let mut prev = from;
        for p in &path {
            for k in 0..10 {
                let step = (p.0[k] - prev.0[k]).abs();
                assert!(step <= o.arm_speed * CYCLE_S * (1.0 + 1e-9), "{k} {step}");
            }
            prev = *p;
        }
        assert!(o.arm_path(&to, &to).is_empty());
        let fast = MotionOptions {
            arm_speed: 90f64.to_radians(),
            ..o
        };
        assert!(fast.validate().unwrap_err().starts_with("the arm speed"));
    }

    #[test]
    fn ramps_take_their_cycles() {
        let o = MotionOptions::default();
        assert_eq!(o.ramp(0.0, o.stiffness, 0), 0.0);
        assert_eq!(o.ramp(0.0, o.stiffness, o.ramp_cycles), o.stiffness);
        assert_eq!(o.ramp(1.0, o.stiffness, 0), 1.0);
        assert!((o.ramp(1.0, 0.8, o.ramp_cycles / 2) - 0.9).abs() < 1e-12);
        assert_eq!(o.ramp_down(0.8, o.ramp_cycles - 1), 0.0);
        assert!(o.ramp_down(0.8, 0) > 0.79);
        assert!(o.validate().is_ok());
        let short = MotionOptions {
            ramp_cycles: 50,
            ..o
        };
        assert!(short.validate().unwrap_err().contains("1 s"));
    }

    #[test]
    fn settling_needs_a_steady_window_and_obstruction_a_persistent_gap() {
        let o = MotionOptions::default();
        let command = JointAngles::default();
        let mut s = Settle::new();
        let mut reading = JointAngles::default();
        for k in 0..o.settle_cycles - 1 {
            reading.set(Joint::LHipPitch, 0.001 * (k % 2) as f64);
            assert_eq!(s.push(&o, &command, &reading), SettleState::Moving);
        }
        assert_eq!(s.push(&o, &command, &reading), SettleState::Settled);
        let mut s = Settle::new();
        reading.set(Joint::LKneePitch, 0.2);
        let states: Vec<_> = (0..o.obstruction_cycles)
            .map(|_| s.push(&o, &command, &reading))
            .collect();
        assert!(
            states[..states.len() - 1]
                .iter()
                .all(|x| *x == SettleState::Moving)
        );
        assert!(matches!(
            states.last().unwrap(),
            SettleState::Obstructed(Joint::LKneePitch, _)
        ));
    }

    #[test]
    fn readings_give_mean_and_spread() {
        let mut r = Readings::default();
        for x in [0.1, 0.3] {
            let mut a = JointAngles::default();
            a.set(Joint::HeadPitch, x);
            r.push(&a);
        }
        assert!((r.mean().get(Joint::HeadPitch) - 0.2).abs() < 1e-12);
        assert!((r.spread() - 0.02f64.sqrt()).abs() < 1e-12);
    }
}
