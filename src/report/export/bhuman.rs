//! B-Human's `cameraCalibration.cfg` (lower camera rotation correction) and
//! `jointCalibration.cfg` (joint offsets), in degrees.
//!
//! Axis mapping, from B-Human's `RobotCameraMatrix::computeRobotCameraMatrix`
//! (`Src/Representations/Perception/ImagePreprocessing/CameraMatrix.cpp`):
//! `rotateY(tiltNeckToLowerCamera + y) · rotateX(x) · rotateZ(z)` in a camera frame with x
//! along the optical axis, y left, z up — naocalib's camera frame and order. So B-Human's
//! x = roll = CamRoll, y = tilt = CamPitch, z = pan = CamYaw, same signs, exactly.
//! Joint offsets: B-Human adds them to requested angles and subtracts them from measured
//! ones, as naocalib's compensation rule says.

use std::fmt::Write as _;
use std::path::Path;

use super::{Calibration, ExportError, header, num, parse_error};
use crate::model::Param;

const UNITS: &str = "angles in degrees (deg)";

/// B-Human's name of each joint, in its `Joints` order (head, left arm, right arm, left
/// leg, right leg), with the naocalib parameter holding its offset, if any.
pub const BHUMAN_JOINTS: [(&str, Option<Param>); 26] = [
    ("headYaw", Some(Param::HeadYaw)),
    ("headPitch", Some(Param::HeadPitch)),
    ("lShoulderPitch", None),
    ("lShoulderRoll", None),
    ("lElbowYaw", None),
    ("lElbowRoll", None),
    ("lWristYaw", None),
    ("lHand", None),
    ("rShoulderPitch", None),
    ("rShoulderRoll", None),
    ("rElbowYaw", None),
    ("rElbowRoll", None),
    ("rWristYaw", None),
    ("rHand", None),
    ("lHipYawPitch", Some(Param::LHipYawPitch)),
    ("lHipRoll", Some(Param::LHipRoll)),
    ("lHipPitch", Some(Param::LHipPitch)),
    ("lKneePitch", Some(Param::LKneePitch)),
    ("lAnklePitch", Some(Param::LAnklePitch)),
    ("lAnkleRoll", Some(Param::LAnkleRoll)),
    ("rHipYawPitch", Some(Param::RHipYawPitch)),
    ("rHipRoll", Some(Param::RHipRoll)),
    ("rHipPitch", Some(Param::RHipPitch)),
    ("rKneePitch", Some(Param::RKneePitch)),
    ("rAnklePitch", Some(Param::RAnklePitch)),
    ("rAnkleRoll", Some(Param::RAnkleRoll)),
];

/// Degrees as B-Human writes angles: `-4.5627deg` (every digit kept: exact read-back).
fn deg(x: f64) -> String {
    format!("{}deg", num(x))
}

/// A B-Human style `cameraCalibration.cfg` block with the lower camera's rotation
/// correction, in degrees:
///
/// ```text
/// lowerCameraRotationCorrection = {x = <CamRoll>deg; y = <CamPitch>deg; z = <CamYaw>deg;};
/// ```
///
/// Mapping: B-Human's camera frame is naocalib's camera frame C (x along the optical axis,
/// y left, z up), and its camera matrix applies the corrections after the fixed tilt as
/// `rotateY(tilt + y) · rotateX(x) · rotateZ(z)` — naocalib's
/// `Ry(tilt) · Ry(α_CamPitch) · Rx(α_CamRoll) · Rz(α_CamYaw)`. So `x = CamRoll`,
/// `y = CamPitch`, `z = CamYaw`, same signs. The upper camera and the body rotation are
/// not calibrated here and are written as zero.
pub fn bhuman_camera_cfg(cal: &Calibration) -> String {
    let mut s = String::new();
    header(&mut s, "//", cal, UNITS);
    let _ = writeln!(
        s,
        "// Mapping: x = CamRoll, y = CamPitch, z = CamYaw (Ry(tilt)·Ry(CamPitch)·Rx(CamRoll)·Rz(CamYaw))."
    );
    let _ = writeln!(
        s,
        "// Only the lower camera is calibrated; the upper camera and body corrections are zero."
    );
    let _ = writeln!(
        s,
        "upperCameraRotationCorrection = {{x = 0deg; y = 0deg; z = 0deg;}};"
    );
    let _ = writeln!(
        s,
        "lowerCameraRotationCorrection = {{x = {}; y = {}; z = {};}};",
        deg(cal.value(Param::CamRoll)),
        deg(cal.value(Param::CamPitch)),
        deg(cal.value(Param::CamYaw))
    );
    let _ = writeln!(s, "bodyRotationCorrection = {{x = 0deg; y = 0deg;}};");
    s
}

/// A B-Human style `jointCalibration.cfg` joint-offset list in degrees, one entry per
/// joint in B-Human's joint order (`offsets = {headYaw = 0deg; …; rAnkleRoll = …deg;};`),
/// with the estimated leg offsets and zero for joints not calibrated (arms; the head unless
/// its offsets were estimated). Sign as naocalib's compensation rule: the value is added to requested
/// angles and subtracted from measured ones.
pub fn bhuman_joint_cfg(cal: &Calibration) -> String {
    let mut s = String::new();
    header(&mut s, "//", cal, UNITS);
    let _ = writeln!(
        s,
        "// One offset per joint in B-Human's joint order; joints not calibrated are 0deg."
    );
    let _ = writeln!(s, "offsets = {{");
    for (name, param) in BHUMAN_JOINTS {
        let entry = param.and_then(|p| cal.get(p));
        let value = entry.map_or(0.0, |e| e.value);
        let note = match entry {
            Some(e) => format!(" // {}", e.describe()),
            None => " // not calibrated".to_string(),
        };
        let _ = writeln!(s, "  {name} = {};{note}", deg(value));
    }
    let _ = writeln!(s, "}};");
    s
}

/// Reads back the lower camera correction of a [`bhuman_camera_cfg`] file: `[x, y, z]`
/// in degrees (CamRoll, CamPitch, CamYaw).
pub fn read_bhuman_camera_cfg(text: &str, path: &Path) -> Result<[f64; 3], ExportError> {
    let line = text
        .lines()
        .find(|l| l.trim_start().starts_with("lowerCameraRotationCorrection"))
        .ok_or_else(|| parse_error(path, "no lowerCameraRotationCorrection"))?;
    let mut out = [f64::NAN; 3];
    for (k, key) in ["x", "y", "z"].iter().enumerate() {
        out[k] = cfg_value(line, key)
            .ok_or_else(|| parse_error(path, format!("lowerCameraRotationCorrection: no {key}")))?;
    }
    Ok(out)
}

/// Reads back the offsets of a [`bhuman_joint_cfg`] file: B-Human joint name → degrees.
pub fn read_bhuman_joint_cfg(text: &str, path: &Path) -> Result<Vec<(String, f64)>, ExportError> {
    let mut out = Vec::new();
    for line in text.lines() {
        let code = line.split("//").next().unwrap_or("").trim();
        let Some((name, rest)) = code.split_once('=') else {
            continue;
        };
        let name = name.trim();
        if name == "offsets" {
            continue;
        }
        let number = rest
            .trim()
            .trim_end_matches(';')
            .trim()
            .trim_end_matches("deg");
        let value: f64 = number.parse().map_err(|_| {
            parse_error(
                path,
                format!("{name}: '{}' is not an angle in deg", rest.trim()),
            )
        })?;
        out.push((name.to_string(), value));
    }
    Ok(out)
}

/// The number after `key = ` in a `{x = 1deg; y = …}` block.
fn cfg_value(line: &str, key: &str) -> Option<f64> {
    let inner = line.split_once('{')?.1;
    inner.split(';').find_map(|part| {
        let (k, v) = part.split_once('=')?;
        (k.trim() == key).then(|| v.trim().trim_end_matches("deg").parse().ok())?
    })
}
