//! Each camera's intrinsics as a calibration carries them: the a-priori intrinsics its
//! corrections are relative to ([`Prior`]: `[camera]` / `[upper_camera]` of the dataset,
//! or what a robot's team file holds), and the calibrated values the teams' files and
//! readers take ([`Intrinsics`]: focal lengths and optical centre in px, opening angles
//! in degrees, each with its one-sigma).

use serde::{Deserialize, Serialize};

use crate::model::{Camera, CameraId, Model, Param};

/// A camera's a-priori intrinsics as a calibration file carries them (`[cameras.lower]`,
/// `[cameras.upper]`): the reference of its corrections `Fx`, `Fy`, `Cx`, `Cy` (`UpperFx`
/// …), in px at `width × height`.
#[derive(Serialize, Deserialize, Debug, Clone, Copy, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Prior {
    /// Image width (px).
    pub width: u32,
    /// Image height (px).
    pub height: u32,
    /// Focal length in x (px).
    pub fx: f64,
    /// Focal length in y (px).
    pub fy: f64,
    /// Optical centre x (px, the centre of the top-left pixel at 0).
    pub cx: f64,
    /// Optical centre y (px).
    pub cy: f64,
}

impl Prior {
    /// The intrinsics of `camera` (its distortion left out).
    pub fn of(camera: &Camera) -> Prior {
        Prior {
            width: camera.width,
            height: camera.height,
            fx: camera.fx,
            fy: camera.fy,
            cx: camera.cx,
            cy: camera.cy,
        }
    }

    /// `[fx, fy, cx, cy]`.
    pub fn values(&self) -> [f64; 4] {
        [self.fx, self.fy, self.cx, self.cy]
    }

    /// These intrinsics seen at `width × height` (the same lens, the image scaled): the
    /// focal lengths and centre scaled by the ratio of the image sizes, each axis by its
    /// own.
    pub fn scaled_to(&self, width: u32, height: u32) -> [f64; 4] {
        let sx = width as f64 / self.width as f64;
        let sy = height as f64 / self.height as f64;
        [self.fx * sx, self.fy * sy, self.cx * sx, self.cy * sy]
    }

    /// Whether the numbers are usable: a positive image size, positive finite focal
    /// lengths and a finite centre.
    pub fn is_valid(&self) -> bool {
        self.width > 0
            && self.height > 0
            && self.fx.is_finite()
            && self.fy.is_finite()
            && self.fx > 0.0
            && self.fy > 0.0
            && self.cx.is_finite()
            && self.cy.is_finite()
    }
}

/// The four corrections of `camera`'s focal lengths and centre: `Fx, Fy, Cx, Cy` or
/// `UpperFx, UpperFy, UpperCx, UpperCy`.
pub fn params(camera: CameraId) -> [Param; 4] {
    let [fx, fy, cx, cy, _, _] = camera.projection_params();
    [fx, fy, cx, cy]
}

/// The prior of every camera of `model` whose intrinsics `estimated` says were
/// estimated: what a calibration of those corrections must carry to say what they mean.
pub fn priors_of(model: &Model, estimated: impl Fn(Param) -> bool) -> Vec<(CameraId, Prior)> {
    CameraId::ALL
        .into_iter()
        .filter(|&c| c == CameraId::Lower || model.upper_camera.is_some())
        .filter(|&c| params(c).into_iter().any(&estimated))
        .map(|c| (c, Prior::of(model.intrinsics(c))))
        .collect()
}

/// One camera's calibrated intrinsics: its prior plus the corrections, in px at the prior's
/// image size, with their one-sigma, and what the teams read of them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Intrinsics {
    /// The camera.
    pub camera: CameraId,
    /// The a-priori intrinsics the corrections are relative to.
    pub prior: Prior,
    /// `[fx, fy, cx, cy]` (px): the prior plus the corrections.
    pub value: [f64; 4],
    /// Their one-sigma (px): `Some(0)` held, `None` not determined by the data.
    pub std: [Option<f64>; 4],
    /// Which of them this calibration estimated and the data determine (what a team
    /// file's `--update` replaces).
    pub calibrated: [bool; 4],
}

impl Intrinsics {
    /// The horizontal and vertical opening angles (deg): `2·atan(W / (2·fx))`,
    /// `2·atan(H / (2·fy))` (B-Human's `CameraInfo::updateFocalLength` inverted).
    pub fn opening_angles(&self) -> [f64; 2] {
        let [fx, fy, _, _] = self.value;
        [
            opening_angle(self.prior.width, fx),
            opening_angle(self.prior.height, fy),
        ]
    }

    /// The one-sigma of [`Intrinsics::opening_angles`] (deg), by the derivative
    /// `d(2·atan(W/2f))/df = −W / (f² + W²/4)`.
    pub fn opening_angles_std(&self) -> [Option<f64>; 2] {
        let [fx, fy, _, _] = self.value;
        let d = |size: u32, f: f64| {
            let w = size as f64;
            (w / (f * f + w * w / 4.0)).to_degrees()
        };
        [
            self.std[0].map(|s| s * d(self.prior.width, fx)),
            self.std[1].map(|s| s * d(self.prior.height, fy)),
        ]
    }

    /// The optical centre's offset from the image's middle `(W/2, H/2)` (px): where the
    /// teams' defaults put it (B-Human's and HULKs' relative centre 0.5).
    pub fn centre_offset(&self) -> [f64; 2] {
        [
            self.value[2] - self.prior.width as f64 / 2.0,
            self.value[3] - self.prior.height as f64 / 2.0,
        ]
    }

    /// The centre relative to the image size, `(cx / W, cy / H)`: B-Human's and HULKs'
    /// normalised optical centre.
    pub fn relative_centre(&self) -> [f64; 2] {
        [
            self.value[2] / self.prior.width as f64,
            self.value[3] / self.prior.height as f64,
        ]
    }

    /// The focal lengths relative to the image size, `(fx / W, fy / H)`: HULKs'
    /// normalised focal lengths.
    pub fn relative_focal_lengths(&self) -> [f64; 2] {
        [
            self.value[0] / self.prior.width as f64,
            self.value[1] / self.prior.height as f64,
        ]
    }
}

impl Intrinsics {
    /// `[fx, fy, cx, cy]` (px) of the same camera at `width × height` (the image scaled):
    /// scaled by the ratio of the image sizes, each axis by its own, as
    /// [`Prior::scaled_to`] — what a team reading its values at its own image size must get.
    pub fn scaled_to(&self, width: u32, height: u32) -> [f64; 4] {
        let [fx, fy, cx, cy] = self.value;
        Prior {
            fx,
            fy,
            cx,
            cy,
            ..self.prior
        }
        .scaled_to(width, height)
    }

    /// The one-sigma of [`Intrinsics::centre_offset`] (px): the centre's own.
    pub fn centre_offset_std(&self) -> [Option<f64>; 2] {
        [self.std[2], self.std[3]]
    }

    /// The camera as the teams read it ([`TeamsView`]).
    pub fn teams_view(&self) -> TeamsView {
        let [aw, ah] = self.opening_angles();
        let [sw, sh] = self.opening_angles_std();
        let [ox, oy] = self.centre_offset();
        let [sx, sy] = self.centre_offset_std();
        let [fx, fy, _, _] = self.value;
        TeamsView {
            values: [aw, ah, fx, fy, ox, oy],
            std: [sw, sh, self.std[0], self.std[1], sx, sy],
            calibrated: [
                self.calibrated[0],
                self.calibrated[1],
                self.calibrated[0],
                self.calibrated[1],
                self.calibrated[2],
                self.calibrated[3],
            ],
        }
    }
}

/// The names and units of the quantities of a [`TeamsView`], in its order.
pub const TEAMS_QUANTITIES: [(&str, &str); 6] = [
    ("opening angle width", "deg"),
    ("opening angle height", "deg"),
    ("focal length x", "px"),
    ("focal length y", "px"),
    ("centre offset x", "px"),
    ("centre offset y", "px"),
];

/// One camera's intrinsics as the teams' files and code read them: the horizontal and
/// vertical opening angles (deg; B-Human, SPQR, NomadZ), the focal lengths (px; HULKs'
/// normalised ones times the image size) and the optical centre's offset from the image's
/// middle (px; where every team's default puts it), in the order of [`TEAMS_QUANTITIES`],
/// at the calibration's image size.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TeamsView {
    /// The values.
    pub values: [f64; 6],
    /// Their one-sigma, propagated from the fit's (`Some(0)` held, `None` not determined).
    pub std: [Option<f64>; 6],
    /// Whether each was calibrated (its correction estimated and determined).
    pub calibrated: [bool; 6],
}

impl TeamsView {
    /// The view of a camera of the intrinsics `[fx, fy, cx, cy]` (px) at `width × height`
    /// with no uncertainty: a robot's previous calibration, for the change.
    pub fn of_values(value: [f64; 4], width: u32, height: u32) -> TeamsView {
        Intrinsics {
            camera: CameraId::Lower,
            prior: Prior {
                width,
                height,
                fx: value[0],
                fy: value[1],
                cx: value[2],
                cy: value[3],
            },
            value,
            std: [Some(0.0); 4],
            calibrated: [false; 4],
        }
        .teams_view()
    }
}

/// The opening angle (deg) of an image side of `size` px at focal length `f` px.
pub fn opening_angle(size: u32, f: f64) -> f64 {
    (2.0 * (size as f64 / (2.0 * f)).atan()).to_degrees()
}

/// The focal length (px) that gives an image side of `size` px the opening angle `deg`.
pub fn focal_length(size: u32, deg: f64) -> f64 {
    size as f64 / (2.0 * (deg.to_radians() / 2.0).tan())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn opening_angles_and_focal_lengths_are_inverse_and_the_sigma_is_the_derivative() {
        // B-Human's defaults: 54.7° × 42.5° at 640 × 480 are 618.7 px and 617.2 px, as
        // HULKs' normalised 0.96666 × 640 and 1.28574 × 480.
        let fx = focal_length(640, 54.7);
        let fy = focal_length(480, 42.5);
        assert!((fx - 0.96666 * 640.0).abs() < 0.05, "{fx}");
        assert!((fy - 1.28574 * 480.0).abs() < 0.05, "{fy}");
        assert!((opening_angle(640, fx) - 54.7).abs() < 1e-12);
        let prior = Prior {
            width: 640,
            height: 480,
            fx,
            fy,
            cx: 320.0,
            cy: 240.0,
        };
        let at = |value: [f64; 4]| Intrinsics {
            camera: CameraId::Upper,
            prior,
            value,
            std: [Some(0.5), Some(0.25), Some(1.0), None],
            calibrated: [true; 4],
        };
        let i = at([fx, fy, 324.0, 231.0]);
        assert_eq!(i.centre_offset(), [4.0, -9.0]);
        assert_eq!(i.relative_centre(), [324.0 / 640.0, 231.0 / 480.0]);
        let [sx, sy] = i.opening_angles_std().map(Option::unwrap);
        let h = 1e-4;
        let numeric = (opening_angle(640, fx - h) - opening_angle(640, fx + h)) / (2.0 * h);
        assert!(
            (sx - 0.5 * numeric).abs() < 1e-9,
            "{sx} vs {}",
            0.5 * numeric
        );
        assert!(sy > 0.0 && sy < sx);
        assert_eq!(
            prior.scaled_to(320, 240),
            [fx / 2.0, fy / 2.0, 160.0, 120.0]
        );
    }

    #[test]
    fn the_teams_view_is_the_opening_angles_focal_lengths_and_centre_offset_with_sigma() {
        let prior = Prior {
            width: 640,
            height: 480,
            fx: 600.0,
            fy: 598.0,
            cx: 320.0,
            cy: 240.0,
        };
        let i = Intrinsics {
            camera: CameraId::Lower,
            prior,
            value: [612.0, 590.0, 329.5, 232.0],
            std: [Some(0.07), Some(0.06), Some(0.15), None],
            calibrated: [true, true, true, false],
        };
        let view = i.teams_view();
        assert_eq!(view.values[..2], i.opening_angles());
        assert_eq!(view.values[2..4], [612.0, 590.0]);
        assert_eq!(view.values[4..], [9.5, -8.0]);
        assert_eq!(view.std[..2], i.opening_angles_std());
        assert_eq!(view.std[2..], [Some(0.07), Some(0.06), Some(0.15), None]);
        assert_eq!(view.calibrated, [true, true, true, true, true, false]);
        // The same camera at half the size: every length halved, the angles kept.
        assert_eq!(i.scaled_to(320, 240), [306.0, 295.0, 164.75, 116.0]);
        let half = TeamsView::of_values(i.scaled_to(320, 240), 320, 240);
        for k in 0..2 {
            assert!((half.values[k] - view.values[k]).abs() < 1e-12);
            assert!((half.values[k + 4] - view.values[k + 4] / 2.0).abs() < 1e-12);
        }
        assert_eq!(half.std, [Some(0.0); 6]);
    }
}
