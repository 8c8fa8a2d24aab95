//! A simulated NAO V6, lying on its back, serving LoLA on a Unix socket: for testing
//! `naocalib capture` end to end without a robot.
//!
//! Each cycle it writes a [`SensorFrame`] and reads the client's [`ActuatorMessage`]
//! (it waits for the answer: a client that answers every message, as capture does, sees
//! exactly LoLA's cycle; it may run faster than real time, [`RobotOptions::speed`]). The
//! joints follow their commands under stiffness (a first-order lag, time constant
//! [`LAG_S`]/stiffness, at most [`MAX_SPEED`]); the readings are the joints quantised to
//! encoder steps of 0.088°; the physical joint is the reading plus the true offsets, the
//! compliance under the gravity torques and the play (the simulator's model with
//! [`RobotOptions::truth`]). The motor currents follow the holding torques and the
//! temperatures rise with the square of the current and cool towards 30 °C.
//!
//! The cameras: the robot writes its state (true parameters, joints) to a file
//! ([`RobotOptions::state`]), from which [`snap`] renders the lower or the upper camera's
//! view (`naocalib simulate-robot snap {path} --state FILE --camera {camera}`, for
//! `capture --camera 'lower=command:…' --camera 'upper=command:…'`).
//!
//! It lies as [`RobotOptions::lying`] says (on its back unless told otherwise), and its
//! IMU says so, as LoLA's does ([`body::imu`]).
//!
//! Faults on request ([`Faults`]): a blocked joint, an overheating motor, a connection
//! dropped, the robot falling silent, a message that does not parse, rolling over, the
//! chest button pressed, a motor's status, a low battery. Every actuator
//! message received can be recorded ([`RobotOptions::record`]) so that tests check the
//! safety rules on what the robot was told.

use std::io::{BufReader, Write as _};
use std::os::unix::net::{UnixListener, UnixStream};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use crate::model::{CameraId, Joint, JointAngles, Model, PARAMETER_COUNT, Side, gravity};
use crate::output::{WriteOptions, write_atomic, write_atomic_unsynced};
use crate::sim::render::{self, RenderOptions};

use super::body::{self, Lying};
use super::lola::{
    self, ActuatorMessage, BATTERY_CHARGE, CHEST_BUTTON, JOINT_NAMES, JOINTS, LolaError,
    SensorFrame, SensorMessage,
};

pub mod request;

/// Time constant of a joint following its command at stiffness 1 (s).
pub const LAG_S: f64 = 0.03;
/// Fastest a joint moves (rad/s).
pub const MAX_SPEED: f64 = 5.0;
/// One encoder step: 4096 per turn (0.088°).
pub const ENCODER_STEP: f64 = std::f64::consts::TAU / 4096.0;
/// The encoder's noise before quantisation, σ in encoder steps: a joint at rest reads
/// one of two or three neighbouring steps, as a NAO's do.
pub const ENCODER_NOISE_STEPS: f64 = 0.35;
/// Temperature the motors cool towards (°C).
pub const AMBIENT: f64 = 30.0;
/// A leg whose HipPitch is within this of zero (rad) lies flat on the floor.
pub const FLAT: f64 = 0.1;

/// Faults the simulated robot can play.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Faults {
    /// A joint that cannot move beyond an angle (rad) away from where it starts (an
    /// obstruction: a cable, the other leg, a hand).
    pub block: Option<(Joint, f64)>,
    /// A motor that heats up fast while it holds a load.
    pub overheat: Option<Joint>,
    /// Close the connection and exit after this many cycles.
    pub drop_after: Option<u64>,
    /// Stop writing (but keep the connection) after this many cycles.
    pub silent_after: Option<u64>,
    /// Write a message that does not parse in this cycle.
    pub garbage_at: Option<u64>,
    /// Close the connection and exit on SIGUSR1 (a test's request mid-run).
    pub drop_on_signal: bool,
    /// Roll over onto the right side from this cycle on (in 40 cycles, 0.5 s).
    pub roll_at: Option<u64>,
    /// The chest button pressed from this cycle on.
    pub chest_at: Option<u64>,
    /// A motor's status (the joint, the status) from a cycle on.
    pub status_at: Option<(Joint, i32, u64)>,
    /// The battery down to 3 % from this cycle on.
    pub low_battery_at: Option<u64>,
}

/// Cycles the robot takes to roll over onto its side ([`Faults::roll_at`]).
pub const ROLL_CYCLES: u64 = 40;

/// The charge of a low battery ([`Faults::low_battery_at`]).
pub const LOW_BATTERY: f32 = 0.03;

/// The simulated robot.
#[derive(Debug, Clone, PartialEq)]
pub struct RobotOptions {
    /// Geometry, camera and sandals.
    pub model: Model,
    /// The `dataset.toml` the model came from (named in the state file for [`snap`]).
    pub config: Option<PathBuf>,
    /// The true parameters (internal units).
    pub truth: [f64; PARAMETER_COUNT],
    /// Speed relative to real time (1: 12 ms cycles; 10: 1.2 ms); 0 runs as fast as the
    /// client answers.
    pub speed: f64,
    /// The posture it lies in at the start (readings frame, rad).
    pub start: JointAngles,
    /// How it lies (its IMU says so): on its back unless a test says otherwise.
    pub lying: Lying,
    /// Its battery's charge (0 … 1).
    pub battery: f32,
    /// Where to write the state for [`snap`].
    pub state: Option<PathBuf>,
    /// Where to write every actuator message received (CSV) when the robot exits.
    pub record: Option<PathBuf>,
    /// Faults to play.
    pub faults: Faults,
    /// How many clients to serve one after the other before exiting.
    pub clients: usize,
    /// Seed of the rendering noise.
    pub seed: u64,
}

/// What a simulated robot's state file holds (JSON), for [`snap`].
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct State {
    /// The `dataset.toml` of the model (the default model when absent).
    pub config: Option<PathBuf>,
    /// True parameters, internal units, in registry order.
    pub truth: Vec<f64>,
    /// The joints now (readings frame before quantisation, rad), in `captures.csv` order.
    pub joints: Vec<f64>,
    /// The cycle.
    pub cycle: u64,
    /// Seed of the rendering noise.
    pub seed: u64,
}

/// Why the simulated robot stopped with an error.
#[derive(Debug, thiserror::Error)]
pub enum RobotError {
    /// The socket could not be made.
    #[error("{}: cannot serve LoLA here: {source}", path.display())]
    Bind {
        /// The socket path.
        path: PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// A file could not be written.
    #[error(transparent)]
    Write(#[from] crate::output::WriteError),
    /// A file could not be read.
    #[error("{}: {message}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// The camera view could not be rendered.
    #[error(transparent)]
    Render(#[from] render::RenderError),
    /// The model could not be read.
    #[error(transparent)]
    Dataset(#[from] crate::dataset::DatasetError),
    /// The socket failed.
    #[error("LoLA socket: {0}")]
    Io(#[from] std::io::Error),
}

/// The LoLA motors naocalib measures (HipYawPitch once).
fn motors() -> Vec<usize> {
    let mut out: Vec<usize> = Joint::ALL.iter().map(|&j| lola::index(j)).collect();
    out.sort();
    out.dedup();
    out
}

/// The body: joints, commands, temperatures.
struct Body {
    pos: [f64; JOINTS],
    command: [f64; JOINTS],
    stiffness: [f64; JOINTS],
    temperature: [f64; JOINTS],
    current: [f64; JOINTS],
    /// The blocked motor, its barrier and whether the barrier is above the start.
    block: Option<(usize, f64, bool)>,
    overheat: Option<usize>,
    cycle: u64,
    /// This cycle's readings.
    readings: [f32; JOINTS],
    rng: rand_chacha::ChaCha8Rng,
}

impl Body {
    fn new(options: &RobotOptions) -> Body {
        let mut pos = lola::put([0.0; JOINTS], &options.start, |q| q);
        // Arms lying beside the body.
        pos[2] = 1.5;
        pos[18] = 1.5;
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

    fn joints(&self) -> JointAngles {
        lola::to_joint_angles(&self.pos)
    }

    fn reading(&self, k: usize) -> f32 {
        self.readings[k]
    }

    /// One cycle of 12 ms.
    fn step(&mut self, model: &Model, motors: &[usize]) {
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

    fn frame(&self, options: &RobotOptions) -> SensorFrame {
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

/// The record of what the robot was told: per cycle, the readings it sent and the answer.
#[derive(Debug, Clone, Default)]
struct Record {
    rows: Vec<String>,
}

impl Record {
    fn header() -> String {
        let mut out = String::from("cycle");
        for prefix in ["reading", "position", "stiffness"] {
            for name in JOINT_NAMES {
                out.push_str(&format!(",{prefix}_{name}"));
            }
        }
        out
    }

    fn push(&mut self, cycle: u64, readings: &[f32; JOINTS], answer: &ActuatorMessage) {
        let mut row = cycle.to_string();
        for values in [readings, &answer.position, &answer.stiffness] {
            for v in values {
                row.push_str(&format!(",{v}"));
            }
        }
        self.rows.push(row);
    }

    fn write(&self, path: &Path) -> Result<(), RobotError> {
        let mut text = Record::header();
        text.push('\n');
        for r in &self.rows {
            text.push_str(r);
            text.push('\n');
        }
        Ok(write_atomic(
            path,
            text.as_bytes(),
            &WriteOptions::new(true),
        )?)
    }
}

/// Writes the state file (atomically, without syncing: it is read at once by [`snap`]).
fn write_state(options: &RobotOptions, body: &Body) -> Result<(), RobotError> {
    let Some(path) = &options.state else {
        return Ok(());
    };
    let state = State {
        config: options.config.clone(),
        truth: options.truth.to_vec(),
        joints: body.joints().0.to_vec(),
        cycle: body.cycle,
        seed: options.seed,
    };
    let bytes = serde_json::to_vec(&state).expect("a state always encodes");
    Ok(write_atomic_unsynced(
        path,
        &bytes,
        &WriteOptions::new(true),
    )?)
}

/// How a client's session ended.
enum Session {
    /// The client went away.
    Gone,
    /// The robot dropped the connection (fault): exit.
    Dropped,
}

/// A socket listening at `socket` that appears there only once it listens (bound under a
/// name of its own beside it, then renamed): a client that sees the path never finds it
/// refusing. A file already at `socket` is refused, as binding there would be.
fn listen(socket: &Path) -> std::io::Result<UnixListener> {
    let name = socket.file_name().unwrap_or_default().to_string_lossy();
    let bound = socket.with_file_name(format!(".{name}.{}.binding", std::process::id()));
    let listener = UnixListener::bind(&bound)?;
    let placed = if socket.symlink_metadata().is_ok() {
        Err(std::io::Error::from(std::io::ErrorKind::AddrInUse))
    } else {
        std::fs::rename(&bound, socket)
    };
    if let Err(e) = placed {
        let _ = std::fs::remove_file(&bound);
        return Err(e);
    }
    Ok(listener)
}

/// Serves LoLA at `socket` until the clients are served, a dropped-connection fault or
/// SIGTERM, SIGINT or SIGHUP (the record and the state written in every case but an
/// error); returns the cycles run.
pub fn serve(socket: &Path, options: &RobotOptions) -> Result<u64, RobotError> {
    if let Ok(meta) = socket.symlink_metadata() {
        use std::os::unix::fs::FileTypeExt;
        if meta.file_type().is_socket() {
            let _ = std::fs::remove_file(socket);
        }
    }
    let listener = listen(socket).map_err(|source| RobotError::Bind {
        path: socket.to_path_buf(),
        source,
    })?;
    let motors = motors();
    let dropped = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    if options.faults.drop_on_signal {
        signal_hook::flag::register(signal_hook::consts::SIGUSR1, dropped.clone())?;
    }
    // SIGTERM, SIGINT or SIGHUP end the robot as its last client would: the record and
    // the state are written, whether a client is served or awaited.
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    for signal in [
        signal_hook::consts::SIGTERM,
        signal_hook::consts::SIGINT,
        signal_hook::consts::SIGHUP,
    ] {
        signal_hook::flag::register(signal, stop.clone())?;
    }
    let mut body = Body::new(options);
    let mut record = Record::default();
    write_state(options, &body)?;
    let mut result = Ok(());
    listener.set_nonblocking(true)?;
    'clients: for _ in 0..options.clients.max(1) {
        let stream = loop {
            if stop.load(std::sync::atomic::Ordering::Relaxed) {
                break 'clients;
            }
            match listener.accept() {
                Ok((s, _)) => break s,
                Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                    std::thread::sleep(Duration::from_millis(5))
                }
                Err(e) => {
                    result = Err(e.into());
                    break 'clients;
                }
            }
        };
        stream.set_nonblocking(false)?;
        match session(
            stream,
            options,
            &motors,
            &mut body,
            &mut record,
            &dropped,
            &stop,
        ) {
            Ok(Session::Gone) => {}
            Ok(Session::Dropped) => break,
            Err(e) => {
                result = Err(e);
                break;
            }
        }
        // LoLA without a client keeps the last command: a robot whose client was killed
        // mid-stance stays stiff where it was told, and the next client finds it so.
    }
    let _ = std::fs::remove_file(socket);
    if let Some(path) = &options.record {
        record.write(path)?;
    }
    write_state(options, &body)?;
    result.map(|()| body.cycle)
}

/// One client's session, cycle by cycle.
fn session(
    stream: UnixStream,
    options: &RobotOptions,
    motors: &[usize],
    body: &mut Body,
    record: &mut Record,
    dropped: &std::sync::atomic::AtomicBool,
    stop: &std::sync::atomic::AtomicBool,
) -> Result<Session, RobotError> {
    let period = if options.speed > 0.0 {
        Some(lola::CYCLE.div_f64(options.speed))
    } else {
        None
    };
    stream.set_read_timeout(Some(Duration::from_secs(2)))?;
    stream.set_write_timeout(Some(Duration::from_millis(100)))?;
    let mut writer = stream.try_clone()?;
    let mut reader = BufReader::new(stream);
    let mut next = Instant::now();
    let mut last_state = body.joints();
    let mut silent = false;
    // A client that stopped reading (after a message that did not parse it ramps the
    // stiffness down blind): the robot only listens.
    let mut deaf = false;
    loop {
        if options.faults.drop_after.is_some_and(|n| body.cycle >= n)
            || dropped.load(std::sync::atomic::Ordering::Relaxed)
            || stop.load(std::sync::atomic::Ordering::Relaxed)
        {
            return Ok(Session::Dropped);
        }
        if options.faults.silent_after.is_some_and(|n| body.cycle >= n) {
            silent = true;
        }
        let frame = body.frame(options);
        if !silent && !deaf {
            let bytes = if options.faults.garbage_at == Some(body.cycle) {
                vec![0xc1; 64]
            } else {
                lola::encode(&frame)
            };
            match writer.write_all(&bytes) {
                Ok(()) => {}
                Err(e)
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                    ) =>
                {
                    deaf = true
                }
                Err(_) => return Ok(Session::Gone),
            }
        }
        match lola::decode_from::<ActuatorMessage>(&mut reader, 1, Duration::from_secs(2)) {
            Ok(answer) => {
                record.push(body.cycle, &frame.joints.position, &answer);
                for k in 0..JOINTS {
                    body.command[k] = answer.position[k] as f64;
                    body.stiffness[k] = answer.stiffness[k] as f64;
                }
            }
            Err(LolaError::Closed) => return Ok(Session::Gone),
            Err(LolaError::Silent { .. }) if silent || deaf => return Ok(Session::Gone),
            // A late answer: LoLA goes on with the last command.
            Err(LolaError::Silent { .. }) => {}
            Err(_) => return Ok(Session::Gone),
        }
        body.step(&options.model, motors);
        let joints = body.joints();
        let moved = (joints - last_state).iter().any(|(_, d)| d.abs() > 1e-6);
        if moved || body.cycle.is_multiple_of(50) {
            write_state(options, body)?;
            last_state = joints;
        }
        if let Some(period) = period {
            next += period;
            let now = Instant::now();
            if next > now {
                std::thread::sleep(next - now);
            } else {
                next = now;
            }
        }
    }
}

/// Reads a state file written by a simulated robot.
pub fn read_state(path: &Path) -> Result<State, RobotError> {
    let bytes = std::fs::read(path).map_err(|e| RobotError::Read {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    let state: State = serde_json::from_slice(&bytes).map_err(|e| RobotError::Read {
        path: path.to_path_buf(),
        message: format!("not a simulated robot's state: {e}"),
    })?;
    if state.truth.len() != PARAMETER_COUNT || state.joints.len() != crate::model::JOINT_COUNT {
        return Err(RobotError::Read {
            path: path.to_path_buf(),
            message: "not a simulated robot's state: wrong number of values".into(),
        });
    }
    Ok(state)
}

/// How the simulated robot's camera is set when [`snap`] takes a picture, as a V6 camera
/// is (`simulate-robot snap`'s `--flip`, `--exposure`, `--gain`; `capture` gives them to
/// its `command:` camera as `{flip}`, `{exposure}`, `{gain}`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SnapSettings {
    /// Both sensor flips set. The V6's upper sensor is mounted turned by 180°, so its
    /// picture is upright only flipped, the lower's only unflipped
    /// ([`crate::robot::camera::settings::CameraSettings::defaults`]). False: the
    /// registers as the sensor starts.
    pub flip: bool,
    /// Manual exposure and gain (the driver's units); `None`: automatic exposure (the
    /// scene as rendered).
    pub manual: Option<(u32, u32)>,
}

/// The brightness of the simulated `camera`'s picture relative to the scene as rendered,
/// at manual `exposure` and `gain`: their product over the product of the camera's team
/// settings (rUNSWift's, naocalib's defaults), so that those give the rendered scene —
/// the scene each camera sees is lit as the teams' values expect — and the brightness
/// scales with exposure × gain (a sensor's response, linear until it saturates).
pub fn exposure_factor(camera: CameraId, exposure: u32, gain: u32) -> f64 {
    let team = crate::robot::camera::settings::CameraSettings::defaults(camera, 0, 0);
    (f64::from(exposure) * f64::from(gain)) / (f64::from(team.exposure) * f64::from(team.gain))
}

/// Renders what `camera` of the robot in `state` (read from `state_path`) sees (the sandal
/// in view, the one whose centre is nearest the image centre; the true intrinsics of the
/// lower camera, the `[upper_camera]` ones of the upper), as its sensor set to `settings`
/// gives it — turned by 180° unless flipped as the camera's mounting needs, brightened or
/// darkened by [`exposure_factor`] — and writes it as PNG to `out` (replacing a picture
/// there, never the state file or the `dataset.toml` it names).
pub fn snap(
    state: &State,
    state_path: &Path,
    camera: CameraId,
    settings: &SnapSettings,
    out: &Path,
    options: &RenderOptions,
) -> Result<(), RobotError> {
    let write = WriteOptions::new(true)
        .protecting([state_path.to_path_buf()])
        .protecting(state.config.clone());
    crate::output::check_writable(out, &write)?;
    let model = match &state.config {
        Some(path) => crate::dataset::read_model(path)?,
        None => Model::default(),
    };
    if camera == CameraId::Upper && model.upper_camera.is_none() {
        return Err(RobotError::Read {
            path: state
                .config
                .clone()
                .unwrap_or_else(|| state_path.to_path_buf()),
            message: "names no upper camera ([upper_camera] of dataset.toml): nothing to \
                      render the upper camera's view with"
                .into(),
        });
    }
    let truth: [f64; PARAMETER_COUNT] = std::array::from_fn(|k| state.truth[k]);
    let model = Model {
        camera: model.intrinsics_at(camera, &truth),
        ..model
    };
    let joints = JointAngles::from_fn(|j| state.joints[j.index()]);
    let (cx, cy) = (
        model.camera.width as f64 / 2.0,
        model.camera.height as f64 / 2.0,
    );
    let side = Side::BOTH
        .into_iter()
        .filter_map(|side| {
            let pose = model
                .chains_for(camera, side, &joints)
                .camera_to_board(&truth);
            let uv = model.camera.project(&pose.translation)?;
            model
                .camera
                .contains(uv, 0.0)
                .then(|| (side, (uv[0] - cx).hypot(uv[1] - cy)))
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map_or(Side::Left, |(s, _)| s);
    let pose = model
        .chains_for(camera, side, &joints)
        .camera_to_board(&truth);
    // The noise of the picture follows the posture (to 1e-7 rad) and the camera, not the
    // cycle it is taken in, so that a run gives the same pictures however fast the robot
    // is played.
    let posture = state.joints.iter().fold(0u64, |h, q| {
        (h ^ ((q * 1e7).round() as i64 as u64)).wrapping_mul(0x0100_0000_01B3)
    });
    let seed = state.seed
        ^ posture.wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ (camera as u64).wrapping_mul(0xD1B5_4A32_D192_ED03);
    let view = options
        .body
        .as_ref()
        .map(|body| crate::sim::scene::body_view(&model, body, camera, side, &joints, &truth));
    let mut image = render::render_with(&model, &pose, view.as_ref(), options, seed)?;
    let upright = crate::robot::camera::settings::CameraSettings::defaults(camera, 0, 0).flip;
    if settings.flip != upright {
        image.turn_half();
    }
    if let Some((exposure, gain)) = settings.manual {
        image.expose(exposure_factor(camera, exposure, gain));
    }
    let bytes = image
        .to_png()
        .map_err(|message| render::RenderError::Encode {
            path: out.to_path_buf(),
            message,
        })?;
    write_atomic(out, &bytes, &write)?;
    Ok(())
}

/// The record a robot wrote ([`RobotOptions::record`]): per cycle, the readings it sent,
/// and the positions and stiffnesses it was told, in LoLA's joint order.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordRow {
    /// The cycle.
    pub cycle: u64,
    /// Readings sent (rad).
    pub reading: [f64; JOINTS],
    /// Positions commanded (rad).
    pub position: [f64; JOINTS],
    /// Stiffness commanded.
    pub stiffness: [f64; JOINTS],
}

/// Reads a record file.
pub fn read_record(path: &Path) -> Result<Vec<RecordRow>, RobotError> {
    let text = std::fs::read_to_string(path).map_err(|e| RobotError::Read {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    let bad = |line: usize| RobotError::Read {
        path: path.to_path_buf(),
        message: format!("line {line}: not a record row"),
    };
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate().skip(1) {
        let values: Vec<f64> = line
            .split(',')
            .map(|v| v.parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|_| bad(n + 1))?;
        if values.len() != 1 + 3 * JOINTS {
            return Err(bad(n + 1));
        }
        let part =
            |k: usize| -> [f64; JOINTS] { std::array::from_fn(|i| values[1 + k * JOINTS + i]) };
        out.push(RecordRow {
            cycle: values[0] as u64,
            reading: part(0),
            position: part(1),
            stiffness: part(2),
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn options() -> RobotOptions {
        RobotOptions {
            model: Model::default(),
            config: None,
            truth: [0.0; PARAMETER_COUNT],
            speed: 0.0,
            start: JointAngles::default(),
            lying: Lying::OnBack,
            battery: 0.9,
            state: None,
            record: None,
            faults: Faults::default(),
            clients: 1,
            seed: 1,
        }
    }

    /// The simulated cameras as a V6's: the upper picture upright only flipped, the lower
    /// only unflipped (else turned by 180°); at the team exposure and gain the scene as
    /// rendered, at the old 100 × 32 near black, twice the product twice as bright.
    #[test]
    fn snapped_pictures_obey_the_flip_and_the_exposure() {
        use crate::robot::camera::{decode_grey, settings::Brightness};
        let dir = tempfile::tempdir().unwrap();
        let cfg = dir.path().join("cfg");
        let mut model = Model::default();
        model.upper_camera = Some(model.camera);
        crate::dataset::Dataset::new(&cfg, model)
            .write(&cfg, false)
            .unwrap();
        let state_path = dir.path().join("state.json");
        let state = State {
            config: Some(cfg.join("dataset.toml")),
            truth: vec![0.0; PARAMETER_COUNT],
            joints: vec![0.0; crate::model::JOINT_COUNT],
            cycle: 0,
            seed: 3,
        };
        let mut n = 0;
        let mut snap_with = |camera, flip, manual| {
            n += 1;
            let out = dir.path().join(format!("{n}.png"));
            let settings = SnapSettings { flip, manual };
            snap(
                &state,
                &state_path,
                camera,
                &settings,
                &out,
                &RenderOptions::default(),
            )
            .unwrap();
            decode_grey(&std::fs::read(&out).unwrap()).unwrap().1
        };
        let upright = snap_with(CameraId::Upper, true, None);
        let mut turned = snap_with(CameraId::Upper, false, None);
        assert_ne!(turned, upright);
        turned.reverse();
        assert_eq!(
            turned, upright,
            "unflipped, the upper picture is turned by 180°"
        );
        assert_eq!(snap_with(CameraId::Upper, true, Some((700, 800))), upright);
        let old = Brightness::of_grey(&snap_with(CameraId::Upper, true, Some((100, 32))));
        assert!(
            old.mean < crate::robot::camera::settings::DARK_MEAN,
            "{old:?}"
        );
        let team = Brightness::of_grey(&upright).mean;
        assert!(team > 60.0 && team < 200.0, "{team}");
        let lower = snap_with(CameraId::Lower, false, Some((1700, 250)));
        let mut flipped = snap_with(CameraId::Lower, true, Some((850, 250)));
        flipped.reverse();
        for (half, full) in flipped.iter().zip(&lower) {
            assert!((f64::from(*half) - f64::from(*full) / 2.0).abs() <= 0.5 + 1e-9);
        }
        assert!((exposure_factor(CameraId::Upper, 1400, 800) - 2.0).abs() < 1e-12);
    }

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

    #[test]
    fn the_socket_appears_listening_and_never_replaces_a_file() {
        let dir = tempfile::tempdir().unwrap();
        let socket = dir.path().join("lola.sock");
        let listener = listen(&socket).unwrap();
        // At once connectable: it was listening before it had its name.
        let client = std::os::unix::net::UnixStream::connect(&socket).unwrap();
        assert!(listener.accept().is_ok());
        drop(client);
        let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(names.len(), 1, "only the socket: {names:?}");
        let file = dir.path().join("notes.txt");
        std::fs::write(&file, "kept").unwrap();
        assert!(listen(&file).is_err());
        assert_eq!(std::fs::read_to_string(&file).unwrap(), "kept");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
    }
}
