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
//! leaves out). The top camera (`cam_rot.top.x/y/z`) is built the same way with its
//! own offset and `rotationY` of 1.2° (`Motion.cpp` lines 473–482,
//! `Framework/Commons/Source/Tools/NaoInfo.h` line 39), `head_rot` applied before it too:
//! UpperCam* the same way as Cam*. An update writes each camera's `x, y, z` so that, with
//! the file's `head_rot.x`, the rotation is naocalib's; the pan comes before the tilt, unlike
//! naocalib's order, so [`super::camera::naoth`] solves `Rz(z) · Ry(tilt + y) · Rx(x) =
//! Ry(tilt) · Rc` exactly. A fresh file carries the head keys too (NaoTH's configuration
//! layers would otherwise take the platform's `head_rot`, which is not zero:
//! `Config/platform/Nao6/CameraMatrixOffset.cfg`).

use std::fmt::Write as _;
use std::path::Path;

use super::format::{DocRow, Format, NameRule};
use super::{Calibration, ExportError, Imported, header, num, parse_error};
use crate::model::{CameraId, Param};

/// The INI section NaoTH reads the offsets from.
pub const SECTION: &str = "CameraMatrixOffset";

/// Each camera's keys: `cam_rot.bottom.x/y/z`, `cam_rot.top.x/y/z`
/// (`CameraMatrixOffset.h` lines 37–43).
fn keys(camera: CameraId) -> [&'static str; 3] {
    match camera {
        CameraId::Lower => ["cam_rot.bottom.x", "cam_rot.bottom.y", "cam_rot.bottom.z"],
        CameraId::Upper => ["cam_rot.top.x", "cam_rot.top.y", "cam_rot.top.z"],
    }
}

/// The head's keys: roll after the pitch, pitch offset, yaw offset.
const HEAD_KEYS: [&str; 3] = ["head_rot.x", "head_rot.y", "head_rot.z"];

/// What a NaoTH file holds (rad), checked plausible: each camera's `[x, y, z]` (`None`
/// for a camera without keys; the bottom camera's are required) and the head's `[x, y, z]`
/// (`None` for an absent key).
struct Values {
    cameras: [Option<[f64; 3]>; 2],
    head: [Option<f64>; 3],
}

fn values(text: &str, path: &Path) -> Result<Values, ExportError> {
    let (entries, _) = super::ini::section(text, SECTION, path)?
        .ok_or_else(|| parse_error(path, format!("no [{SECTION}] section")))?;
    let mut cameras = [None; 2];
    for (c, camera) in super::camera::CAMERAS.into_iter().enumerate() {
        let keys = keys(camera);
        if camera == CameraId::Upper && !entries.iter().any(|e| keys.contains(&e.key.as_str())) {
            continue;
        }
        let mut v = [0.0; 3];
        for (k, key) in keys.iter().enumerate() {
            let (x, e) = super::ini::number(&entries, key, path)?
                .ok_or_else(|| parse_error(path, format!("[{SECTION}] {key}: missing")))?;
            super::check_plausible(path, e.line, key, x.to_degrees(), super::CAMERA_LIMIT_DEG)?;
            v[k] = x;
        }
        cameras[c] = Some(v);
    }
    let mut head = [None; 3];
    for (k, key) in HEAD_KEYS.iter().enumerate() {
        if let Some((x, e)) = super::ini::number(&entries, key, path)? {
            super::check_plausible(path, e.line, key, x.to_degrees(), super::CAMERA_LIMIT_DEG)?;
            head[k] = Some(x);
        }
    }
    Ok(Values { cameras, head })
}

/// NaoTH's `CameraMatrixOffset.cfg`: the bottom camera, the top camera when the
/// calibration knows all three of its offsets, and the head offsets (`head_rot.y/z`,
/// `head_rot.x` zero) when known.
#[derive(Debug, Clone, Copy)]
pub struct Camera;

impl Format for Camera {
    fn name(&self) -> &'static str {
        "naoth-camera"
    }
    fn file(&self) -> &'static str {
        "naoth/CameraMatrixOffset.cfg"
    }
    fn description(&self) -> &'static str {
        "NaoTH: [CameraMatrixOffset] cam_rot.bottom/top.x/y/z and head_rot.x/y/z in rad"
    }
    fn doc_row(&self) -> DocRow {
        DocRow {
            carries: "`[CameraMatrixOffset]` `cam_rot.bottom.x/y/z`, `cam_rot.top.x/y/z`, \
                      `head_rot.x/y/z` (and `body_rot.x/y`, not calibrated; NaoTH \
                      `CameraMatrixOffset.h:29–43`)",
            units: "rad",
            axes: "`rotateZ(HeadYaw + head_rot.z)·rotateY(HeadPitch + head_rot.y)·rotateX(head_rot.x)`\
                   ·translate·`rotateZ(z)·rotateY(y + tilt)·rotateX(x)` (`CameraGeometry.cpp:316–334`): \
                   head_rot.z/y are the head offsets (α = +head_rot), head_rot.x is folded into the \
                   cameras on import and kept on update; the pan comes before the tilt, so z mixes \
                   CamYaw and CamRoll; `cam_rot.top` the same with the top camera's `rotationY` of \
                   1.2° (`Motion.cpp:473–482`, `NaoInfo.h:39`)",
        }
    }
    fn recognise(&self, code: &str) -> bool {
        code.contains("[CameraMatrixOffset]")
    }
    fn write(&self, cal: &Calibration) -> String {
        let mut s = String::new();
        header(&mut s, "#", cal, "radians (rad)");
        let upper = super::camera::complete(cal, CameraId::Upper).is_some();
        if upper {
            let _ = writeln!(
                s,
                "# Both cameras and the head offsets are calibrated; other keys keep their values."
            );
        } else {
            let _ = writeln!(
                s,
                "# Only the lower (bottom) camera and the head offsets are calibrated; other keys keep \
                 their values."
            );
        }
        let _ = writeln!(s, "[{SECTION}]");
        for camera in super::camera::CAMERAS {
            if camera == CameraId::Upper && !upper {
                continue;
            }
            let values = super::camera::naoth(cal, camera);
            for (key, x) in keys(camera).iter().zip(values) {
                let _ = writeln!(s, "{key}={}", num(x));
            }
        }
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
    /// naocalib's offsets (deg) of the bottom camera and of the top camera when the file
    /// has it, `head_rot.x` folded into each, and the head offsets `α = head_rot.z,
    /// head_rot.y` (deg) when the file has them; other keys allowed.
    fn read(&self, text: &str, path: &Path) -> Result<Imported, ExportError> {
        use super::camera::{nominal_tilt_deg, offsets_deg_of, rot_x, rot_y, rot_z};
        let Values { cameras, head } = values(text, path)?;
        let [head_x, head_y, head_z] = head;
        let mut out = Vec::new();
        for (camera, found) in super::camera::CAMERAS.into_iter().zip(cameras) {
            let Some([x, y, z]) = found else { continue };
            let tilt = nominal_tilt_deg(camera).to_radians();
            let m = rot_x(head_x.unwrap_or(0.0)) * rot_z(z) * rot_y(tilt + y) * rot_x(x);
            let offsets = offsets_deg_of(&m, camera);
            out.extend(super::camera::params(camera).into_iter().zip(offsets));
        }
        out.extend(head_z.map(|a| (Param::HeadYaw, a.to_degrees())));
        out.extend(head_y.map(|a| (Param::HeadPitch, a.to_degrees())));
        Ok(out)
    }
    /// `text` with each camera's offsets replaced when this calibration determined that
    /// camera (written so that, with the file's `head_rot.x`, the rotation is naocalib's;
    /// the top camera's keys added when missing), and `head_rot.y/z` when it estimated the
    /// head offsets (entries added when missing); every other byte kept.
    fn update(&self, text: &str, path: &Path, cal: &Calibration) -> Result<String, ExportError> {
        use super::camera::{head_from_camera, naoth_of, rot_x};
        let head_x = values(text, path)?.head[0].unwrap_or(0.0);
        let mut values: Vec<(&str, String)> = Vec::new();
        for camera in super::camera::CAMERAS {
            if super::camera::determined(cal, camera, path)? {
                let new = naoth_of(&(rot_x(-head_x) * head_from_camera(cal, camera)), camera);
                values.extend(keys(camera).iter().zip(new).map(|(k, x)| (*k, num(x))));
            }
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
    fn file_names(&self) -> NameRule {
        NameRule::Exactly("cameramatrixoffset.cfg")
    }
}

impl Camera {
    /// `camera`'s `[x, y, z]` (rad) as the file stores it — as read, not checked plausible
    /// (NaoTH's angles of a large correction may exceed the ±30° of an import); `None` when
    /// the file has none of its keys.
    pub fn stored(
        text: &str,
        path: &Path,
        camera: CameraId,
    ) -> Result<Option<[f64; 3]>, ExportError> {
        let (entries, _) = super::ini::section(text, SECTION, path)?
            .ok_or_else(|| parse_error(path, format!("no [{SECTION}] section")))?;
        let keys = keys(camera);
        if !entries.iter().any(|e| keys.contains(&e.key.as_str())) {
            return Ok(None);
        }
        let mut out = [0.0; 3];
        for (k, key) in keys.iter().enumerate() {
            out[k] = super::ini::number(&entries, key, path)?
                .ok_or_else(|| parse_error(path, format!("[{SECTION}] {key}: missing")))?
                .0;
        }
        Ok(Some(out))
    }
}
