//! HULKs (Rust): the per-head and per-body parameter JSON files (`etc/parameters/
//! head.<id>.json`, `body.<id>.json`), which HULKs merges over its defaults. Radians.
//!
//! - Head: `camera_matrix_parameters.calibration.correction_in_camera_bottom = [x, y, z]`,
//!   turned into `Rotation3::from_euler_angles(x, y, z)` = `Rz(z) · Ry(y) · Rx(x)` and
//!   applied as `correction_in_camera * head_to_camera` (HULKs
//!   `crates/projection/src/camera_matrix.rs`, `CameraMatrix::to_corrected`), where
//!   `head_to_camera = Rx(−pitch) · Ry(−π/2) · Rx(π/2) · T(−p)` maps the head frame into
//!   an optical camera frame (z forward, x right, y down; HULKs
//!   `crates/control/src/camera_matrix_calculator.rs`), a camera looking down having a
//!   negative pitch (HULKs `crates/projection/tests/projection.rs`), here −39.7°. [`super::camera::hulks`] solves
//!   that for naocalib's rotation exactly; for small angles `x ≈ CamPitch`,
//!   `y ≈ CamYaw`, `z ≈ −CamRoll` (the optical frame's axes are others).
//! - Body: `joint_calibration_offsets.{head,left_leg,right_leg}.<joint>` in radians
//!   (`hip_yaw_pitch`, `hip_roll`, `hip_pitch`, `knee_pitch`, `ankle_pitch`,
//!   `ankle_roll`; head `yaw`, `pitch`), added to commands and subtracted from sensor
//!   readings as naocalib's compensation rule says.
//!
//! JSON has no comments: the units and the compensation rule are in the docs; a result
//! that is not a calibration gets a top-level `naocalib_not_a_calibration` key, which
//! HULKs does not know and so refuses to load.

use std::collections::BTreeMap;
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::{Calibration, ExportError, parse_error};
use crate::model::{Param, Side};

/// HULKs' name of each leg joint, in naocalib's leg order.
pub const LEG_JOINTS: [&str; 6] = [
    "hip_yaw_pitch",
    "hip_roll",
    "hip_pitch",
    "knee_pitch",
    "ankle_pitch",
    "ankle_roll",
];

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct HeadFile {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    naocalib_not_a_calibration: Option<Vec<String>>,
    camera_matrix_parameters: CameraMatrixParameters,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraMatrixParameters {
    calibration: CameraCalibration,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraCalibration {
    correction_in_camera_bottom: [f64; 3],
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct BodyFile {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    naocalib_not_a_calibration: Option<Vec<String>>,
    joint_calibration_offsets: BTreeMap<String, BTreeMap<String, f64>>,
}

fn marker(cal: &Calibration) -> Option<Vec<String>> {
    let problems = cal.problems();
    (!problems.is_empty()).then_some(problems)
}

fn pretty(value: &impl Serialize) -> String {
    let mut s = serde_json::to_string_pretty(value).expect("JSON of plain values");
    s.push('\n');
    s
}

/// The per-head JSON: the lower camera's correction `[x, y, z]` (rad).
pub fn head_json(cal: &Calibration) -> String {
    pretty(&HeadFile {
        naocalib_not_a_calibration: marker(cal),
        camera_matrix_parameters: CameraMatrixParameters {
            calibration: CameraCalibration {
                correction_in_camera_bottom: super::camera::hulks(cal),
            },
        },
    })
}

/// The leg (and head, when estimated) joint offsets of `cal` by HULKs group and name
/// (rad); joints whose offsets are absent are left out (HULKs keeps its default).
fn offsets(cal: &Calibration) -> BTreeMap<String, BTreeMap<String, f64>> {
    let mut out: BTreeMap<String, BTreeMap<String, f64>> = BTreeMap::new();
    for side in [Side::Left, Side::Right] {
        let group = match side {
            Side::Left => "left_leg",
            Side::Right => "right_leg",
        };
        for (joint, name) in side.leg_joints().iter().zip(LEG_JOINTS) {
            if let Some(e) = cal.get(joint.offset()) {
                out.entry(group.into())
                    .or_default()
                    .insert(name.into(), e.value.to_radians());
            }
        }
    }
    for (param, name) in [(Param::HeadYaw, "yaw"), (Param::HeadPitch, "pitch")] {
        if let Some(e) = cal.get(param) {
            out.entry("head".into())
                .or_default()
                .insert(name.into(), e.value.to_radians());
        }
    }
    out
}

/// The per-body JSON: `joint_calibration_offsets` (rad).
pub fn body_json(cal: &Calibration) -> String {
    pretty(&BodyFile {
        naocalib_not_a_calibration: marker(cal),
        joint_calibration_offsets: offsets(cal),
    })
}

/// Reads back a [`head_json`] file: the correction `[x, y, z]` (rad).
pub fn read_head_json(text: &str, path: &Path) -> Result<[f64; 3], ExportError> {
    let file: HeadFile = serde_json::from_str(text)
        .map_err(|e| parse_error(path, format!("line {}: {e}", e.line())))?;
    Ok(file
        .camera_matrix_parameters
        .calibration
        .correction_in_camera_bottom)
}

/// Reads back a [`body_json`] file: each offset by naocalib parameter (rad).
pub fn read_body_json(text: &str, path: &Path) -> Result<Vec<(Param, f64)>, ExportError> {
    let file: BodyFile = serde_json::from_str(text)
        .map_err(|e| parse_error(path, format!("line {}: {e}", e.line())))?;
    let mut out = Vec::new();
    for (group, joints) in file.joint_calibration_offsets {
        for (name, value) in joints {
            let param = match group.as_str() {
                "head" => match name.as_str() {
                    "yaw" => Some(Param::HeadYaw),
                    "pitch" => Some(Param::HeadPitch),
                    _ => None,
                },
                "left_leg" | "right_leg" => {
                    let side = if group == "left_leg" {
                        Side::Left
                    } else {
                        Side::Right
                    };
                    LEG_JOINTS
                        .iter()
                        .position(|n| *n == name)
                        .map(|k| side.leg_joints()[k].offset())
                }
                _ => None,
            };
            let param = param.ok_or_else(|| {
                parse_error(
                    path,
                    format!("joint_calibration_offsets.{group}.{name}: unknown joint"),
                )
            })?;
            out.push((param, value));
        }
    }
    Ok(out)
}
