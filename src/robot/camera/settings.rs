//! What a camera is set to before anything moves — flip, exposure, gain, white balance,
//! size, frame rate — with the SPL teams' values as defaults; and the check of a camera's
//! first picture (its size, not near black, not saturated).
//!
//! Team code cited: HULKs `HULKs/hulk` @27921c5d, B-Human `bhuman/BHumanCodeRelease`
//! @d89d603f, rUNSWift `UNSWComputing/rUNSWift-2022-release` @9213f6d3.

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

/// How one camera is driven: what capture writes to it (and reads back) before anything
/// moves.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CameraSettings {
    /// Both flips of the sensor (UVC extension unit 3, selectors 12 and 13) set: the V6's
    /// upper camera is mounted turned by 180°, so that its picture is upright only
    /// flipped (HULKs `etc/parameters/hardware.json:27,70`, `flip_sensor` false for the
    /// bottom camera, true for the top; `crates/nao_camera/src/flip.rs:13-30`).
    pub flip: bool,
    /// Manual exposure in the driver's units (0 … [`MAX_EXPOSURE`]).
    pub exposure: u32,
    /// Gain in the driver's units (0 … [`MAX_GAIN`]).
    pub gain: u32,
    /// The white balance temperature (K); `None`: automatic white balance, as every team
    /// runs it (HULKs `hardware.json`, `white_balance_temperature_auto: true`; B-Human
    /// `Config/Locations/Default/cameraSettings.cfg:7,24`; rUNSWift
    /// `image/home/nao/data/runswift.cfg:70,80`).
    pub white_balance: Option<u32>,
    /// Frames per second: 30, as B-Human (`NaoCamera.cpp:36`, `setFrameRate(1, 30)`) and
    /// HULKs (`hardware.json`, `time_per_frame` 1/30) stream.
    pub fps: u32,
    /// Picture width (px): the dataset's intrinsics' (640 or 1280 on a V6).
    pub width: u32,
    /// Picture height (px): the dataset's intrinsics' (480 or 960 on a V6).
    pub height: u32,
}

impl CameraSettings {
    /// The defaults of `camera` at `width`×`height`: rUNSWift's manual exposure and gain
    /// (`image/home/nao/data/runswift.cfg:72-73` top 800/700, `:82-83` bottom 250/1700 —
    /// gain/exposure), the upper camera flipped and the lower not, automatic white balance,
    /// 30 frames/s.
    pub fn defaults(camera: CameraId, width: u32, height: u32) -> CameraSettings {
        let (flip, exposure, gain) = match camera {
            CameraId::Upper => (true, 700, 800),
            CameraId::Lower => (false, 1700, 250),
        };
        CameraSettings {
            flip,
            exposure,
            gain,
            white_balance: None,
            fps: 30,
            width,
            height,
        }
    }

    /// These settings with what `changes` sets.
    pub fn with(mut self, changes: &SettingsChanges) -> CameraSettings {
        let c = changes;
        self.flip = c.flip.unwrap_or(self.flip);
        self.exposure = c.exposure.unwrap_or(self.exposure);
        self.gain = c.gain.unwrap_or(self.gain);
        self.white_balance = c.white_balance_k.or(self.white_balance);
        self.fps = c.fps.unwrap_or(self.fps);
        self
    }
}

impl std::fmt::Display for CameraSettings {
    /// `640×480 at 30 frames/s, flip 1, exposure 700, gain 800, white balance auto`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{}×{} at {} frames/s, flip {}, exposure {}, gain {}, white balance ",
            self.width,
            self.height,
            self.fps,
            u8::from(self.flip),
            self.exposure,
            self.gain
        )?;
        match self.white_balance {
            Some(k) => write!(f, "{k} K"),
            None => write!(f, "auto"),
        }
    }
}

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

/// The settings of `camera` on the robot `model`: the team defaults at the size of its
/// intrinsics, changed by its `dataset.toml` table (`file`, as
/// [`crate::dataset::read_camera_settings`] gives them), then by the command line's
/// `flags` (each for the cameras it names, in order).
pub fn settings_for(
    camera: CameraId,
    model: &crate::model::Model,
    file: &[(CameraId, SettingsChanges)],
    flags: &[(Vec<CameraId>, SettingsChanges)],
) -> CameraSettings {
    let size = model.intrinsics(camera);
    let mut changes = SettingsChanges::default();
    for (c, ch) in file {
        if *c == camera {
            changes = changes.then(ch);
        }
    }
    for (cs, ch) in flags {
        if cs.contains(&camera) {
            changes = changes.then(ch);
        }
    }
    CameraSettings::defaults(camera, size.width, size.height).with(&changes)
}

/// A picture's brightness: its mean grey level and the share of saturated pixels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Brightness {
    /// Mean grey level (0 … 255).
    pub mean: f64,
    /// Share of pixels at 250 or more.
    pub saturated: f64,
}

/// Below this mean grey level a picture is near black: no board's corners can be found.
pub const DARK_MEAN: f64 = 25.0;
/// Above this share of saturated pixels a picture is washed out.
pub const SATURATED_SHARE: f64 = 0.25;

impl Brightness {
    /// The brightness of 8-bit grey `pixels` (a picture with none is black).
    pub fn of_grey(pixels: &[u8]) -> Brightness {
        if pixels.is_empty() {
            return Brightness {
                mean: 0.0,
                saturated: 0.0,
            };
        }
        let n = pixels.len() as f64;
        let sum: u64 = pixels.iter().map(|&p| u64::from(p)).sum();
        let saturated = pixels.iter().filter(|&&p| p >= 250).count();
        Brightness {
            mean: sum as f64 / n,
            saturated: saturated as f64 / n,
        }
    }

    /// `Err` with what to change when the picture is near black or saturated.
    pub fn check(&self, settings: Option<&CameraSettings>) -> Result<(), String> {
        let now = |what: &str| match settings {
            Some(s) => format!(" (now exposure {}, gain {}){what}", s.exposure, s.gain),
            None => what.to_string(),
        };
        let hint = " — [camera]/[upper_camera] exposure and gain in dataset.toml, or \
                    --camera-setting CAMERA.exposure=…";
        if self.mean < DARK_MEAN {
            return Err(format!(
                "is near black (mean brightness {:.0} of 255, at least {DARK_MEAN:.0} \
                 needed): raise the exposure or the gain{}",
                self.mean,
                now(hint)
            ));
        }
        if self.saturated > SATURATED_SHARE {
            return Err(format!(
                "is saturated ({:.0} % of its pixels at 250 or more, mean brightness {:.0} of \
                 255): lower the exposure or the gain{}",
                100.0 * self.saturated,
                self.mean,
                now(hint)
            ));
        }
        Ok(())
    }
}

/// A camera's first picture as checked before anything moves.
#[derive(Debug, Clone, PartialEq)]
pub struct FirstPicture {
    /// The camera.
    pub camera: CameraId,
    /// The settings written and read back (`None` for a `command:` camera, which sets
    /// its camera itself).
    pub settings: Option<CameraSettings>,
    /// The picture's size (width, height).
    pub size: (u32, u32),
    /// Its brightness.
    pub brightness: Brightness,
    /// The picture (for a person to look at).
    pub picture: super::Picture,
}

/// Checks a camera's first picture: `size` must be `expected` (the dataset's intrinsics),
/// and its brightness neither near black nor saturated. `Err` says what is wrong and what
/// to change.
pub fn check_first(
    camera: CameraId,
    size: (u32, u32),
    expected: (u32, u32),
    brightness: &Brightness,
    settings: Option<&CameraSettings>,
) -> Result<(), String> {
    if size != expected {
        return Err(format!(
            "the {camera} camera's first picture is {}×{} pixels; the dataset's intrinsics \
             are for {}×{} (the camera's width and height in dataset.toml)",
            size.0, size.1, expected.0, expected.1
        ));
    }
    brightness
        .check(settings)
        .map_err(|e| format!("the {camera} camera's first picture {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_follow_the_teams_and_changes_apply_on_top() {
        let upper = CameraSettings::defaults(CameraId::Upper, 1280, 960);
        let lower = CameraSettings::defaults(CameraId::Lower, 640, 480);
        assert!(upper.flip && !lower.flip);
        assert_eq!((upper.exposure, upper.gain), (700, 800));
        assert_eq!((lower.exposure, lower.gain), (1700, 250));
        assert_eq!((upper.width, upper.height, upper.fps), (1280, 960, 30));
        let mut c = SettingsChanges::default();
        c.set("exposure", "1000").unwrap();
        c.set("flip", "false").unwrap();
        let s = upper.with(&c);
        assert_eq!((s.exposure, s.gain, s.flip), (1000, 800, false));
        let mut later = SettingsChanges::default();
        later.set("exposure", "900").unwrap();
        later.set("white_balance_k", "4000").unwrap();
        let both = c.then(&later);
        assert_eq!(both.exposure, Some(900));
        assert_eq!(both.flip, Some(false));
        assert_eq!(upper.with(&both).white_balance, Some(4000));
        assert!(upper.to_string().contains("flip 1, exposure 700, gain 800"));
    }

    #[test]
    fn the_command_line_overrides_the_file_which_overrides_the_defaults() {
        let mut model = crate::model::Model::default();
        let mut upper = model.camera;
        upper.width = 1280;
        upper.height = 960;
        model.upper_camera = Some(upper);
        let mut file = SettingsChanges::default();
        file.set("exposure", "900").unwrap();
        file.set("gain", "100").unwrap();
        let file = vec![(CameraId::Upper, file)];
        let flags = vec![parse_setting("gain=120").unwrap()];
        let s = settings_for(CameraId::Upper, &model, &file, &flags);
        assert_eq!(
            (s.exposure, s.gain, s.width, s.height),
            (900, 120, 1280, 960)
        );
        let s = settings_for(CameraId::Lower, &model, &file, &flags);
        assert_eq!((s.exposure, s.gain, s.width), (1700, 120, 640));
    }

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

    #[test]
    fn dark_saturated_and_wrong_sized_first_pictures_say_what_to_change() {
        let s = CameraSettings::defaults(CameraId::Lower, 640, 480);
        let dark = Brightness::of_grey(&[3; 100]);
        let e = check_first(CameraId::Lower, (640, 480), (640, 480), &dark, Some(&s)).unwrap_err();
        assert!(
            e.contains("near black") && e.contains("mean brightness 3"),
            "{e}"
        );
        assert!(
            e.contains("raise the exposure") && e.contains("exposure 1700"),
            "{e}"
        );
        let bright = Brightness::of_grey(&[255; 100]);
        let e = check_first(CameraId::Upper, (640, 480), (640, 480), &bright, None).unwrap_err();
        assert!(
            e.contains("saturated") && e.contains("lower the exposure"),
            "{e}"
        );
        assert!(e.contains("upper camera"), "{e}");
        let fine = Brightness::of_grey(&[120; 100]);
        assert!(check_first(CameraId::Lower, (640, 480), (640, 480), &fine, Some(&s)).is_ok());
        let e = check_first(CameraId::Lower, (640, 480), (1280, 960), &fine, None).unwrap_err();
        assert!(e.contains("640×480") && e.contains("1280×960"), "{e}");
        // A picture half saturated, half dark is washed out, not dark.
        let mut half = vec![255u8; 50];
        half.extend([10u8; 50]);
        let b = Brightness::of_grey(&half);
        assert!((b.saturated - 0.5).abs() < 1e-12);
        assert!(b.check(None).unwrap_err().contains("saturated"));
    }
}
