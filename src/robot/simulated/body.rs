//! The simulated robot's body: its joints following their commands under stiffness, the
//! readings in encoder steps, the motors' currents and temperatures, how it lies, and the
//! sensor message LoLA would write of it.

use crate::model::{JointAngles, Model, Side, gravity};

use super::super::body;
use super::super::lola::{self, BATTERY_CHARGE, CHEST_BUTTON, JOINTS, SensorFrame, SensorMessage};
use super::{
    AMBIENT, ENCODER_NOISE_STEPS, ENCODER_STEP, FLAT, LAG_S, LOW_BATTERY, MAX_SPEED, ROLL_CYCLES,
    RobotOptions,
};

/// The body: joints, commands, temperatures.
pub(super) struct Body {
    pub(super) pos: [f64; JOINTS],
    pub(super) command: [f64; JOINTS],
    pub(super) stiffness: [f64; JOINTS],
    pub(super) temperature: [f64; JOINTS],
    pub(super) current: [f64; JOINTS],
    /// The blocked motor, its barrier and whether the barrier is above the start.
    block: Option<(usize, f64, bool)>,
    overheat: Option<usize>,
    pub(super) cycle: u64,
    /// This cycle's readings.
    readings: [f32; JOINTS],
    rng: rand_chacha::ChaCha8Rng,
}

impl Body {
    pub(super) fn new(options: &RobotOptions) -> Body {
        // Arms lying beside the body, as the robot is laid down.
        let pos = crate::robot::arms::put(
            lola::put([0.0; JOINTS], &options.start, |q| q),
            &crate::body::ArmPosture::BESIDE_BODY,
            |q| q,
        );
        let mut temperature: [f64; JOINTS] = std::array::from_fn(|k| 34.0 + (k % 5) as f64);
        let overheat = options.faults.overheat.map(lola::index);
        if let Some(k) = overheat {
            temperature[k] = 62.0;
        }
        let block = options.faults.block.map(|(j, b)| {
            let k = lola::index(j);
            (k, b, b > pos[k])
        });
        Body {
            pos,
            command: pos,
            stiffness: [0.0; JOINTS],
            temperature,
            current: [0.0; JOINTS],
            block,
            overheat,
            cycle: 0,
            readings: pos.map(|p| p as f32),
            rng: rand::SeedableRng::seed_from_u64(options.seed ^ 0x5eed),
        }
        .read()
    }

    /// Takes this cycle's readings: the joints with encoder noise, in encoder steps.
    fn read(mut self) -> Body {
        self.sample();
        self
    }

    fn sample(&mut self) {
        use rand_distr::Distribution;
        let noise = rand_distr::Normal::new(0.0, ENCODER_NOISE_STEPS).expect("valid σ");
        for k in 0..JOINTS {
            let steps = self.pos[k] / ENCODER_STEP + noise.sample(&mut self.rng);
            self.readings[k] = (steps.round() * ENCODER_STEP) as f32;
        }
    }

    pub(super) fn joints(&self) -> JointAngles {
        lola::to_joint_angles(&self.pos)
    }

    /// Where the arms are.
    pub(super) fn arms(&self) -> crate::body::ArmPosture {
        crate::body::ArmPosture(crate::robot::arms::indices().map(|k| self.pos[k]))
    }

    pub(super) fn reading(&self, k: usize) -> f32 {
        self.readings[k]
    }

    /// One cycle of 12 ms.
    pub(super) fn step(&mut self, model: &Model, motors: &[usize]) {
        let dt = lola::CYCLE_S;
        let mut speed = [0.0; JOINTS];
        for &k in motors {
            let s = self.stiffness[k].clamp(0.0, 1.0);
            if s <= 0.0 {
                continue;
            }
            let alpha = 1.0 - (-dt * s / LAG_S).exp();
            let step =
                ((self.command[k] - self.pos[k]) * alpha).clamp(-MAX_SPEED * dt, MAX_SPEED * dt);
            let mut next = self.pos[k] + step;
            if let Some((b, barrier, above)) = self.block
                && b == k
            {
                next = if above {
                    next.min(barrier)
                } else {
                    next.max(barrier)
                };
            }
            speed[k] = (next - self.pos[k]) / dt;
            self.pos[k] = next;
        }
        let joints = self.joints();
        let mut torque = [0.0; JOINTS];
        for side in Side::BOTH {
            // A leg lying flat rests on the floor: nothing to hold.
            if joints.get(side.leg_joints()[2]).abs() < FLAT {
                continue;
            }
            let t = gravity::leg_torques(&model.robot, &model.board, side, &joints);
            for (j, t) in side.leg_joints().iter().zip(t) {
                torque[lola::index(*j)] += t.abs();
            }
        }
        for &k in motors {
            let s = self.stiffness[k].clamp(0.0, 1.0);
            let blocked = matches!(self.block, Some((b, _, _)) if b == k)
                && (self.command[k] - self.pos[k]).abs() > 0.02;
            self.current[k] = if s > 0.0 {
                0.03 + 0.4 * torque[k] + 0.05 * speed[k].abs() + if blocked { 1.0 * s } else { 0.0 }
            } else {
                0.0
            };
            let rise = if self.overheat == Some(k) {
                // The faulty motor: 3 °C/s while it holds a load, cooling in 30 s.
                let heat = if s > 0.0 && torque[k] > 0.05 {
                    3.0
                } else {
                    0.0
                };
                heat - (self.temperature[k] - AMBIENT) / 30.0
            } else {
                // 0.05 °C/s per A², cooling in 300 s.
                0.05 * self.current[k].powi(2) - (self.temperature[k] - AMBIENT) / 300.0
            };
            self.temperature[k] += rise * dt;
        }
        self.cycle += 1;
        self.sample();
    }

    /// "Up" in the torso's frame now: as it lies, turning onto its right side from
    /// `roll_at` on.
    fn up(&self, options: &RobotOptions) -> [f64; 3] {
        let up = options.lying.up();
        let Some(at) = options.faults.roll_at.filter(|&at| self.cycle >= at) else {
            return up;
        };
        let phi =
            ((self.cycle - at) as f64 / ROLL_CYCLES as f64).min(1.0) * std::f64::consts::FRAC_PI_2;
        // Turned about the torso's long axis (z).
        let (s, c) = phi.sin_cos();
        [c * up[0] - s * up[1], s * up[0] + c * up[1], up[2]]
    }

    pub(super) fn frame(&self, options: &RobotOptions) -> SensorFrame {
        let after = |at: Option<u64>| at.is_some_and(|at| self.cycle >= at);
        let (accelerometer, angles) = body::imu(self.up(options));
        let mut battery = [options.battery, 0.0, -0.4, 30.0];
        if after(options.faults.low_battery_at) {
            battery[BATTERY_CHARGE] = LOW_BATTERY;
        }
        let mut touch = [0.0; 14];
        if after(options.faults.chest_at) {
            touch[CHEST_BUTTON] = 1.0;
        }
        let mut status = self.temperature.map(|t| {
            if t >= 85.0 {
                3
            } else if t >= 75.0 {
                2
            } else if t >= 70.0 {
                1
            } else {
                0
            }
        });
        if let Some((joint, value, at)) = options.faults.status_at
            && self.cycle >= at
            && options
                .faults
                .status_until
                .is_none_or(|end| self.cycle < end)
        {
            let k = lola::index(joint);
            status[k] = status[k].max(value);
        }
        SensorFrame {
            joints: SensorMessage {
                stiffness: self.stiffness.map(|s| s as f32),
                position: std::array::from_fn(|k| self.reading(k)),
                temperature: self.temperature.map(|t| t as f32),
                current: self.current.map(|c| c as f32),
                battery,
                accelerometer,
                angles,
                touch,
                status,
            },
            gyroscope: [0.0; 3],
            sonar: [2.5, 2.5],
            fsr: [0.0; 8],
            robot_config: [
                "P0000074A05S94700015".into(),
                "6.0.0".into(),
                "P0000073A07S9BA00035".into(),
                "6.0.0".into(),
            ],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Joint;
    use crate::robot::body::Lying;
    use crate::robot::simulated::motors;
    use crate::robot::simulated::tests::options;

    #[test]
    fn joints_follow_commands_under_stiffness_and_read_in_encoder_steps() {
        let o = options();
        let motors = motors();
        let mut body = Body::new(&o);
        let k = lola::index(Joint::LKneePitch);
        body.command[k] = 0.5;
        for _ in 0..50 {
            body.step(&o.model, &motors);
        }
        assert_eq!(body.pos[k], 0.0, "no stiffness, no motion");
        body.stiffness[k] = 1.0;
        for _ in 0..50 {
            body.step(&o.model, &motors);
        }
        assert!((body.pos[k] - 0.5).abs() < 1e-3, "{}", body.pos[k]);
        let mut sum = 0.0;
        for _ in 0..400 {
            body.step(&o.model, &motors);
            let r = body.reading(k) as f64;
            assert!((r / ENCODER_STEP - (r / ENCODER_STEP).round()).abs() < 1e-3);
            assert!((r - body.pos[k]).abs() <= 3.5 * ENCODER_STEP);
            sum += r;
        }
        // Dithered: the mean of the readings finds the joint between the steps.
        assert!((sum / 400.0 - body.pos[k]).abs() < 0.1 * ENCODER_STEP);
    }

    #[test]
    fn arms_lie_beside_the_body_and_follow_their_commands_like_the_legs() {
        use crate::body::ArmPosture;
        let o = options();
        let motors = motors();
        let mut body = Body::new(&o);
        assert_eq!(body.arms(), ArmPosture::BESIDE_BODY);
        let k = lola::index(Joint::LKneePitch);
        let shoulder = 18; // RShoulderPitch
        body.command[shoulder] = 0.0;
        for _ in 0..50 {
            body.step(&o.model, &motors);
        }
        assert_eq!(
            body.arms(),
            ArmPosture::BESIDE_BODY,
            "no stiffness, no motion"
        );
        body.stiffness[shoulder] = 1.0;
        body.stiffness[k] = 1.0;
        for _ in 0..100 {
            body.step(&o.model, &motors);
        }
        assert!(body.pos[shoulder].abs() < 1e-3, "{}", body.pos[shoulder]);
        assert!(
            body.arms().0[6] == ArmPosture::BESIDE_BODY.0[6],
            "the roll stays"
        );
    }

    #[test]
    fn a_blocked_joint_stops_at_its_barrier() {
        let mut o = options();
        o.faults.block = Some((Joint::LKneePitch, 0.3));
        let motors = motors();
        let mut body = Body::new(&o);
        let k = lola::index(Joint::LKneePitch);
        body.command[k] = 1.0;
        body.stiffness[k] = 1.0;
        for _ in 0..100 {
            body.step(&o.model, &motors);
        }
        assert_eq!(body.pos[k], 0.3);
        assert!(body.current[k] > 0.5);
    }

    #[test]
    fn the_imu_says_how_it_lies_and_rolls_over_when_told() {
        let limits = body::BodyLimits::default();
        let mut o = options();
        o.faults.roll_at = Some(5);
        o.faults.chest_at = Some(7);
        o.faults.status_at = Some((Joint::LAnkleRoll, 2, 6));
        o.faults.low_battery_at = Some(8);
        let motors = motors();
        let mut body = Body::new(&o);
        let lies = |b: &Body| body::lying(&limits, &b.frame(&o).joints);
        assert_eq!(lies(&body), Lying::OnBack);
        assert_eq!(body.frame(&o).joints.accelerometer, [-9.81, 0.0, 0.0]);
        for _ in 0..5 {
            body.step(&o.model, &motors);
        }
        let m = body.frame(&o).joints;
        assert_eq!(m.touch[CHEST_BUTTON], 0.0);
        assert_eq!(m.status[lola::index(Joint::LAnkleRoll)], 0);
        for _ in 0..ROLL_CYCLES {
            body.step(&o.model, &motors);
        }
        assert_eq!(lies(&body), Lying::OnRightSide);
        let m = body.frame(&o).joints;
        assert_eq!(m.touch[CHEST_BUTTON], 1.0);
        assert_eq!(m.status[lola::index(Joint::LAnkleRoll)], 2);
        assert_eq!(m.battery[BATTERY_CHARGE], LOW_BATTERY);
        for (l, _, _) in Lying::NAMED {
            let o = RobotOptions {
                lying: l,
                ..options()
            };
            assert_eq!(body::lying(&limits, &Body::new(&o).frame(&o).joints), l);
        }
    }

    #[test]
    fn the_robots_frame_is_a_v6_message() {
        let o = options();
        let body = Body::new(&o);
        assert_eq!(
            lola::encode(&body.frame(&o)).len(),
            lola::SENSOR_MESSAGE_BYTES
        );
    }
}
