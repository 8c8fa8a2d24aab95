//! The rest guard: whatever ends capture — a fatal signal, an abort, the kernel's
//! out-of-memory kill, a panic in any thread — the robot ends at rest with its stiffness
//! ramped down.
//!
//! Every way out capture itself handles (a fault, a stop signal, a panic it catches) ends at
//! rest ([`super::Session::run`]); the ones it cannot handle (SIGKILL, an abort, the OOM
//! killer) end the process at once, and LoLA keeps its last command: a raised leg stays
//! stiff in the air. So capture starts a small guard process first (`naocalib rest-guard`,
//! hidden; the same executable), before it connects to LoLA: the guard holds the read end
//! of a pipe whose write end only capture holds. Capture tells it through the pipe when it
//! takes the robot over (`armed`) and when it has left it at rest and limp (`done`). When
//! the pipe reaches its end while armed and not done, capture is gone — the kernel closed
//! its descriptors, LoLA's socket among them — and the guard connects to LoLA as the next
//! client, takes the robot over from what it reports and, within [`BUDGET_CYCLES`] (1.8 s),
//! commands the rest posture at the joints' speed limits and ramps every motor's stiffness
//! to 0 ([`take_over`]).
//!
//! LoLA takes one client at a time (HULKs `docs/hula.md` line 4): the guard is not a second
//! client beside capture but the next one, after capture's socket closed. The teams do the
//! same with a process of their own that outlives the one that moves the robot: HULKs' HuLA
//! (`services/hula/src/proxy.rs`) holds LoLA and the robotics process connects to it;
//! NaoTH's `lola_adaptor` (`NaoTHSoccer/Source/Cognition/…/LolaAdaptor.cpp`, lines 159–168)
//! sits the robot down when `naoth` stops answering. naocalib's guard holds no connection
//! while capture runs, so that capture answers LoLA itself every 12 ms, as before.
//!
//! The guard is in a process group of its own and ignores SIGHUP, SIGINT, SIGQUIT and
//! SIGTERM: a Ctrl-C or a lost terminal reaches capture (which goes to rest itself), not the
//! guard.

use std::io::{BufRead, BufReader, Write as _};
use std::path::Path;
use std::process::{Child, ChildStdin, Command, Stdio};

use crate::model::JointAngles;
use crate::robot::lola::{self, ActuatorMessage, JOINTS, Link, LolaError};
use crate::robot::motion::MotionOptions;

/// The hidden subcommand of naocalib that runs the guard.
pub const SUBCOMMAND: &str = "rest-guard";

/// The most cycles the guard's way out lasts from the robot's first message: 150 cycles of
/// 12 ms, 1.8 s (the rest of 2 s is for noticing capture is gone and connecting).
pub const BUDGET_CYCLES: u32 = 150;

/// The fastest the guard moves a leg joint (rad/s): the fastest a run may be told to
/// (`--leg-speed` at most 60°/s), used only when the run's own speed would not reach rest
/// within [`BUDGET_CYCLES`].
pub const FASTEST_LEG: f64 = 60.0 * std::f64::consts::PI / 180.0;

/// The fastest the guard moves a head joint (rad/s), as [`FASTEST_LEG`] (`--head-speed`
/// at most 180°/s).
pub const FASTEST_HEAD: f64 = std::f64::consts::PI;

/// What capture writes to the guard when it takes the robot over.
const ARMED: &str = "armed";
/// What capture writes to the guard once the robot is at rest and limp.
const DONE: &str = "done";
/// What the guard writes once it watches.
const READY: &str = "ready";

/// Why the guard could not be started or could not take the robot over.
#[derive(Debug, thiserror::Error)]
pub enum GuardError {
    /// The guard process could not be started or told.
    #[error("the rest guard ({program}): {source}")]
    Start {
        /// The program run.
        program: String,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// The guard ended before it said it watches.
    #[error("the rest guard ({program}) ended before it was ready")]
    NotReady {
        /// The program run.
        program: String,
    },
    /// LoLA failed while the guard took the robot over.
    #[error(transparent)]
    Lola(#[from] LolaError),
}

/// Capture's end of the guard: the guard process and the pipe to it.
#[derive(Debug)]
pub struct Guard {
    child: Child,
    input: Option<ChildStdin>,
    program: String,
}

impl Guard {
    /// Starts `program rest-guard --lola SOCKET …` (naocalib itself) for the robot at
    /// `socket`, moved with `motion`'s speeds and ramp, and waits until it watches.
    pub fn spawn(
        program: &Path,
        socket: &Path,
        motion: &MotionOptions,
    ) -> Result<Guard, GuardError> {
        use std::os::unix::process::CommandExt as _;
        let name = program.display().to_string();
        let start = |source| GuardError::Start {
            program: name.clone(),
            source,
        };
        let mut child = Command::new(program)
            .arg(SUBCOMMAND)
            .arg("--lola")
            .arg(socket)
            .arg("--leg-speed")
            .arg(motion.leg_speed.to_degrees().to_string())
            .arg("--head-speed")
            .arg(motion.head_speed.to_degrees().to_string())
            .arg("--ramp-cycles")
            .arg(motion.ramp_cycles.to_string())
            .process_group(0)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .map_err(start)?;
        let mut line = String::new();
        let said = child
            .stdout
            .take()
            .map(|out| BufReader::new(out).read_line(&mut line));
        if !matches!(said, Some(Ok(_))) || line.trim() != READY {
            let _ = child.kill();
            let _ = child.wait();
            return Err(GuardError::NotReady { program: name });
        }
        let input = child.stdin.take();
        Ok(Guard {
            child,
            input,
            program: name,
        })
    }

    fn tell(&mut self, word: &str) -> Result<(), GuardError> {
        let Some(input) = &mut self.input else {
            return Ok(());
        };
        input
            .write_all(format!("{word}\n").as_bytes())
            .and_then(|()| input.flush())
            .map_err(|source| GuardError::Start {
                program: self.program.clone(),
                source,
            })
    }

    /// Tells the guard that capture takes the robot over: from now on, capture gone
    /// without [`Guard::release`] makes the guard take the robot to rest.
    pub fn arm(&mut self) -> Result<(), GuardError> {
        self.tell(ARMED)
    }

    /// Tells the guard that the robot is at rest and limp (or was never commanded), and
    /// waits for it to end.
    pub fn release(mut self) {
        let _ = self.tell(DONE);
        self.input = None;
        let _ = self.child.wait();
    }

    /// Lets the guard take the robot to rest now (capture lost its connection before the
    /// robot was limp, and has closed it), and waits for it to end.
    pub fn hand_over(mut self) {
        self.input = None;
        let _ = self.child.wait();
    }
}

/// What the guard saw of capture.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Watched {
    /// Capture left the robot at rest and limp, or never commanded it.
    Released,
    /// Capture ended while it held the robot.
    Gone,
}

/// Reads capture's words from `input` until its end: [`Watched::Gone`] when capture armed
/// the guard and ended without releasing it.
pub fn watch(input: impl BufRead) -> Watched {
    let mut armed = false;
    for line in input.lines() {
        match line.as_deref().map(str::trim) {
            Ok(ARMED) => armed = true,
            Ok(DONE) => return Watched::Released,
            Ok(_) => {}
            Err(_) => break,
        }
    }
    if armed {
        Watched::Gone
    } else {
        Watched::Released
    }
}

/// Says to capture (on `out`) that the guard watches.
pub fn ready(out: &mut impl std::io::Write) -> std::io::Result<()> {
    writeln!(out, "{READY}")?;
    out.flush()
}

/// How the guard left the robot.
#[derive(Debug, Clone, PartialEq)]
pub struct TakenOver {
    /// Messages sent.
    pub cycles: u32,
    /// The highest stiffness the robot reported when the guard took it over.
    pub stiffness: f64,
    /// Whether every message after the first came (else the rest was sent blind, one per
    /// 12 ms).
    pub answered: bool,
}

/// Takes the robot behind `link` over from its next message, as capture would have left
/// it: the command moves from the posture it reports towards `rest` at `motion`'s speed
/// limits (faster, up to [`FASTEST_LEG`] and [`FASTEST_HEAD`], when those would not reach
/// rest within [`BUDGET_CYCLES`]) while each motor holds the stiffness it reports, then ramps every stiffness to 0
/// over `motion`'s ramp, moving on towards rest; all within [`BUDGET_CYCLES`] (the ramp
/// shortened to fit). A joint whose reading is not a number is commanded to rest at once
/// (its stiffness ramps down with the others'). When the robot stops answering, the rest is
/// sent blind, one message per 12 ms.
pub fn take_over(
    link: &mut dyn Link,
    motion: &MotionOptions,
    rest: &JointAngles,
) -> Result<TakenOver, LolaError> {
    let first = link.receive()?;
    let base = first.position;
    let from = JointAngles::from_fn(|j| {
        let q = f64::from(first.position[lola::index(j)]);
        if q.is_finite() { q } else { rest.get(j) }
    });
    let stiffness: [f64; JOINTS] = first.stiffness.map(|s| {
        let s = f64::from(s);
        if s.is_finite() {
            s.clamp(0.0, 1.0)
        } else {
            1.0
        }
    });
    // At the run's speeds, or faster (up to the fastest a run may be told) when those
    // would not reach rest within the budget.
    let mut path = motion.path(&from, rest);
    if path.len() as u32 > BUDGET_CYCLES {
        let f = path.len() as f64 / f64::from(BUDGET_CYCLES);
        let faster = MotionOptions {
            leg_speed: (motion.leg_speed * f).min(FASTEST_LEG),
            head_speed: (motion.head_speed * f).min(FASTEST_HEAD),
            ..*motion
        };
        path = faster.path(&from, rest);
    }
    let ramp = motion.ramp_cycles.clamp(1, BUDGET_CYCLES);
    let hold = (path.len() as u32).min(BUDGET_CYCLES - ramp);
    let down = MotionOptions {
        ramp_cycles: ramp,
        ..*motion
    };
    let mut answered = true;
    let total = hold + ramp;
    for k in 0..total {
        let target = path.get(k as usize).unwrap_or(rest);
        let message = ActuatorMessage {
            position: lola::put(base, target, |q| q as f32),
            stiffness: stiffness.map(|s| {
                if k < hold {
                    s as f32
                } else {
                    down.ramp_down(s, k - hold) as f32
                }
            }),
        };
        match link.send(&message) {
            Ok(()) => {}
            Err(LolaError::Closed) if k > 0 => break,
            Err(e) => return Err(e),
        }
        if k + 1 == total {
            break;
        }
        if answered {
            if link.receive().is_err() {
                answered = false;
            }
        } else {
            std::thread::sleep(lola::CYCLE);
        }
    }
    Ok(TakenOver {
        cycles: total,
        stiffness: stiffness.iter().copied().fold(0.0, f64::max),
        answered,
    })
}

/// The guard's whole life: tells `out` it watches, waits on `input` (capture's pipe) and,
/// when capture is gone while it held the robot, connects to LoLA at `socket` and takes the
/// robot over ([`take_over`]). `None` when capture released it.
pub fn run(
    socket: &Path,
    motion: &MotionOptions,
    input: impl BufRead,
    out: &mut impl std::io::Write,
) -> Result<Option<TakenOver>, GuardError> {
    ready(out).map_err(|source| GuardError::Start {
        program: SUBCOMMAND.into(),
        source,
    })?;
    if watch(input) == Watched::Released {
        return Ok(None);
    }
    let rest = crate::plan::route::rest_posture();
    let mut link = connect(socket)?;
    Ok(Some(take_over(&mut link, motion, &rest)?))
}

/// Connects to LoLA at `socket`, trying for up to 0.2 s (the socket may still be held by
/// capture's end for a moment), waiting up to 0.5 s for each message.
fn connect(socket: &Path) -> Result<lola::Connection, LolaError> {
    let start = std::time::Instant::now();
    loop {
        match lola::Connection::connect(socket, 42) {
            Ok(c) => return Ok(c),
            Err(e) if start.elapsed() > std::time::Duration::from_millis(200) => return Err(e),
            Err(_) => std::thread::sleep(std::time::Duration::from_millis(5)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Joint;
    use crate::robot::lola::SensorMessage;

    /// A robot that holds every command at once and records it.
    struct Held {
        now: SensorMessage,
        sent: Vec<ActuatorMessage>,
    }

    impl Link for Held {
        fn receive(&mut self) -> Result<SensorMessage, LolaError> {
            Ok(self.now.clone())
        }

        fn send(&mut self, message: &ActuatorMessage) -> Result<(), LolaError> {
            self.now.position = message.position;
            self.now.stiffness = message.stiffness;
            self.sent.push(message.clone());
            Ok(())
        }
    }

    #[test]
    fn capture_gone_while_armed_and_only_then_is_a_take_over() {
        assert_eq!(watch(&b"armed\n"[..]), Watched::Gone);
        assert_eq!(watch(&b"armed\ndone\n"[..]), Watched::Released);
        assert_eq!(watch(&b""[..]), Watched::Released);
        assert_eq!(watch(&b"arm"[..]), Watched::Released);
    }

    /// A stiff robot with a leg raised is taken over from the stiffness and posture it
    /// reports, moved to rest at the speed limits and made limp within the budget.
    #[test]
    fn the_take_over_goes_to_rest_and_ramps_down_within_the_budget() {
        let rest = crate::plan::route::rest_posture();
        let mut raised = rest;
        raised.set(Joint::LHipPitch, -0.6);
        raised.set(Joint::LKneePitch, 0.9);
        let mut now = SensorMessage::on_back(lola::put([0.0; JOINTS], &raised, |q| q as f32));
        now.stiffness = lola::put([0.0; JOINTS], &JointAngles::fill(0.8), |s| s as f32);
        let mut robot = Held {
            now: now.clone(),
            sent: Vec::new(),
        };
        let motion = MotionOptions::default();
        let t = take_over(&mut robot, &motion, &rest).unwrap();
        assert!(t.answered);
        assert!((t.stiffness - 0.8).abs() < 1e-6);
        let sent = &robot.sent;
        assert_eq!(sent.len() as u32, t.cycles);
        assert!(t.cycles <= BUDGET_CYCLES);
        let knee = lola::index(Joint::LKneePitch);
        assert_eq!(sent[0].stiffness[knee], 0.8, "taken over as it was");
        let last = sent.last().unwrap();
        assert!(last.stiffness.iter().all(|&s| s == 0.0));
        let at = lola::to_joint_angles(&last.position);
        assert!((at - rest).iter().all(|(_, d)| d.abs() < 1e-6), "{at:?}");
        let mut previous = lola::to_joint_angles(&now.position);
        for (m, w) in sent
            .iter()
            .zip(std::iter::once(None).chain(sent.windows(2).map(Some)))
        {
            let q = lola::to_joint_angles(&m.position);
            for (j, d) in (q - previous).iter() {
                assert!(d.abs() <= motion.speed(j) * lola::CYCLE_S + 1e-6, "{j:?}");
            }
            previous = q;
            if let Some(w) = w {
                for k in 0..JOINTS {
                    let ds = w[0].stiffness[k] - w[1].stiffness[k];
                    assert!((0.0..=0.8 / 84.0 + 1e-6).contains(&f64::from(ds)));
                }
            }
        }
        // The arms keep the posture they were read in.
        assert_eq!(last.position[2], now.position[2]);
    }
}
