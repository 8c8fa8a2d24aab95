//! NomadZ: `Config/Robots/<robot>/jointCalibration.cfg`, one entry per joint in B-Human's
//! joint order (NomadZ descends from B-Human 2013):
//!
//! ```text
//! lKneePitch = {offset = -0.178186; minAngle = -5; maxAngle = 120; jointPlay = 2.63675;};
//! ```
//!
//! `offset`, `minAngle`, `maxAngle` and `jointPlay` are in degrees (NomadZ
//! `Config/Robots/Default/jointCalibration.cfg`). The offset is added to requested angles
//! and subtracted from measured ones (B-Human's rule, naocalib's too). `jointPlay` is the
//! full width of the joint's play (backlash): naocalib's play family, parameter
//! `<Joint>Play`, looked up in the registry by name — a joint without such a parameter,
//! or one whose play was held fixed at zero, gets 0. The joint limits are NomadZ's
//! defaults, which naocalib does not estimate.

use std::fmt::Write as _;
use std::path::Path;

use super::bhuman::BHUMAN_JOINTS;
use super::{Calibration, ExportError, header, num, parse_error};
use crate::model::Param;

/// NomadZ's default `(minAngle, maxAngle)` (deg) of each joint, in [`BHUMAN_JOINTS`]
/// order.
pub const LIMITS_DEG: [(f64, f64); 26] = [
    (-120.0, 120.0),
    (-40.0, 30.0),
    (-120.0, 120.0),
    (0.0, 90.0),
    (-120.0, 120.0),
    (-90.0, 0.0),
    (-104.5, 104.5),
    (0.0, 0.0),
    (-120.0, 120.0),
    (-80.0, 20.0),
    (-120.0, 120.0),
    (0.0, 90.0),
    (-104.5, 104.5),
    (0.0, 0.0),
    (-65.0, 43.0),
    (-21.0, 45.0),
    (-92.0, 21.0),
    (-5.0, 120.0),
    (-68.0, 52.0),
    (-23.0, 44.0),
    (-65.0, 43.0),
    (-45.0, 21.0),
    (-92.0, 21.0),
    (-5.0, 120.0),
    (-68.0, 52.0),
    (-44.0, 23.0),
];

/// The naocalib play parameter of the joint whose offset is `offset` (`LKneePitch` →
/// `LKneePitchPlay`), looked up by name in the registry.
pub fn play_param(offset: Param) -> Option<Param> {
    Param::from_name(&format!("{}Play", offset.name()))
}

/// One joint as NomadZ reads it (deg).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointEntry {
    /// The offset.
    pub offset: f64,
    /// The lower limit.
    pub min_angle: f64,
    /// The upper limit.
    pub max_angle: f64,
    /// The full width of the play.
    pub joint_play: f64,
}

/// The `jointCalibration.cfg` of `cal`.
pub fn joint_calibration_cfg(cal: &Calibration) -> String {
    let mut s = String::new();
    header(
        &mut s,
        "//",
        cal,
        "offset, minAngle, maxAngle and jointPlay in degrees; jointPlay is the full width \
         of the play",
    );
    for ((name, param), (min, max)) in BHUMAN_JOINTS.iter().zip(LIMITS_DEG) {
        let entry = param.and_then(|p| cal.get(p));
        let play = param.and_then(play_param).and_then(|p| cal.get(p));
        let mut notes = Vec::new();
        match entry {
            Some(e) => notes.push(format!("offset {}", e.describe())),
            None => notes.push("offset not calibrated".into()),
        }
        if let Some(p) = play {
            notes.push(format!("play {}", p.describe()));
        }
        let _ = writeln!(
            s,
            "{name} = {{offset = {}; minAngle = {}; maxAngle = {}; jointPlay = {};}}; // {}",
            num(entry.map_or(0.0, |e| e.value)),
            num(min),
            num(max),
            num(play.map_or(0.0, |e| e.value)),
            notes.join("; ")
        );
    }
    s
}

/// Reads back a [`joint_calibration_cfg`] file: NomadZ joint name → entry.
pub fn read_joint_calibration_cfg(
    text: &str,
    path: &Path,
) -> Result<Vec<(String, JointEntry)>, ExportError> {
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let code = line.split("//").next().unwrap_or("").trim();
        if code.is_empty() {
            continue;
        }
        let at = |m: String| parse_error(path, format!("line {}: {m}", n + 1));
        let (name, rest) = code
            .split_once('=')
            .ok_or_else(|| at("expected `joint = {…};`".into()))?;
        let name = name.trim().to_string();
        let inner = rest
            .trim()
            .strip_prefix('{')
            .and_then(|r| r.trim_end().strip_suffix("};"))
            .ok_or_else(|| at(format!("{name}: expected {{…}};")))?;
        let field = |key: &str| -> Result<f64, ExportError> {
            inner
                .split(';')
                .filter_map(|part| part.split_once('='))
                .find(|(k, _)| k.trim() == key)
                .ok_or_else(|| at(format!("{name}.{key}: missing")))
                .and_then(|(_, v)| {
                    v.trim()
                        .parse()
                        .map_err(|_| at(format!("{name}.{key}: '{}' is not a number", v.trim())))
                })
        };
        let entry = JointEntry {
            offset: field("offset")?,
            min_angle: field("minAngle")?,
            max_angle: field("maxAngle")?,
            joint_play: field("jointPlay")?,
        };
        out.push((name, entry));
    }
    Ok(out)
}
