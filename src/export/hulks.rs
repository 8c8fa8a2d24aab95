//! HULKs (Rust): the per-head and per-body parameter JSON files (`etc/parameters/
//! head.<id>.json`, `body.<id>.json`), which HULKs merges over its defaults. Radians.
//!
//! - Head: `camera_matrix_parameters.calibration.correction_in_camera_bottom = [x, y, z]`
//!   (and `correction_in_camera_top` for the upper camera, the same way),
//!   turned into `Rotation3::from_euler_angles(x, y, z)` = `Rz(z) · Ry(y) · Rx(x)` and
//!   applied as `correction_in_camera * head_to_camera` (HULKs
//!   `crates/projection/src/camera_matrix.rs`, `CameraMatrix::to_corrected`), where
//!   `head_to_camera = Rx(−pitch) · Ry(−π/2) · Rx(π/2) · T(−p)` maps the head frame into
//!   an optical camera frame (z forward, x right, y down; HULKs
//!   `crates/control/src/camera_matrix_calculator.rs`), a camera looking down having a
//!   negative pitch (HULKs `crates/projection/tests/projection.rs`), here −39.7° (the top
//!   camera: −1.2°, `etc/parameters/default.json`). [`super::camera::hulks`] solves
//!   that for naocalib's rotation exactly; for small angles `x ≈ CamPitch`,
//!   `y ≈ CamYaw`, `z ≈ −CamRoll` (the optical frame's axes are others).
//! - Body: `joint_calibration_offsets.{head,left_leg,right_leg}.<joint>` in radians
//!   (`hip_yaw_pitch`, `hip_roll`, `hip_pitch`, `knee_pitch`, `ankle_pitch`,
//!   `ankle_roll`; head `yaw`, `pitch`). HULKs subtracts the stored value from the sensor
//!   readings (`crates/control/src/sensor_data_receiver.rs`, line 155 at commit
//!   21e8a3de9: `sensor_data.positions - joint_calibration_offsets`) and adds it to the
//!   motor commands (`crates/control/src/motion/command_sender.rs`, line 52), so the file
//!   stores **−α**.
//!
//! - Intrinsics (a calibration that estimated them): `camera_matrix_parameters.vision_top`
//!   (the upper camera) and `vision_bottom` (the lower), `focal_lengths = [fx/W, fy/H]` and
//!   `cc_optical_center = [cx/W, cy/H]`, which the head file overrides of HULKs'
//!   `default.json` (merged key by key, `crates/parameters/src/directory.rs` lines 84–91,
//!   `json.rs` lines 3–14). HULKs multiplies both by its image size of 640 × 480
//!   (`camera_matrix_calculator.rs` lines 66, 74–97; `CameraMatrix::
//!   from_normalized_focal_and_center`, `crates/projection/src/camera_matrix.rs` lines
//!   49–54) and projects a point `(x, y, z)` of its optical camera frame to the pixel
//!   `(fx·x/z + cx, fy·y/z + cy)` (`crates/projection/src/intrinsic.rs`, lines 47–60), the
//!   pixel of index `i` at coordinate `i` (`crates/vision/src/field_border_detection.rs`,
//!   line 74) — naocalib's convention, so `cx` needs no half-pixel shift.
//!
//! JSON has no comments: the units and the compensation rule are in the docs; a result
//! that is not a calibration gets a top-level `naocalib_not_a_calibration` key, which
//! HULKs does not know and so refuses to load.

use std::collections::BTreeMap;
use std::path::Path;

use serde::Serialize;

use super::format::{DocRow, Format};
use super::jsonedit;
use super::{Calibration, ExportError, Imported, num, parse_error};
use crate::model::{CameraId, Param, Side};

/// HULKs' name of each leg joint, in naocalib's leg order.
pub const LEG_JOINTS: [&str; 6] = [
    "hip_yaw_pitch",
    "hip_roll",
    "hip_pitch",
    "knee_pitch",
    "ankle_pitch",
    "ankle_roll",
];

#[derive(Serialize)]
struct HeadFile {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    naocalib_not_a_calibration: Option<Vec<String>>,
    camera_matrix_parameters: CameraMatrixParameters,
}

#[derive(Serialize)]
struct CameraMatrixParameters {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    vision_top: Option<Vision>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    vision_bottom: Option<Vision>,
    calibration: CameraCalibration,
}

/// One camera's normalised intrinsics (`camera_matrix_parameters.vision_top` /
/// `vision_bottom`; their `camera_pitch` is HULKs' default, not written).
#[derive(Serialize)]
struct Vision {
    focal_lengths: [f64; 2],
    cc_optical_center: [f64; 2],
}

#[derive(Serialize)]
struct CameraCalibration {
    correction_in_camera_bottom: [f64; 3],
    #[serde(default, skip_serializing_if = "Option::is_none")]
    correction_in_camera_top: Option<[f64; 3]>,
}

#[derive(Serialize)]
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

/// Every joint naocalib calibrates: `(group, name, parameter)` in HULKs' names.
pub fn joints() -> Vec<(&'static str, &'static str, Param)> {
    let mut out = vec![
        ("head", "yaw", Param::HeadYaw),
        ("head", "pitch", Param::HeadPitch),
    ];
    for (side, group) in [(Side::Left, "left_leg"), (Side::Right, "right_leg")] {
        for (joint, name) in side.leg_joints().iter().zip(LEG_JOINTS) {
            out.push((group, name, joint.offset()));
        }
    }
    out
}

/// The stored values (−α, rad) of `cal`'s determined joint offsets by HULKs group and
/// name; joints without a determined offset are left out (HULKs keeps its default).
fn offsets(cal: &Calibration) -> BTreeMap<String, BTreeMap<String, f64>> {
    let mut out: BTreeMap<String, BTreeMap<String, f64>> = BTreeMap::new();
    for (group, name, param) in joints() {
        if let Some(alpha) = cal.robot_value(param) {
            out.entry(group.into())
                .or_default()
                .insert(name.into(), (-alpha).to_radians());
        }
    }
    out
}

/// A number with the byte span of its text.
type Spanned = (f64, usize, usize);

/// Where each camera's correction is in a head file.
fn correction_path(camera: CameraId) -> [&'static str; 3] {
    [
        "camera_matrix_parameters",
        "calibration",
        match camera {
            CameraId::Lower => "correction_in_camera_bottom",
            CameraId::Upper => "correction_in_camera_top",
        },
    ]
}

/// The `[x, y, z]` (rad) of `camera`'s correction in a parsed head file, checked
/// plausible, with each number's span.
fn correction_at(
    root: &jsonedit::Value,
    path: &Path,
    camera: CameraId,
) -> Result<Option<[Spanned; 3]>, ExportError> {
    let at = correction_path(camera);
    let Some(v) = root.get(&at) else {
        return Ok(None);
    };
    let key = at.join(".");
    let bad = || {
        parse_error(
            path,
            format!("line {}: {key}: expected [x, y, z] in rad", v.line),
        )
    };
    let jsonedit::Kind::Array(items) = &v.kind else {
        return Err(bad());
    };
    if items.len() != 3 {
        return Err(bad());
    }
    let mut out = [(0.0, 0, 0); 3];
    for (k, item) in items.iter().enumerate() {
        let jsonedit::Kind::Number(x) = item.kind else {
            return Err(bad());
        };
        super::check_plausible(
            path,
            item.line,
            &key,
            x.to_degrees(),
            super::CAMERA_LIMIT_DEG,
        )?;
        out[k] = (x, item.start, item.end);
    }
    Ok(Some(out))
}

/// The stored joint offsets (rad) of a parsed body file, checked plausible.
fn offsets_at(root: &jsonedit::Value, path: &Path) -> Result<Vec<(Param, f64)>, ExportError> {
    let mut out = Vec::new();
    for (group, name, param) in joints() {
        let at = ["joint_calibration_offsets", group, name];
        if let Some(v) = root.get(&at) {
            let jsonedit::Kind::Number(x) = v.kind else {
                return Err(parse_error(
                    path,
                    format!("line {}: {}: expected a number (rad)", v.line, at.join(".")),
                ));
            };
            super::check_plausible(
                path,
                v.line,
                &at.join("."),
                x.to_degrees(),
                super::JOINT_LIMIT_DEG,
            )?;
            out.push((param, x));
        }
    }
    Ok(out)
}

/// HULKs' per-head parameter JSON (`head.<id>.json`): the lower camera's correction
/// `[x, y, z]` (rad), the upper camera's when the calibration knows all three of its
/// offsets, and each camera's normalised intrinsics (`vision_top`, `vision_bottom`:
/// `focal_lengths`, `cc_optical_center`) when the calibration carries them.
#[derive(Debug, Clone, Copy)]
pub struct Head;

impl Format for Head {
    fn name(&self) -> &'static str {
        "hulks-head"
    }
    fn file(&self) -> &'static str {
        "hulks/head.json"
    }
    fn description(&self) -> &'static str {
        "HULKs head.<id>.json: correction_in_camera_bottom/_top [x, y, z] in rad; with \
         intrinsics, vision_top/_bottom focal_lengths and cc_optical_center normalised"
    }
    fn doc_row(&self) -> DocRow {
        DocRow {
            carries: "`camera_matrix_parameters.calibration.correction_in_camera_bottom = [x, y, z]`, \
                      `correction_in_camera_top`; for a calibration of the intrinsics \
                      `camera_matrix_parameters.vision_top` / `vision_bottom` \
                      `focal_lengths = [fx/W, fy/H]`, `cc_optical_center = [cx/W, cy/H]`",
            units: "rad; intrinsics normalised by the image size",
            axes: "`Rz(z)·Ry(y)·Rx(x)` applied before `head_to_camera`, in HULKs' optical camera \
                   frame (z forward, x right, y down); small angles: x ≈ CamPitch, y ≈ CamYaw, \
                   z ≈ −CamRoll; the top camera the same with its `camera_pitch` of −1.2° \
                   (`camera_matrix_calculator.rs:67–73, 104–108, 115–116`); intrinsics times \
                   640 × 480 (`camera_matrix_calculator.rs:66, 74–97`, `camera_matrix.rs:49–54`), \
                   pixel `(f·x/z + c)` in the optical frame, pixel centres at integers as naocalib \
                   (`intrinsic.rs:47–60`)",
        }
    }
    fn recognise(&self, code: &str) -> bool {
        code.contains("\"correction_in_camera_bottom\"")
            || code.contains("\"correction_in_camera_top\"")
    }
    fn write(&self, cal: &Calibration) -> String {
        let upper = super::camera::complete(cal, CameraId::Upper).is_some();
        pretty(&HeadFile {
            naocalib_not_a_calibration: marker(cal),
            camera_matrix_parameters: CameraMatrixParameters {
                vision_top: vision(cal, CameraId::Upper),
                vision_bottom: vision(cal, CameraId::Lower),
                calibration: CameraCalibration {
                    correction_in_camera_bottom: super::camera::hulks(cal, CameraId::Lower),
                    correction_in_camera_top: upper
                        .then(|| super::camera::hulks(cal, CameraId::Upper)),
                },
            },
        })
    }
    /// naocalib's offsets (deg) of the lower camera (required) and of the upper camera
    /// (when the file has it); any other keys allowed.
    fn read(&self, text: &str, path: &Path) -> Result<Imported, ExportError> {
        let root = jsonedit::parse(text, path)?;
        let mut out = Vec::new();
        for camera in super::camera::CAMERAS {
            let Some(found) = correction_at(&root, path, camera)? else {
                if camera == CameraId::Lower {
                    let key = correction_path(camera).join(".");
                    return Err(parse_error(path, format!("{key}: missing")));
                }
                continue;
            };
            let values = super::camera::from_hulks(found.map(|(v, _, _)| v), camera);
            out.extend(super::camera::params(camera).into_iter().zip(values));
        }
        Ok(out)
    }
    /// `text` with each camera's correction (`correction_in_camera_bottom`,
    /// `correction_in_camera_top`) replaced (inserted when missing) when this calibration
    /// determined that camera; every other byte kept.
    fn update(&self, text: &str, path: &Path, cal: &Calibration) -> Result<String, ExportError> {
        let root = jsonedit::parse(text, path)?;
        for camera in super::camera::CAMERAS {
            correction_at(&root, path, camera)?;
        }
        let mut out = text.to_string();
        for camera in super::camera::CAMERAS {
            if !super::camera::determined(cal, camera, path)? {
                continue;
            }
            let new = super::camera::hulks(cal, camera);
            let root = jsonedit::parse(&out, path)?;
            out = match correction_at(&root, path, camera)? {
                Some(old) => super::cfg::splice(
                    &out,
                    old.iter()
                        .zip(new)
                        .map(|(&(_, s, e), x)| (s, e, num(x)))
                        .collect(),
                ),
                None => {
                    let array = format!("[{}, {}, {}]", num(new[0]), num(new[1]), num(new[2]));
                    jsonedit::set(&out, &correction_path(camera), &array, path)?
                }
            };
        }
        for camera in super::camera::CAMERAS {
            vision_at(&root, path, camera)?;
        }
        for camera in super::camera::CAMERAS {
            let Some(i) = cal.intrinsics(camera) else {
                continue;
            };
            let values = normalised(&i);
            let calibrated = |a: usize| [i.calibrated[2 * a], i.calibrated[2 * a + 1]];
            // An array the file lacks is written whole: what was not calibrated at HULKs'
            // default, which the robot ran with.
            let array = |a: usize| {
                let c = calibrated(a);
                let v = |k: usize| {
                    num(if c[k] {
                        values[2 * a + k]
                    } else {
                        DEFAULT_INTRINSICS[2 * a + k]
                    })
                };
                format!("[{}, {}]", v(0), v(1))
            };
            let wanted: Vec<usize> = (0..2)
                .filter(|&a| calibrated(a).iter().any(|c| *c))
                .collect();
            let root = jsonedit::parse(&out, path)?;
            let first = vision_path(camera, VISION_KEYS[0]);
            let object = &first[..2];
            if !wanted.is_empty() && root.get(object).is_none() {
                let members: Vec<String> = wanted
                    .iter()
                    .map(|&a| format!("\"{}\": {}", VISION_KEYS[a], array(a)))
                    .collect();
                let text = format!("{{{}}}", members.join(", "));
                out = jsonedit::set(&out, object, &text, path)?;
                continue;
            }
            // `focal_lengths` (values 0, 1), then `cc_optical_center` (2, 3).
            for a in wanted {
                let c = calibrated(a);
                let root = jsonedit::parse(&out, path)?;
                out = match vision_at(&root, path, camera)?[a] {
                    Some(old) => super::cfg::splice(
                        &out,
                        (0..2)
                            .filter(|&k| c[k])
                            .map(|k| (old[k].1, old[k].2, num(values[2 * a + k])))
                            .collect(),
                    ),
                    None => {
                        jsonedit::set(&out, &vision_path(camera, VISION_KEYS[a]), &array(a), path)?
                    }
                };
            }
        }
        Ok(out)
    }
    /// Each camera's intrinsics the head file holds (`vision_top`, `vision_bottom`), at
    /// HULKs' 640 × 480; a key the file lacks is HULKs' default.
    fn read_cameras(
        &self,
        text: &str,
        path: &Path,
    ) -> Result<Vec<(CameraId, crate::calibration::Prior)>, ExportError> {
        let root = jsonedit::parse(text, path)?;
        let mut out = Vec::new();
        for camera in super::camera::CAMERAS {
            let found = vision_at(&root, path, camera)?;
            if found.iter().all(Option::is_none) {
                continue;
            }
            let value = |k: usize| found[k / 2].map_or(DEFAULT_INTRINSICS[k], |a| a[k % 2].0);
            let (width, height) = IMAGE;
            let (w, h) = (f64::from(width), f64::from(height));
            out.push((
                camera,
                crate::calibration::Prior {
                    width,
                    height,
                    fx: value(0) * w,
                    fy: value(1) * h,
                    cx: value(2) * w,
                    cy: value(3) * h,
                },
            ));
        }
        Ok(out)
    }
}

/// The image size HULKs computes its cameras at: `CameraMatrixCalculator::cycle` sets
/// `image_size = vector![640.0, 480.0]` for both (`crates/control/src/
/// camera_matrix_calculator.rs`, line 66, commit 21e8a3de9).
pub const IMAGE: (u32, u32) = (640, 480);

/// HULKs' default intrinsics of both cameras, normalised (`etc/parameters/default.json`,
/// lines 91–92 and 96–97, commit 21e8a3de9): `focal_lengths` `[0.96666, 1.28574]`,
/// `cc_optical_center` `[0.5, 0.5]`.
pub const DEFAULT_INTRINSICS: [f64; 4] = [0.96666, 1.28574, 0.5, 0.5];

/// The keys of a camera's intrinsics below `vision_top` / `vision_bottom`.
const VISION_KEYS: [&str; 2] = ["focal_lengths", "cc_optical_center"];

/// `camera_matrix_parameters.vision_top.<key>` (`vision_bottom` for the lower camera):
/// HULKs' top camera is the upper one (`camera_matrix_calculator.rs`, lines 37–38, 67–81).
fn vision_path(camera: CameraId, key: &'static str) -> [&'static str; 3] {
    [
        "camera_matrix_parameters",
        match camera {
            CameraId::Upper => "vision_top",
            CameraId::Lower => "vision_bottom",
        },
        key,
    ]
}

/// What HULKs' head file stores of calibrated intrinsics `i`: `[fx/W, fy/H, cx/W, cy/H]`
/// (W × H the calibration's image), which HULKs multiplies by its 640 × 480
/// (`CameraMatrix::from_normalized_focal_and_center`, `crates/projection/src/
/// camera_matrix.rs`, lines 49–54, commit 21e8a3de9).
fn normalised(i: &crate::calibration::Intrinsics) -> [f64; 4] {
    let [fx, fy] = i.relative_focal_lengths();
    let [cx, cy] = i.relative_centre();
    [fx, fy, cx, cy]
}

/// The normalised intrinsics of `camera` for a fresh head file, when `cal` carries them.
fn vision(cal: &Calibration, camera: CameraId) -> Option<Vision> {
    let [fx, fy, cx, cy] = normalised(&cal.intrinsics(camera)?);
    Some(Vision {
        focal_lengths: [fx, fy],
        cc_optical_center: [cx, cy],
    })
}

/// `camera`'s `[focal_lengths, cc_optical_center]` in a parsed head file, each `[a, b]`
/// with its spans when present, checked plausible (a focal length of an opening angle of
/// 10 … 150°, a centre within the image).
fn vision_at(
    root: &jsonedit::Value,
    path: &Path,
    camera: CameraId,
) -> Result<[Option<[Spanned; 2]>; 2], ExportError> {
    let mut out = [None; 2];
    for (a, key) in VISION_KEYS.iter().enumerate() {
        let at = vision_path(camera, key);
        let Some(v) = root.get(&at) else {
            continue;
        };
        let name = at.join(".");
        let (expected, range) = if a == 0 {
            // 2·atan(0.5 / f) from 150° to 10°.
            (
                "[fx, fy], normalised focal lengths of 0.134 … 5.7",
                0.134..=5.7,
            )
        } else {
            ("[x, y], a normalised optical centre of 0 … 1", 0.0..=1.0)
        };
        let bad =
            |line: usize| parse_error(path, format!("line {line}: {name}: expected {expected}"));
        let jsonedit::Kind::Array(items) = &v.kind else {
            return Err(bad(v.line));
        };
        if items.len() != 2 {
            return Err(bad(v.line));
        }
        let mut pair = [(0.0, 0, 0); 2];
        for (k, item) in items.iter().enumerate() {
            match item.kind {
                jsonedit::Kind::Number(x) if range.contains(&x) => {
                    pair[k] = (x, item.start, item.end)
                }
                _ => return Err(bad(item.line)),
            }
        }
        out[a] = Some(pair);
    }
    Ok(out)
}

impl Head {
    /// `camera`'s correction `[x, y, z]` (rad) as a head file stores it, checked plausible;
    /// `None` when the file has none for it.
    pub fn stored(
        text: &str,
        path: &Path,
        camera: CameraId,
    ) -> Result<Option<[f64; 3]>, ExportError> {
        let root = jsonedit::parse(text, path)?;
        Ok(correction_at(&root, path, camera)?.map(|found| found.map(|(x, _, _)| x)))
    }
}

/// HULKs' per-body parameter JSON (`body.<id>.json`): `joint_calibration_offsets` (rad),
/// storing −α.
#[derive(Debug, Clone, Copy)]
pub struct Body;

impl Format for Body {
    fn name(&self) -> &'static str {
        "hulks-body"
    }
    fn file(&self) -> &'static str {
        "hulks/body.json"
    }
    fn description(&self) -> &'static str {
        "HULKs body.<id>.json: joint_calibration_offsets = -alpha in rad"
    }
    fn doc_row(&self) -> DocRow {
        DocRow {
            carries: "`joint_calibration_offsets.{head,left_leg,right_leg}.<joint>`, stored −α",
            units: "rad",
            axes: "—",
        }
    }
    fn recognise(&self, code: &str) -> bool {
        code.contains("\"joint_calibration_offsets\"")
    }
    fn write(&self, cal: &Calibration) -> String {
        pretty(&BodyFile {
            naocalib_not_a_calibration: marker(cal),
            joint_calibration_offsets: offsets(cal),
        })
    }
    /// α = −stored (deg) of each joint the file lists; any other keys allowed.
    fn read(&self, text: &str, path: &Path) -> Result<Imported, ExportError> {
        let root = jsonedit::parse(text, path)?;
        Ok(offsets_at(&root, path)?
            .into_iter()
            .map(|(p, x)| (p, 0.0 - x.to_degrees()))
            .collect())
    }
    /// `text` with the joint offsets this calibration determined replaced (inserted when
    /// missing): stored = −α (rad) for raw angles, stored_old − α for corrected ones; every
    /// other byte kept.
    fn update(&self, text: &str, path: &Path, cal: &Calibration) -> Result<String, ExportError> {
        let root = jsonedit::parse(text, path)?;
        let old = offsets_at(&root, path)?;
        let mut out = text.to_string();
        for (group, name, param) in joints() {
            if cal.determined_here(param).is_none() {
                continue;
            }
            let old_deg = old
                .iter()
                .find(|(p, _)| *p == param)
                .map_or(0.0, |(_, x)| x.to_degrees());
            let new = cal.stored_joint_value(param, old_deg, path)?.to_radians();
            out = jsonedit::set(
                &out,
                &["joint_calibration_offsets", group, name],
                &num(new),
                path,
            )?;
        }
        Ok(out)
    }
    fn joints(&self) -> bool {
        true
    }
}

impl Body {
    /// The joint offsets as a body file stores them (other keys allowed): each by naocalib
    /// parameter (rad, −α), checked plausible.
    pub fn stored(text: &str, path: &Path) -> Result<Vec<(Param, f64)>, ExportError> {
        offsets_at(&jsonedit::parse(text, path)?, path)
    }
}
