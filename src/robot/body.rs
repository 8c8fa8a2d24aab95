//! The robot as a whole, as LoLA reports it: how it lies (the IMU), its chest button, its
//! motors' temperature status and its battery — what a capture run checks before anything
//! moves and watches every cycle after ([`BodyWatch`]).
//!
//! How a robot lies is told from the accelerometer (conventions in
//! [`super::lola::SensorMessage`]): the direction "up" in the torso's frame is the negated
//! reading, and the robot lies as the torso axis nearest to it says, when within
//! [`BodyLimits::facing`] m/s² of it — HULKs' rule and threshold (`fall_state_estimation.rs`
//! lines 110–146: `FacingUp` when the negated reading is within
//! `gravitational_acceleration_threshold` of (g, 0, 0); `etc/parameters/default.json` line
//! 782: 7.0), after HULKs' low-pass filter of the accelerometer (`default.json` line 779,
//! `linear_acceleration_low_pass_factor` 0.05). `Angles` must agree: the torso pitched
//! back by more than 60°, NaoTH's "lying on back" (`BodyStateProvider.cpp` lines 100–101,
//! `avg.y < -getup_threshold` over LoLA's `Angles`; `getup_threshold=60` in
//! `Config/scheme/NaoTHLabor/BodyStateParameters.cfg` line 3, the scheme `scheme.cfg`
//! selects; NaoTH 79e1e750).

use crate::model::Joint;

use super::lola::{self, BATTERY_CHARGE, CHEST_BUTTON, SensorMessage};

/// Gravity (m/s²).
pub const G: f64 = 9.81;

/// How the robot lies: the torso axis that points up.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Lying {
    /// On its back, face up (the torso's x axis up): where a capture runs.
    OnBack,
    /// On its front, face down.
    OnFront,
    /// On its left side (its right side up).
    OnLeftSide,
    /// On its right side (its left side up).
    OnRightSide,
    /// Upright: standing, sitting or held.
    Upright,
    /// Upside down.
    UpsideDown,
    /// None of these: tilted in between, or moving.
    Tilted,
}

impl Lying {
    /// How a robot lies whose torso sees "up" along `up` (m/s², the negated accelerometer):
    /// the torso axis within `facing` m/s² of `up`, scaled to g.
    pub fn of(up: [f64; 3], facing: f64) -> Lying {
        let axes = [
            ([G, 0.0, 0.0], Lying::OnBack),
            ([-G, 0.0, 0.0], Lying::OnFront),
            ([0.0, -G, 0.0], Lying::OnLeftSide),
            ([0.0, G, 0.0], Lying::OnRightSide),
            ([0.0, 0.0, G], Lying::Upright),
            ([0.0, 0.0, -G], Lying::UpsideDown),
        ];
        axes.into_iter()
            .find(|(axis, _)| distance(*axis, up) < facing)
            .map_or(Lying::Tilted, |(_, lying)| lying)
    }

    /// The ways a robot can lie, each with its name (`--lying` of `simulate-robot`) and the
    /// unit vector "up" in its torso's frame.
    pub const NAMED: [(Lying, &'static str, [f64; 3]); 7] = [
        (Lying::OnBack, "back", [1.0, 0.0, 0.0]),
        (Lying::OnFront, "front", [-1.0, 0.0, 0.0]),
        (Lying::OnLeftSide, "left-side", [0.0, -1.0, 0.0]),
        (Lying::OnRightSide, "right-side", [0.0, 1.0, 0.0]),
        (Lying::Upright, "standing", [0.0, 0.0, 1.0]),
        (Lying::UpsideDown, "upside-down", [0.0, 0.0, -1.0]),
        (
            Lying::Tilted,
            "tilted",
            [
                std::f64::consts::FRAC_1_SQRT_2,
                std::f64::consts::FRAC_1_SQRT_2,
                0.0,
            ],
        ),
    ];

    /// The way of lying named `name` ([`Lying::NAMED`]).
    pub fn from_name(name: &str) -> Option<Lying> {
        Lying::NAMED
            .iter()
            .find(|(_, n, _)| *n == name)
            .map(|(l, _, _)| *l)
    }

    /// Its name ([`Lying::NAMED`]).
    pub fn name(self) -> &'static str {
        Lying::NAMED
            .iter()
            .find(|(l, _, _)| *l == self)
            .map_or("", |(_, n, _)| n)
    }

    /// "Up" in the torso's frame, a unit vector ([`Lying::NAMED`]).
    pub fn up(self) -> [f64; 3] {
        Lying::NAMED
            .iter()
            .find(|(l, _, _)| *l == self)
            .map_or([1.0, 0.0, 0.0], |(_, _, u)| *u)
    }

    /// In words, for messages.
    pub fn words(self) -> &'static str {
        match self {
            Lying::OnBack => "on its back",
            Lying::OnFront => "on its front",
            Lying::OnLeftSide => "on its left side",
            Lying::OnRightSide => "on its right side",
            Lying::Upright => "upright",
            Lying::UpsideDown => "upside down",
            Lying::Tilted => "tilted, neither on its back nor on a side",
        }
    }
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt()
}

/// The angle (rad) between two directions.
fn angle(a: [f64; 3], b: [f64; 3]) -> f64 {
    let dot: f64 = (0..3).map(|k| a[k] * b[k]).sum();
    let norm = |v: [f64; 3]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    (dot / (norm(a) * norm(b))).clamp(-1.0, 1.0).acos()
}

/// What LoLA reports of a torso that sees "up" along the unit vector `up`: the
/// accelerometer (gravity itself, −g·up) and the angles (roll, pitch; pitch positive
/// leaning forward), as in [`super::lola::SensorMessage`].
pub fn imu(up: [f64; 3]) -> ([f32; 3], [f32; 2]) {
    let acc = up.map(|u| (-G * u) as f32);
    let roll = up[1].atan2(up[2]);
    let pitch = (-up[0]).atan2(up[1].hypot(up[2]));
    (acc, [roll as f32, pitch as f32])
}

/// "Up" in the torso's frame (m/s²): the negated accelerometer of `message`.
pub fn up(message: &SensorMessage) -> [f64; 3] {
    message.accelerometer.map(|a| -(a as f64))
}

/// What the robot as a whole may report before a run starts and while it goes on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyLimits {
    /// The robot lies on its back when "up" is within this (m/s²) of the torso's x axis
    /// scaled to g (HULKs' 7.0: about 42°).
    pub facing: f64,
    /// Smoothing of the accelerometer, each cycle's share (HULKs' 0.05).
    pub low_pass: f64,
    /// The torso may turn this far (rad) from how it lay at the start; farther, the robot
    /// rolled over and the run stops.
    pub max_turn: f64,
    /// `Angles`' pitch (rad) must be below this to agree that the torso lies back
    /// (NaoTH's −60°).
    pub max_pitch: f64,
    /// The chest button stops the run when pressed in this many cycles in a row.
    pub chest_cycles: u32,
    /// A head or leg motor's status at or above this stops the run (the firmware has cut
    /// its stiffness by over 30 %); status 1 rests the legs as when hot.
    pub stop_status: i32,
    /// Below this charge (0 … 1) a run does not start, and one under way stops.
    pub min_battery: f64,
}

impl Default for BodyLimits {
    /// HULKs' facing threshold (7 m/s²) and filter (0.05); a turn of 20° (lying on its
    /// back the torso rocks by a few degrees as the legs move; rolling onto a side turns
    /// it by 90°; naocalib's own: no team code watches a robot lying still for a turn, the
    /// nearest thresholds being NaoTH's 60° for lying on a side and B-Human's 55° to tell
    /// how a fallen robot lies, `fallDownStateProvider.cfg` line 18); `Angles` pitched back
    /// by more than 60° (NaoTH's `getup_threshold`); the chest button held 3 cycles
    /// (36 ms: nothing else uses it during a capture; B-Human `NaoProvider.cpp` lines
    /// 325–331 and NaoTH `LolaAdaptor.cpp` lines 159–168 shut down after 3 s, as the
    /// button has other uses in a game); status 2 (nao_lola `JointStatuses.msg`: "stiffness
    /// reduced over 30%"); battery 5 % (B-Human `robotHealthProvider.cfg` line 1,
    /// `batteryLow = 5`, the level at which it warns "Low battery",
    /// `RobotHealthProvider.cpp` lines 86–91).
    fn default() -> Self {
        BodyLimits {
            facing: 7.0,
            low_pass: 0.05,
            max_turn: 20f64.to_radians(),
            max_pitch: -60f64.to_radians(),
            chest_cycles: 3,
            stop_status: 2,
            min_battery: 0.05,
        }
    }
}

impl BodyLimits {
    /// Checks the limits; the message names the limit.
    pub fn validate(&self) -> Result<(), String> {
        if !(self.facing > 0.0 && self.facing < G) {
            return Err("the facing threshold must be above 0 and below g".into());
        }
        if !(self.low_pass > 0.0 && self.low_pass <= 1.0) {
            return Err("the accelerometer filter must be above 0 and at most 1".into());
        }
        if !(self.max_turn > 0.0 && self.max_turn < std::f64::consts::FRAC_PI_2) {
            return Err("the largest turn of the torso must be above 0° and below 90°".into());
        }
        if self.chest_cycles == 0 || self.stop_status < 1 {
            return Err("the chest button cycles and the stop status must be at least 1".into());
        }
        if !(0.0..1.0).contains(&self.min_battery) {
            return Err("the battery limit must be 0 … 1".into());
        }
        Ok(())
    }
}

/// Why the robot as a whole cannot start a run, or stops one.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BodyStop {
    /// The robot does not lie on its back.
    #[error(
        "the robot lies {} (accelerometer {}, angles {}): a capture runs with the robot \
         lying on its back, face up; lay it so{}",
        lying.words(), vector(accelerometer), vector(angles),
        if *lying == Lying::OnBack { " (the torso angles disagree: is the IMU working?)" } else { "" }
    )]
    NotOnBack {
        /// How it lies.
        lying: Lying,
        /// The accelerometer (m/s²).
        accelerometer: [f32; 3],
        /// The torso angles (rad).
        angles: [f32; 2],
    },
    /// The IMU reports what no robot at rest reports.
    #[error(
        "the accelerometer reads {} ({:.1} m/s², at rest about 9.8): is the IMU working?",
        vector(accelerometer),
        norm(accelerometer)
    )]
    Imu {
        /// The accelerometer (m/s²).
        accelerometer: [f32; 3],
    },
    /// The torso turned too far from how it lay at the start.
    #[error(
        "the robot rolled over: its torso turned {:.0}° from how it lay at the start (limit \
         {:.0}°){}; lay it on its back, clear what made it roll, and go on with --resume",
        turn.to_degrees(), limit.to_degrees(),
        if *lying == Lying::OnBack { String::new() } else { format!(", it now lies {}", lying.words()) }
    )]
    Rolled {
        /// The turn (rad).
        turn: f64,
        /// The limit (rad).
        limit: f64,
        /// How it lies now.
        lying: Lying,
    },
    /// The chest button was pressed.
    #[error("the chest button was pressed: go on with --resume when ready")]
    ChestButton,
    /// A motor's status says the firmware cut its stiffness.
    #[error(
        "{} reports status {status} (the firmware reduces its stiffness: the motor is too \
         hot); let the motors cool with the stiffness off, then go on with --resume",
        joint.name()
    )]
    Status {
        /// The joint.
        joint: Joint,
        /// Its status.
        status: i32,
    },
    /// The battery is low.
    #[error(
        "the battery is at {:.0} % (limit {:.0} %): charge it (or plug the robot in) and \
         go on with --resume",
        charge * 100.0, limit * 100.0
    )]
    Battery {
        /// The charge (0 … 1).
        charge: f64,
        /// The limit (0 … 1).
        limit: f64,
    },
}

/// A vector for messages: `(x, y, z)` to two decimals.
pub fn vector<const N: usize>(v: &[f32; N]) -> String {
    let parts: Vec<String> = v.iter().map(|x| format!("{x:.2}")).collect();
    format!("({})", parts.join(", "))
}

fn norm(v: &[f32; 3]) -> f64 {
    v.iter().map(|&x| (x as f64).powi(2)).sum::<f64>().sqrt()
}

/// How the robot lies by one message: [`Lying::of`] the accelerometer, and
/// [`Lying::Tilted`] when `Angles` do not agree that the torso lies back.
pub fn lying(limits: &BodyLimits, message: &SensorMessage) -> Lying {
    match Lying::of(up(message), limits.facing) {
        Lying::OnBack
            if (message.angles[1] as f64 >= limits.max_pitch) || message.angles[1].is_nan() =>
        {
            Lying::Tilted
        }
        l => l,
    }
}

/// The first check of a run, before anything is commanded: the IMU plausible, the robot
/// on its back, the battery above its limit, no head or leg motor's status at the stop
/// level.
pub fn check_start(limits: &BodyLimits, message: &SensorMessage) -> Result<(), BodyStop> {
    let g = norm(&message.accelerometer);
    if !(g.is_finite() && (G - 3.0..=G + 3.0).contains(&g)) {
        return Err(BodyStop::Imu {
            accelerometer: message.accelerometer,
        });
    }
    let lies = lying(limits, message);
    if lies != Lying::OnBack {
        return Err(BodyStop::NotOnBack {
            lying: Lying::of(up(message), limits.facing),
            accelerometer: message.accelerometer,
            angles: message.angles,
        });
    }
    check_battery(limits, message)?;
    check_status(limits, message)
}

fn check_battery(limits: &BodyLimits, message: &SensorMessage) -> Result<(), BodyStop> {
    let charge = message.battery[BATTERY_CHARGE] as f64;
    if charge.is_nan() || charge < limits.min_battery {
        return Err(BodyStop::Battery {
            charge,
            limit: limits.min_battery,
        });
    }
    Ok(())
}

/// The head or leg motor with the highest status, and it.
pub fn worst_status(message: &SensorMessage) -> (Joint, i32) {
    Joint::ALL
        .iter()
        .map(|&j| (j, message.status[lola::index(j)]))
        .fold(
            (Joint::HeadYaw, i32::MIN),
            |a, b| if b.1 > a.1 { b } else { a },
        )
}

fn check_status(limits: &BodyLimits, message: &SensorMessage) -> Result<(), BodyStop> {
    let (joint, status) = worst_status(message);
    if status >= limits.stop_status {
        return Err(BodyStop::Status { joint, status });
    }
    Ok(())
}

/// The watch on the robot as a whole, one message per cycle.
#[derive(Debug, Clone)]
pub struct BodyWatch {
    limits: BodyLimits,
    /// "Up" at the start.
    start: [f64; 3],
    /// "Up", low-pass filtered.
    filtered: [f64; 3],
    /// Cycles in a row the chest button was pressed.
    chest: u32,
}

impl BodyWatch {
    /// The watch of a run whose first message is `first`, which must pass
    /// [`check_start`].
    pub fn start(limits: BodyLimits, first: &SensorMessage) -> Result<BodyWatch, BodyStop> {
        check_start(&limits, first)?;
        let up = up(first);
        Ok(BodyWatch {
            limits,
            start: up,
            filtered: up,
            chest: 0,
        })
    }

    /// Checks one message: the torso turned too far, the chest button, a motor's status,
    /// the battery.
    pub fn check(&mut self, message: &SensorMessage) -> Result<(), BodyStop> {
        let now = up(message);
        if now.iter().all(|a| a.is_finite()) {
            let a = self.limits.low_pass;
            self.filtered = std::array::from_fn(|k| (1.0 - a) * self.filtered[k] + a * now[k]);
        }
        let turn = angle(self.start, self.filtered);
        if turn > self.limits.max_turn || turn.is_nan() {
            return Err(BodyStop::Rolled {
                turn,
                limit: self.limits.max_turn,
                lying: Lying::of(self.filtered, self.limits.facing),
            });
        }
        if message.touch[CHEST_BUTTON] > 0.5 {
            self.chest += 1;
            if self.chest >= self.limits.chest_cycles {
                return Err(BodyStop::ChestButton);
            }
        } else {
            self.chest = 0;
        }
        check_status(&self.limits, message)?;
        check_battery(&self.limits, message)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::lola::JOINTS;

    fn lying_as(accelerometer: [f32; 3], angles: [f32; 2]) -> SensorMessage {
        let mut m = SensorMessage::on_back([0.0; JOINTS]);
        m.accelerometer = accelerometer;
        m.angles = angles;
        m
    }

    #[test]
    fn how_the_robot_lies_follows_the_teams_conventions() {
        let limits = BodyLimits::default();
        let half = std::f32::consts::FRAC_PI_2;
        let cases = [
            ([-9.81, 0.0, 0.0], [0.0, -half], Lying::OnBack),
            ([9.81, 0.0, 0.0], [0.0, half], Lying::OnFront),
            ([0.0, 0.0, -9.81], [0.0, 0.0], Lying::Upright),
            ([0.0, 9.81, 0.0], [half, 0.0], Lying::OnLeftSide),
            ([0.0, -9.81, 0.0], [-half, 0.0], Lying::OnRightSide),
            ([0.0, 0.0, 9.81], [0.0, 0.0], Lying::UpsideDown),
            // 30° from the back, towards the right side: still on its back.
            ([-8.5, -4.9, 0.0], [0.0, -half], Lying::OnBack),
            // 45°: between back and side.
            ([-6.94, -6.94, 0.0], [0.0, -half], Lying::Tilted),
            // The accelerometer on its back, angles upright: they disagree.
            ([-9.81, 0.0, 0.0], [0.0, 0.0], Lying::Tilted),
            // Pitched back by 65° and by 55°: on its back only beyond NaoTH's 60°.
            ([-9.81, 0.0, 0.0], [0.0, -1.134], Lying::OnBack),
            ([-9.81, 0.0, 0.0], [0.0, -0.96], Lying::Tilted),
        ];
        for (acc, angles, expected) in cases {
            assert_eq!(lying(&limits, &lying_as(acc, angles)), expected, "{acc:?}");
        }
    }

    #[test]
    fn each_named_way_of_lying_reads_as_itself() {
        let limits = BodyLimits::default();
        for (l, name, up) in Lying::NAMED {
            assert_eq!(Lying::from_name(name), Some(l));
            let (acc, angles) = imu(up);
            assert_eq!(lying(&limits, &lying_as(acc, angles)), l, "{name}");
        }
        let (acc, angles) = imu(Lying::OnBack.up());
        assert_eq!(acc, [-9.81, 0.0, 0.0]);
        assert_eq!(angles, [0.0, -std::f32::consts::FRAC_PI_2]);
    }

    #[test]
    fn a_run_starts_only_on_the_back_with_a_plausible_imu_and_battery() {
        let limits = BodyLimits::default();
        assert_eq!(
            check_start(&limits, &SensorMessage::on_back([0.0; JOINTS])),
            Ok(())
        );
        let standing = lying_as([0.0, 0.0, -9.81], [0.0, 0.0]);
        let e = check_start(&limits, &standing).unwrap_err();
        assert!(matches!(
            e,
            BodyStop::NotOnBack {
                lying: Lying::Upright,
                ..
            }
        ));
        assert!(e.to_string().contains("lies upright"), "{e}");
        assert!(e.to_string().contains("lay it so"), "{e}");
        let e = check_start(&limits, &lying_as([0.0, 0.0, 0.0], [0.0, 0.0])).unwrap_err();
        assert!(matches!(e, BodyStop::Imu { .. }), "{e}");
        let mut low = SensorMessage::on_back([0.0; JOINTS]);
        low.battery[BATTERY_CHARGE] = 0.03;
        let e = check_start(&limits, &low).unwrap_err();
        assert_eq!(
            e.to_string().split(':').next(),
            Some("the battery is at 3 % (limit 5 %)")
        );
        let mut hot = SensorMessage::on_back([0.0; JOINTS]);
        hot.status[lola::index(Joint::LKneePitch)] = 2;
        // An arm's status does not count: its stiffness stays 0.
        hot.status[lola::index(Joint::LKneePitch) - 8] = 3;
        let e = check_start(&limits, &hot).unwrap_err();
        assert_eq!(
            e,
            BodyStop::Status {
                joint: Joint::LKneePitch,
                status: 2
            }
        );
    }

    #[test]
    fn the_watch_stops_on_a_roll_the_chest_button_a_status_and_a_low_battery() {
        let limits = BodyLimits::default();
        let back = SensorMessage::on_back([0.0; JOINTS]);
        let mut w = BodyWatch::start(limits, &back).unwrap();
        // A single jolt of the accelerometer is filtered away.
        let mut jolt = back.clone();
        jolt.accelerometer = [0.0, -9.81, 0.0];
        assert_eq!(w.check(&jolt), Ok(()));
        for _ in 0..100 {
            assert_eq!(w.check(&back), Ok(()));
        }
        // Rolled onto its left side: stopped within a few tenths of a second.
        let side = lying_as([0.0, 9.81, 0.0], [1.57, 0.0]);
        let cycles = (1..100).find(|_| w.check(&side).is_err()).unwrap();
        assert!(cycles < 25, "{cycles} cycles");
        let e = w.check(&side).unwrap_err();
        assert!(e.to_string().starts_with("the robot rolled over"), "{e}");

        let mut w = BodyWatch::start(limits, &back).unwrap();
        let mut pressed = back.clone();
        pressed.touch[CHEST_BUTTON] = 1.0;
        assert_eq!(w.check(&pressed), Ok(()));
        assert_eq!(w.check(&back), Ok(()), "a bounce of one cycle");
        assert_eq!(w.check(&pressed), Ok(()));
        assert_eq!(w.check(&pressed), Ok(()));
        assert_eq!(w.check(&pressed), Err(BodyStop::ChestButton));

        let mut w = BodyWatch::start(limits, &back).unwrap();
        let mut hot = back.clone();
        hot.status[lola::index(Joint::RAnklePitch)] = 1;
        assert_eq!(w.check(&hot), Ok(()), "status 1 rests as when hot");
        hot.status[lola::index(Joint::RAnklePitch)] = 2;
        assert!(matches!(
            w.check(&hot),
            Err(BodyStop::Status {
                joint: Joint::RAnklePitch,
                status: 2
            })
        ));
        let mut low = back.clone();
        low.battery[BATTERY_CHARGE] = 0.049;
        assert!(matches!(w.check(&low), Err(BodyStop::Battery { .. })));
    }
}
