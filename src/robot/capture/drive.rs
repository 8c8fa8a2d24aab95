//! The robot, cycle by cycle: every sensor message is answered with the command, its
//! readings are checked (plausible, temperatures, currents) and the stop flag is watched.
//! On the cycle stand the stiffness ramps, the bounded-speed moves that wait for the
//! joints to settle, the rest that lets the motors cool, the way out (rest, then the
//! ramp-down) and the blind ramp-down when LoLA's stream cannot be trusted.

use std::sync::atomic::{AtomicBool, Ordering};

use crate::body::ArmPosture;
use crate::model::{Joint, JointAngles};
use crate::robot::arms::{self, ArmWatch};
use crate::robot::body::BodyWatch;
use crate::robot::lola::{self, ActuatorMessage, JOINTS, Link, LolaError, SensorMessage};
use crate::robot::motion::{Settle, SettleState};
use crate::robot::plausible::Believed;
use crate::robot::safety::{SafetyLimits, Verdict, Watch};

use super::{CaptureError, CaptureOptions, End};

/// Why a stance or the run halts.
#[derive(Debug)]
pub(super) enum Halt {
    /// LoLA failed: closed, silent or a message that does not parse.
    Link(LolaError),
    /// A fault: a safety limit, an implausible reading, the camera, the disk.
    Fault(CaptureError),
    /// The stop flag was set (a signal).
    Interrupted,
}

impl From<LolaError> for Halt {
    fn from(e: LolaError) -> Self {
        Halt::Link(e)
    }
}

/// How a move ended that did not settle at its target.
#[derive(Debug)]
pub(super) enum Unsettled {
    /// A head or leg motor is hot or reports a status above 0 (the joint, °C, its status):
    /// the legs are to rest until it cools.
    Hot(Joint, f64, i32),
    /// A joint was obstructed or the joints did not settle (why); the command holds the
    /// joints where they are.
    Abandoned(String),
}

/// The robot behind the link: one actuator message per sensor message.
pub(super) struct Drive<'a> {
    link: &'a mut dyn Link,
    options: &'a CaptureOptions,
    stop: &'a AtomicBool,
    watch: Watch,
    /// How the robot lies, its chest button, status and battery.
    body: BodyWatch,
    last: SensorMessage,
    /// The readings believed ([`Believed`]).
    believed: Believed,
    /// Positions of the joints naocalib does not move (hands), as first read.
    base: [f32; JOINTS],
    /// The commanded posture.
    command: JointAngles,
    /// The commanded arm posture: as first read until the arms move
    /// ([`Drive::move_arms`]).
    arms: ArmPosture,
    /// Whether the arms were moved away from where they were first read.
    arms_moved: bool,
    /// The watch on the arm motors.
    arm_watch: ArmWatch,
    /// The commanded stiffness of each motor (LoLA's order).
    stiffness: [f64; JOINTS],
    /// LoLA cycles so far.
    pub(super) cycles: u64,
    hot: Option<(Joint, f64, i32)>,
    /// On the way out: only a broken link stops the rest and ramp-down.
    finishing: bool,
    /// Whether the ramp-up ended and the robot was moved.
    moved: bool,
}

impl<'a> Drive<'a> {
    /// Takes over the robot from LoLA's first message: its readings must be plausible
    /// ([`Believed::start`]) and the robot lie on its back with its battery charged and no
    /// motor's stiffness cut ([`BodyWatch::start`]); the command holds the posture they
    /// report, at the stiffness the robot reports. Nothing is sent yet.
    pub(super) fn start(
        link: &'a mut dyn Link,
        options: &'a CaptureOptions,
        stop: &'a AtomicBool,
    ) -> Result<Drive<'a>, CaptureError> {
        let first = link.receive()?;
        let believed =
            Believed::start(options.safety.readings, &first).map_err(CaptureError::FirstReading)?;
        let body = BodyWatch::start(options.safety.body, &first)
            .map_err(|e| CaptureError::NotReady(e.to_string()))?;
        Ok(Drive {
            link,
            options,
            stop,
            watch: Watch::default(),
            body,
            base: first.position,
            command: believed.readings(),
            arms: arms::read(&first.position),
            arms_moved: false,
            arm_watch: ArmWatch::default(),
            believed,
            stiffness: first.stiffness.map(f64::from),
            last: first,
            cycles: 0,
            hot: None,
            finishing: false,
            moved: false,
        })
    }

    /// The command as LoLA takes it: head, legs and arms as commanded, the hands where
    /// they were first read.
    fn message(&self) -> ActuatorMessage {
        let position = lola::put(self.base, &self.command, |q| q as f32);
        ActuatorMessage {
            position: arms::put(position, &self.arms, |q| q as f32),
            stiffness: self.stiffness.map(|s| s as f32),
        }
    }

    /// Answers the last message with the command and reads the next one.
    pub(super) fn cycle(&mut self) -> Result<(), Halt> {
        self.link.send(&self.message())?;
        self.last = self.link.receive()?;
        self.cycles += 1;
        let fault = self.believed.check(&self.last);
        if self.finishing {
            return Ok(());
        }
        if let Some(fault) = fault {
            return Err(Halt::Fault(CaptureError::Reading(fault)));
        }
        match self.watch.check(&self.options.safety, &self.last) {
            Verdict::Fine => self.hot = None,
            Verdict::Hot(j, t) => self.hot = Some((j, t, 0)),
            Verdict::Status(j, status, t) => self.hot = Some((j, t, status)),
            stop => {
                let name = |j: crate::model::Joint| j.name().to_string();
                if let Some(why) = stop.stops(&self.options.safety, name) {
                    return Err(Halt::Fault(CaptureError::Safety(why)));
                }
            }
        }
        let arms_stiff = arms::indices().iter().any(|&k| self.stiffness[k] > 0.0);
        if arms_stiff && let Err(why) = self.arm_watch.check(&self.options.safety, &self.last) {
            return Err(Halt::Fault(CaptureError::Safety(why)));
        }
        if let Err(stop) = self.body.check(&self.last) {
            return Err(Halt::Fault(CaptureError::Body(stop)));
        }
        if self.stop.load(Ordering::Relaxed) {
            return Err(Halt::Interrupted);
        }
        Ok(())
    }

    /// The commanded posture.
    pub(super) fn command(&self) -> &JointAngles {
        &self.command
    }

    /// The believed readings; a joint no longer believed reads as commanded (so that
    /// nothing follows it on the way out).
    pub(super) fn reading(&self) -> JointAngles {
        let readings = self.believed.readings();
        JointAngles::from_fn(|j| {
            if self.believed.lost(j) {
                self.command.get(j)
            } else {
                readings.get(j)
            }
        })
    }

    /// Whether every joint's reading of the last cycle was believed (a cycle with a
    /// glitch is left out of a capture's readings).
    pub(super) fn all_believed(&self) -> bool {
        self.believed.all_believed()
    }

    /// Ramps each motor's stiffness from what the robot reported at the start to the
    /// measuring stiffness (head, legs and arms) or 0 (hands), holding the posture
    /// measured at the start: a leg that sags meanwhile does not drag the command along.
    /// The robot counts as moved once the ramp is done.
    pub(super) fn ramp_up(&mut self) -> Result<(), Halt> {
        let m = self.options.motion;
        let from = self.stiffness;
        let to = lola::put([0.0; JOINTS], &JointAngles::fill(m.stiffness), |s| s);
        let to = arms::put(to, &ArmPosture([m.stiffness; 10]), |s| s);
        for k in 0..=m.ramp_cycles {
            self.stiffness = std::array::from_fn(|i| m.ramp(from[i], to[i], k));
            self.cycle()?;
        }
        self.moved = true;
        Ok(())
    }

    /// Ramps the stiffness down to 0, holding the command.
    fn ramp_down(&mut self) -> Result<(), Halt> {
        let m = self.options.motion;
        let from = self.stiffness;
        for k in 0..m.ramp_cycles {
            self.stiffness = from.map(|s| m.ramp_down(s, k));
            self.cycle()?;
        }
        Ok(())
    }

    /// Moves to `target` at bounded speed, then waits for the readings to settle.
    /// `Ok(None)` when settled; else why not, after which the command holds the joints
    /// where they are. A hot motor ends the move only when `watch_hot`.
    pub(super) fn move_to(
        &mut self,
        target: &JointAngles,
        watch_hot: bool,
    ) -> Result<Option<Unsettled>, Halt> {
        let m = self.options.motion;
        let mut settle = Settle::new();
        let path = m.path(&self.command, target);
        let timeout = m.settle_timeout_cycles as usize;
        for k in 0..path.len() + timeout {
            self.command = *path.get(k).unwrap_or(target);
            self.cycle()?;
            if watch_hot && let Some((j, t, status)) = self.hot {
                return Ok(Some(Unsettled::Hot(j, t, status)));
            }
            let reading = self.reading();
            match settle.push(&m, &self.command, &reading) {
                SettleState::Settled if k + 1 >= path.len() => return Ok(None),
                SettleState::Obstructed(j, gap) => {
                    // Stop pushing against what is in the way: the command comes back to
                    // where the joints are, at bounded speed.
                    for p in m.path(&self.command, &reading) {
                        self.command = p;
                        self.cycle()?;
                    }
                    return Ok(Some(Unsettled::Abandoned(format!(
                        "{} stayed {:.1}° from its command for {} cycles (obstructed?)",
                        j.name(),
                        gap.to_degrees(),
                        m.obstruction_cycles
                    ))));
                }
                _ => {}
            }
        }
        Ok(Some(Unsettled::Abandoned(format!(
            "the joints did not settle within {} cycles",
            timeout
        ))))
    }

    /// Moves to the rest posture (a hot motor does not stop the way there).
    pub(super) fn rest(&mut self) -> Result<(), Halt> {
        let rest = self.options.rest;
        self.move_to(&rest, false).map(|_| ())
    }

    /// Moves the arms to `target` at the arm speed (`MotionOptions::arm_speed`), head
    /// and legs holding their command, then waits until every arm joint has read within
    /// half the obstruction gap (2°) of `target` for the settling window. An arm joint
    /// that stays farther than the obstruction gap from its command for the obstruction
    /// cycles, or arms that do not get there within the settling timeout after the move,
    /// end it: the arm command comes back to where the arms are, at the arm speed, and
    /// `Ok(Err(why))` says why. `Ok(Ok(cycles))` when the arms got there.
    pub(super) fn move_arms(&mut self, target: &ArmPosture) -> Result<Result<u64, String>, Halt> {
        let m = self.options.motion;
        let path = m.arm_path(&self.arms, target);
        let start = self.cycles;
        let mut far = 0u32;
        let mut near = 0u32;
        for k in 0..path.len() + m.settle_timeout_cycles as usize {
            if let Some(p) = path.get(k) {
                self.arms = *p;
                self.arms_moved = true;
            }
            self.cycle()?;
            let reading = arms::read(&self.last.position);
            let gap = arms::distance(&reading, &self.arms);
            far = if gap > m.obstruction { far + 1 } else { 0 };
            if far >= m.obstruction_cycles {
                let k = (0..10)
                    .max_by(|&a, &b| {
                        let d = |i: usize| (reading.0[i] - self.arms.0[i]).abs();
                        d(a).total_cmp(&d(b))
                    })
                    .unwrap_or(0);
                let why = format!(
                    "{} stayed {:.1}° from its command for {} cycles (are the arms held or \
                     in the way of something?)",
                    crate::body::ARM_JOINTS[k],
                    gap.to_degrees(),
                    m.obstruction_cycles
                );
                let back = if reading.0.iter().all(|q| q.is_finite()) {
                    m.arm_path(&self.arms, &reading)
                } else {
                    Vec::new()
                };
                for p in back {
                    self.arms = p;
                    self.cycle()?;
                }
                return Ok(Err(why));
            }
            let there =
                k + 1 >= path.len() && arms::distance(&reading, target) <= m.obstruction / 2.0;
            near = if there { near + 1 } else { 0 };
            if near >= m.settle_cycles {
                return Ok(Ok(self.cycles - start));
            }
        }
        Ok(Err(format!(
            "the arms did not reach their posture within {} cycles",
            m.settle_timeout_cycles
        )))
    }

    /// Rests until the head and leg motors are at or below the resume temperature and none
    /// reports a status above 0 ([`SafetyLimits::cooled`]).
    pub(super) fn cool(&mut self) -> Result<(), Halt> {
        let limits = self.options.safety;
        self.rest()?;
        for _ in 0..limits.max_pause_cycles {
            self.cycle()?;
            if limits.cooled(&self.last) {
                return Ok(());
            }
        }
        let (j, t) = SafetyLimits::hottest(&self.last);
        let (sj, status) = crate::robot::body::worst_status(&self.last);
        Err(Halt::Fault(CaptureError::Safety(format!(
            "{} still at {t:.1} °C ({} status {status}) after {} cycles at rest",
            j.name(),
            sj.name(),
            limits.max_pause_cycles
        ))))
    }

    /// The way out of a run that ends with `end`: back to rest (unless the robot never
    /// moved: stopped during the ramp-up, it ramps down where it lies), the arms, when a
    /// completed run moved them, back beside the body ([`ArmPosture::BESIDE_BODY`]; on any
    /// other end they stay where they are), then the stiffness ramp-down; only a broken link stops them. When LoLA's stream cannot be trusted or
    /// read (a message that did not parse, silence, a socket error) the ramp-down is sent
    /// blind, holding the posture; only a closed connection leaves nothing to send to.
    /// Whether the ramp-down was sent to its end (the robot limp).
    pub(super) fn finish(&mut self, end: &End) -> bool {
        self.finishing = true;
        match end {
            End::Stopped(CaptureError::Lola(LolaError::Closed)) => false,
            End::Stopped(CaptureError::Lola(_)) => self.blind_ramp_down(),
            _ => {
                let arms_back = matches!(end, End::Completed) && self.arms_moved;
                let back = if self.moved { self.rest() } else { Ok(()) }
                    .and_then(|()| {
                        if arms_back {
                            // Arms that cannot get back stay where they stopped.
                            self.move_arms(&ArmPosture::BESIDE_BODY).map(|_| ())
                        } else {
                            Ok(())
                        }
                    })
                    .and_then(|()| self.ramp_down());
                match back {
                    Ok(()) => true,
                    Err(Halt::Link(LolaError::Closed)) => false,
                    Err(_) => self.blind_ramp_down(),
                }
            }
        }
    }

    /// Sends a stiffness ramp-down without reading (after a message that did not parse,
    /// the stream cannot be trusted): one message per 12 ms. Whether every message was sent.
    fn blind_ramp_down(&mut self) -> bool {
        let options = &self.options.motion;
        let mut message = self.message();
        let from = message.stiffness;
        for k in 0..options.ramp_cycles {
            let f = options.ramp_down(1.0, k) as f32;
            for (s, s0) in message.stiffness.iter_mut().zip(from) {
                *s = s0 * f;
            }
            self.link.drain();
            if self.link.send(&message).is_err() {
                return false;
            }
            std::thread::sleep(lola::CYCLE);
        }
        std::thread::sleep(lola::CYCLE);
        self.link.drain();
        true
    }
}
