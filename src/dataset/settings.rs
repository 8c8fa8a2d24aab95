//! The capture settings a dataset records per camera (`dataset.toml`'s `[camera]` and
//! `[upper_camera]`: flip, exposure, gain, white balance, frame rate) and that
//! `--camera-setting` changes, with the V6 driver's limits they are checked against.
//! How capture drives a camera with them is `crate::robot::camera::settings`.
//!
//! Team code cited: rUNSWift `UNSWComputing/rUNSWift-2022-release` @9213f6d3.

use crate::model::CameraId;

/// The largest manual exposure the V6's driver takes (2²⁰ − 1; rUNSWift
/// `robot/perception/vision/camera/NaoCamera.cpp:143`, `V6_MAX_EXPOSURE_ABSOLUTE`).
pub const MAX_EXPOSURE: u32 = 1_048_575;
/// The largest gain the V6's driver takes (rUNSWift `NaoCamera.cpp:142`, `V6_MAX_GAIN`).
pub const MAX_GAIN: u32 = 1023;
/// The white balance temperatures a V6 camera is set to (K).
pub const WHITE_BALANCE_K: (u32, u32) = (2500, 6500);
/// The frame rates a V6 camera streams at both sizes (frames/s).
pub const FPS: (u32, u32) = (1, 30);

/// The settings a camera's `dataset.toml` table or the command line changes; the keys are
/// [`SETTING_KEYS`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SettingsChanges {
    /// `flip`: both sensor flips set (true) or clear (false).
    pub flip: Option<bool>,
    /// `exposure`: manual exposure (driver units).
    pub exposure: Option<u32>,
    /// `gain`: gain (driver units).
    pub gain: Option<u32>,
    /// `white_balance_k`: a fixed white balance temperature (K) instead of automatic.
    pub white_balance_k: Option<u32>,
    /// `fps`: frames per second.
    pub fps: Option<u32>,
}

/// The settings' keys, as written in `dataset.toml`'s `[camera]` and `[upper_camera]` and
/// in `--camera-setting [CAMERA.]KEY=VALUE`, with what each takes.
pub const SETTING_KEYS: [(&str, &str); 5] = [
    ("flip", "true or false"),
    ("exposure", "0 … 1048575 (driver units)"),
    ("gain", "0 … 1023 (driver units)"),
    ("white_balance_k", "2500 … 6500 (K; absent: automatic)"),
    ("fps", "1 … 30 (frames/s)"),
];

impl SettingsChanges {
    /// The first value out of range, as (key, message).
    pub fn check(&self) -> Result<(), (&'static str, String)> {
        let within = |key: &'static str, v: Option<u32>, (lo, hi): (u32, u32)| match v {
            Some(v) if v < lo || v > hi => Err((key, format!("must be {lo} … {hi}, got {v}"))),
            _ => Ok(()),
        };
        within("exposure", self.exposure, (0, MAX_EXPOSURE))?;
        within("gain", self.gain, (0, MAX_GAIN))?;
        within("white_balance_k", self.white_balance_k, WHITE_BALANCE_K)?;
        within("fps", self.fps, FPS)
    }

    /// Sets `key` (one of [`SETTING_KEYS`]) from its text `value`, checked.
    pub fn set(&mut self, key: &str, value: &str) -> Result<(), String> {
        let number = || {
            value
                .trim()
                .parse::<u32>()
                .map_err(|_| format!("{key}: '{value}' is not a whole number ≥ 0"))
        };
        let mut next = *self;
        match key {
            "flip" => {
                next.flip = Some(match value.trim() {
                    "true" | "1" => true,
                    "false" | "0" => false,
                    _ => return Err(format!("flip: '{value}' is not true or false")),
                })
            }
            "exposure" => next.exposure = Some(number()?),
            "gain" => next.gain = Some(number()?),
            "white_balance_k" => next.white_balance_k = Some(number()?),
            "fps" => next.fps = Some(number()?),
            _ => {
                let keys: Vec<&str> = SETTING_KEYS.iter().map(|(k, _)| *k).collect();
                return Err(format!(
                    "unknown camera setting '{key}' (one of {})",
                    keys.join(", ")
                ));
            }
        }
        next.check().map_err(|(k, m)| format!("{k}: {m}"))?;
        *self = next;
        Ok(())
    }

    /// `self` with what `later` sets on top.
    pub fn then(&self, later: &SettingsChanges) -> SettingsChanges {
        SettingsChanges {
            flip: later.flip.or(self.flip),
            exposure: later.exposure.or(self.exposure),
            gain: later.gain.or(self.gain),
            white_balance_k: later.white_balance_k.or(self.white_balance_k),
            fps: later.fps.or(self.fps),
        }
    }
}

/// Parses `--camera-setting [CAMERA.]KEY=VALUE` (`upper.exposure=1000`, or `gain=300` for
/// both cameras): the cameras it is for and the change.
pub fn parse_setting(text: &str) -> Result<(Vec<CameraId>, SettingsChanges), String> {
    let (lhs, value) = text
        .split_once('=')
        .ok_or_else(|| format!("'{text}': expected [lower.|upper.]KEY=VALUE"))?;
    let (cameras, key) = match lhs.split_once('.') {
        Some((camera, key)) => {
            let id = CameraId::ALL
                .into_iter()
                .find(|c| c.name() == camera)
                .ok_or_else(|| format!("'{text}': '{camera}' is not lower or upper"))?;
            (vec![id], key)
        }
        None => (CameraId::ALL.to_vec(), lhs),
    };
    let mut changes = SettingsChanges::default();
    changes
        .set(key.trim(), value)
        .map_err(|e| format!("'{text}': {e}"))?;
    Ok((cameras, changes))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn out_of_range_and_unknown_settings_are_refused_with_the_key() {
        let mut c = SettingsChanges::default();
        assert!(
            c.set("exposure", "1048576")
                .unwrap_err()
                .contains("0 … 1048575")
        );
        assert!(c.set("gain", "1024").unwrap_err().contains("gain"));
        assert!(c.set("fps", "60").unwrap_err().contains("fps"));
        assert!(
            c.set("white_balance_k", "100")
                .unwrap_err()
                .contains("2500")
        );
        assert!(
            c.set("flip", "maybe")
                .unwrap_err()
                .contains("true or false")
        );
        assert!(
            c.set("exposure", "-3")
                .unwrap_err()
                .contains("whole number")
        );
        assert!(c.set("iso", "3").unwrap_err().contains("exposure, gain"));
    }

    #[test]
    fn command_line_settings_name_their_camera_or_both() {
        let (cams, c) = parse_setting("upper.exposure=1000").unwrap();
        assert_eq!(cams, vec![CameraId::Upper]);
        assert_eq!(c.exposure, Some(1000));
        let (cams, c) = parse_setting("gain=300").unwrap();
        assert_eq!(cams.len(), 2);
        assert_eq!(c.gain, Some(300));
        assert!(
            parse_setting("top.gain=3")
                .unwrap_err()
                .contains("lower or upper")
        );
        assert!(parse_setting("gain").unwrap_err().contains("KEY=VALUE"));
    }
}
