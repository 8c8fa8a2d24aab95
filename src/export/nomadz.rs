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
//!
//! **Intrinsics**: `upperCameraInfo.cfg` and `lowerCameraInfo.cfg`, one per camera
//! ([`CameraInfo`]): opening angles in radians, the optical centre in pixels.

use std::fmt::Write as _;
use std::path::Path;

use super::bhuman::{BHUMAN_JOINTS, joint_param};
use super::cfg::{self, Kind};
use super::format::{DocRow, Format, NameRule};
use super::source::has_key;
use super::{Calibration, ExportError, Imported, header, num, parse_error};
use crate::model::{CameraId, Param};

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

/// NomadZ's default image size of each camera (`Config/Robots/Default/upperCameraInfo.cfg`:
/// 640 × 480, `lowerCameraInfo.cfg`: 320 × 240, commit 2a597dac), at which a fresh file
/// of it is written: the file's `width` and `height` are the resolution NomadZ opens the
/// camera at (`CameraProvider.cpp`, lines 49–51), which naocalib does not change.
pub fn default_image(camera: CameraId) -> (u32, u32) {
    match camera {
        CameraId::Upper => (640, 480),
        CameraId::Lower => (320, 240),
    }
}

/// NomadZ's default opening angles of both cameras (rad; 54.7° × 42.5°, the centre at the
/// image's middle: `Config/Robots/Default/*CameraInfo.cfg`, commit 2a597dac).
const DEFAULT_OPENING_RAD: [f64; 2] = [0.9546951, 0.7417649];

/// The keys of a camera's intrinsics in a NomadZ `CameraInfo` file, in the order of
/// [`camera_info_values`].
const CAMERA_INFO_KEYS: [&[&str]; 4] = [
    &["openingAngleWidth"],
    &["openingAngleHeight"],
    &["opticalCenter", "x"],
    &["opticalCenter", "y"],
];

/// What a NomadZ `CameraInfo` file at `width × height` stores of calibrated intrinsics
/// `i`: the opening angles (rad) and the optical centre (px) of the same camera at that
/// image size.
fn camera_info_values(i: &crate::calibration::Intrinsics, width: u32, height: u32) -> [f64; 4] {
    let [fx, fy, cx, cy] = i.scaled_to(width, height);
    [
        crate::calibration::intrinsics::opening_angle(width, fx).to_radians(),
        crate::calibration::intrinsics::opening_angle(height, fy).to_radians(),
        cx,
        cy,
    ]
}

/// A NomadZ `CameraInfo` file as read: the camera, the image size, and the four values
/// of [`CAMERA_INFO_KEYS`] (rad, rad, px, px) with their spans.
struct CameraInfoFile {
    camera: CameraId,
    width: u32,
    height: u32,
    values: [(f64, usize, usize); 4],
}

/// Reads a NomadZ `CameraInfo` file, each value checked: `camera` upper or lower, a
/// positive `width` and `height`, opening angles of 10 … 150° as plain radians (NomadZ
/// streams them as floats, without units: `CameraInfo.cpp`, lines 18–19), the centre
/// inside the image.
fn camera_info(text: &str, path: &Path) -> Result<CameraInfoFile, ExportError> {
    let root = cfg::parse(text, path)?;
    let scalar = |key: &str| -> Result<(&str, usize), ExportError> {
        let v = root
            .get(&[key])
            .ok_or_else(|| parse_error(path, format!("{key}: missing")))?;
        let s = v.scalar().ok_or_else(|| {
            parse_error(path, format!("line {}: {key}: expected a value", v.line))
        })?;
        Ok((s, v.line))
    };
    let (name, line) = scalar("camera")?;
    let camera = CameraId::ALL
        .into_iter()
        .find(|c| c.name() == name.trim())
        .ok_or_else(|| {
            parse_error(
                path,
                format!("line {line}: camera: '{name}' is neither upper nor lower"),
            )
        })?;
    let mut size = [0u32; 2];
    for (k, key) in ["width", "height"].iter().enumerate() {
        let (text, line) = scalar(key)?;
        size[k] = text.trim().parse().ok().filter(|n| *n > 0).ok_or_else(|| {
            parse_error(
                path,
                format!("line {line}: {key}: '{text}' is not a positive number of pixels"),
            )
        })?;
    }
    let [width, height] = size;
    let mut values = [(0.0, 0, 0); 4];
    for (k, keys) in CAMERA_INFO_KEYS.iter().enumerate() {
        let key = keys.join(".");
        let v = root
            .get(keys)
            .ok_or_else(|| parse_error(path, format!("{key}: missing")))?;
        let text = v.scalar().ok_or_else(|| {
            parse_error(path, format!("line {}: {key}: expected a number", v.line))
        })?;
        let x = cfg::number(text);
        let (ok, expected) = match k {
            0 | 1 => (
                x.is_some_and(|x| (10f64.to_radians()..150f64.to_radians()).contains(&x)),
                "an opening angle of 10 … 150° in radians (NomadZ reads no unit)".to_string(),
            ),
            2 => (
                x.is_some_and(|x| (0.0..=f64::from(width)).contains(&x)),
                format!("an optical centre of 0 … {width} px"),
            ),
            _ => (
                x.is_some_and(|x| (0.0..=f64::from(height)).contains(&x)),
                format!("an optical centre of 0 … {height} px"),
            ),
        };
        match x.filter(|_| ok) {
            Some(x) => values[k] = (x, v.start, v.end),
            None => {
                return Err(parse_error(
                    path,
                    format!("line {}: {key}: '{text}' is not {expected}", v.line),
                ));
            }
        }
    }
    Ok(CameraInfoFile {
        camera,
        width,
        height,
        values,
    })
}

/// NomadZ's `upperCameraInfo.cfg` / `lowerCameraInfo.cfg` (B-Human 2013's `CameraInfo`),
/// one file per camera in `Config/Robots/<robot>/`, which NomadZ reads before
/// `Config/Robots/Default/` (`Src/Core/System/File.cpp`, lines 52–53, commit 2a597dac;
/// `Src/Modules/Infrastructure/CameraProvider.cpp`, lines 38–43): the camera, the image
/// size, the opening angles in radians and the optical centre in pixels at that size.
///
/// NomadZ's `CameraInfo::serialize` (`Src/Representations/Infrastructure/CameraInfo.cpp`,
/// line 22) makes one focal length `width / (2·tan(openingAngleWidth / 2))`, which
/// `Src/Tools/Geometry/Transformations.cpp` uses for both image axes, looking from pixel
/// `(u, v)` along `(f, cx − u, cy − v)` (lines 81–82, 155, 332; a point is rounded to the
/// pixel `(int)(0.5 + cx − y·f/x)`, line 36: pixel centres at integers, as naocalib);
/// `openingAngleHeight` is the image's vertical field of view (the image's top edge at
/// `tan(openingAngleHeight / 2)`, `Transformations.cpp` lines 351–352,
/// `CameraMatrixProvider.cpp` line 33). So the file stores `2·atan(w / (2·fx))`,
/// `2·atan(h / (2·fy))`, `cx`, `cy` of naocalib's camera at the file's `w × h`; the
/// difference of `fx` and `fy` is lost to NomadZ's projection, which uses `fx`.
#[derive(Debug, Clone, Copy)]
pub struct CameraInfo(pub CameraId);

impl Format for CameraInfo {
    fn name(&self) -> &'static str {
        match self.0 {
            CameraId::Upper => "nomadz-upper-camera-info",
            CameraId::Lower => "nomadz-lower-camera-info",
        }
    }
    fn file(&self) -> &'static str {
        match self.0 {
            CameraId::Upper => "nomadz/upperCameraInfo.cfg",
            CameraId::Lower => "nomadz/lowerCameraInfo.cfg",
        }
    }
    fn description(&self) -> &'static str {
        match self.0 {
            CameraId::Upper => {
                "NomadZ upperCameraInfo.cfg: the upper camera's opening angles in rad and optical \
                 centre in px"
            }
            CameraId::Lower => {
                "NomadZ lowerCameraInfo.cfg: the lower camera's opening angles in rad and optical \
                 centre in px"
            }
        }
    }
    fn doc_row(&self) -> DocRow {
        DocRow {
            carries: match self.0 {
                CameraId::Upper => {
                    "`camera = upper; width; height; openingAngleWidth; openingAngleHeight; \
                     opticalCenter = {x; y;};` (NomadZ's `CameraInfo`): the upper camera's \
                     intrinsics, written only for a calibration that estimated them"
                }
                CameraId::Lower => "the same for `camera = lower`",
            },
            units: "rad; centre in px at `width × height`",
            axes: "`f = width / (2·tan(openingAngleWidth/2))` for both axes (`CameraInfo.cpp:22`, \
                   `Transformations.cpp:81–82`), `openingAngleHeight` the vertical field of view \
                   (`Transformations.cpp:351–352`), centre in px, pixel centres at integers as \
                   naocalib (`Transformations.cpp:36`)",
        }
    }
    fn recognise(&self, code: &str) -> bool {
        has_key(code, "openingAngleWidth")
            && has_key(code, "opticalCenter")
            && !has_key(code, "cameras")
            && cfg::parse(code, Path::new("-"))
                .ok()
                .and_then(|root| {
                    root.get(&["camera"])
                        .and_then(|v| v.scalar().map(str::to_owned))
                })
                .is_some_and(|c| c.trim() == self.0.name())
    }
    fn intrinsics(&self) -> bool {
        true
    }
    fn has_intrinsics_for(&self, cal: &Calibration) -> bool {
        cal.cameras.contains_key(&self.0)
    }
    fn write(&self, cal: &Calibration) -> String {
        let mut s = String::new();
        header(
            &mut s,
            "//",
            cal,
            "opening angles in radians (rad), optical centre in pixels at width x height",
        );
        let (width, height) = default_image(self.0);
        let _ = writeln!(
            s,
            "// NomadZ's focal length is width / (2 tan(openingAngleWidth / 2)) for both axes;"
        );
        let [aw, ah, cx, cy] = match cal.intrinsics(self.0) {
            Some(i) => {
                let [fx, fy, _, _] = i.scaled_to(width, height);
                let _ = writeln!(
                    s,
                    "// calibrated fx {fx:.3} px, fy {fy:.3} px at {width} x {height}."
                );
                camera_info_values(&i, width, height)
            }
            None => {
                // A directory export leaves the file out (Format::has_intrinsics_for).
                let _ = writeln!(
                    s,
                    "// the {} camera's intrinsics are not calibrated here: NomadZ's default",
                    self.0
                );
                let (w, h) = (f64::from(width), f64::from(height));
                [
                    DEFAULT_OPENING_RAD[0],
                    DEFAULT_OPENING_RAD[1],
                    w / 2.0,
                    h / 2.0,
                ]
            }
        };
        let _ = writeln!(s, "camera = {};", self.0);
        let _ = writeln!(s, "width = {width};");
        let _ = writeln!(s, "height = {height};");
        let _ = writeln!(
            s,
            "openingAngleWidth = {}; // {:.4}deg",
            num(aw),
            aw.to_degrees()
        );
        let _ = writeln!(
            s,
            "openingAngleHeight = {}; // {:.4}deg",
            num(ah),
            ah.to_degrees()
        );
        let _ = writeln!(
            s,
            "opticalCenter = {{ x = {}; y = {}; }};",
            num(cx),
            num(cy)
        );
        s
    }
    fn read(&self, text: &str, path: &Path) -> Result<Imported, ExportError> {
        // Its values are the camera's intrinsics ([`Format::read_cameras`]).
        self.read_cameras(text, path).map(|_| Vec::new())
    }
    /// The file's camera at its `width × height`: `fx`, `fy` from the opening angles, the
    /// centre as stored.
    fn read_cameras(
        &self,
        text: &str,
        path: &Path,
    ) -> Result<Vec<(CameraId, crate::calibration::Prior)>, ExportError> {
        use crate::calibration::intrinsics::focal_length;
        let f = camera_info(text, path)?;
        let [aw, ah, cx, cy] = f.values.map(|(v, _, _)| v);
        Ok(vec![(
            f.camera,
            crate::calibration::Prior {
                width: f.width,
                height: f.height,
                fx: focal_length(f.width, aw.to_degrees()),
                fy: focal_length(f.height, ah.to_degrees()),
                cx,
                cy,
            },
        )])
    }
    /// `text` with the opening angles and centre coordinates this calibration estimated
    /// replaced, at the file's own `width × height` (which stay); every other byte kept (a
    /// comment beside a value too).
    fn update(&self, text: &str, path: &Path, cal: &Calibration) -> Result<String, ExportError> {
        let f = camera_info(text, path)?;
        let Some(i) = cal.intrinsics(f.camera) else {
            return Ok(text.to_string());
        };
        let values = camera_info_values(&i, f.width, f.height);
        let edits = (0..4)
            .filter(|&k| i.calibrated[k])
            .map(|k| (f.values[k].1, f.values[k].2, num(values[k])))
            .collect();
        Ok(cfg::splice(text, edits))
    }
    fn file_names(&self) -> NameRule {
        match self.0 {
            CameraId::Upper => NameRule::Exactly("uppercamerainfo.cfg"),
            CameraId::Lower => NameRule::Exactly("lowercamerainfo.cfg"),
        }
    }
}
