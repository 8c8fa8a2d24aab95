//! Camera presets for simulation: the paper's V4 lower camera, and the V6 lower camera at
//! its two resolutions.
//!
//! The V6 presets come from the published field of view of the NAO V6 cameras, 56.3°
//! horizontally × 43.7° vertically: focal lengths `fx = (w/2) / tan(hfov/2)`, `fy = (h/2)
//! / tan(vfov/2)`, the principal point at the image centre `(w/2, h/2)`, no distortion —
//! a nominal camera, not a calibrated one. A team with its own intrinsics writes them into
//! the dataset's `dataset.toml` (`[camera]`: width, height, fx, fy, cx, cy, distortion).

use crate::model::Camera;

/// A named camera for `naocalib simulate --camera`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CameraPreset {
    /// The paper's V4 lower camera: 640×480, focal length 562.5 px, centre (324, 189).
    V4,
    /// The V6 lower camera at 640×480, from its field of view.
    V6,
    /// The V6 lower camera at 1280×960, from its field of view.
    V6Hd,
}

/// The V6 cameras' horizontal field of view (deg).
pub const V6_HFOV_DEG: f64 = 56.3;
/// The V6 cameras' vertical field of view (deg).
pub const V6_VFOV_DEG: f64 = 43.7;

impl CameraPreset {
    /// Every preset with its name.
    pub const ALL: [(CameraPreset, &'static str); 3] = [
        (CameraPreset::V4, "v4"),
        (CameraPreset::V6, "v6"),
        (CameraPreset::V6Hd, "v6-1280x960"),
    ];

    /// The preset named `name` (`v4`, `v6`, `v6-1280x960`; `v6-640x480` is `v6`).
    pub fn from_name(name: &str) -> Option<Self> {
        if name == "v6-640x480" {
            return Some(CameraPreset::V6);
        }
        Self::ALL.iter().find(|(_, n)| *n == name).map(|(p, _)| *p)
    }

    /// The preset's name.
    pub fn name(self) -> &'static str {
        Self::ALL
            .iter()
            .find(|(p, _)| *p == self)
            .map_or("", |(_, n)| n)
    }

    /// The camera: intrinsics as described in the module documentation.
    pub fn camera(self) -> Camera {
        match self {
            CameraPreset::V4 => Camera::default(),
            CameraPreset::V6 => from_fov(640, 480, V6_HFOV_DEG, V6_VFOV_DEG),
            CameraPreset::V6Hd => from_fov(1280, 960, V6_HFOV_DEG, V6_VFOV_DEG),
        }
    }
}

/// A distortion-free camera of `width` × `height` pixels with the given fields of view
/// (deg): `fx = (w/2) / tan(hfov/2)`, `fy = (h/2) / tan(vfov/2)`, principal point at the
/// image centre.
pub fn from_fov(width: u32, height: u32, hfov_deg: f64, vfov_deg: f64) -> Camera {
    let focal = |size: u32, fov: f64| (f64::from(size) / 2.0) / (fov.to_radians() / 2.0).tan();
    Camera {
        width,
        height,
        fx: focal(width, hfov_deg),
        fy: focal(height, vfov_deg),
        cx: f64::from(width) / 2.0,
        cy: f64::from(height) / 2.0,
        distortion: [0.0; 5],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn v6_field_of_view_comes_back() {
        for preset in [CameraPreset::V6, CameraPreset::V6Hd] {
            let c = preset.camera();
            let hfov = 2.0 * (f64::from(c.width) / 2.0 / c.fx).atan();
            let vfov = 2.0 * (f64::from(c.height) / 2.0 / c.fy).atan();
            assert!((hfov.to_degrees() - V6_HFOV_DEG).abs() < 1e-9);
            assert!((vfov.to_degrees() - V6_VFOV_DEG).abs() < 1e-9);
        }
        // 1280×960 has twice the focal length of 640×480.
        let (a, b) = (CameraPreset::V6.camera(), CameraPreset::V6Hd.camera());
        assert!((b.fx - 2.0 * a.fx).abs() < 1e-9 && (b.cy - 2.0 * a.cy).abs() < 1e-9);
        assert_eq!(CameraPreset::from_name("v6"), Some(CameraPreset::V6));
        assert_eq!(CameraPreset::from_name("v5"), None);
    }

    /// The z-scores `(estimate − truth)/σ` of the paper's parameters over a few simulated
    /// datasets of `preset`.
    fn z_scores(preset: CameraPreset) -> Vec<f64> {
        use crate::model::{FixedSet, Model, PAPER_PARAMETERS, Param};
        use crate::sim::{SimOptions, simulate};
        use crate::solve::{Problem, UncertaintyOptions, backend, calibrate};
        let model = Model {
            camera: preset.camera(),
            ..Model::default()
        };
        let mut z = Vec::new();
        for seed in 1..=4 {
            let options = SimOptions {
                seed,
                stances: 10,
                heads: 2,
                ..SimOptions::default()
            };
            let dataset = simulate(&model, &options).expect("stances in view");
            let truth = dataset.truth.as_ref().expect("a truth").values;
            let problem = Problem::from_dataset(&dataset, FixedSet::default()).unwrap();
            let lm = backend("lm", false).unwrap();
            let s = calibrate(&problem, lm.as_ref(), &UncertaintyOptions::plain()).unwrap();
            assert!(s.summary.converged, "{} seed {seed}", preset.name());
            for p in &Param::ALL[..PAPER_PARAMETERS] {
                z.push((s.values[p.index()] - truth[p.index()]) / s.std[p.index()]);
            }
        }
        z
    }

    #[test]
    fn v6_datasets_calibrate_to_their_truth_as_v4_does() {
        for preset in [CameraPreset::V4, CameraPreset::V6, CameraPreset::V6Hd] {
            let z = z_scores(preset);
            let rms = (z.iter().map(|z| z * z).sum::<f64>() / z.len() as f64).sqrt();
            let max = z.iter().fold(0.0f64, |m, z| m.max(z.abs()));
            eprintln!("{}: rms z {rms:.3}, max |z| {max:.2}", preset.name());
            // Unbiased estimates with honest sigmas: z-scores like draws of N(0, 1).
            assert!((0.6..1.5).contains(&rms), "{}: rms z {rms}", preset.name());
            assert!(max < 4.5, "{}: max |z| {max}", preset.name());
        }
    }
}
