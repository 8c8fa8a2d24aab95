//! NaoTH / Berlin United: `CameraMatrixOffset.cfg`, an INI (GLib key file) section with
//! rotation corrections in radians. The keys are NaoTH's own
//! (`NaoTHSoccer/Source/Representations/Modeling/CameraMatrixOffset.h`, lines 29–43; real
//! robots' files: `NaoTHSoccer/Config/robots/<robot>/CameraMatrixOffset.cfg`, commit
//! 79e1e750b):
//!
//! ```text
//! [CameraMatrixOffset]
//! body_rot.x=<torso roll>          body_rot.y=<torso pitch>
//! cam_rot.bottom.x=<roll>          cam_rot.bottom.y=<tilt>      cam_rot.bottom.z=<pan>
//! cam_rot.top.x=…                  cam_rot.top.y=…              cam_rot.top.z=…
//! head_rot.x=<roll after pitch>    head_rot.y=<head pitch>      head_rot.z=<head yaw>
//! ```
//!
//! NaoTH builds the camera matrix (`NaoTHSoccer/Source/Tools/CameraGeometry.cpp`,
//! `CameraGeometry::calculateCameraMatrixFromChestPose`, lines 316–334, called by
//! `Motion::updateCameraMatrix`, `NaoTHSoccer/Source/Motion/Motion.cpp` lines 462–470) as
//! torso · `rotateZ(HeadYaw + head_rot.z) · rotateY(HeadPitch + head_rot.y) ·
//! rotateX(head_rot.x)` · translate(camera offset) · `rotateZ(z) · rotateY(y + tilt) ·
//! rotateX(x)` in a camera frame with x along the optical axis, y left, z up. So
//! `head_rot.z` and `head_rot.y` are head joint offsets in naocalib's sense (true angle =
//! sensor + head_rot: α = +head_rot, not −stored), and `head_rot.x`, a roll between the head and
//! the camera, is folded into the camera rotation on import (exact for the rotation; the
//! camera position moves by `head_rot.x` × the 5 cm camera offset, which naocalib's import
//! leaves out). An update writes the bottom camera's `x, y, z` so that, with the file's
//! `head_rot.x`, the rotation is naocalib's; the pan comes before the tilt, unlike
//! naocalib's order, so [`super::camera::naoth`] solves `Rz(z) · Ry(tilt + y) · Rx(x) =
//! Ry(tilt) · Rc` exactly. A fresh file carries the head keys too (NaoTH's configuration
//! layers would otherwise take the platform's `head_rot`, which is not zero:
//! `Config/platform/Nao6/CameraMatrixOffset.cfg`).

use std::fmt::Write as _;
use std::path::Path;

use super::{Calibration, ExportError, Imported, header, num, parse_error};
use crate::model::Param;

/// The INI section NaoTH reads the offsets from.
pub const SECTION: &str = "CameraMatrixOffset";

/// The `CameraMatrixOffset.cfg` of `cal`: the bottom camera, and the head offsets
/// (`head_rot.y/z`, `head_rot.x` zero) when known.
pub fn camera_matrix_offset_cfg(cal: &Calibration) -> String {
    let mut s = String::new();
    header(&mut s, "#", cal, "radians (rad)");
    let _ = writeln!(
        s,
        "# Only the lower (bottom) camera and the head offsets are calibrated; other keys keep \
         their values."
    );
    let [x, y, z] = super::camera::naoth(cal);
    let _ = writeln!(s, "[{SECTION}]");
    let _ = writeln!(s, "cam_rot.bottom.x={}", num(x));
    let _ = writeln!(s, "cam_rot.bottom.y={}", num(y));
    let _ = writeln!(s, "cam_rot.bottom.z={}", num(z));
    if let (Some(yaw), Some(pitch)) = (
        cal.robot_value(Param::HeadYaw),
        cal.robot_value(Param::HeadPitch),
    ) {
        let _ = writeln!(s, "head_rot.x=0");
        let _ = writeln!(s, "head_rot.y={}", num(pitch.to_radians()));
        let _ = writeln!(s, "head_rot.z={}", num(yaw.to_radians()));
    }
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

/// The head's keys: roll after the pitch, pitch offset, yaw offset.
const HEAD_KEYS: [&str; 3] = ["head_rot.x", "head_rot.y", "head_rot.z"];

/// The bottom camera's `[x, y, z]` and the head's `[x, y, z]` (rad; `None` for an absent
/// head key) of a NaoTH file, checked plausible.
#[allow(clippy::type_complexity)]
fn values(text: &str, path: &Path) -> Result<([f64; 3], [Option<f64>; 3]), ExportError> {
    let (entries, _) = super::ini::section(text, SECTION, path)?
        .ok_or_else(|| parse_error(path, format!("no [{SECTION}] section")))?;
    let mut camera = [0.0; 3];
    for (k, key) in KEYS.iter().enumerate() {
        let (x, e) = super::ini::number(&entries, key, path)?
            .ok_or_else(|| parse_error(path, format!("[{SECTION}] {key}: missing")))?;
        super::check_plausible(path, e.line, key, x.to_degrees(), super::CAMERA_LIMIT_DEG)?;
        camera[k] = x;
    }
    let mut head = [None; 3];
    for (k, key) in HEAD_KEYS.iter().enumerate() {
        if let Some((x, e)) = super::ini::number(&entries, key, path)? {
            super::check_plausible(path, e.line, key, x.to_degrees(), super::CAMERA_LIMIT_DEG)?;
            head[k] = Some(x);
        }
    }
    Ok((camera, head))
}

/// Reads a NaoTH `CameraMatrixOffset.cfg` (other keys allowed): naocalib's camera offsets
/// (deg), `head_rot.x` folded in, and the head offsets `α = head_rot.z, head_rot.y` (deg)
/// when the file has them.
pub fn import(text: &str, path: &Path) -> Result<Imported, ExportError> {
    use super::camera::{offsets_deg_of, rot_x, rot_y, rot_z};
    let ([x, y, z], [head_x, head_y, head_z]) = values(text, path)?;
    let tilt = super::camera::NOMINAL_TILT_DEG.to_radians();
    let [yaw, pitch, roll] =
        offsets_deg_of(&(rot_x(head_x.unwrap_or(0.0)) * rot_z(z) * rot_y(tilt + y) * rot_x(x)));
    let mut out = vec![
        (Param::CamYaw, yaw),
        (Param::CamPitch, pitch),
        (Param::CamRoll, roll),
    ];
    out.extend(head_z.map(|a| (Param::HeadYaw, a.to_degrees())));
    out.extend(head_y.map(|a| (Param::HeadPitch, a.to_degrees())));
    Ok(out)
}

/// A robot's `CameraMatrixOffset.cfg` with the bottom camera's offsets replaced when this
/// calibration determined the lower camera (written so that, with the file's
/// `head_rot.x`, the rotation is naocalib's), and `head_rot.y/z` when it estimated the head
/// offsets (entries added when missing); every other byte kept.
pub fn update(text: &str, path: &Path, cal: &Calibration) -> Result<String, ExportError> {
    use super::camera::{head_from_camera, rot_x, zyx_angles};
    let head_x = if super::ini::section(text, SECTION, path)?.is_some() {
        values(text, path)?.1[0].unwrap_or(0.0)
    } else {
        0.0
    };
    let mut values: Vec<(&str, String)> = Vec::new();
    if super::camera_determined(cal, path)? {
        let [z, b, x] = zyx_angles(&(rot_x(-head_x) * head_from_camera(cal)));
        let new = [x, b - super::camera::NOMINAL_TILT_DEG.to_radians(), z];
        values.extend(KEYS.iter().zip(new).map(|(k, x)| (*k, num(x))));
    }
    for (key, p) in [
        (HEAD_KEYS[1], Param::HeadPitch),
        (HEAD_KEYS[2], Param::HeadYaw),
    ] {
        if let Some(a) = cal.determined_here(p) {
            values.push((key, num(a.to_radians())));
        }
    }
    if values.is_empty() {
        return Ok(text.to_string());
    }
    super::ini::set(text, SECTION, &values, path)
}
