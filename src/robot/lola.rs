//! LoLA, the NAO V6's low-level interface: its messages, its joint order, and the framing.
//!
//! LoLA serves a Unix stream socket (`/tmp/robocup`). In every 12 ms cycle it writes one
//! MessagePack map of sensor readings ([`SensorFrame`], 896 bytes on a V6), and the client
//! answers with one map of actuator commands ([`ActuatorMessage`]: `Position` and
//! `Stiffness`, 25 values each). The layout below was checked against two public clients:
//!
//! - HULKs (`HULKs/hulk` 27921c5d), `crates/hula_types/src/robot_state.rs` lines 7–31
//!   (`RobotState`: the keys and `[f32; N]` arrays, `RobotConfig` four strings) and
//!   `crates/hula_types/src/lola.rs` lines 5–28 (`LolaControlFrame`), and
//!   `services/hula/src/proxy.rs` lines 170–171 (LoLA's message read as 896 bytes) and
//!   226 (the answer written with `rmp_serde::encode::write_named`, a map with string keys);
//! - ijnek/nao_lola (0fd9c77), `include/nao_lola/lola_enums.hpp` lines 25–53 (the 25 joints in LoLA's
//!   order), `include/nao_lola/connection.hpp` line 23 (`MSGPACK_READ_LENGTH 896`),
//!   `src/connection.cpp` line 18 (`/tmp/robocup`) and `src/msgpack_packer.cpp` lines
//!   31–37 (the answer holds only the keys it sets, e.g. `Position` and `Stiffness`).
//!
//! With every array at its length, `Status` as small integers and the four `RobotConfig`
//! strings of a V6 (20-character ids, `6.0.0` versions), the sensor map is exactly 896
//! bytes ([`SENSOR_MESSAGE_BYTES`], checked by a test). naocalib does not rely on the size:
//! it decodes one MessagePack value after the other from the stream.
//!
//! There is one HipYawPitch motor (LoLA index 7, `LHipYawPitch`); naocalib's
//! `RHipYawPitch` reads and commands the same motor.

use std::io::{BufRead, BufReader, Read, Write};
use std::os::unix::net::UnixStream;
use std::path::Path;
use std::time::Duration;

use serde::{Deserialize, Serialize};

use crate::model::{Joint, JointAngles};

/// The socket LoLA serves on a NAO V6.
pub const DEFAULT_SOCKET: &str = "/tmp/robocup";

/// One LoLA cycle: 12 ms (83 Hz).
pub const CYCLE: Duration = Duration::from_millis(12);

/// Seconds per LoLA cycle.
pub const CYCLE_S: f64 = 0.012;

/// Number of joints in LoLA's arrays.
pub const JOINTS: usize = 25;

/// The size of a V6's sensor message in bytes (see the module documentation).
pub const SENSOR_MESSAGE_BYTES: usize = 896;

/// LoLA's joints in the order of its `Position`, `Stiffness`, `Temperature`, `Current` and
/// `Status` arrays (nao_lola `lola_enums.hpp` lines 25–53; HULKs `lola.rs` `JointsArray`).
pub const JOINT_NAMES: [&str; JOINTS] = [
    "HeadYaw",
    "HeadPitch",
    "LShoulderPitch",
    "LShoulderRoll",
    "LElbowYaw",
    "LElbowRoll",
    "LWristYaw",
    "LHipYawPitch",
    "LHipRoll",
    "LHipPitch",
    "LKneePitch",
    "LAnklePitch",
    "LAnkleRoll",
    "RHipRoll",
    "RHipPitch",
    "RKneePitch",
    "RAnklePitch",
    "RAnkleRoll",
    "RShoulderPitch",
    "RShoulderRoll",
    "RElbowYaw",
    "RElbowRoll",
    "RWristYaw",
    "LHand",
    "RHand",
];

/// LoLA's index of a measured joint (`RHipYawPitch` is the one HipYawPitch motor, index 7).
pub fn index(joint: Joint) -> usize {
    match joint {
        Joint::RHipYawPitch => 7,
        j => JOINT_NAMES
            .iter()
            .position(|n| *n == j.name())
            .expect("every measured joint but RHipYawPitch is a LoLA joint"),
    }
}

/// The measured joints' values from one of LoLA's 25-value arrays (both HipYawPitch
/// angles from the one motor).
pub fn to_joint_angles<T: Copy + Into<f64>>(values: &[T; JOINTS]) -> JointAngles {
    JointAngles::from_fn(|j| values[index(j)].into())
}

/// `base`, one value per LoLA joint, with `f` of each measured joint's value of `joints` in
/// its place (the one HipYawPitch motor gets RHipYawPitch's, the last written).
pub fn put<T>(mut base: [T; JOINTS], joints: &JointAngles, f: impl Fn(f64) -> T) -> [T; JOINTS] {
    for (j, q) in joints.iter() {
        base[index(j)] = f(q);
    }
    base
}

/// A LoLA sensor message as the robot writes it, every key of the V6 (HULKs `lola.rs`
/// lines 5–33): what naocalib reads ([`SensorMessage`], first) and the rest. naocalib's
/// simulated robot writes it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SensorFrame {
    /// The joint arrays, the IMU, the buttons, the motors' status and the battery.
    #[serde(flatten)]
    pub joints: SensorMessage,
    /// Gyroscope (rad/s).
    #[serde(rename = "Gyroscope")]
    pub gyroscope: [f32; 3],
    /// Sonar distances (m).
    #[serde(rename = "Sonar")]
    pub sonar: [f32; 2],
    /// Foot pressure sensors (kg).
    #[serde(rename = "FSR")]
    pub fsr: [f32; 8],
    /// Body id, body version, head id, head version.
    #[serde(rename = "RobotConfig")]
    pub robot_config: [String; 4],
}

/// Index of the chest button in LoLA's `Touch` array (B-Human `NaoProvider.cpp` line 69,
/// `keyMappings[0] = KeyStates::chest`; nao_lola `lola_enums.hpp` line 79,
/// `ChestBoard_Button` first; NaoTH `LolaDataConverter.h` line 255).
pub const CHEST_BUTTON: usize = 0;

/// Index of the charge (0 … 1) in LoLA's `Battery` array: charge, status, current,
/// temperature (B-Human `NaoProvider.cpp` lines 386–395, HULKs `hulk_nao/src/hula.rs`
/// lines 24–29; nao_lola `lola_enums.hpp` line 55 orders the other three differently, all
/// three put the charge first).
pub const BATTERY_CHARGE: usize = 0;

/// What naocalib reads of a sensor message (every array required, at its length; other
/// keys are ignored).
///
/// The IMU as LoLA gives it: `Accelerometer` reads gravity itself, not the floor's push,
/// so about (0, 0, −9.81) m/s² when the robot stands upright — B-Human negates it on
/// reading (`NaoProvider.cpp` lines 294–295, `acc *= -1`), HULKs too
/// (`hulk_nao/src/hula.rs` line 69, `linear_acceleration: -accelerometer`), after which
/// upright is (0, 0, +g) and lying on the back, face up, (+g, 0, 0) (HULKs
/// `fall_state_estimation.rs` lines 110–121, `gravitational_force_up` is `FacingUp`); so
/// a V6 on its back reads about (−9.81, 0, 0) here. `Angles` are the torso's roll and
/// pitch (rad), pitch positive leaning forward (nao_lola `Angle.msg`: "Forward is positive
/// angle, Backwards is negative"; B-Human `FallEngine.cpp` line 66: falling back is
/// `angle.y() < 0`): about (0, −π/2) on the back.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SensorMessage {
    /// Stiffness of each joint, 0 … 1.
    #[serde(rename = "Stiffness")]
    pub stiffness: [f32; JOINTS],
    /// Joint angle readings (rad), raw: no calibration applied.
    #[serde(rename = "Position")]
    pub position: [f32; JOINTS],
    /// Motor temperatures (°C).
    #[serde(rename = "Temperature")]
    pub temperature: [f32; JOINTS],
    /// Motor currents (A).
    #[serde(rename = "Current")]
    pub current: [f32; JOINTS],
    /// Battery: charge (0 … 1), status, current, temperature ([`BATTERY_CHARGE`]).
    #[serde(rename = "Battery")]
    pub battery: [f32; 4],
    /// Accelerometer (m/s²), gravity as LoLA reads it (see above).
    #[serde(rename = "Accelerometer")]
    pub accelerometer: [f32; 3],
    /// Torso roll and pitch (rad).
    #[serde(rename = "Angles")]
    pub angles: [f32; 2],
    /// Buttons and touch sensors, 0 or 1 ([`CHEST_BUTTON`] first).
    #[serde(rename = "Touch")]
    pub touch: [f32; 14],
    /// Temperature status of each motor: 0 normal, 1 hot (the firmware starts reducing
    /// its stiffness), 2 very hot (stiffness reduced by over 30 %), 3 critical (stiffness
    /// 0) (nao_lola `JointStatuses.msg` lines 1–5). LoLA writes small integers (B-Human
    /// `NaoProvider.cpp` line 401); a float is read as well (nao_lola
    /// `msgpack_parser.cpp` line 144 reads them as floats).
    #[serde(rename = "Status", deserialize_with = "statuses")]
    pub status: [i32; JOINTS],
}

/// Reads `Status`, integers or floats.
fn statuses<'de, D: serde::Deserializer<'de>>(d: D) -> Result<[i32; JOINTS], D::Error> {
    let values = <[f64; JOINTS]>::deserialize(d)?;
    Ok(values.map(|v| {
        if v.is_finite() {
            v.round() as i32
        } else {
            i32::MAX
        }
    }))
}

impl SensorMessage {
    /// A limp robot lying on its back, its joints at `position`, temperatures 35 °C, a full
    /// battery, nothing pressed.
    pub fn on_back(position: [f32; JOINTS]) -> SensorMessage {
        SensorMessage {
            stiffness: [0.0; JOINTS],
            position,
            temperature: [35.0; JOINTS],
            current: [0.0; JOINTS],
            battery: [0.9, 0.0, -0.5, 30.0],
            accelerometer: [-9.81, 0.0, 0.0],
            angles: [0.0, -std::f32::consts::FRAC_PI_2],
            touch: [0.0; 14],
            status: [0; JOINTS],
        }
    }

    /// The measured joints' readings (rad).
    pub fn joints(&self) -> JointAngles {
        to_joint_angles(&self.position)
    }
}

/// The client's answer in a cycle: target angle and stiffness of every joint (a map with
/// the keys `Position` and `Stiffness`; LoLA keeps its LEDs as they are).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ActuatorMessage {
    /// Target joint angles (rad).
    #[serde(rename = "Position")]
    pub position: [f32; JOINTS],
    /// Stiffness, 0 … 1.
    #[serde(rename = "Stiffness")]
    pub stiffness: [f32; JOINTS],
}

/// Why talking to LoLA failed.
#[derive(Debug, thiserror::Error)]
pub enum LolaError {
    /// The socket could not be opened.
    #[error("cannot connect to LoLA at {path}: {source} (is LoLA running, and no other client?)")]
    Connect {
        /// The socket path.
        path: String,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// The robot closed the connection.
    #[error("LoLA closed the connection")]
    Closed,
    /// No message came for the given number of cycles.
    #[error("no message from LoLA for {cycles} cycles ({ms} ms)")]
    Silent {
        /// Cycles waited.
        cycles: u32,
        /// Milliseconds waited.
        ms: u64,
    },
    /// A message did not parse.
    #[error("a LoLA message does not parse: {0}")]
    Parse(String),
    /// Reading or writing the socket failed.
    #[error("LoLA socket: {0}")]
    Io(#[from] std::io::Error),
}

/// Encodes an actuator or sensor message as LoLA does: a MessagePack map with string keys.
pub fn encode<T: Serialize>(message: &T) -> Vec<u8> {
    rmp_serde::to_vec_named(message).expect("LoLA messages always encode")
}

/// Reads one MessagePack value of type `T` from `reader`.
pub fn decode_from<T: serde::de::DeserializeOwned>(
    reader: &mut impl Read,
    silent_cycles: u32,
    timeout: Duration,
) -> Result<T, LolaError> {
    use rmp_serde::decode::Error as E;
    rmp_serde::from_read(reader).map_err(|e| {
        let io = match &e {
            E::InvalidMarkerRead(io) | E::InvalidDataRead(io) => Some(io.kind()),
            _ => None,
        };
        match io {
            Some(std::io::ErrorKind::UnexpectedEof) => LolaError::Closed,
            Some(std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut) => {
                LolaError::Silent {
                    cycles: silent_cycles,
                    ms: timeout.as_millis() as u64,
                }
            }
            Some(std::io::ErrorKind::ConnectionReset) => LolaError::Closed,
            _ => LolaError::Parse(e.to_string()),
        }
    })
}

/// The robot, cycle by cycle: what a capture run talks to.
pub trait Link {
    /// The next sensor message (blocks until it comes).
    fn receive(&mut self) -> Result<SensorMessage, LolaError>;
    /// Answers the last sensor message.
    fn send(&mut self, message: &ActuatorMessage) -> Result<(), LolaError>;
    /// Reads and drops whatever the robot has sent without waiting (when its messages
    /// cannot be trusted any more, so that closing leaves nothing unread: an unread
    /// message would make the robot's end of a Unix socket see a reset).
    fn drain(&mut self) {}
}

/// A link whose next message is one already read (by the checks before a run), then the
/// link's own.
pub struct Replay<'a> {
    first: Option<SensorMessage>,
    link: &'a mut dyn Link,
}

impl<'a> Replay<'a> {
    /// `link`, its next message `first`.
    pub fn new(first: SensorMessage, link: &'a mut dyn Link) -> Replay<'a> {
        Replay {
            first: Some(first),
            link,
        }
    }
}

impl Link for Replay<'_> {
    fn receive(&mut self) -> Result<SensorMessage, LolaError> {
        match self.first.take() {
            Some(m) => Ok(m),
            None => self.link.receive(),
        }
    }

    fn send(&mut self, message: &ActuatorMessage) -> Result<(), LolaError> {
        self.link.send(message)
    }

    fn drain(&mut self) {
        self.link.drain()
    }
}

/// A connection to LoLA over its Unix socket.
#[derive(Debug)]
pub struct Connection {
    reader: BufReader<UnixStream>,
    writer: UnixStream,
    silent_cycles: u32,
    timeout: Duration,
}

impl Connection {
    /// Connects to LoLA at `path`; a message that does not come within `silent_cycles`
    /// cycles of 12 ms is an error ([`LolaError::Silent`]).
    pub fn connect(path: &Path, silent_cycles: u32) -> Result<Connection, LolaError> {
        let stream = UnixStream::connect(path).map_err(|source| LolaError::Connect {
            path: path.display().to_string(),
            source,
        })?;
        let timeout = CYCLE * silent_cycles.max(1);
        stream.set_read_timeout(Some(timeout))?;
        stream.set_write_timeout(Some(timeout))?;
        let writer = stream.try_clone()?;
        Ok(Connection {
            reader: BufReader::with_capacity(4 * SENSOR_MESSAGE_BYTES, stream),
            writer,
            silent_cycles,
            timeout,
        })
    }
}

impl Link for Connection {
    fn receive(&mut self) -> Result<SensorMessage, LolaError> {
        decode_from(&mut self.reader, self.silent_cycles, self.timeout)
    }

    fn send(&mut self, message: &ActuatorMessage) -> Result<(), LolaError> {
        match self.writer.write_all(&encode(message)) {
            Ok(()) => Ok(()),
            Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Err(LolaError::Closed),
            Err(e) => Err(e.into()),
        }
    }

    fn drain(&mut self) {
        let stream = self.reader.get_ref();
        if stream.set_nonblocking(true).is_err() {
            return;
        }
        let _ = self
            .reader
            .fill_buf()
            .map(|b| b.len())
            .map(|n| self.reader.consume(n));
        let mut scratch = [0u8; 4096];
        while matches!(self.reader.get_mut().read(&mut scratch), Ok(n) if n > 0) {}
        let _ = self.reader.get_ref().set_nonblocking(false);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v6_frame() -> SensorFrame {
        let mut joints = SensorMessage::on_back(std::array::from_fn(|k| 0.01 * k as f32));
        joints.current = [0.01; JOINTS];
        SensorFrame {
            joints,
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

    /// The frame as a map of its keys.
    fn as_map(frame: &SensorFrame) -> std::collections::BTreeMap<String, serde_json::Value> {
        rmp_serde::from_slice(&encode(frame)).unwrap()
    }

    #[test]
    fn the_imu_buttons_status_and_battery_are_read() {
        let mut frame = v6_frame();
        frame.joints.touch[CHEST_BUTTON] = 1.0;
        frame.joints.status[9] = 2;
        let m: SensorMessage = decode_from(&mut &encode(&frame)[..], 1, CYCLE).unwrap();
        assert_eq!(m, frame.joints);
        assert_eq!(m.accelerometer, [-9.81, 0.0, 0.0]);
        assert_eq!(m.battery[BATTERY_CHARGE], 0.9);
        // Status as floats (as nao_lola reads it) is read as well.
        let mut map = as_map(&frame);
        map.insert(
            "Status".into(),
            serde_json::json!(
                (0..JOINTS)
                    .map(|k| if k == 9 { 2.0 } else { 0.0 })
                    .collect::<Vec<f64>>()
            ),
        );
        let m: SensorMessage = decode_from(&mut &encode(&map)[..], 1, CYCLE).unwrap();
        assert_eq!(m.status, frame.joints.status);
    }

    #[test]
    fn a_v6_sensor_message_has_the_size_lola_writes() {
        let bytes = encode(&v6_frame());
        assert_eq!(bytes.len(), SENSOR_MESSAGE_BYTES);
    }

    #[test]
    fn the_client_reads_what_the_robot_writes() {
        let frame = v6_frame();
        let mut bytes = encode(&frame);
        bytes.extend(encode(&frame));
        let mut reader = &bytes[..];
        for _ in 0..2 {
            let m: SensorMessage = decode_from(&mut reader, 1, CYCLE).unwrap();
            assert_eq!(m.position, frame.joints.position);
            assert_eq!(
                m.joints().get(Joint::RHipYawPitch),
                frame.joints.position[7] as f64
            );
            assert_eq!(
                m.joints().get(Joint::RAnkleRoll),
                frame.joints.position[17] as f64
            );
        }
        let end = decode_from::<SensorMessage>(&mut reader, 1, CYCLE).unwrap_err();
        assert!(matches!(end, LolaError::Closed), "{end}");
    }

    #[test]
    fn a_message_without_positions_or_with_short_arrays_does_not_parse() {
        #[derive(Serialize)]
        struct Partial {
            #[serde(rename = "Stiffness")]
            stiffness: Vec<f32>,
        }
        let bytes = encode(&Partial {
            stiffness: vec![0.0; JOINTS],
        });
        let e = decode_from::<SensorMessage>(&mut &bytes[..], 1, CYCLE).unwrap_err();
        assert!(matches!(e, LolaError::Parse(_)), "{e}");
        // Every array is needed: without the accelerometer, how the robot lies is unknown.
        let mut map = as_map(&v6_frame());
        map.remove("Accelerometer");
        let bytes = encode(&map);
        let e = decode_from::<SensorMessage>(&mut &bytes[..], 1, CYCLE).unwrap_err();
        assert!(matches!(e, LolaError::Parse(_)), "{e}");
        let mut frame = encode(&v6_frame());
        let at = frame.windows(9).position(|w| w == b"\xa8Position").unwrap();
        assert_eq!(frame[at + 9], 0xdc, "an array of 25");
        frame[at + 9] = 0xc1; // never used in MessagePack
        let e = decode_from::<SensorMessage>(&mut &frame[..], 1, CYCLE).unwrap_err();
        assert!(matches!(e, LolaError::Parse(_)), "{e}");
    }

    #[test]
    fn the_answer_is_a_map_of_position_and_stiffness() {
        let m = ActuatorMessage {
            position: [0.5; JOINTS],
            stiffness: [1.0; JOINTS],
        };
        let bytes = encode(&m);
        assert_eq!(bytes[0], 0x82, "a map of two entries");
        assert_eq!(&bytes[1..10], b"\xa8Position");
        let back: ActuatorMessage = decode_from(&mut &bytes[..], 1, CYCLE).unwrap();
        assert_eq!(back, m);
    }

    #[test]
    fn joint_indices_follow_lola() {
        assert_eq!(index(Joint::HeadYaw), 0);
        assert_eq!(index(Joint::LHipYawPitch), 7);
        assert_eq!(index(Joint::RHipYawPitch), 7);
        assert_eq!(index(Joint::LAnkleRoll), 12);
        assert_eq!(index(Joint::RHipRoll), 13);
        assert_eq!(index(Joint::RAnkleRoll), 17);
    }
}
