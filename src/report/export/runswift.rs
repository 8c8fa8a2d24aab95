//! rUNSWift: the `[kinematics]` camera entries of a head's config
//! (`image/home/nao/data/configs/<head>.cfg`), in degrees:
//!
//! ```text
//! [kinematics]
//! cameraYawBottom=<deg>
//! cameraPitchBottom=<deg>
//! cameraRollBottom=<deg>
//! ```
//!
//! rUNSWift's camera chain is Denavit-Hartenberg (`createDHMatrix(a, α, d, θ)` =
//! `Rx(α) · Tx(a) · Rz(θ) · Tz(d)`, rUNSWift `robot/utils/matrix_helpers`); after the
//! head yaw its rotations are `DH(−π/2, tilt − π + headPitch) · DH(−π/2, π/2 + yaw) ·
//! DH(−π/2 + pitch, roll)` with the three entries above in radians (rUNSWift
//! `robot/perception/kinematics/Kinematics.cpp`, `Kinematics::updateDHChain`), ending in
//! an optical camera frame (z forward, x right, y down). [`super::camera::runswift`] solves
//! that for naocalib's rotation exactly; for small angles `pitch ≈ CamPitch`, while yaw
//! and roll act about the optical axes (see the export tests).

use std::fmt::Write as _;
use std::path::Path;

use super::{Calibration, ExportError, Imported, header, num, parse_error};
use crate::model::Param;

/// The INI section rUNSWift reads the entries from.
pub const SECTION: &str = "kinematics";

/// The `[kinematics]` camera entries of `cal`.
pub fn kinematics_cfg(cal: &Calibration) -> String {
    let mut s = String::new();
    header(&mut s, "#", cal, "degrees (deg)");
    let _ = writeln!(
        s,
        "# Only the bottom camera is calibrated; merge these entries into the head's config."
    );
    let [yaw, pitch, roll] = super::camera::runswift(cal).map(f64::to_degrees);
    let _ = writeln!(s, "[{SECTION}]");
    let _ = writeln!(s, "cameraYawBottom={}", num(yaw));
    let _ = writeln!(s, "cameraPitchBottom={}", num(pitch));
    let _ = writeln!(s, "cameraRollBottom={}", num(roll));
    s
}

/// Reads back a [`kinematics_cfg`] file: `[yaw, pitch, roll]` (deg).
pub fn read_kinematics_cfg(text: &str, path: &Path) -> Result<[f64; 3], ExportError> {
    let values = ini_section(text, SECTION, path)?;
    let mut out = [0.0; 3];
    for (k, key) in ["cameraYawBottom", "cameraPitchBottom", "cameraRollBottom"]
        .iter()
        .enumerate()
    {
        out[k] = values
            .iter()
            .find(|(name, _)| name == key)
            .map(|(_, v)| *v)
            .ok_or_else(|| parse_error(path, format!("[{SECTION}] {key}: missing")))?;
    }
    Ok(out)
}

/// The `key=number` entries of INI section `section` (comments `#` and `;`), in file
/// order; an error names the line.
pub fn ini_section(
    text: &str,
    section: &str,
    path: &Path,
) -> Result<Vec<(String, f64)>, ExportError> {
    let mut inside = false;
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') || line.starts_with(';') {
            continue;
        }
        if let Some(name) = line.strip_prefix('[').and_then(|l| l.strip_suffix(']')) {
            inside = name.trim() == section;
            continue;
        }
        if !inside {
            continue;
        }
        let (key, value) = line
            .split_once('=')
            .ok_or_else(|| parse_error(path, format!("line {}: expected key=value", n + 1)))?;
        let value: f64 = value.trim().parse().map_err(|_| {
            parse_error(
                path,
                format!(
                    "line {}: {}: '{}' is not a number",
                    n + 1,
                    key.trim(),
                    value.trim()
                ),
            )
        })?;
        out.push((key.trim().to_string(), value));
    }
    Ok(out)
}

const KEYS: [&str; 3] = ["cameraYawBottom", "cameraPitchBottom", "cameraRollBottom"];

/// The bottom camera's `[yaw, pitch, roll]` (deg) of a rUNSWift config, checked plausible.
fn bottom(text: &str, path: &Path) -> Result<[f64; 3], ExportError> {
    let (entries, _) = super::ini::section(text, SECTION, path)?
        .ok_or_else(|| parse_error(path, format!("no [{SECTION}] section")))?;
    let mut out = [0.0; 3];
    for (k, key) in KEYS.iter().enumerate() {
        let (x, e) = super::ini::number(&entries, key, path)?
            .ok_or_else(|| parse_error(path, format!("[{SECTION}] {key}: missing")))?;
        super::check_plausible(path, e.line, key, x, super::CAMERA_LIMIT_DEG)?;
        out[k] = x;
    }
    Ok(out)
}

/// Reads a rUNSWift head config (other keys and sections allowed): naocalib's camera
/// offsets (deg).
pub fn import(text: &str, path: &Path) -> Result<Imported, ExportError> {
    let [yaw, pitch, roll] = super::camera::from_runswift(bottom(text, path)?.map(f64::to_radians));
    Ok(vec![
        (Param::CamYaw, yaw),
        (Param::CamPitch, pitch),
        (Param::CamRoll, roll),
    ])
}

/// A robot's head config with the bottom camera's entries replaced when this calibration
/// determined the lower camera (added when missing); every other byte kept.
pub fn update(text: &str, path: &Path, cal: &Calibration) -> Result<String, ExportError> {
    if let Some((entries, _)) = super::ini::section(text, SECTION, path)? {
        for key in KEYS {
            if let Some((x, e)) = super::ini::number(&entries, key, path)? {
                super::check_plausible(path, e.line, key, x, super::CAMERA_LIMIT_DEG)?;
            }
        }
    }
    if !super::camera_determined(cal, path)? {
        return Ok(text.to_string());
    }
    let new = super::camera::runswift(cal).map(f64::to_degrees);
    let values: Vec<(&str, String)> = KEYS.iter().zip(new).map(|(k, x)| (*k, num(x))).collect();
    super::ini::set(text, SECTION, &values, path)
}
