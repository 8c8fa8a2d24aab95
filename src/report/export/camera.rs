//! The lower camera's rotation correction in each team's parameterisation.
//!
//! naocalib's camera frame `C` has x along the optical axis, y left, z up, and the head →
//! camera rotation is `Ry(tilt) · Rc` with the correction `Rc = Ry(CamPitch) · Rx(CamRoll)
//! · Rz(CamYaw)` (docs/MODEL.md). The teams write the same physical rotation with other
//! Euler orders, other places for the correction (before or after the fixed tilt), and —
//! HULKs and rUNSWift — camera frames with z along the optical axis, x right and y down
//! ([`OPTICAL_AXES`]). Each function here solves the team's formula for its parameters
//! exactly (no small-angle approximation); the export tests rebuild the team's camera
//! rotation with the team's own formula and compare.
//!
//! Every team hard-codes the NAO's nominal lower-camera tilt, [`NOMINAL_TILT_DEG`]; the
//! conversions use it too (a dataset with another tilt would need that team's constant
//! changed as well).

use nalgebra::{Matrix3, Rotation3, Vector3};

use super::Calibration;
use crate::model::Param;

/// The lower camera's tilt below the head's x axis that the teams' code hard-codes (deg)
/// (`tiltNeckToLowerCamera`, `CAMERA_BOTTOM_PITCH_DEGREES`, `camera_bottom_angle`, …).
pub const NOMINAL_TILT_DEG: f64 = 39.7;

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

/// naocalib's camera offsets `(CamYaw, CamPitch, CamRoll)` (rad) of `cal`.
pub fn offsets_rad(cal: &Calibration) -> [f64; 3] {
    [Param::CamYaw, Param::CamPitch, Param::CamRoll].map(|p| cal.value(p).to_radians())
}

/// naocalib's correction `Rc = Ry(pitch) · Rx(roll) · Rz(yaw)` (rad).
pub fn correction(yaw: f64, pitch: f64, roll: f64) -> Matrix3<f64> {
    rot_y(pitch) * rot_x(roll) * rot_z(yaw)
}

/// naocalib's camera → head rotation `Ry(tilt) · Rc` (camera frame C) for the offsets of
/// `cal`, with the nominal tilt.
pub fn head_from_camera(cal: &Calibration) -> Matrix3<f64> {
    let [yaw, pitch, roll] = offsets_rad(cal);
    rot_y(NOMINAL_TILT_DEG.to_radians()) * correction(yaw, pitch, roll)
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

/// B-Human (and its descendants): `rotateY(tilt + y) · rotateX(x) · rotateZ(z)` in the
/// same camera frame — naocalib's order, so `[x, y, z] = [CamRoll, CamPitch, CamYaw]`
/// (rad), exactly.
pub fn bhuman(cal: &Calibration) -> [f64; 3] {
    let [yaw, pitch, roll] = offsets_rad(cal);
    [roll, pitch, yaw]
}

/// NaoTH: `rotateZ(z) · rotateY(y + tilt) · rotateX(x)` in the same camera frame (x
/// forward, y left, z up): `[x, y, z]` (rad) with `Rz(z) · Ry(tilt + y) · Rx(x) = Ry(tilt)
/// · Rc`.
pub fn naoth(cal: &Calibration) -> [f64; 3] {
    let [z, b, x] = zyx_angles(&head_from_camera(cal));
    [x, b - NOMINAL_TILT_DEG.to_radians(), z]
}

/// HULKs: the head → camera rotation (optical frame) is `C · R₀` with the correction
/// `C = Rz(z) · Ry(y) · Rx(x)` (nalgebra's `from_euler_angles(x, y, z)`) applied on the
/// camera side. With `Q` = [`optical_axes`], `C = Qᵀ · Rcᵀ · Q`; returns `[x, y, z]` (rad).
pub fn hulks(cal: &Calibration) -> [f64; 3] {
    let [yaw, pitch, roll] = offsets_rad(cal);
    let q = optical_axes();
    let c = q.transpose() * correction(yaw, pitch, roll).transpose() * q;
    let [z, y, x] = zyx_angles(&c);
    [x, y, z]
}

/// rUNSWift's fixed part of the head → camera chain, `A = Rx(−π/2) · Rz(tilt − π) ·
/// Rx(−π/2)` (the Denavit-Hartenberg rotations before the offsets, head pitch 0).
pub fn runswift_base() -> Matrix3<f64> {
    use std::f64::consts::{FRAC_PI_2, PI};
    rot_x(-FRAC_PI_2) * rot_z(NOMINAL_TILT_DEG.to_radians() - PI) * rot_x(-FRAC_PI_2)
}

/// rUNSWift: camera → head is `A · Rz(π/2 + yaw) · Rx(−π/2 + pitch) · Rz(roll)` in the
/// optical camera frame; returns `[yaw, pitch, roll]` (rad) with that equal to
/// `Ry(tilt) · Rc · Q`.
pub fn runswift(cal: &Calibration) -> [f64; 3] {
    use std::f64::consts::FRAC_PI_2;
    let target = head_from_camera(cal) * optical_axes();
    let [a, b, c] = zxz_angles_negative(&(runswift_base().transpose() * target));
    [a - FRAC_PI_2, b + FRAC_PI_2, c]
}

/// `(a, b, c)` with `m = Ry(a) · Rx(b) · Rz(c)`, `b` in [−π/2, π/2]: naocalib's order.
pub fn yxz_angles(m: &Matrix3<f64>) -> [f64; 3] {
    let b = (-m[(1, 2)]).clamp(-1.0, 1.0).asin();
    let a = m[(0, 2)].atan2(m[(2, 2)]);
    let c = m[(1, 0)].atan2(m[(1, 1)]);
    [a, b, c]
}

/// naocalib's camera offsets `[CamYaw, CamPitch, CamRoll]` (deg) of the camera → head
/// rotation `head_from_camera` (naocalib's camera frame), with the nominal tilt.
pub fn offsets_deg_of(head_from_camera: &Matrix3<f64>) -> [f64; 3] {
    let rc = rot_y(-NOMINAL_TILT_DEG.to_radians()) * head_from_camera;
    let [pitch, roll, yaw] = yxz_angles(&rc);
    [yaw, pitch, roll].map(f64::to_degrees)
}

/// The inverse of [`naoth`]: naocalib's `[CamYaw, CamPitch, CamRoll]` (deg) of NaoTH's
/// `[x, y, z]` (rad).
pub fn from_naoth([x, y, z]: [f64; 3]) -> [f64; 3] {
    offsets_deg_of(&(rot_z(z) * rot_y(NOMINAL_TILT_DEG.to_radians() + y) * rot_x(x)))
}

/// The inverse of [`hulks`]: naocalib's `[CamYaw, CamPitch, CamRoll]` (deg) of HULKs'
/// `[x, y, z]` (rad).
pub fn from_hulks([x, y, z]: [f64; 3]) -> [f64; 3] {
    let q = optical_axes();
    let c = rot_z(z) * rot_y(y) * rot_x(x);
    let rc = q * c.transpose() * q.transpose();
    offsets_deg_of(&(rot_y(NOMINAL_TILT_DEG.to_radians()) * rc))
}

/// The inverse of [`runswift`]: naocalib's `[CamYaw, CamPitch, CamRoll]` (deg) of
/// rUNSWift's `[yaw, pitch, roll]` (rad).
pub fn from_runswift([yaw, pitch, roll]: [f64; 3]) -> [f64; 3] {
    use std::f64::consts::FRAC_PI_2;
    let chain = runswift_base() * rot_z(FRAC_PI_2 + yaw) * rot_x(-FRAC_PI_2 + pitch) * rot_z(roll);
    offsets_deg_of(&(chain * optical_axes().transpose()))
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
