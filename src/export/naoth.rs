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
//!
//! **Intrinsics**: `CameraInfoTop.cfg` and `CameraInfoBottom.cfg`, one diagonal opening
//! angle per camera ([`CameraInfo`]).

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

/// NaoTH's image size (`Framework/Commons/Source/Representations/Infrastructure/
/// CameraInfo.h`, lines 18–19 and 63–64, commit 79e1e750b; the V6 cameras run at it).
pub const IMAGE: (u32, u32) = (640, 480);

/// The section (and file name) of each camera's `CameraInfo`: `CameraInfoTop` for the
/// upper camera, `CameraInfoBottom` for the lower (`CameraInfo.h`, lines 53–58, 95–103;
/// `CameraInfo.cpp`, line 81).
fn info_section(camera: CameraId) -> &'static str {
    match camera {
        CameraId::Upper => "CameraInfoTop",
        CameraId::Lower => "CameraInfoBottom",
    }
}

/// NaoTH's V6 diagonal opening angle of both cameras (deg; `Config/platform/Nao6/
/// CameraInfoTop.cfg`, `CameraInfoBottom.cfg`, commit 79e1e750b).
const DEFAULT_DIAGONAL_DEG: f64 = 67.4;

/// The one key of NaoTH's `CameraInfo`: the diagonal opening angle (deg in the file:
/// `PARAMETER_ANGLE_REGISTER`, `ParameterList.h` lines 86–94, 177).
const DIAGONAL: &str = "openingAngleDiagonal";

/// NaoTH's focal length (px) of the diagonal opening angle `deg` at `width × height`:
/// `CameraInfo::getFocalLength` (`CameraInfo.cpp`, lines 19–26): half the image's
/// diagonal over `tan(deg / 2)`.
pub fn focal_length_of_diagonal(width: u32, height: u32, deg: f64) -> f64 {
    0.5 * f64::from(width).hypot(f64::from(height)) / (0.5 * deg.to_radians()).tan()
}

/// The diagonal opening angle (deg) NaoTH's file stores for calibrated intrinsics `i`:
/// that of the mean of `fx` and `fy` at NaoTH's 640 × 480 (NaoTH has one focal length).
pub fn diagonal_of(i: &crate::calibration::Intrinsics) -> f64 {
    let (width, height) = IMAGE;
    let [fx, fy, _, _] = i.scaled_to(width, height);
    let f = 0.5 * (fx + fy);
    (2.0 * (0.5 * f64::from(width).hypot(f64::from(height)) / f).atan()).to_degrees()
}

/// NaoTH's `CameraInfoTop.cfg` / `CameraInfoBottom.cfg`: one camera's diagonal opening
/// angle, in the platform's `Config/platform/Nao6/` and — per robot — in
/// `Config/robots/<robot>/` or `Config/robot_heads/<head>/`, which NaoTH loads after the
/// platform's, key by key (`Framework/Commons/Source/Representations/Infrastructure/
/// Configuration.cpp`, lines 71, 82, 85 and 153–162, commit 79e1e750b).
///
/// NaoTH has one focal length for both axes, `f = ½·hypot(W, H) / tan(½·openingAngleDiagonal)`
/// (`CameraInfo.cpp`, lines 19–26), and the optical centre at the image's middle, not
/// configurable: `getOpticalCenterX() = W / 2`, used as `W/2 − 0.5` with the pixel centres
/// at integers (`CameraInfo.cpp` lines 36–42, `NaoTHSoccer/Source/Tools/CameraGeometry.cpp`
/// lines 58–63 and 102–105) — naocalib's `(W − 1)/2`. So the file takes the diagonal of the
/// mean of the calibrated `fx` and `fy` (at 640 × 480); the difference of `fx` and `fy`
/// and the centre's offset are lost to NaoTH, and the file's header says how much.
#[derive(Debug, Clone, Copy)]
pub struct CameraInfo(pub CameraId);

impl Format for CameraInfo {
    fn name(&self) -> &'static str {
        match self.0 {
            CameraId::Upper => "naoth-camera-info-top",
            CameraId::Lower => "naoth-camera-info-bottom",
        }
    }
    fn file(&self) -> &'static str {
        match self.0 {
            CameraId::Upper => "naoth/CameraInfoTop.cfg",
            CameraId::Lower => "naoth/CameraInfoBottom.cfg",
        }
    }
    fn description(&self) -> &'static str {
        match self.0 {
            CameraId::Upper => {
                "NaoTH CameraInfoTop.cfg: the upper camera's openingAngleDiagonal in deg (one \
                 focal length, the centre at the image's middle)"
            }
            CameraId::Lower => {
                "NaoTH CameraInfoBottom.cfg: the lower camera's openingAngleDiagonal in deg (one \
                 focal length, the centre at the image's middle)"
            }
        }
    }
    fn doc_row(&self) -> DocRow {
        DocRow {
            carries: match self.0 {
                CameraId::Upper => {
                    "`[CameraInfoTop]` `openingAngleDiagonal` (NaoTH's `CameraInfo`): the upper \
                     camera's focal length, written only for a calibration that estimated it"
                }
                CameraId::Lower => {
                    "`[CameraInfoBottom]` `openingAngleDiagonal`: the lower camera's"
                }
            },
            units: "deg",
            axes: "`f = ½·hypot(640, 480) / tan(½·openingAngleDiagonal)` for both axes \
                   (`CameraInfo.cpp:19–26`), written from the mean of fx and fy; the centre is \
                   NaoTH's fixed image middle (`CameraGeometry.cpp:58–63`), naocalib's calibrated \
                   centre is not written",
        }
    }
    fn recognise(&self, code: &str) -> bool {
        has_section(code, info_section(self.0)) && super::source::has_key(code, DIAGONAL)
    }
    fn intrinsics(&self) -> bool {
        true
    }
    fn has_intrinsics_for(&self, cal: &Calibration) -> bool {
        cal.cameras.contains_key(&self.0)
    }
    fn write(&self, cal: &Calibration) -> String {
        let mut s = String::new();
        header(&mut s, "#", cal, "degrees (deg)");
        let section = info_section(self.0);
        let Some(i) = cal.intrinsics(self.0) else {
            // A directory export leaves the file out (Format::has_intrinsics_for).
            let _ = writeln!(
                s,
                "# the {} camera's intrinsics are not calibrated here: NaoTH's default",
                self.0
            );
            let _ = writeln!(s, "[{section}]");
            let _ = writeln!(s, "{DIAGONAL}={}", num(DEFAULT_DIAGONAL_DEG));
            return s;
        };
        let (width, height) = IMAGE;
        let [fx, fy, cx, cy] = i.scaled_to(width, height);
        let _ = writeln!(
            s,
            "# NaoTH has one focal length for both axes, hypot(W, H)/2 / tan(openingAngleDiagonal/2),"
        );
        let _ = writeln!(
            s,
            "# and the optical centre at the image's middle: written from the mean of the calibrated"
        );
        let _ = writeln!(
            s,
            "# fx {fx:.3} px and fy {fy:.3} px at {width} x {height}; NaoTH cannot take their \
             difference ({:+.3} px)",
            fx - fy
        );
        let (mx, my) = (
            (f64::from(width) - 1.0) / 2.0,
            (f64::from(height) - 1.0) / 2.0,
        );
        let _ = writeln!(
            s,
            "# nor the centre's offset ({:+.3}, {:+.3}) px from NaoTH's ({mx}, {my}).",
            cx - mx,
            cy - my
        );
        let _ = writeln!(s, "[{section}]");
        let _ = writeln!(s, "{DIAGONAL}={}", num(diagonal_of(&i)));
        s
    }
    fn read(&self, text: &str, path: &Path) -> Result<Imported, ExportError> {
        // Its value is the camera's intrinsics ([`Format::read_cameras`]).
        self.read_cameras(text, path).map(|_| Vec::new())
    }
    /// The camera as NaoTH sees it at 640 × 480: both focal lengths of the diagonal, the
    /// centre at NaoTH's image middle `((W − 1)/2, (H − 1)/2)` in naocalib's pixels.
    fn read_cameras(
        &self,
        text: &str,
        path: &Path,
    ) -> Result<Vec<(CameraId, crate::calibration::Prior)>, ExportError> {
        let deg = diagonal_at(text, path, self.0)?.0;
        let (width, height) = IMAGE;
        let f = focal_length_of_diagonal(width, height, deg);
        Ok(vec![(
            self.0,
            crate::calibration::Prior {
                width,
                height,
                fx: f,
                fy: f,
                cx: (f64::from(width) - 1.0) / 2.0,
                cy: (f64::from(height) - 1.0) / 2.0,
            },
        )])
    }
    /// `text` with `openingAngleDiagonal` replaced when this calibration estimated either
    /// focal length; every other byte kept.
    fn update(&self, text: &str, path: &Path, cal: &Calibration) -> Result<String, ExportError> {
        diagonal_at(text, path, self.0)?;
        let Some(i) = cal.intrinsics(self.0) else {
            return Ok(text.to_string());
        };
        if !(i.calibrated[0] || i.calibrated[1]) {
            return Ok(text.to_string());
        }
        super::ini::set(
            text,
            info_section(self.0),
            &[(DIAGONAL, num(diagonal_of(&i)))],
            path,
        )
    }
    fn file_names(&self) -> NameRule {
        match self.0 {
            CameraId::Upper => NameRule::Exactly("camerainfotop.cfg"),
            CameraId::Lower => NameRule::Exactly("camerainfobottom.cfg"),
        }
    }
}

/// Whether `code` has the INI section `[name]`.
fn has_section(code: &str, name: &str) -> bool {
    code.lines().any(|l| {
        l.trim()
            .strip_prefix('[')
            .and_then(|l| l.strip_suffix(']'))
            .is_some_and(|n| n.trim() == name)
    })
}

/// The diagonal opening angle (deg) of `camera`'s `CameraInfo` file, checked plausible (10
/// … 150°), with its line.
fn diagonal_at(text: &str, path: &Path, camera: CameraId) -> Result<(f64, usize), ExportError> {
    let section = info_section(camera);
    let (entries, _) = super::ini::section(text, section, path)?
        .ok_or_else(|| parse_error(path, format!("no [{section}] section")))?;
    let (deg, e) = super::ini::number(&entries, DIAGONAL, path)?
        .ok_or_else(|| parse_error(path, format!("[{section}] {DIAGONAL}: missing")))?;
    if !(10.0..=150.0).contains(&deg) {
        return Err(parse_error(
            path,
            format!(
                "line {}: {DIAGONAL} = {deg} is not an opening angle of 10 … 150 deg",
                e.line
            ),
        ));
    }
    Ok((deg, e.line))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibration::{Intrinsics, Prior};

    #[test]
    fn naoths_diagonal_is_its_one_focal_length() {
        // NaoTH's V6 default, 67.4°, is a focal length of 600 px at 640 × 480.
        let f = focal_length_of_diagonal(640, 480, DEFAULT_DIAGONAL_DEG);
        assert!((f - 600.0).abs() < 0.3, "{f}");
        // The diagonal written is that of the mean focal length, at NaoTH's image size
        // whatever the calibration's.
        let prior = Prior {
            width: 1280,
            height: 960,
            fx: 1196.0,
            fy: 1196.0,
            cx: 640.0,
            cy: 480.0,
        };
        let i = Intrinsics {
            camera: CameraId::Upper,
            prior,
            value: [1220.0, 1180.0, 650.0, 470.0],
            std: [Some(0.1); 4],
            calibrated: [true; 4],
        };
        let f = focal_length_of_diagonal(640, 480, diagonal_of(&i));
        assert!((f - 600.0).abs() < 1e-9, "{f}");
    }
}
