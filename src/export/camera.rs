//! Each camera's rotation correction in each team's parameterisation.
//!
//! naocalib's camera frame `C` has x along the optical axis, y left, z up, and the head →
//! camera rotation is `Ry(tilt) · Rc` with the correction `Rc = Ry(pitch) · Rx(roll) ·
//! Rz(yaw)` (docs/MODEL.md): `CamYaw`, `CamPitch`, `CamRoll` for the lower camera,
//! `UpperCamYaw`, `UpperCamPitch`, `UpperCamRoll` for the upper one ([`params`]). The teams
//! write the same physical rotation with other Euler orders, other places for the
//! correction (before or after the fixed tilt), and — HULKs and rUNSWift — camera frames
//! with z along the optical axis, x right and y down ([`OPTICAL_AXES`]). Each function
//! here solves the team's formula for its parameters exactly (no small-angle
//! approximation); the export tests rebuild the team's camera rotation with the team's own
//! formula and compare.
//!
//! Every team hard-codes the NAO's nominal camera tilts, [`nominal_tilt_deg`] (39.7° lower,
//! 1.2° upper); the conversions use them too (a dataset with another tilt would need that
//! team's constant changed as well).

use nalgebra::{Matrix3, Rotation3, Vector3};

use super::Calibration;
use crate::model::{CameraId, Param};

/// The lower camera's tilt below the head's x axis that the teams' code hard-codes (deg)
/// (`tiltNeckToLowerCamera`, `CAMERA_BOTTOM_PITCH_DEGREES`, `camera_bottom_angle`, …).
pub const NOMINAL_TILT_DEG: f64 = 39.7;

/// The upper camera's tilt that the teams' code hard-codes (deg) (`tiltNeckToUpperCamera`,
/// `camera_top_angle`, HULKs' top `camera_pitch` of −1.2, NaoTH's top `rotationY`).
pub const UPPER_NOMINAL_TILT_DEG: f64 = 1.2;

/// The camera's nominal tilt (deg) in the teams' code.
pub fn nominal_tilt_deg(camera: CameraId) -> f64 {
    match camera {
        CameraId::Lower => NOMINAL_TILT_DEG,
        CameraId::Upper => UPPER_NOMINAL_TILT_DEG,
    }
}

/// naocalib's offsets of the camera's correction: `[yaw, pitch, roll]`
/// ([`CameraId::rotation_params`]).
pub fn params(camera: CameraId) -> [Param; 3] {
    camera.rotation_params()
}

/// The axes of an "optical" camera frame (z forward along the optical axis, x right, y
/// down; HULKs, rUNSWift) as columns in naocalib's camera frame (x forward, y left, z up).
pub const OPTICAL_AXES: [[f64; 3]; 3] = [[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]];

/// A rotation about x.
pub fn rot_x(a: f64) -> Matrix3<f64> {
    *Rotation3::from_axis_angle(&Vector3::x_axis(), a).matrix()
}

/// A rotation about y.
pub fn rot_y(a: f64) -> Matrix3<f64> {
    *Rotation3::from_axis_angle(&Vector3::y_axis(), a).matrix()
}

/// A rotation about z.
pub fn rot_z(a: f64) -> Matrix3<f64> {
    *Rotation3::from_axis_angle(&Vector3::z_axis(), a).matrix()
}

/// [`OPTICAL_AXES`] as a matrix `Q` (optical-frame coordinates → naocalib camera frame).
pub fn optical_axes() -> Matrix3<f64> {
    Matrix3::from_fn(|r, c| OPTICAL_AXES[r][c])
}

/// naocalib's offsets `[yaw, pitch, roll]` (rad) of `camera` in `cal`.
pub fn offsets_rad(cal: &Calibration, camera: CameraId) -> [f64; 3] {
    params(camera).map(|p| cal.value(p).to_radians())
}

/// naocalib's correction `Rc = Ry(pitch) · Rx(roll) · Rz(yaw)` (rad).
pub fn correction(yaw: f64, pitch: f64, roll: f64) -> Matrix3<f64> {
    rot_y(pitch) * rot_x(roll) * rot_z(yaw)
}

/// naocalib's camera → head rotation `Ry(tilt) · Rc` (camera frame C) of `camera` for the
/// offsets of `cal`, with the nominal tilt.
pub fn head_from_camera(cal: &Calibration, camera: CameraId) -> Matrix3<f64> {
    let [yaw, pitch, roll] = offsets_rad(cal, camera);
    rot_y(nominal_tilt_deg(camera).to_radians()) * correction(yaw, pitch, roll)
}

/// `(a, b, c)` with `m = Rz(a) · Ry(b) · Rx(c)`, `b` in [−π/2, π/2].
pub fn zyx_angles(m: &Matrix3<f64>) -> [f64; 3] {
    let b = (-m[(2, 0)]).clamp(-1.0, 1.0).asin();
    let a = m[(1, 0)].atan2(m[(0, 0)]);
    let c = m[(2, 1)].atan2(m[(2, 2)]);
    [a, b, c]
}

/// `(a, b, c)` with `m = Rz(a) · Rx(b) · Rz(c)`, `b` in (−π, 0) (the branch near the
/// camera's −π/2 of rUNSWift's chain).
pub fn zxz_angles_negative(m: &Matrix3<f64>) -> [f64; 3] {
    let b = -m[(2, 2)].clamp(-1.0, 1.0).acos();
    let s = b.sin();
    let a = (m[(0, 2)] / s).atan2(-m[(1, 2)] / s);
    let c = (m[(2, 0)] / s).atan2(m[(2, 1)] / s);
    [a, b, c]
}

/// B-Human (and its descendants, NomadZ): `rotateY(tilt + y) · rotateX(x) · rotateZ(z)` in
/// the same camera frame — naocalib's order, so `[x, y, z] = [roll, pitch, yaw]` (rad),
/// exactly, for either camera.
pub fn bhuman(cal: &Calibration, camera: CameraId) -> [f64; 3] {
    let [yaw, pitch, roll] = offsets_rad(cal, camera);
    [roll, pitch, yaw]
}

/// NaoTH: `rotateZ(z) · rotateY(y + tilt) · rotateX(x)` in the same camera frame (x
/// forward, y left, z up): `[x, y, z]` (rad) with `Rz(z) · Ry(tilt + y) · Rx(x) = Ry(tilt)
/// · Rc`.
pub fn naoth(cal: &Calibration, camera: CameraId) -> [f64; 3] {
    naoth_of(&head_from_camera(cal, camera), camera)
}

/// NaoTH's `[x, y, z]` (rad) of the camera → head rotation `m` (after the head's roll):
/// `Rz(z) · Ry(tilt + y) · Rx(x) = m`.
pub fn naoth_of(m: &Matrix3<f64>, camera: CameraId) -> [f64; 3] {
    let [z, b, x] = zyx_angles(m);
    [x, b - nominal_tilt_deg(camera).to_radians(), z]
}

/// HULKs: the head → camera rotation (optical frame) is `C · R₀` with the correction
/// `C = Rz(z) · Ry(y) · Rx(x)` (nalgebra's `from_euler_angles(x, y, z)`) applied on the
/// camera side. With `Q` = [`optical_axes`], `C = Qᵀ · Rcᵀ · Q` (the tilt is in `R₀`, so
/// the same for either camera); returns `[x, y, z]` (rad).
pub fn hulks(cal: &Calibration, camera: CameraId) -> [f64; 3] {
    let [yaw, pitch, roll] = offsets_rad(cal, camera);
    let q = optical_axes();
    let c = q.transpose() * correction(yaw, pitch, roll).transpose() * q;
    let [z, y, x] = zyx_angles(&c);
    [x, y, z]
}

/// rUNSWift's fixed part of the head → camera chain, `A = Rx(−π/2) · Rz(tilt − π) ·
/// Rx(−π/2)` (the Denavit-Hartenberg rotations before the offsets, head pitch 0; `tilt`
/// is `camera_bottom_angle` or `camera_top_angle`).
pub fn runswift_base(camera: CameraId) -> Matrix3<f64> {
    use std::f64::consts::{FRAC_PI_2, PI};
    rot_x(-FRAC_PI_2) * rot_z(nominal_tilt_deg(camera).to_radians() - PI) * rot_x(-FRAC_PI_2)
}

/// rUNSWift: camera → head is `A · Rz(π/2 + yaw) · Rx(−π/2 + pitch) · Rz(roll)` in the
/// optical camera frame; returns `[yaw, pitch, roll]` (rad) with that equal to
/// `Ry(tilt) · Rc · Q`.
pub fn runswift(cal: &Calibration, camera: CameraId) -> [f64; 3] {
    use std::f64::consts::FRAC_PI_2;
    let target = head_from_camera(cal, camera) * optical_axes();
    let [a, b, c] = zxz_angles_negative(&(runswift_base(camera).transpose() * target));
    [a - FRAC_PI_2, b + FRAC_PI_2, c]
}

/// `(a, b, c)` with `m = Ry(a) · Rx(b) · Rz(c)`, `b` in [−π/2, π/2]: naocalib's order.
pub fn yxz_angles(m: &Matrix3<f64>) -> [f64; 3] {
    let b = (-m[(1, 2)]).clamp(-1.0, 1.0).asin();
    let a = m[(0, 2)].atan2(m[(2, 2)]);
    let c = m[(1, 0)].atan2(m[(1, 1)]);
    [a, b, c]
}

/// naocalib's offsets `[yaw, pitch, roll]` (deg) of `camera` for the camera → head
/// rotation `head_from_camera` (naocalib's camera frame), with the nominal tilt.
pub fn offsets_deg_of(head_from_camera: &Matrix3<f64>, camera: CameraId) -> [f64; 3] {
    let rc = rot_y(-nominal_tilt_deg(camera).to_radians()) * head_from_camera;
    let [pitch, roll, yaw] = yxz_angles(&rc);
    [yaw, pitch, roll].map(f64::to_degrees)
}

/// The inverse of [`naoth`]: naocalib's `[yaw, pitch, roll]` (deg) of NaoTH's `[x, y, z]`
/// (rad).
pub fn from_naoth([x, y, z]: [f64; 3], camera: CameraId) -> [f64; 3] {
    let tilt = nominal_tilt_deg(camera).to_radians();
    offsets_deg_of(&(rot_z(z) * rot_y(tilt + y) * rot_x(x)), camera)
}

/// The inverse of [`hulks`]: naocalib's `[yaw, pitch, roll]` (deg) of HULKs' `[x, y, z]`
/// (rad).
pub fn from_hulks([x, y, z]: [f64; 3], camera: CameraId) -> [f64; 3] {
    let q = optical_axes();
    let c = rot_z(z) * rot_y(y) * rot_x(x);
    let rc = q * c.transpose() * q.transpose();
    offsets_deg_of(&(rot_y(nominal_tilt_deg(camera).to_radians()) * rc), camera)
}

/// The inverse of [`runswift`]: naocalib's `[yaw, pitch, roll]` (deg) of rUNSWift's
/// `[yaw, pitch, roll]` (rad).
pub fn from_runswift([yaw, pitch, roll]: [f64; 3], camera: CameraId) -> [f64; 3] {
    use std::f64::consts::FRAC_PI_2;
    let chain =
        runswift_base(camera) * rot_z(FRAC_PI_2 + yaw) * rot_x(-FRAC_PI_2 + pitch) * rot_z(roll);
    offsets_deg_of(&(chain * optical_axes().transpose()), camera)
}

/// Whether `cal` determined `camera`, for formats whose parameterisation mixes its three
/// offsets: `false` when none was estimated; an error (nothing written) when only some are
/// known.
pub fn determined(
    cal: &Calibration,
    camera: CameraId,
    path: &std::path::Path,
) -> Result<bool, super::ExportError> {
    let cams = params(camera);
    if cams.iter().all(|&p| cal.determined_here(p).is_none()) {
        return Ok(false);
    }
    if cams.iter().any(|&p| cal.robot_value(p).is_none()) {
        return Err(super::parse_error(
            path,
            format!(
                "the {} camera's offsets are only partly determined, and this format mixes \
                 them: not updated",
                camera.name()
            ),
        ));
    }
    Ok(true)
}

/// Both cameras, lower first.
pub const CAMERAS: [CameraId; 2] = CameraId::ALL;

/// Whether a fresh file carries `camera`'s correction from `cal` (the upper camera's is
/// otherwise zero or absent): when `cal` estimated one of its offsets and the data
/// determine it, or when `cal` is a robot's calibration read by `naocalib import` that
/// holds one. An offset merely held (at zero, or at a start value for a dataset without
/// that camera's captures) is nothing this calibration knows of the camera.
pub fn known(cal: &Calibration, camera: CameraId) -> bool {
    let ps = params(camera);
    ps.iter().any(|&p| cal.determined_here(p).is_some())
        || (cal.is_import() && ps.iter().any(|&p| cal.robot_value(p).is_some()))
}

/// `camera`'s three offsets `[yaw, pitch, roll]` (deg) for a fresh file of a format that
/// mixes them: when [`known`] and all three have a value a robot file can take.
pub fn complete(cal: &Calibration, camera: CameraId) -> Option<[f64; 3]> {
    if !known(cal, camera) {
        return None;
    }
    let [yaw, pitch, roll] = params(camera).map(|p| cal.robot_value(p));
    Some([yaw?, pitch?, roll?])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decompositions_invert_their_products() {
        let m = rot_z(0.3) * rot_y(-0.2) * rot_x(0.1);
        let [a, b, c] = zyx_angles(&m);
        assert!((a - 0.3).abs() < 1e-12 && (b + 0.2).abs() < 1e-12 && (c - 0.1).abs() < 1e-12);
        let m = rot_z(0.3) * rot_x(-1.4) * rot_z(-0.2);
        let [a, b, c] = zxz_angles_negative(&m);
        assert!((a - 0.3).abs() < 1e-12 && (b + 1.4).abs() < 1e-12 && (c + 0.2).abs() < 1e-12);
        let m = rot_y(0.3) * rot_x(-0.2) * rot_z(0.1);
        let [a, b, c] = yxz_angles(&m);
        assert!((a - 0.3).abs() < 1e-12 && (b + 0.2).abs() < 1e-12 && (c - 0.1).abs() < 1e-12);
    }
}
