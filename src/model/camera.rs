//! The NAO's two cameras ([`CameraId`]), the pinhole camera with optional OpenCV
//! distortion, and its projection as data ([`Projection`]): each camera's intrinsics and
//! first two distortion coefficients may carry calibration parameters (families
//! `intrinsics` and `distortion`: `Fx` … `K2` for the lower camera, `UpperFx` … `UpperK2`
//! for the upper one; see docs/MODEL.md).

use super::chain::Affine;
use super::parameters::{PARAMETER_COUNT, Param};
use super::scalar::{Scalar, lift};

/// Which of the NAO's two head cameras took a picture.
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Hash,
    PartialOrd,
    Ord,
    Default,
    serde::Serialize,
    serde::Deserialize,
)]
#[serde(rename_all = "lowercase")]
pub enum CameraId {
    /// The lower camera (mouth), tilted 39.7° down: the paper's camera.
    #[default]
    Lower,
    /// The upper camera (forehead), tilted 1.2° down.
    Upper,
}

impl CameraId {
    /// Both cameras, lower first.
    pub const ALL: [CameraId; 2] = [CameraId::Lower, CameraId::Upper];

    /// `lower` or `upper`, as in the `camera` column of `captures.csv`.
    pub fn name(self) -> &'static str {
        match self {
            CameraId::Lower => "lower",
            CameraId::Upper => "upper",
        }
    }

    /// Parses `lower` / `upper`.
    pub fn from_name(name: &str) -> Option<CameraId> {
        CameraId::ALL.into_iter().find(|c| c.name() == name)
    }

    /// The camera's rotation offsets: yaw, pitch, roll (`CamYaw, CamPitch, CamRoll` or
    /// `UpperCamYaw, UpperCamPitch, UpperCamRoll`).
    pub fn rotation_params(self) -> [Param; 3] {
        match self {
            CameraId::Lower => [Param::CamYaw, Param::CamPitch, Param::CamRoll],
            CameraId::Upper => [
                Param::UpperCamYaw,
                Param::UpperCamPitch,
                Param::UpperCamRoll,
            ],
        }
    }

    /// The camera's intrinsics and distortion corrections, in the order fx, fy, cx, cy,
    /// k1, k2 (`Fx` … `K2` or `UpperFx` … `UpperK2`).
    pub fn projection_params(self) -> [Param; 6] {
        match self {
            CameraId::Lower => [
                Param::Fx,
                Param::Fy,
                Param::Cx,
                Param::Cy,
                Param::K1,
                Param::K2,
            ],
            CameraId::Upper => [
                Param::UpperFx,
                Param::UpperFy,
                Param::UpperCx,
                Param::UpperCy,
                Param::UpperK1,
                Param::UpperK2,
            ],
        }
    }
}

impl std::fmt::Display for CameraId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A-priori intrinsic calibration of one camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Focal length in x (px).
    pub fx: f64,
    /// Focal length in y (px).
    pub fy: f64,
    /// Optical centre, x (px).
    pub cx: f64,
    /// Optical centre, y (px).
    pub cy: f64,
    /// OpenCV distortion `[k1, k2, p1, p2, k3]`.
    pub distortion: [f64; 5],
}

impl Default for Camera {
    /// The paper's intrinsics (focal length 562.5 px, centre (324, 189)) at VGA.
    fn default() -> Self {
        Camera {
            width: 640,
            height: 480,
            fx: 562.5,
            fy: 562.5,
            cx: 324.0,
            cy: 189.0,
            distortion: [0.0; 5],
        }
    }
}

/// OpenCV's lens distortion `[k1, k2, p1, p2, k3]` applied to normalised coordinates
/// `(a, b)`: the one place the distortion formula is written.
pub fn distort<T: Scalar>(a: T, b: T, k: &[T; 5]) -> [T; 2] {
    let [k1, k2, p1, p2, k3] = k.clone();
    let r2 = a.clone() * a.clone() + b.clone() * b.clone();
    let radial = lift::<T>(1.0) + r2.clone() * (k1 + r2.clone() * (k2 + r2.clone() * k3));
    let ab = a.clone() * b.clone();
    let da =
        ab.clone() * p1.clone() * 2.0 + (r2.clone() + a.clone() * a.clone() * 2.0) * p2.clone();
    let db = (r2 + b.clone() * b.clone() * 2.0) * p1 + ab * p2 * 2.0;
    [a * radial.clone() + da, b * radial + db]
}

impl Camera {
    /// Whether the lens distortion is not all zero.
    pub fn is_distorted(&self) -> bool {
        self.distortion.iter().any(|&k| k != 0.0)
    }

    /// Projects a point given in the camera frame `C` (x along the optical axis) to pixels.
    /// `None` when the point is not in front of the camera (`x ≤ 0`).
    pub fn project<T: Scalar>(&self, p: &[T; 3]) -> Option<[T; 2]> {
        self.constant_projection().project::<T>(&[], p)
    }

    /// The projection with no parameter attached (the a-priori intrinsics as constants).
    pub fn constant_projection(&self) -> Projection {
        let [k1, k2, p1, p2, k3] = self.distortion;
        let c = Affine::constant;
        Projection {
            fx: c(self.fx),
            fy: c(self.fy),
            cx: c(self.cx),
            cy: c(self.cy),
            k1: c(k1),
            k2: c(k2),
            p1,
            p2,
            k3,
        }
    }

    /// The projection as data, with the intrinsics and distortion parameters (Fx, Fy, Cx,
    /// Cy, K1, K2) added to the a-priori values: the lower camera's.
    pub fn projection(&self) -> Projection {
        self.projection_of(CameraId::Lower)
    }

    /// The projection as data of `camera` with these a-priori intrinsics: its six
    /// corrections ([`CameraId::projection_params`]) added to the a-priori values.
    pub fn projection_of(&self, camera: CameraId) -> Projection {
        let [fx, fy, cx, cy, k1, k2] = camera.projection_params();
        Projection {
            fx: Affine::constant(self.fx).plus(fx, 1.0),
            fy: Affine::constant(self.fy).plus(fy, 1.0),
            cx: Affine::constant(self.cx).plus(cx, 1.0),
            cy: Affine::constant(self.cy).plus(cy, 1.0),
            k1: Affine::constant(self.distortion[0]).plus(k1, 1.0),
            k2: Affine::constant(self.distortion[1]).plus(k2, 1.0),
            ..self.constant_projection()
        }
    }

    /// These intrinsics with `camera`'s corrections in `params` (internal units, indexed
    /// by [`Param::index`]) added: the true camera of a simulated robot.
    pub fn corrected(&self, camera: CameraId, params: &[f64]) -> Camera {
        let [fx, fy, cx, cy, k1, k2] = camera.projection_params().map(|p| params[p.index()]);
        let mut out = *self;
        out.fx += fx;
        out.fy += fy;
        out.cx += cx;
        out.cy += cy;
        out.distortion[0] += k1;
        out.distortion[1] += k2;
        out
    }

    /// Removes the lens distortion: the undistorted normalised coordinates `(a, b)`
    /// (`a = −y/x`, `b = −z/x`) of pixel `(u, v)` (Newton's method on [`distort`]).
    pub fn undistort(&self, u: f64, v: f64) -> [f64; 2] {
        let ad = (u - self.cx) / self.fx;
        let bd = (v - self.cy) / self.fy;
        if !self.is_distorted() {
            return [ad, bd];
        }
        let k = &self.distortion;
        let (mut a, mut b) = (ad, bd);
        for _ in 0..20 {
            let [fa, fb] = distort(a, b, k);
            let (ea, eb) = (fa - ad, fb - bd);
            if ea.abs() < 1e-14 && eb.abs() < 1e-14 {
                break;
            }
            let h = 1e-7;
            let [fa1, fb1] = distort(a + h, b, k);
            let [fa2, fb2] = distort(a, b + h, k);
            let (j11, j21) = ((fa1 - fa) / h, (fb1 - fb) / h);
            let (j12, j22) = ((fa2 - fa) / h, (fb2 - fb) / h);
            let det = j11 * j22 - j12 * j21;
            if det.abs() < 1e-12 {
                break;
            }
            a -= (j22 * ea - j12 * eb) / det;
            b -= (-j21 * ea + j11 * eb) / det;
        }
        [a, b]
    }

    /// Whether a pixel position lies inside the image, at least `margin` pixels from its
    /// border.
    pub fn contains(&self, uv: [f64; 2], margin: f64) -> bool {
        uv[0] >= margin
            && uv[1] >= margin
            && uv[0] <= self.width as f64 - 1.0 - margin
            && uv[1] <= self.height as f64 - 1.0 - margin
    }
}

/// The projection `P` as data: `u = cx + fx·a'`, `v = cy + fy·b'` with `(a', b')` the
/// distorted normalised coordinates of `(a, b) = (−y/x, −z/x)`. The intrinsics and the first
/// two distortion coefficients may depend on calibration parameters; Rust and the Ceres shim
/// evaluate the same description.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Projection {
    /// Focal length in x (px).
    pub fx: Affine,
    /// Focal length in y (px).
    pub fy: Affine,
    /// Optical centre x (px).
    pub cx: Affine,
    /// Optical centre y (px).
    pub cy: Affine,
    /// Radial distortion k1.
    pub k1: Affine,
    /// Radial distortion k2.
    pub k2: Affine,
    /// Tangential distortion p1 (constant).
    pub p1: f64,
    /// Tangential distortion p2 (constant).
    pub p2: f64,
    /// Radial distortion k3 (constant).
    pub k3: f64,
}

impl Projection {
    /// The six parameterised coefficients, in the order fx, fy, cx, cy, k1, k2.
    pub fn coefficients(&self) -> [&Affine; 6] {
        [&self.fx, &self.fy, &self.cx, &self.cy, &self.k1, &self.k2]
    }

    /// Whether the distortion polynomial must be evaluated (a coefficient is non-zero or
    /// may become so).
    pub fn is_distorted(&self) -> bool {
        self.k1.depends() || self.k2.depends() || {
            [
                self.k1.constant,
                self.k2.constant,
                self.p1,
                self.p2,
                self.k3,
            ]
            .iter()
            .any(|&k| k != 0.0)
        }
    }

    /// The projection with every parameter in `held` replaced by its value in `values`.
    pub fn freeze(&self, held: &[bool; PARAMETER_COUNT], values: &[f64]) -> Projection {
        let f = |a: &Affine| a.freeze(held, values);
        Projection {
            fx: f(&self.fx),
            fy: f(&self.fy),
            cx: f(&self.cx),
            cy: f(&self.cy),
            k1: f(&self.k1),
            k2: f(&self.k2),
            ..*self
        }
    }

    /// Projects a point of the camera frame `C` to pixels for parameters `params`
    /// (indexed by [`Param::index`]; may be empty when no coefficient depends on one).
    /// `None` when the point is not in front of the camera (`x ≤ 0`).
    pub fn project<T: Scalar>(&self, params: &[T], p: &[T; 3]) -> Option<[T; 2]> {
        self.project_with(&self.coefficients_at(params), p)
    }

    /// The six coefficients (fx, fy, cx, cy, k1, k2) at `params`: evaluated once for many
    /// points ([`Projection::project_with`]).
    pub fn coefficients_at<T: Scalar>(&self, params: &[T]) -> [T; 6] {
        self.coefficients().map(|a| a.eval(params))
    }

    /// [`Projection::project`] with the six coefficients (fx, fy, cx, cy, k1, k2) given as
    /// values, e.g. dual numbers seeded for their derivatives.
    pub fn project_with<T: Scalar>(&self, coefficients: &[T; 6], p: &[T; 3]) -> Option<[T; 2]> {
        if p[0].re() <= 0.0 {
            return None;
        }
        let [fx, fy, cx, cy, k1, k2] = coefficients.clone();
        let inv = p[0].recip();
        let a = -(p[1].clone() * inv.clone());
        let b = -(p[2].clone() * inv);
        let [a, b] = if self.is_distorted() {
            distort(a, b, &[k1, k2, lift(self.p1), lift(self.p2), lift(self.k3)])
        } else {
            [a, b]
        };
        Some([a * fx + cx, b * fy + cy])
    }

    /// The parameters the projection depends on, in order, without repeats.
    pub fn params(&self) -> Vec<Param> {
        let mut out = Vec::new();
        for a in self.coefficients() {
            for (p, _) in a.terms() {
                if !out.contains(&p) {
                    out.push(p);
                }
            }
        }
        out
    }
}
