//! NomadZ (descended from B-Human 2013): `Config/Robots/<robot>/jointCalibration.cfg` and
//! `cameraCalibration.cfg`.
//!
//! **Joints**, one entry per joint in B-Human's 2013 joint order, in degrees
//! (`Src/Representations/Configuration/JointCalibration.h`, `JointInfo::serialize` converts
//! with `toDegrees`/`fromDegrees`), on one line as in `Config/Robots/Default/` or spread
//! over several as in `Config/Robots/Borin/`:
//!
//! ```text
//! lKneePitch = {offset = 0.178186; minAngle = -5; maxAngle = 120; jointPlay = 2.63675;};
//! ```
//!
//! NomadZ subtracts `offset` from the sensor readings (`Src/Modules/Infrastructure/
//! NaoProvider.cpp`, line 173: `sensors[j++] - theJointCalibration.joints[i].offset`) and
//! adds it to the requests (line 123), so `offset` stores **−α**. `jointPlay` is the full
//! width of the joint's play (backlash): naocalib's play family, parameter
//! `<Joint>Play`, looked up in the registry by name. The joint limits are NomadZ's
//! defaults, which naocalib does not estimate; `--update` keeps a robot's.
//!
//! **Camera**: `cameraTiltCorrection`, `cameraRollCorrection`, `cameraPanCorrection` in
//! radians (`Src/Representations/Configuration/CameraCalibration.h`), applied after the
//! head joints as `rotateY(headTiltToCameraTilt + tilt) · rotateX(roll) · rotateZ(pan)`
//! (`Src/Representations/Perception/CameraMatrix.cpp`, lines 589–591) — B-Human's order:
//! tilt = CamPitch, roll = CamRoll, pan = CamYaw, exactly. The upper camera's
//! `upperCameraTiltCorrection`, `upperCameraRollCorrection`, `upperCameraPanCorrection`
//! (radians) enter the same way after `headTiltToUpperCameraTilt` (1.2°; lines 582–586):
//! UpperCamPitch, UpperCamRoll, UpperCamYaw. The `body…` keys are not calibrated here.

use std::fmt::Write as _;
use std::path::Path;

use super::bhuman::{BHUMAN_JOINTS, joint_param};
use super::cfg::{self, Kind};
use super::format::{DocRow, Format};
use super::source::has_key;
use super::{Calibration, ExportError, Imported, header, num, parse_error};
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

/// A number at `at` below `root`, with its span; `None` when absent.
fn number_at(
    root: &cfg::Value,
    at: &[&str],
    path: &Path,
) -> Result<Option<(f64, usize, usize, usize)>, ExportError> {
    let Some(v) = root.get(at) else {
        return Ok(None);
    };
    let text = v.scalar().unwrap_or("{…}");
    let x = cfg::number(text).ok_or_else(|| {
        parse_error(
            path,
            format!(
                "line {}: {}: '{text}' is not a number",
                v.line,
                at.join(".")
            ),
        )
    })?;
    Ok(Some((x, v.start, v.end, v.line)))
}

/// NomadZ's lower-camera keys and naocalib's parameter of each (same rotation, radians).
pub const CAMERA_KEYS: [(&str, Param); 3] = [
    ("cameraTiltCorrection", Param::CamPitch),
    ("cameraRollCorrection", Param::CamRoll),
    ("cameraPanCorrection", Param::CamYaw),
];

/// NomadZ's upper-camera keys and naocalib's parameter of each (same rotation, radians;
/// `Src/Representations/Perception/CameraMatrix.cpp` lines 582–586).
pub const UPPER_CAMERA_KEYS: [(&str, Param); 3] = [
    ("upperCameraTiltCorrection", Param::UpperCamPitch),
    ("upperCameraRollCorrection", Param::UpperCamRoll),
    ("upperCameraPanCorrection", Param::UpperCamYaw),
];

/// The cameras' corrections of a NomadZ camera file (rad, with spans), checked plausible:
/// the lower camera's (required) and the upper camera's keys the file has.
fn camera_values(
    root: &cfg::Value,
    path: &Path,
) -> Result<Vec<(Param, f64, usize, usize)>, ExportError> {
    let mut out = Vec::new();
    for (k, (key, param)) in CAMERA_KEYS.iter().chain(&UPPER_CAMERA_KEYS).enumerate() {
        let Some((x, start, end, line)) = number_at(root, &[*key], path)? else {
            if k < CAMERA_KEYS.len() {
                return Err(parse_error(path, format!("{key}: missing")));
            }
            continue;
        };
        super::check_plausible(path, line, key, x.to_degrees(), super::CAMERA_LIMIT_DEG)?;
        out.push((*param, x, start, end));
    }
    Ok(out)
}

/// NomadZ's `jointCalibration.cfg` (the one-line layout): per joint `{offset; minAngle;
/// maxAngle; jointPlay}` in degrees, `offset` = −α, `jointPlay` naocalib's play.
#[derive(Debug, Clone, Copy)]
pub struct Joints;

impl Format for Joints {
    fn name(&self) -> &'static str {
        "nomadz-joints"
    }
    fn file(&self) -> &'static str {
        "nomadz/jointCalibration.cfg"
    }
    fn description(&self) -> &'static str {
        "NomadZ: <joint> = {offset = -alpha; minAngle; maxAngle; jointPlay} in deg"
    }
    fn doc_row(&self) -> DocRow {
        DocRow {
            carries: "per joint `{offset; minAngle; maxAngle; jointPlay}`, offset stored −α",
            units: "deg",
            axes: "`jointPlay` is the full width of the play: naocalib's `<Joint>Play` (play \
                   family; 0 when not estimated)",
        }
    }
    fn recognise(&self, code: &str) -> bool {
        has_key(code, "minAngle") && has_key(code, "jointPlay")
    }
    fn write(&self, cal: &Calibration) -> String {
        let mut s = String::new();
        header(
            &mut s,
            "//",
            cal,
            "offset, minAngle, maxAngle and jointPlay in degrees; offset = -alpha; jointPlay is \
             the full width of the play",
        );
        for ((name, param), (min, max)) in BHUMAN_JOINTS.iter().zip(LIMITS_DEG) {
            let entry = param.and_then(|p| cal.get(p));
            let offset = param.and_then(|p| cal.robot_value(p)).map_or(0.0, |a| -a);
            let play_param = param.and_then(play_param);
            let play = play_param.and_then(|p| cal.robot_value(p)).unwrap_or(0.0);
            let mut notes = Vec::new();
            match entry {
                Some(e) => notes.push(format!("alpha {}", e.describe())),
                None => notes.push("offset not calibrated".into()),
            }
            if let Some(s) = param
                .and_then(|p| cal.standing_offset(p))
                .filter(|_| cal.posture == super::Posture::Standing)
            {
                notes.push(format!("standing alpha {s} deg"));
            }
            if let Some(p) = play_param.and_then(|p| cal.get(p)) {
                notes.push(format!("play {}", p.describe()));
            }
            let _ = writeln!(
                s,
                "{name} = {{offset = {}; minAngle = {}; maxAngle = {}; jointPlay = {};}}; // {}",
                num(offset),
                num(min),
                num(max),
                num(play),
                notes.join("; ")
            );
        }
        s
    }
    /// α = −offset (deg) of every joint naocalib models, and its play (`jointPlay`).
    fn read(&self, text: &str, path: &Path) -> Result<Imported, ExportError> {
        let mut out = Vec::new();
        for (name, entry) in Joints::stored(text, path)? {
            if let Some(p) = joint_param(&name) {
                out.push((p, 0.0 - entry.offset));
                if let Some(play) = play_param(p) {
                    out.push((play, entry.joint_play));
                }
            }
        }
        Ok(out)
    }
    /// `text` with the offsets this calibration determined replaced (stored = −α, or
    /// stored_old − α for corrected angles) and `jointPlay` where it determined the play;
    /// every other byte kept.
    fn update(&self, text: &str, path: &Path, cal: &Calibration) -> Result<String, ExportError> {
        Joints::stored(text, path)?;
        let root = cfg::parse(text, path)?;
        let mut edits = Vec::new();
        for (name, param) in BHUMAN_JOINTS {
            let Some(param) = param else { continue };
            if cal.determined_here(param).is_some() {
                let (old, start, end, _) = number_at(&root, &[name, "offset"], path)?
                    .ok_or_else(|| parse_error(path, format!("{name}.offset: missing")))?;
                edits.push((start, end, num(cal.stored_joint_value(param, old, path)?)));
            }
            if let Some(play) = play_param(param).and_then(|p| cal.determined_here(p)) {
                let (_, start, end, _) = number_at(&root, &[name, "jointPlay"], path)?
                    .ok_or_else(|| parse_error(path, format!("{name}.jointPlay: missing")))?;
                edits.push((start, end, num(play)));
            }
        }
        Ok(cfg::splice(text, edits))
    }
    fn joints(&self) -> bool {
        true
    }
}

impl Joints {
    /// The joints as a NomadZ `jointCalibration.cfg` (either layout) stores them: joint
    /// name → entry (deg), every offset checked plausible and every leg joint's `jointPlay`
    /// within the play family's bound ([`crate::model::bounds`], 0 … 5°).
    pub fn stored(text: &str, path: &Path) -> Result<Vec<(String, JointEntry)>, ExportError> {
        let root = cfg::parse(text, path)?;
        let Kind::Map(entries) = &root.kind else {
            unreachable!("a file is a map")
        };
        let mut out = Vec::new();
        for (name, v) in entries {
            if !matches!(v.kind, Kind::Map(_)) {
                return Err(parse_error(
                    path,
                    format!(
                        "line {}: {name}: expected {{offset; minAngle; maxAngle; jointPlay}}",
                        v.line
                    ),
                ));
            }
            let field = |key: &str| -> Result<f64, ExportError> {
                number_at(&root, &[name.as_str(), key], path)?
                    .map(|(x, ..)| x)
                    .ok_or_else(|| {
                        parse_error(path, format!("line {}: {name}.{key}: missing", v.line))
                    })
            };
            let entry = JointEntry {
                offset: field("offset")?,
                min_angle: field("minAngle")?,
                max_angle: field("maxAngle")?,
                joint_play: field("jointPlay")?,
            };
            let (_, _, _, line) =
                number_at(&root, &[name.as_str(), "offset"], path)?.expect("read above");
            super::check_plausible(
                path,
                line,
                &format!("{name}.offset"),
                entry.offset,
                super::JOINT_LIMIT_DEG,
            )?;
            // The play of a joint naocalib models must be one it can hold: a width within
            // the play family's bound.
            if let Some(play) = joint_param(name).and_then(play_param) {
                let bound = crate::model::bounds::bound(play);
                if !bound.contains(entry.joint_play) {
                    let (_, _, _, line) =
                        number_at(&root, &[name.as_str(), "jointPlay"], path)?.expect("read above");
                    return Err(parse_error(
                        path,
                        format!(
                            "line {line}: {name}.jointPlay = {} deg is outside naocalib's {} … {} \
                                 deg for {play} ({}): naocalib's model cannot hold it; correct the \
                                 file by hand first",
                            entry.joint_play, bound.min, bound.max, bound.why
                        ),
                    ));
                }
            }
            out.push((name.clone(), entry));
        }
        Ok(out)
    }
}

/// NomadZ's `cameraCalibration.cfg` (radians): the cameras' tilt, roll and pan
/// corrections, the upper camera's zero unless the calibration knows them, the body's zero
/// (not calibrated here; an update keeps a robot's).
#[derive(Debug, Clone, Copy)]
pub struct Camera;

impl Format for Camera {
    fn name(&self) -> &'static str {
        "nomadz-camera"
    }
    fn file(&self) -> &'static str {
        "nomadz/cameraCalibration.cfg"
    }
    fn description(&self) -> &'static str {
        "NomadZ: camera/upperCamera Tilt/Roll/PanCorrection in rad"
    }
    fn doc_row(&self) -> DocRow {
        DocRow {
            carries: "`cameraTiltCorrection`, `cameraRollCorrection`, `cameraPanCorrection`, \
                      `upperCameraTiltCorrection`, `upperCameraRollCorrection`, \
                      `upperCameraPanCorrection` (and the body's, not calibrated)",
            units: "rad",
            axes: "tilt = CamPitch, roll = CamRoll, pan = CamYaw: `rotateY(tilt₀ + tilt)·rotateX(roll)\
                   ·rotateZ(pan)` (`CameraMatrix.cpp:589–591`), identical; `upperCamera…` the same \
                   with UpperCam* after `headTiltToUpperCameraTilt` 1.2° (`CameraMatrix.cpp:582–586`)",
        }
    }
    fn recognise(&self, code: &str) -> bool {
        has_key(code, "cameraTiltCorrection")
    }
    fn write(&self, cal: &Calibration) -> String {
        let mut s = String::new();
        header(&mut s, "//", cal, "radians (rad), body translation in mm");
        let upper = super::camera::known(cal, crate::model::CameraId::Upper);
        if upper {
            let _ = writeln!(
                s,
                "// tilt = CamPitch, roll = CamRoll, pan = CamYaw; upperCamera…: UpperCamPitch, \
                 UpperCamRoll, UpperCamYaw."
            );
            let _ = writeln!(
                s,
                "// The body is zero here; `naocalib export --update <file>` keeps a robot's."
            );
        } else {
            let _ = writeln!(
                s,
                "// tilt = CamPitch, roll = CamRoll, pan = CamYaw. Only the lower camera is calibrated:"
            );
            let _ = writeln!(
                s,
                "// upper camera and body are zero here; `naocalib export --update <file>` keeps a robot's."
            );
        }
        for (k, (key, param)) in CAMERA_KEYS.iter().chain(&UPPER_CAMERA_KEYS).enumerate() {
            let known = k < CAMERA_KEYS.len() || upper;
            let x = cal.robot_value(*param).filter(|_| known).unwrap_or(0.0);
            let _ = writeln!(s, "{key} = {};", num(x.to_radians()));
        }
        for key in ["bodyTiltCorrection", "bodyRollCorrection"] {
            let _ = writeln!(s, "{key} = 0;");
        }
        let _ = writeln!(s, "bodyTranslationCorrection = {{x = 0; y = 0; z = 0;}};");
        s
    }
    /// naocalib's camera offsets (deg), both cameras'.
    fn read(&self, text: &str, path: &Path) -> Result<Imported, ExportError> {
        let root = cfg::parse(text, path)?;
        Ok(camera_values(&root, path)?
            .into_iter()
            .map(|(p, x, _, _)| (p, x.to_degrees()))
            .collect())
    }
    /// `text` with the cameras' corrections this calibration determined replaced; every
    /// other byte kept.
    fn update(&self, text: &str, path: &Path, cal: &Calibration) -> Result<String, ExportError> {
        let root = cfg::parse(text, path)?;
        let found = camera_values(&root, path)?;
        let mut edits = Vec::new();
        for (key, param) in CAMERA_KEYS.iter().chain(&UPPER_CAMERA_KEYS) {
            let Some(v) = cal.determined_here(*param) else {
                continue;
            };
            let (_, _, start, end) = found
                .iter()
                .find(|(p, ..)| p == param)
                .ok_or_else(|| parse_error(path, format!("{key}: missing")))?;
            edits.push((*start, *end, num(v.to_radians())));
        }
        Ok(cfg::splice(text, edits))
    }
}
