//! NaoTH / Berlin United: `CameraMatrixOffset.cfg`, an INI (GLib key file) section with the
//! lower camera's rotation offsets in radians:
//!
//! ```text
//! [CameraMatrixOffset]
//! cam_rot.bottom.x=<roll>
//! cam_rot.bottom.y=<tilt>
//! cam_rot.bottom.z=<pan>
//! ```
//!
//! NaoTH builds the camera matrix as `… · translate(camera offset) · rotateZ(z) ·
//! rotateY(y + tilt) · rotateX(x)` in a camera frame with x along the optical axis, y left,
//! z up (NaoTH `NaoTHSoccer/Source/Tools/CameraGeometry.cpp`,
//! `CameraGeometry::calculateCameraMatrix`). The pan comes before the tilt, unlike
//! naocalib's order, so [`super::camera::naoth`] solves `Rz(z) · Ry(tilt + y) · Rx(x) =
//! Ry(tilt) · Rc` exactly; for small angles `x ≈ CamRoll`, `y ≈ CamPitch` and `z` mixes
//! CamYaw and CamRoll through the tilt.

use std::fmt::Write as _;
use std::path::Path;

use super::{Calibration, ExportError, Imported, header, num, parse_error};
use crate::model::Param;

/// The INI section NaoTH reads the offsets from.
pub const SECTION: &str = "CameraMatrixOffset";

/// The `CameraMatrixOffset.cfg` of `cal`.
pub fn camera_matrix_offset_cfg(cal: &Calibration) -> String {
    let mut s = String::new();
    header(&mut s, "#", cal, "radians (rad)");
    let _ = writeln!(
        s,
        "# Only the lower (bottom) camera is calibrated; other keys keep their values."
    );
    let [x, y, z] = super::camera::naoth(cal);
    let _ = writeln!(s, "[{SECTION}]");
    let _ = writeln!(s, "cam_rot.bottom.x={}", num(x));
    let _ = writeln!(s, "cam_rot.bottom.y={}", num(y));
    let _ = writeln!(s, "cam_rot.bottom.z={}", num(z));
    s
}

/// Reads back a [`camera_matrix_offset_cfg`] file: `[x, y, z]` (rad).
pub fn read_camera_matrix_offset_cfg(text: &str, path: &Path) -> Result<[f64; 3], ExportError> {
    let values = super::runswift::ini_section(text, SECTION, path)?;
    let mut out = [0.0; 3];
    for (k, axis) in ["x", "y", "z"].iter().enumerate() {
        let key = format!("cam_rot.bottom.{axis}");
        out[k] = values
            .iter()
            .find(|(name, _)| *name == key)
            .map(|(_, v)| *v)
            .ok_or_else(|| parse_error(path, format!("[{SECTION}] {key}: missing")))?;
    }
    Ok(out)
}

const KEYS: [&str; 3] = ["cam_rot.bottom.x", "cam_rot.bottom.y", "cam_rot.bottom.z"];

/// The bottom camera's `[x, y, z]` (rad) of a NaoTH file, checked plausible.
fn bottom(text: &str, path: &Path) -> Result<Vec<f64>, ExportError> {
    let (entries, _) = super::ini::section(text, SECTION, path)?
        .ok_or_else(|| parse_error(path, format!("no [{SECTION}] section")))?;
    let mut out = Vec::new();
    for key in KEYS {
        let (x, e) = super::ini::number(&entries, key, path)?
            .ok_or_else(|| parse_error(path, format!("[{SECTION}] {key}: missing")))?;
        super::check_plausible(path, e.line, key, x.to_degrees(), super::CAMERA_LIMIT_DEG)?;
        out.push(x);
    }
    Ok(out)
}

/// Reads a NaoTH `CameraMatrixOffset.cfg` (other keys allowed): naocalib's camera offsets
/// (deg).
pub fn import(text: &str, path: &Path) -> Result<Imported, ExportError> {
    let v = bottom(text, path)?;
    let [yaw, pitch, roll] = super::camera::from_naoth([v[0], v[1], v[2]]);
    Ok(vec![
        (Param::CamYaw, yaw),
        (Param::CamPitch, pitch),
        (Param::CamRoll, roll),
    ])
}

/// A robot's `CameraMatrixOffset.cfg` with the bottom camera's offsets replaced when this
/// calibration determined the lower camera (entries added when missing); every other byte
/// kept.
pub fn update(text: &str, path: &Path, cal: &Calibration) -> Result<String, ExportError> {
    if let Some((entries, _)) = super::ini::section(text, SECTION, path)? {
        for key in KEYS {
            if let Some((x, e)) = super::ini::number(&entries, key, path)? {
                super::check_plausible(path, e.line, key, x.to_degrees(), super::CAMERA_LIMIT_DEG)?;
            }
        }
    }
    if !super::camera_determined(cal, path)? {
        return Ok(text.to_string());
    }
    let new = super::camera::naoth(cal);
    let values: Vec<(&str, String)> = KEYS.iter().zip(new).map(|(k, x)| (*k, num(x))).collect();
    super::ini::set(text, SECTION, &values, path)
}
