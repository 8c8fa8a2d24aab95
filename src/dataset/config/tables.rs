//! The tables of `dataset.toml` (`[camera]`, `[upper_camera]`, `[board]`, `[robot]`,
//! `[joints]`) as serde types, and how each maps to and from the model's values.

use std::fmt;

use serde::de::{self, Deserializer, SeqAccess, Visitor};
use serde::{Deserialize, Serialize, Serializer};

use crate::dataset::AngleKind;
use crate::dataset::settings::SettingsChanges;
use crate::dataset::units::degrees_for;
use crate::model::{Board, Camera, RobotGeometry};

/// `[joints]`: whether `captures.csv` holds raw encoder readings or angles a framework has
/// already corrected with the robot's joint calibration (docs/MODEL.md §7).
#[derive(Debug, Clone, PartialEq, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub(super) struct JointsToml {
    pub(super) angles: AngleKind,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) corrected_by: Option<String>,
}

/// `[camera]` and `[upper_camera]`: a camera's a-priori intrinsics.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct CameraToml {
    pub(super) width: u32,
    pub(super) height: u32,
    pub(super) fx: f64,
    pub(super) fy: f64,
    pub(super) cx: f64,
    pub(super) cy: f64,
    /// OpenCV's `[k1, k2, p1, p2, k3]`; zero when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) distortion: Option<Numbers<5>>,
    /// How capture drives the camera (`crate::robot::camera::settings`); the team
    /// defaults where absent. Not part of the model: a dataset's copy holds none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) flip: Option<bool>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) exposure: Option<u32>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) gain: Option<u32>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) white_balance_k: Option<u32>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) fps: Option<u32>,
}

impl CameraToml {
    /// Sets the capture settings `changes` gives.
    pub(super) fn set_settings(&mut self, changes: &SettingsChanges) {
        self.flip = changes.flip;
        self.exposure = changes.exposure;
        self.gain = changes.gain;
        self.white_balance_k = changes.white_balance_k;
        self.fps = changes.fps;
    }

    /// The capture settings this table changes.
    pub(super) fn settings(&self) -> SettingsChanges {
        SettingsChanges {
            flip: self.flip,
            exposure: self.exposure,
            gain: self.gain,
            white_balance_k: self.white_balance_k,
            fps: self.fps,
        }
    }
}

/// `[board]`: the sandal pattern, its mount and its mass; every key optional.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub(super) struct BoardToml {
    pub(super) squares_x: u32,
    pub(super) squares_y: u32,
    pub(super) square_mm: f64,
    pub(super) mount_origin_mm: Numbers<3>,
    /// Roll, pitch, yaw.
    pub(super) mount_rpy_deg: Numbers<3>,
    pub(super) mass_g: f64,
    pub(super) com_mm: Numbers<3>,
}

/// `[robot]`: link lengths, the cameras' mountings and gravity; every key optional. The
/// upper camera's mounting is written only when it differs from the default or the model
/// has an upper camera, so that a lower-camera dataset is written as before.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub(super) struct RobotToml {
    pub(super) hip_offset_y_mm: f64,
    pub(super) hip_to_neck_z_mm: f64,
    pub(super) thigh_mm: f64,
    pub(super) tibia_mm: f64,
    pub(super) foot_height_mm: f64,
    pub(super) lower_camera_offset_mm: Numbers<3>,
    pub(super) lower_camera_tilt_deg: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) upper_camera_offset_mm: Option<Numbers<3>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) upper_camera_tilt_deg: Option<f64>,
    /// The direction of gravity in the origin frame; normalised when read.
    pub(super) gravity: Numbers<3>,
}

impl Default for BoardToml {
    fn default() -> Self {
        BoardToml::from(&Board::default())
    }
}

impl Default for RobotToml {
    fn default() -> Self {
        RobotToml::from(&RobotGeometry::default())
    }
}

impl From<&Camera> for CameraToml {
    fn from(c: &Camera) -> Self {
        CameraToml {
            width: c.width,
            height: c.height,
            fx: c.fx,
            fy: c.fy,
            cx: c.cx,
            cy: c.cy,
            distortion: Some(Numbers(c.distortion)),
            flip: None,
            exposure: None,
            gain: None,
            white_balance_k: None,
            fps: None,
        }
    }
}

impl From<CameraToml> for Camera {
    fn from(c: CameraToml) -> Self {
        Camera {
            width: c.width,
            height: c.height,
            fx: c.fx,
            fy: c.fy,
            cx: c.cx,
            cy: c.cy,
            distortion: c.distortion.map_or([0.0; 5], |d| d.0),
        }
    }
}

impl From<&Board> for BoardToml {
    fn from(b: &Board) -> Self {
        BoardToml {
            squares_x: b.squares_x,
            squares_y: b.squares_y,
            square_mm: b.square,
            mount_origin_mm: Numbers(b.mount_origin),
            mount_rpy_deg: Numbers(b.mount_rpy.map(degrees_for)),
            mass_g: b.mass_g,
            com_mm: Numbers(b.com_mm),
        }
    }
}

impl From<&RobotGeometry> for RobotToml {
    fn from(r: &RobotGeometry) -> Self {
        let nominal = RobotGeometry::default();
        RobotToml {
            hip_offset_y_mm: r.hip_offset_y,
            hip_to_neck_z_mm: r.hip_to_neck_z,
            thigh_mm: r.thigh,
            tibia_mm: r.tibia,
            foot_height_mm: r.foot_height,
            lower_camera_offset_mm: Numbers(r.lower_camera_offset),
            lower_camera_tilt_deg: degrees_for(r.lower_camera_tilt),
            upper_camera_offset_mm: (r.upper_camera_offset != nominal.upper_camera_offset)
                .then_some(Numbers(r.upper_camera_offset)),
            upper_camera_tilt_deg: (r.upper_camera_tilt != nominal.upper_camera_tilt)
                .then(|| degrees_for(r.upper_camera_tilt)),
            gravity: Numbers(r.gravity),
        }
    }
}

/// Exactly `N` numbers: a TOML array of that length (serde's own arrays would accept a
/// longer one and drop the rest).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Numbers<const N: usize>(pub(super) [f64; N]);

impl<'de, const N: usize> Deserialize<'de> for Numbers<N> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Expect<const N: usize>;
        impl<'de, const N: usize> Visitor<'de> for Expect<N> {
            type Value = Numbers<N>;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                write!(f, "an array of {N} numbers")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
                let mut out = [0.0; N];
                let mut n = 0;
                while let Some(x) = seq.next_element::<f64>()? {
                    if let Some(slot) = out.get_mut(n) {
                        *slot = x;
                    }
                    n += 1;
                }
                if n != N {
                    return Err(de::Error::invalid_length(n, &self));
                }
                Ok(Numbers(out))
            }
        }
        d.deserialize_seq(Expect::<N>)
    }
}

impl<const N: usize> Serialize for Numbers<N> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(self.0.iter())
    }
}
