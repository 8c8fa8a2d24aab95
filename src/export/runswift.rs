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
//!
//! The top camera's chain is the same with `camera_top_angle` = 1.2° (`Kinematics.cpp`
//! lines 54, 63, 449–451), and its entries come in three sets, for the head looking
//! straight, left and right (`camera{Yaw,Pitch,Roll}TopWhenLooking{Straight,Left,Right}`,
//! lines 378–388), interpolated linearly in the head yaw up to ±70° (lines 401–427).
//! naocalib's model has one correction for every head yaw: an export writes it into all
//! three sets (so that the interpolation gives it at every yaw), and an import reads the
//! straight set.

use std::fmt::Write as _;
use std::path::Path;

use super::format::{DocRow, Format};
use super::{Calibration, ExportError, Imported, header, num, parse_error};
use crate::model::CameraId;

/// The INI section rUNSWift reads the entries from.
pub const SECTION: &str = "kinematics";

/// The top camera's keys for the head looking left, straight and right, by axis
/// (`image/home/nao/data/configs/<head>.cfg`, read by `motion_launch.py` lines 117–130):
/// `[yaw, pitch, roll]` of each direction.
pub const TOP_KEYS: [[&str; 3]; 3] = [
    [
        "cameraYawTopWhenLookingStraight",
        "cameraPitchTopWhenLookingStraight",
        "cameraRollTopWhenLookingStraight",
    ],
    [
        "cameraYawTopWhenLookingLeft",
        "cameraPitchTopWhenLookingLeft",
        "cameraRollTopWhenLookingLeft",
    ],
    [
        "cameraYawTopWhenLookingRight",
        "cameraPitchTopWhenLookingRight",
        "cameraRollTopWhenLookingRight",
    ],
];

/// Every key of `camera`, `[yaw, pitch, roll]` in turn (the top camera's three directions).
fn keys(camera: CameraId) -> Vec<&'static str> {
    match camera {
        CameraId::Lower => KEYS.to_vec(),
        CameraId::Upper => TOP_KEYS.concat(),
    }
}

/// `camera`'s entries (deg) of `cal`, in the order of [`keys`].
fn values(cal: &Calibration, camera: CameraId) -> Vec<f64> {
    let v = super::camera::runswift(cal, camera).map(f64::to_degrees);
    match camera {
        CameraId::Lower => v.to_vec(),
        CameraId::Upper => v.repeat(3),
    }
}

/// The bottom camera's keys: `[yaw, pitch, roll]`.
const KEYS: [&str; 3] = ["cameraYawBottom", "cameraPitchBottom", "cameraRollBottom"];

/// The `[kinematics]` entries of a rUNSWift config, and every camera key's value (deg),
/// checked plausible.
fn entries(text: &str, path: &Path) -> Result<Vec<(&'static str, f64)>, ExportError> {
    let (entries, _) = super::ini::section(text, SECTION, path)?
        .ok_or_else(|| parse_error(path, format!("no [{SECTION}] section")))?;
    let mut out = Vec::new();
    for key in keys(CameraId::Lower)
        .into_iter()
        .chain(keys(CameraId::Upper))
    {
        if let Some((x, e)) = super::ini::number(&entries, key, path)? {
            super::check_plausible(path, e.line, key, x, super::CAMERA_LIMIT_DEG)?;
            out.push((key, x));
        }
    }
    Ok(out)
}

/// The `[yaw, pitch, roll]` (deg) under `keys` in `found`; `None` when none is there. A
/// key missing beside the others is 0, as rUNSWift runs it: its launch file passes only
/// the keys a config has (`motion_launch.py` lines 117–156, no `[kinematics]` in
/// `runswift.cfg`) and the parameters default to 0 (`motion_adapter.cpp` lines 123–135).
fn triple(found: &[(&str, f64)], keys: &[&str]) -> Option<[f64; 3]> {
    let get = |k: &str| found.iter().find(|(key, _)| *key == k).map(|(_, x)| *x);
    if keys.iter().all(|k| get(k).is_none()) {
        return None;
    }
    Some([0, 1, 2].map(|k| get(keys[k]).unwrap_or(0.0)))
}

/// rUNSWift's `[kinematics]` camera entries of a head's config (deg): the bottom camera's,
/// and the top camera's (the same values for looking left, straight and right) when the
/// calibration knows all three of its offsets.
#[derive(Debug, Clone, Copy)]
pub struct Camera;

impl Format for Camera {
    fn name(&self) -> &'static str {
        "runswift-camera"
    }
    fn file(&self) -> &'static str {
        "runswift/kinematics.cfg"
    }
    fn description(&self) -> &'static str {
        "rUNSWift: [kinematics] camera{Yaw,Pitch,Roll}Bottom, …TopWhenLooking{Straight,Left,Right} in deg"
    }
    fn doc_row(&self) -> DocRow {
        DocRow {
            carries: "`[kinematics]` `cameraYawBottom/cameraPitchBottom/cameraRollBottom`, \
                      `camera{Yaw,Pitch,Roll}TopWhenLooking{Straight,Left,Right}`",
            units: "deg",
            axes: "Denavit-Hartenberg `DH(−π/2, π/2 + yaw) · DH(−π/2 + pitch, roll)` after the head \
                   pitch, optical camera frame; small angles: pitch ≈ CamPitch; the top camera the \
                   same with `camera_top_angle` 1.2° (`Kinematics.cpp:449–451`), its three sets \
                   interpolated in the head yaw (`Kinematics.cpp:401–427`): naocalib writes its one \
                   correction into all three and imports the straight set",
        }
    }
    fn recognise(&self, code: &str) -> bool {
        code.contains("[kinematics]")
    }
    fn write(&self, cal: &Calibration) -> String {
        let mut s = String::new();
        header(&mut s, "#", cal, "degrees (deg)");
        let upper = super::camera::complete(cal, CameraId::Upper).is_some();
        if upper {
            let _ = writeln!(
                s,
                "# Both cameras are calibrated (the top camera's one correction for every head yaw);"
            );
            let _ = writeln!(s, "# merge these entries into the head's config.");
        } else {
            let _ = writeln!(
                s,
                "# Only the bottom camera is calibrated; merge these entries into the head's config."
            );
        }
        let _ = writeln!(s, "[{SECTION}]");
        for camera in super::camera::CAMERAS {
            if camera == CameraId::Upper && !upper {
                continue;
            }
            for (key, x) in keys(camera).into_iter().zip(values(cal, camera)) {
                let _ = writeln!(s, "{key}={}", num(x));
            }
        }
        s
    }
    /// naocalib's offsets (deg) of the bottom camera (required) and of the top camera when
    /// the config has it — the entries for the head looking straight (rUNSWift interpolates
    /// towards the left and right entries as the head turns; naocalib's model has one
    /// correction for every head yaw); other keys and sections allowed.
    fn read(&self, text: &str, path: &Path) -> Result<Imported, ExportError> {
        let found = entries(text, path)?;
        let mut out = Vec::new();
        for (camera, keys) in [(CameraId::Lower, &KEYS), (CameraId::Upper, &TOP_KEYS[0])] {
            let Some(v) = triple(&found, keys) else {
                if camera == CameraId::Lower {
                    return Err(parse_error(
                        path,
                        format!("[{SECTION}] {}: missing", KEYS[0]),
                    ));
                }
                continue;
            };
            let offsets = super::camera::from_runswift(v.map(f64::to_radians), camera);
            out.extend(super::camera::params(camera).into_iter().zip(offsets));
        }
        Ok(out)
    }
    /// `text` with each camera's entries replaced when this calibration determined that
    /// camera (added when missing; the top camera's for every head direction, all alike);
    /// every other byte kept.
    fn update(&self, text: &str, path: &Path, cal: &Calibration) -> Result<String, ExportError> {
        if super::ini::section(text, SECTION, path)?.is_some() {
            entries(text, path)?;
        }
        let mut values_set: Vec<(&str, String)> = Vec::new();
        for camera in super::camera::CAMERAS {
            if super::camera::determined(cal, camera, path)? {
                values_set.extend(
                    keys(camera)
                        .into_iter()
                        .zip(values(cal, camera))
                        .map(|(k, x)| (k, num(x))),
                );
            }
        }
        if values_set.is_empty() {
            return Ok(text.to_string());
        }
        super::ini::set(text, SECTION, &values_set, path)
    }
}

impl Camera {
    /// `camera`'s `[yaw, pitch, roll]` (deg) as the config stores it (the top camera's set
    /// for the head looking straight), checked plausible, a key missing beside the others
    /// read as 0; `None` when the config has none of its keys.
    pub fn stored(
        text: &str,
        path: &Path,
        camera: CameraId,
    ) -> Result<Option<[f64; 3]>, ExportError> {
        let keys: &[&str] = match camera {
            CameraId::Lower => &KEYS,
            CameraId::Upper => &TOP_KEYS[0],
        };
        Ok(triple(&entries(text, path)?, keys))
    }
}
