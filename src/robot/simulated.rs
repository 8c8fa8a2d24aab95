//! A simulated NAO V6, lying on its back, serving LoLA on a Unix socket: for testing
//! `naocalib capture` end to end without a robot.
//!
//! Each cycle it writes a [`SensorFrame`](lola::SensorFrame) and reads the client's [`ActuatorMessage`]
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
//! IMU says so, as LoLA's does ([`imu`](crate::robot::body::imu)).
//!
//! Faults on request ([`Faults`]): a blocked joint, an overheating motor, a connection
//! dropped, the robot falling silent, a message that does not parse, rolling over, the
//! chest button pressed, a motor's status, a low battery. Every actuator
//! message received can be recorded with the client that sent it ([`RobotOptions::record`])
//! so that tests check the safety rules on what the robot was told. Between clients the
//! robot runs on with the last command, as LoLA does.
//!
//! The parts: `body` (the joints, motors and IMU, and the message LoLA writes of them),
//! `record` (what the robot was told), `snap` (its cameras) and [`request`] (what
//! `naocalib simulate-robot` is asked for); the serving loop is here.

use std::io::{BufReader, Write as _};
use std::os::unix::net::{UnixListener, UnixStream};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use crate::model::{Joint, JointAngles, Model, PARAMETER_COUNT};
use crate::output::{WriteOptions, write_atomic_unsynced};
use crate::sim::render;

use super::body::Lying;
use super::lola::{self, ActuatorMessage, JOINTS, LolaError};

mod body;
mod record;
pub mod request;
mod snap;

use body::Body;
use record::Record;
pub use record::{RecordRow, read_record};
pub use snap::{SnapSettings, exposure_factor, snap};

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
    /// The cycle at which that status is gone again (never when `None`).
    pub status_until: Option<u64>,
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
    /// The stiffness commanded now, in LoLA's joint order (empty in a state written before
    /// it was kept).
    #[serde(default)]
    pub stiffness: Vec<f64>,
    /// The arm joints now (rad), in [`crate::body::ARM_JOINTS`] order (empty in a state
    /// written before they were kept: the body drawn with its own arm posture).
    #[serde(default)]
    pub arms: Vec<f64>,
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

/// The LoLA motors that follow their commands: the ones naocalib measures (HipYawPitch
/// once) and the arms'.
fn motors() -> Vec<usize> {
    let mut out: Vec<usize> = Joint::ALL.iter().map(|&j| lola::index(j)).collect();
    out.extend(super::arms::indices());
    out.sort();
    out.dedup();
    out
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
        stiffness: body.stiffness.to_vec(),
        arms: body.arms().0.to_vec(),
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
    let mut last = Last::of(&body);
    let period = period(options);
    'clients: for client in 0..options.clients.max(1) as u32 {
        let mut next = Instant::now();
        let stream = loop {
            if stop.load(std::sync::atomic::Ordering::Relaxed) {
                break 'clients;
            }
            match listener.accept() {
                Ok((s, _)) => break s,
                Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                    // LoLA without a client keeps the last command, cycle by cycle: a
                    // robot whose client was killed mid-stance stays stiff where it was
                    // told, and the next client finds it so.
                    match period.filter(|_| client > 0) {
                        Some(period) => {
                            tick(options, &motors, &mut body, &mut last)?;
                            pace(&mut next, period);
                        }
                        None => std::thread::sleep(Duration::from_millis(5)),
                    }
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
            client,
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
        last = Last::of(&body);
    }
    let _ = std::fs::remove_file(socket);
    if let Some(path) = &options.record {
        record.write(path)?;
    }
    write_state(options, &body)?;
    result.map(|()| body.cycle)
}

/// The wall time of a cycle at the robot's speed; `None` at speed 0 (as fast as the
/// client answers).
fn period(options: &RobotOptions) -> Option<Duration> {
    (options.speed > 0.0).then(|| lola::CYCLE.div_f64(options.speed))
}

/// Sleeps until `next`, the end of this cycle, and moves it on by `period`.
fn pace(next: &mut Instant, period: Duration) {
    *next += period;
    let now = Instant::now();
    if *next > now {
        std::thread::sleep(*next - now);
    } else {
        *next = now;
    }
}

/// The joints and stiffness last written to the state file.
struct Last {
    joints: JointAngles,
    arms: crate::body::ArmPosture,
    stiffness: [f64; JOINTS],
}

impl Last {
    fn of(body: &Body) -> Last {
        Last {
            joints: body.joints(),
            arms: body.arms(),
            stiffness: body.stiffness,
        }
    }
}

/// One cycle of the body; the state written when the joints or the arms moved or the stiffness
/// changed, and every 50 cycles.
fn tick(
    options: &RobotOptions,
    motors: &[usize],
    body: &mut Body,
    last: &mut Last,
) -> Result<(), RobotError> {
    body.step(&options.model, motors);
    let joints = body.joints();
    let moved = (joints - last.joints).iter().any(|(_, d)| d.abs() > 1e-6)
        || super::arms::distance(&body.arms(), &last.arms) > 1e-6;
    if moved || body.stiffness != last.stiffness || body.cycle.is_multiple_of(50) {
        write_state(options, body)?;
        *last = Last::of(body);
    }
    Ok(())
}

/// One client's session (the `client`th, from 0), cycle by cycle.
#[allow(clippy::too_many_arguments)]
fn session(
    stream: UnixStream,
    client: u32,
    options: &RobotOptions,
    motors: &[usize],
    body: &mut Body,
    record: &mut Record,
    dropped: &std::sync::atomic::AtomicBool,
    stop: &std::sync::atomic::AtomicBool,
) -> Result<Session, RobotError> {
    let period = period(options);
    stream.set_read_timeout(Some(Duration::from_secs(2)))?;
    stream.set_write_timeout(Some(Duration::from_millis(100)))?;
    let mut writer = stream.try_clone()?;
    let mut reader = BufReader::new(stream);
    let mut next = Instant::now();
    let mut last = Last::of(body);
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
                record.push(body.cycle, client, &frame.joints.position, &answer);
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
        tick(options, motors, body, &mut last)?;
        if let Some(period) = period {
            pace(&mut next, period);
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

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    pub(crate) fn options() -> RobotOptions {
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
