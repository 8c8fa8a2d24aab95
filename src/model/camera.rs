//! The pinhole camera with optional OpenCV distortion (SPEC section 3).

use super::scalar::{Scalar, lift};

/// A-priori intrinsic calibration of the lower camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Focal length in x [px].
    pub fx: f64,
    /// Focal length in y [px].
    pub fy: f64,
    /// Optical centre, x [px].
    pub cx: f64,
    /// Optical centre, y [px].
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

impl Camera {
    /// Whether the lens distortion is not all zero.
    pub fn is_distorted(&self) -> bool {
        self.distortion.iter().any(|&k| k != 0.0)
    }

    /// Projects a point given in the camera frame `C` (x along the optical axis) to pixels.
    /// `None` when the point is not in front of the camera (`x ≤ 0`).
    pub fn project<T: Scalar>(&self, p: &[T; 3]) -> Option<[T; 2]> {
        if p[0].re() <= 0.0 {
            return None;
        }
        let inv = p[0].recip();
        let mut a = -(p[1].clone() * inv.clone());
        let mut b = -(p[2].clone() * inv);
        if self.is_distorted() {
            let [k1, k2, p1, p2, k3] = self.distortion;
            let r2 = a.clone() * a.clone() + b.clone() * b.clone();
            let radial = lift::<T>(1.0)
                + r2.clone() * (lift::<T>(k1) + r2.clone() * (lift::<T>(k2) + r2.clone() * k3));
            let ab = a.clone() * b.clone();
            let da = ab.clone() * (2.0 * p1) + (r2.clone() + a.clone() * a.clone() * 2.0) * p2;
            let db = (r2 + b.clone() * b.clone() * 2.0) * p1 + ab * (2.0 * p2);
            a = a * radial.clone() + da;
            b = b * radial + db;
        }
        Some([a * self.fx + self.cx, b * self.fy + self.cy])
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
