//! B-Human's `Config/Robots/<robot>/cameraCalibration.cfg` (camera rotation corrections)
//! and `jointCalibration.cfg` (joint offsets), in degrees — and the frameworks built on
//! B-Human's code (SPQR, …), which read the same files.
//!
//! **Camera.** B-Human's `RobotCameraMatrix::computeRobotCameraMatrix`
//! (`Src/Representations/Perception/ImagePreprocessing/CameraMatrix.cpp`, lines 309–312 of
//! the 2025 Code Release) applies, after the head joints, `rotateY(tiltNeckToLowerCamera +
//! y) · rotateX(x) · rotateZ(z)` in a camera frame with x along the optical axis, y left,
//! z up — naocalib's camera frame and order. So x = CamRoll, y = CamPitch, z = CamYaw,
//! same signs, exactly; the upper camera the same way after `tiltNeckToUpperCamera`
//! (1.2°, lines 301–304): x = UpperCamRoll, y = UpperCamPitch, z = UpperCamYaw. The layout B-Human reads since its 2019 Code Release
//! (`Src/Representations/Configuration/CameraCalibration.h`: an enum-indexed array over
//! `CameraInfo::Camera`):
//!
//! ```text
//! cameraRotationCorrections = {
//!   upper = {x = 0deg; y = -3.5deg; z = 0deg;};
//!   lower = {x = 0deg; y = -3deg; z = 0deg;};
//! };
//! bodyRotationCorrection = {x = 0deg; y = 0deg;};
//! ```
//!
//! Releases up to 2018 read `lowerCameraRotationCorrection = {x; y; z;}` and
//! `upperCameraRotationCorrection` instead (CodeRelease 2018, `CameraMatrix.cpp` lines
//! 302–311; [`Camera2016`], format `bhuman-camera-2016`).
//!
//! **Joints.** B-Human computes the true angle as the sensor reading minus the stored
//! offset (`Src/Modules/Infrastructure/JointAnglesProvider/JointAnglesProvider.cpp`, line
//! 15: `jointAngles.angles[joint] -= theJointCalibration.offsets[joint]`) and sends the
//! request plus the offset to the motor (`Src/Modules/Infrastructure/RobotProvider/
//! NaoProvider.cpp`, line 471). naocalib's α means true = logged + α, so the file stores
//! **−α**. The 2025 file lists `waistYaw` (not present on the NAO) after `headPitch`.

use std::fmt::Write as _;
use std::path::Path;

use super::cfg::{self, Kind};
use super::format::{DocRow, Format, NameRule};
use super::source::has_key;
use super::{Calibration, ExportError, Imported, header, num, parse_error};
use crate::model::{CameraId, Param};

const UNITS: &str = "angles in degrees (deg)";

/// The NAO's joints by B-Human's names, in B-Human's `Joints` order before 2025 (head,
/// left arm, right arm, left leg, right leg; NomadZ keeps it), with the naocalib parameter
/// holding each one's offset, if any.
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

/// The naocalib parameter of a B-Human joint name (`lKneePitch` → `LKneePitch`).
pub fn joint_param(name: &str) -> Option<Param> {
    BHUMAN_JOINTS
        .iter()
        .find(|(n, _)| *n == name)
        .and_then(|(_, p)| *p)
}

/// Degrees as B-Human writes angles: `-4.5627deg` (every digit kept: exact read-back).
fn deg(x: f64) -> String {
    format!("{}deg", num(x))
}

/// The correction `[x, y, z]` (deg) of `camera` in `cal`: `[roll, pitch, yaw]` (0 for an
/// offset a robot file cannot take, and for the upper camera unless
/// [`super::camera::known`]).
fn correction(cal: &Calibration, camera: CameraId) -> [f64; 3] {
    let [yaw, pitch, roll] = super::camera::params(camera);
    let known = camera == CameraId::Lower || super::camera::known(cal, camera);
    [roll, pitch, yaw].map(|p| cal.robot_value(p).filter(|_| known).unwrap_or(0.0))
}

/// `{x = …deg; y = …deg; z = …deg;}` of `camera` in `cal`.
fn braces(cal: &Calibration, camera: CameraId) -> String {
    let [x, y, z] = correction(cal, camera);
    format!("{{x = {}; y = {}; z = {};}}", deg(x), deg(y), deg(z))
}

fn camera_notes(s: &mut String, cal: &Calibration) {
    let upper = super::camera::known(cal, CameraId::Upper);
    let _ = writeln!(
        s,
        "// Mapping: x = CamRoll, y = CamPitch, z = CamYaw (Ry(tilt)·Ry(CamPitch)·Rx(CamRoll)·Rz(CamYaw))."
    );
    if upper {
        let _ = writeln!(
            s,
            "// Upper: x = UpperCamRoll, y = UpperCamPitch, z = UpperCamYaw, the same way (tilt 1.2deg)."
        );
        let _ = writeln!(
            s,
            "// Both cameras are calibrated: the body correction is written as zero here."
        );
    } else {
        let _ = writeln!(
            s,
            "// Only the lower camera is calibrated: the upper camera and the body correction are"
        );
        let _ = writeln!(
            s,
            "// written as zero here. Use `naocalib export --update <robot's file>` to keep them."
        );
    }
}

/// B-Human's `cameraCalibration.cfg` as its framework reads it since 2019 (SPQR's too):
/// the cameras' rotation corrections (deg), the upper camera's zero unless the calibration
/// knows it, the body correction zero (not calibrated here; an update keeps a robot's own).
#[derive(Debug, Clone, Copy)]
pub struct Camera;

impl Format for Camera {
    fn name(&self) -> &'static str {
        "bhuman-camera"
    }
    fn file(&self) -> &'static str {
        "cameraCalibration.cfg"
    }
    fn description(&self) -> &'static str {
        "B-Human (2019+), SPQR: cameraRotationCorrections.{lower,upper} {x; y; z} in deg"
    }
    fn doc_row(&self) -> DocRow {
        DocRow {
            carries: "`cameraRotationCorrections = { upper = {x; y; z;}; lower = {x; y; z;}; }; \
                      bodyRotationCorrection = {x; y;};` (B-Human Code Release 2019+, SPQR)",
            units: "deg",
            axes: "x = CamRoll, y = CamPitch, z = CamYaw: `rotateY(tilt + y)·rotateX(x)·rotateZ(z)` \
                   (`CameraMatrix.cpp:309–312`), identical; `upper` the same with UpperCam* and \
                   `tiltNeckToUpperCamera` 1.2° (`CameraMatrix.cpp:301–304, 311–312`)",
        }
    }
    fn recognise(&self, code: &str) -> bool {
        has_key(code, "cameraRotationCorrections")
    }
    fn write(&self, cal: &Calibration) -> String {
        let mut s = String::new();
        header(&mut s, "//", cal, UNITS);
        camera_notes(&mut s, cal);
        let _ = writeln!(s, "cameraRotationCorrections = {{");
        let _ = writeln!(s, "  upper = {};", braces(cal, CameraId::Upper));
        let _ = writeln!(s, "  lower = {};", braces(cal, CameraId::Lower));
        let _ = writeln!(s, "}};");
        let _ = writeln!(s, "bodyRotationCorrection = {{x = 0deg; y = 0deg;}};");
        s
    }
    fn read(&self, text: &str, path: &Path) -> Result<Imported, ExportError> {
        read_cameras(text, path)
    }
    fn update(&self, text: &str, path: &Path, cal: &Calibration) -> Result<String, ExportError> {
        update_cameras(text, path, cal)
    }
    fn file_names(&self) -> NameRule {
        NameRule::Containing {
            ending: ".cfg",
            word: "camera",
        }
    }
}

impl Camera {
    /// `camera`'s correction `[x, y, z]` (deg; roll, pitch, yaw) as a B-Human camera file of
    /// either layout stores it; `None` when the file has none for it.
    pub fn stored(
        text: &str,
        path: &Path,
        camera: CameraId,
    ) -> Result<Option<[f64; 3]>, ExportError> {
        camera_at(&cfg::parse(text, path)?, path, camera)
    }
}

/// B-Human's `cameraCalibration.cfg` as its releases up to 2018 read it
/// (`lowerCameraRotationCorrection`, `upperCameraRotationCorrection`), the values of
/// [`Camera`].
#[derive(Debug, Clone, Copy)]
pub struct Camera2016;

impl Format for Camera2016 {
    fn name(&self) -> &'static str {
        "bhuman-camera-2016"
    }
    fn file(&self) -> &'static str {
        "bhuman2016/cameraCalibration.cfg"
    }
    fn description(&self) -> &'static str {
        "B-Human up to 2018: lower/upperCameraRotationCorrection {x; y; z} in deg"
    }
    fn doc_row(&self) -> DocRow {
        DocRow {
            carries: "`lowerCameraRotationCorrection = {x; y; z;}`, \
                      `upperCameraRotationCorrection` (B-Human up to 2018)",
            units: "deg",
            axes: "as `bhuman-camera` (CodeRelease 2018 `CameraMatrix.cpp:302–304, 309–311`)",
        }
    }
    fn recognise(&self, code: &str) -> bool {
        has_key(code, "lowerCameraRotationCorrection")
    }
    fn write(&self, cal: &Calibration) -> String {
        let mut s = String::new();
        header(&mut s, "//", cal, UNITS);
        camera_notes(&mut s, cal);
        let _ = writeln!(
            s,
            "lowerCameraRotationCorrection = {};",
            braces(cal, CameraId::Lower)
        );
        let _ = writeln!(
            s,
            "upperCameraRotationCorrection = {};",
            braces(cal, CameraId::Upper)
        );
        let _ = writeln!(s, "bodyRotationCorrection = {{x = 0deg; y = 0deg;}};");
        s
    }
    fn read(&self, text: &str, path: &Path) -> Result<Imported, ExportError> {
        read_cameras(text, path)
    }
    fn update(&self, text: &str, path: &Path, cal: &Calibration) -> Result<String, ExportError> {
        update_cameras(text, path, cal)
    }
}

/// B-Human's 2025 `jointCalibration.cfg` (SPQR's too): one offset per joint in its joint
/// order (`waistYaw` after `headPitch`), the value stored being **−α** (deg): B-Human
/// subtracts it from sensor readings and adds it to requests. Joints not calibrated (arms;
/// the head unless its offsets were estimated or held at a robot's values; a parameter the
/// data do not determine) are 0deg.
#[derive(Debug, Clone, Copy)]
pub struct Joints;

impl Format for Joints {
    fn name(&self) -> &'static str {
        "bhuman-joints"
    }
    fn file(&self) -> &'static str {
        "jointCalibration.cfg"
    }
    fn description(&self) -> &'static str {
        "B-Human, SPQR: offsets {<joint> = -alpha deg; ...}"
    }
    fn doc_row(&self) -> DocRow {
        DocRow {
            carries: "`offsets = {headYaw = …deg; headPitch; waistYaw; …}` in B-Human's 2025 joint \
                      order, stored −α",
            units: "deg",
            axes: "—",
        }
    }
    fn recognise(&self, code: &str) -> bool {
        !code.trim_start().starts_with('{')
            && has_key(code, "offsets")
            && !code.contains("minAngle")
    }
    fn write(&self, cal: &Calibration) -> String {
        let mut s = String::new();
        header(&mut s, "//", cal, UNITS);
        let _ = writeln!(
            s,
            "// Stored = -alpha: B-Human's true angle = sensor - stored; its motor command = request + stored."
        );
        let _ = writeln!(s, "// Joints not calibrated are 0deg.");
        let _ = writeln!(s, "offsets = {{");
        for (k, (name, param)) in BHUMAN_JOINTS.iter().enumerate() {
            if k == 2 {
                let _ = writeln!(s, "  waistYaw = 0deg; // not present on the NAO");
            }
            let entry = param.and_then(|p| cal.get(p));
            let value = param.and_then(|p| cal.robot_value(p)).map_or(0.0, |a| -a);
            let standing = param
                .and_then(|p| cal.standing_offset(p))
                .filter(|_| cal.posture == super::Posture::Standing)
                .map(|s| format!("; standing alpha = {s} deg"))
                .unwrap_or_default();
            let note = match entry {
                Some(e) if e.is_determined() => format!(" // alpha = {}{standing}", e.describe()),
                Some(e) => format!(" // {}: written as 0", e.describe()),
                None => " // not calibrated".to_string(),
            };
            let _ = writeln!(s, "  {name} = {};{note}", deg(value));
        }
        let _ = writeln!(s, "}};");
        s
    }
    /// The joint offsets as naocalib parameters: α = −stored (deg).
    fn read(&self, text: &str, path: &Path) -> Result<Imported, ExportError> {
        Ok(Joints::stored(text, path)?
            .into_iter()
            .filter_map(|(name, stored)| joint_param(&name).map(|p| (p, 0.0 - stored)))
            .collect())
    }
    /// `text` with the offsets this calibration determined replaced: stored = −α for raw
    /// angles, stored_old − α for angles already corrected by this file
    /// ([`Calibration::stored_joint_value`]); every other byte kept.
    fn update(&self, text: &str, path: &Path, cal: &Calibration) -> Result<String, ExportError> {
        let root = cfg::parse(text, path)?;
        let mut edits = Vec::new();
        for (name, param) in BHUMAN_JOINTS {
            let at = ["offsets", name];
            let found = angle_at(&root, &at, path, super::JOINT_LIMIT_DEG)?;
            let Some(param) = param else { continue };
            if cal.determined_here(param).is_none() {
                continue;
            }
            let (old, start, end) =
                found.ok_or_else(|| parse_error(path, format!("offsets.{name}: missing")))?;
            let new = cal.stored_joint_value(param, old, path)?;
            edits.push((start, end, deg(new)));
        }
        Ok(cfg::splice(text, edits))
    }
    fn joints(&self) -> bool {
        true
    }
    fn file_names(&self) -> NameRule {
        NameRule::Containing {
            ending: ".cfg",
            word: "joint",
        }
    }
}

impl Joints {
    /// The offsets as a B-Human `jointCalibration.cfg` stores them: joint name → stored
    /// value (deg), in the file's order.
    pub fn stored(text: &str, path: &Path) -> Result<Vec<(String, f64)>, ExportError> {
        let root = cfg::parse(text, path)?;
        let offsets = root
            .get(&["offsets"])
            .ok_or_else(|| parse_error(path, "no `offsets = {…};`"))?;
        let Kind::Map(entries) = &offsets.kind else {
            return Err(parse_error(
                path,
                format!("line {}: offsets: expected {{…}}", offsets.line),
            ));
        };
        let mut out = Vec::new();
        for (name, _) in entries {
            let (deg, _, _) = angle_at(&root, &["offsets", name], path, super::JOINT_LIMIT_DEG)?
                .expect("the entry exists");
            out.push((name.clone(), deg));
        }
        Ok(out)
    }
}

/// The path of `camera`'s correction in a camera file of either B-Human layout.
fn camera_path(root: &cfg::Value, camera: CameraId) -> Option<Vec<&'static str>> {
    let (name, old) = match camera {
        CameraId::Lower => ("lower", "lowerCameraRotationCorrection"),
        CameraId::Upper => ("upper", "upperCameraRotationCorrection"),
    };
    if root.get(&["cameraRotationCorrections", name]).is_some() {
        Some(vec!["cameraRotationCorrections", name])
    } else if root.get(&[old]).is_some() {
        Some(vec![old])
    } else {
        None
    }
}

/// An angle at `at` below `root` (deg), checked plausible, with its span.
fn angle_at(
    root: &cfg::Value,
    at: &[&str],
    path: &Path,
    limit_deg: f64,
) -> Result<Option<(f64, usize, usize)>, ExportError> {
    let Some(v) = root.get(at) else {
        return Ok(None);
    };
    let key = at.join(".");
    let text = v
        .scalar()
        .ok_or_else(|| parse_error(path, format!("line {}: {key}: expected an angle", v.line)))?;
    let deg = cfg::angle_deg(text).ok_or_else(|| {
        parse_error(
            path,
            format!("line {}: {key}: '{text}' is not an angle", v.line),
        )
    })?;
    super::check_plausible(path, v.line, &key, deg, limit_deg)?;
    Ok(Some((deg, v.start, v.end)))
}

/// The correction `[x, y, z]` (deg; roll, pitch, yaw) of `camera` in a parsed B-Human
/// camera file of either layout; `None` when the file has none for it.
fn camera_at(
    root: &cfg::Value,
    path: &Path,
    camera: CameraId,
) -> Result<Option<[f64; 3]>, ExportError> {
    let Some(base) = camera_path(root, camera) else {
        return Ok(None);
    };
    let mut out = [0.0; 3];
    for (k, axis) in ["x", "y", "z"].iter().enumerate() {
        let mut at = base.clone();
        at.push(axis);
        out[k] = angle_at(root, &at, path, super::CAMERA_LIMIT_DEG)?
            .ok_or_else(|| parse_error(path, format!("{}: missing", at.join("."))))?
            .0;
    }
    Ok(Some(out))
}

/// The camera values of a B-Human camera file of either layout as naocalib parameters
/// (deg): the lower camera's (required) and the upper camera's (when the file has it).
fn read_cameras(text: &str, path: &Path) -> Result<Imported, ExportError> {
    let root = cfg::parse(text, path)?;
    if camera_path(&root, CameraId::Lower).is_none() {
        return Err(parse_error(
            path,
            "no cameraRotationCorrections.lower (nor the pre-2019 lowerCameraRotationCorrection)",
        ));
    }
    let mut out = Vec::new();
    for camera in super::camera::CAMERAS {
        if let Some([x, y, z]) = camera_at(&root, path, camera)? {
            let [yaw, pitch, roll] = super::camera::params(camera);
            out.extend([(roll, x), (pitch, y), (yaw, z)]);
        }
    }
    Ok(out)
}

/// `text` (a robot's `cameraCalibration.cfg`, either layout) with each camera's correction
/// replaced where this calibration determined it; every other byte kept.
fn update_cameras(text: &str, path: &Path, cal: &Calibration) -> Result<String, ExportError> {
    let root = cfg::parse(text, path)?;
    if camera_path(&root, CameraId::Lower).is_none() {
        return Err(parse_error(
            path,
            "no cameraRotationCorrections.lower (nor lowerCameraRotationCorrection) to update",
        ));
    }
    let mut edits = Vec::new();
    for camera in super::camera::CAMERAS {
        let base = camera_path(&root, camera);
        let [yaw, pitch, roll] = super::camera::params(camera);
        for (axis, param) in [("x", roll), ("y", pitch), ("z", yaw)] {
            let found = match &base {
                Some(base) => {
                    let mut at = base.clone();
                    at.push(axis);
                    angle_at(&root, &at, path, super::CAMERA_LIMIT_DEG)?
                }
                None => None,
            };
            if let Some(value) = cal.determined_here(param) {
                let (_, start, end) = found.ok_or_else(|| {
                    parse_error(
                        path,
                        format!(
                            "the {} camera's correction ({axis}): missing",
                            camera.name()
                        ),
                    )
                })?;
                edits.push((start, end, deg(value)));
            }
        }
    }
    Ok(cfg::splice(text, edits))
}

/// The cameras in the order of B-Human's `CameraInfo::Camera` (`upper`, `lower`), which
/// its enum-indexed `cameras` arrays follow.
const BHUMAN_CAMERAS: [CameraId; 2] = [CameraId::Upper, CameraId::Lower];

/// B-Human's default intrinsics of both cameras (`Config/Robots/Default/
/// cameraIntrinsics.cfg`, Code Release 2025, commit d89d603f): opening angles 54.7° ×
/// 42.5°, optical centre at the image's middle.
const BHUMAN_DEFAULT_INTRINSICS: [f64; 4] = [54.7, 42.5, 0.5, 0.5];

/// The image size naocalib reads B-Human's intrinsics at (the NAO V6's 640 × 480; B-Human's
/// values are relative, so any size of that aspect gives the same camera).
const BHUMAN_IMAGE: (u32, u32) = (640, 480);

/// The keys of one camera's intrinsics below `cameras.<camera>`, in the order of
/// [`intrinsics_values`].
const INTRINSICS_KEYS: [&[&str]; 4] = [
    &["openingAngleWidth"],
    &["openingAngleHeight"],
    &["opticalCenter", "x"],
    &["opticalCenter", "y"],
];

/// What B-Human's file stores for calibrated intrinsics `i`: the opening angles (deg) and
/// the optical centre relative to the image size.
fn intrinsics_values(i: &crate::calibration::Intrinsics) -> [f64; 4] {
    let [w, h] = i.opening_angles();
    let [x, y] = i.relative_centre();
    [w, h, x, y]
}

/// The text of the value `k` of [`INTRINSICS_KEYS`]: an angle in degrees or a number.
fn intrinsics_text(k: usize, value: f64) -> String {
    if k < 2 { deg(value) } else { num(value) }
}

/// B-Human's `cameraIntrinsics.cfg` as its Code Release 2025 reads it (SPQR's too): each
/// camera's opening angles and optical centre relative to the image size.
///
/// B-Human's `CameraProvider::setupCamera` (`Src/Modules/Infrastructure/CameraProvider/
/// CameraProvider.cpp`, lines 212–217, commit d89d603f) takes `openingAngleWidth`,
/// `openingAngleHeight` and `opticalCenter` times the image's width and height, and
/// `CameraInfo::updateFocalLength` (`Src/Representations/Infrastructure/CameraInfo.cpp`,
/// lines 14 and 18) makes the focal lengths `width / (2·tan(openingAngleWidth / 2))` and
/// `height / (2·tan(openingAngleHeight / 2))`; `Transformation::imageToRobot`
/// (`Src/Tools/Math/Transformation.cpp`, line 74) looks along `(1, (cx − u)/f, (cy − v)/f_h)`
/// from pixel `(u, v)`, the centre of the top-left pixel at 0 as in naocalib. So the file
/// stores `2·atan(W / (2·fx))`, `2·atan(H / (2·fy))`, `cx / W`, `cy / H` of naocalib's
/// intrinsics (W × H the dataset's image), the upper camera first
/// (`CameraInfo::Camera` is `upper, lower`). SPQR's 2024 code
/// (`Src/Modules/Infrastructure/CameraProvider/CameraProvider.cpp`, line 295, commit
/// e2e482a7) reads the same file the same way; NomadZ keeps B-Human's older per-camera
/// `CameraInfo` files instead.
#[derive(Debug, Clone, Copy)]
pub struct Intrinsics;

impl Format for Intrinsics {
    fn name(&self) -> &'static str {
        "bhuman-intrinsics"
    }
    fn file(&self) -> &'static str {
        "cameraIntrinsics.cfg"
    }
    fn description(&self) -> &'static str {
        "B-Human (2025), SPQR: cameras.{upper,lower} opening angles in deg and optical centre \
         relative to the image size"
    }
    fn doc_row(&self) -> DocRow {
        DocRow {
            carries: "`cameras = { upper = {openingAngleWidth; openingAngleHeight; opticalCenter \
                      = {x; y;};}; lower = {…}; };` (B-Human Code Release 2025, SPQR): the \
                      cameras' intrinsics, written only for a calibration that estimated them",
            units: "deg; centre relative to the image size",
            axes: "`f = W / (2·tan(openingAngleWidth/2))`, `f_h = H / (2·tan(openingAngleHeight/2))`, \
                   centre `(x·W, y·H)` (`CameraInfo.cpp:14, 18`, `CameraProvider.cpp:212–217`), \
                   pixel centres at integers as naocalib (`Transformation.cpp:74`)",
        }
    }
    fn recognise(&self, code: &str) -> bool {
        has_key(code, "cameras") && has_key(code, "openingAngleWidth")
    }
    fn intrinsics(&self) -> bool {
        true
    }
    fn write(&self, cal: &Calibration) -> String {
        let mut s = String::new();
        header(
            &mut s,
            "//",
            cal,
            "opening angles in degrees (deg), optical centre relative to the image size",
        );
        let _ = writeln!(s, "cameras = {{");
        for camera in BHUMAN_CAMERAS {
            let values = match cal.intrinsics(camera) {
                Some(i) => intrinsics_values(&i),
                None => {
                    let _ = writeln!(
                        s,
                        "  // {camera}: not calibrated here, B-Human's default (`--update` keeps \
                         a robot's own)"
                    );
                    BHUMAN_DEFAULT_INTRINSICS
                }
            };
            let _ = writeln!(s, "  {} = {{", camera.name());
            let _ = writeln!(
                s,
                "    openingAngleWidth = {};",
                intrinsics_text(0, values[0])
            );
            let _ = writeln!(
                s,
                "    openingAngleHeight = {};",
                intrinsics_text(1, values[1])
            );
            let _ = writeln!(
                s,
                "    opticalCenter = {{ x = {}; y = {}; }};",
                intrinsics_text(2, values[2]),
                intrinsics_text(3, values[3])
            );
            let _ = writeln!(s, "  }};");
        }
        let _ = writeln!(s, "}};");
        s
    }
    fn read(&self, text: &str, path: &Path) -> Result<Imported, ExportError> {
        // Its values are the cameras' intrinsics ([`Format::read_cameras`]).
        self.read_cameras(text, path).map(|_| Vec::new())
    }
    fn read_cameras(
        &self,
        text: &str,
        path: &Path,
    ) -> Result<Vec<(CameraId, crate::calibration::Prior)>, ExportError> {
        let root = cfg::parse(text, path)?;
        let mut out = Vec::new();
        for camera in BHUMAN_CAMERAS {
            let Some(found) = intrinsics_at(&root, path, camera)? else {
                continue;
            };
            let [w, h, x, y] = found.map(|(v, _, _)| v);
            let (width, height) = BHUMAN_IMAGE;
            use crate::calibration::intrinsics::focal_length;
            out.push((
                camera,
                crate::calibration::Prior {
                    width,
                    height,
                    fx: focal_length(width, w),
                    fy: focal_length(height, h),
                    cx: x * width as f64,
                    cy: y * height as f64,
                },
            ));
        }
        if out.is_empty() {
            return Err(parse_error(path, "no cameras.upper nor cameras.lower"));
        }
        Ok(out)
    }
    fn update(&self, text: &str, path: &Path, cal: &Calibration) -> Result<String, ExportError> {
        let root = cfg::parse(text, path)?;
        let mut edits = Vec::new();
        for camera in BHUMAN_CAMERAS {
            let Some(i) = cal.intrinsics(camera) else {
                continue;
            };
            if !i.calibrated.iter().any(|c| *c) {
                continue;
            }
            let found = intrinsics_at(&root, path, camera)?
                .ok_or_else(|| parse_error(path, format!("cameras.{}: missing", camera.name())))?;
            let values = intrinsics_values(&i);
            // The opening angles follow the focal lengths, the centre its own coordinate.
            for (k, (_, start, end)) in found.into_iter().enumerate() {
                if i.calibrated[k] {
                    edits.push((start, end, intrinsics_text(k, values[k])));
                }
            }
        }
        Ok(cfg::splice(text, edits))
    }
    fn file_names(&self) -> NameRule {
        NameRule::Exactly("cameraintrinsics.cfg")
    }
}

/// A value with the byte span of its text.
type Spanned = (f64, usize, usize);

/// The four intrinsics values of `camera` in a parsed `cameraIntrinsics.cfg` (opening
/// angles in deg, relative centre), each checked plausible, with their spans; `None` when
/// the file has no `cameras.<camera>`.
fn intrinsics_at(
    root: &cfg::Value,
    path: &Path,
    camera: CameraId,
) -> Result<Option<[Spanned; 4]>, ExportError> {
    let base = ["cameras", camera.name()];
    if root.get(&base).is_none() {
        return Ok(None);
    }
    let mut out = [(0.0, 0, 0); 4];
    for (k, keys) in INTRINSICS_KEYS.iter().enumerate() {
        let at: Vec<&str> = base.iter().chain(keys.iter()).copied().collect();
        let key = at.join(".");
        let v = root
            .get(&at)
            .ok_or_else(|| parse_error(path, format!("{key}: missing")))?;
        let text = v.scalar().ok_or_else(|| {
            parse_error(path, format!("line {}: {key}: expected a number", v.line))
        })?;
        let (value, ok) = if k < 2 {
            let deg = cfg::angle_deg(text);
            (deg, deg.is_some_and(|d| d > 10.0 && d < 150.0))
        } else {
            let x = cfg::number(text);
            (x, x.is_some_and(|x| (0.0..=1.0).contains(&x)))
        };
        let Some(value) = value.filter(|_| ok) else {
            let expected = if k < 2 {
                "an opening angle of 10 … 150deg"
            } else {
                "a relative centre of 0 … 1"
            };
            return Err(parse_error(
                path,
                format!("line {}: {key}: '{text}' is not {expected}", v.line),
            ));
        };
        out[k] = (value, v.start, v.end);
    }
    Ok(Some(out))
}
