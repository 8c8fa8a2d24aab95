//! What a camera is set to before anything moves — flip, exposure, gain, white balance,
//! size, frame rate — with the SPL teams' values as defaults; and the check of a camera's
//! first picture (its size, not near black, not saturated).
//!
//! Team code cited: HULKs `HULKs/hulk` @27921c5d, B-Human `bhuman/BHumanCodeRelease`
//! @d89d603f, rUNSWift `UNSWComputing/rUNSWift-2022-release` @9213f6d3.

use crate::dataset::settings::SettingsChanges;
use crate::model::CameraId;

/// How one camera is driven: what capture writes to it (and reads back) before anything
/// moves.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CameraSettings {
    /// Both flips of the sensor (UVC extension unit 3, selectors 12 and 13) set: the V6's
    /// upper camera is mounted turned by 180°, so that its picture is upright only
    /// flipped (HULKs `etc/parameters/hardware.json:27,70`, `flip_sensor` false for the
    /// bottom camera, true for the top; `crates/nao_camera/src/flip.rs:13-30`).
    pub flip: bool,
    /// Manual exposure in the driver's units (0 … [`crate::dataset::settings::MAX_EXPOSURE`]).
    pub exposure: u32,
    /// Gain in the driver's units (0 … [`crate::dataset::settings::MAX_GAIN`]).
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

impl CameraSettings {
    /// Refuses a flip that turns `camera`'s picture upside down: the V6's upper sensor is
    /// mounted turned by 180° (upright pictures only flipped), the lower one upright (only
    /// unflipped) — HULKs `etc/parameters/hardware.json:27,70`. The model calibrates
    /// upright pictures only, so such a run could give no calibration.
    pub fn check_upright(&self, camera: CameraId) -> Result<(), String> {
        let mounted = CameraSettings::defaults(camera, self.width, self.height).flip;
        if self.flip == mounted {
            return Ok(());
        }
        Err(format!(
            "the {camera} camera's flip is {} ([{}] flip in dataset.toml or --camera-setting \
             {camera}.flip): the V6's {camera} sensor is mounted {}, so its pictures would be \
             upside down and nothing could be calibrated from them; leave flip at {} (the \
             default)",
            self.flip,
            table_name(camera),
            if mounted {
                "turned by 180° (its picture is upright only flipped)"
            } else {
                "upright (its picture is upright only unflipped)"
            },
            mounted
        ))
    }

    /// Every setting as a change (`white_balance_k` absent: automatic).
    pub fn as_changes(&self) -> SettingsChanges {
        SettingsChanges {
            flip: Some(self.flip),
            exposure: Some(self.exposure),
            gain: Some(self.gain),
            white_balance_k: self.white_balance,
            fps: Some(self.fps),
        }
    }

    /// What a `command:` camera's placeholders stand for ([`PLACEHOLDERS`]): `{flip}` 1
    /// or 0, `{exposure}`, `{gain}`, `{white_balance_k}` (K, or `auto`), `{fps}`,
    /// `{width}`, `{height}`.
    pub fn placeholders(&self) -> [(&'static str, String); 7] {
        [
            ("{flip}", u8::from(self.flip).to_string()),
            ("{exposure}", self.exposure.to_string()),
            ("{gain}", self.gain.to_string()),
            (
                "{white_balance_k}",
                self.white_balance
                    .map_or_else(|| "auto".to_string(), |k| k.to_string()),
            ),
            ("{fps}", self.fps.to_string()),
            ("{width}", self.width.to_string()),
            ("{height}", self.height.to_string()),
        ]
    }
}

/// The placeholders a `command:` camera may use for its camera's settings
/// ([`CameraSettings::placeholders`]).
pub const PLACEHOLDERS: [&str; 7] = [
    "{flip}",
    "{exposure}",
    "{gain}",
    "{white_balance_k}",
    "{fps}",
    "{width}",
    "{height}",
];

/// The `dataset.toml` table of `camera`'s intrinsics and settings.
pub fn table_name(camera: CameraId) -> &'static str {
    match camera {
        CameraId::Lower => "camera",
        CameraId::Upper => "upper_camera",
    }
}

/// How a camera was driven with its settings in a run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Driven {
    /// A V4L2 device: every setting written and read back.
    ReadBack,
    /// A `command:` camera: the settings its command takes through placeholders were
    /// given to it (naocalib cannot read them back).
    GivenToCommand,
}

/// The settings a camera was driven with in a run, as its dataset records them (the keys
/// of [`crate::dataset::settings::SETTING_KEYS`] in its `dataset.toml` table).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct UsedSettings {
    /// The camera.
    pub camera: CameraId,
    /// The values it was driven with; a key it was not driven with is `None`
    /// (`white_balance_k` `None` with [`UsedSettings::white_balance`]: automatic).
    pub values: SettingsChanges,
    /// Whether its white balance was driven (automatic or fixed).
    pub white_balance: bool,
    /// How.
    pub driven: Driven,
}

impl UsedSettings {
    /// A V4L2 camera set to `settings`, every value read back.
    pub fn read_back(camera: CameraId, settings: &CameraSettings) -> UsedSettings {
        UsedSettings {
            camera,
            values: settings.as_changes(),
            white_balance: true,
            driven: Driven::ReadBack,
        }
    }

    /// A `command:` camera whose command line is `command`, given `settings` through the
    /// placeholders it holds.
    pub fn given_to(camera: CameraId, settings: &CameraSettings, command: &str) -> UsedSettings {
        let all = settings.as_changes();
        let takes = |p: &str| command.contains(p);
        UsedSettings {
            camera,
            values: SettingsChanges {
                flip: all.flip.filter(|_| takes("{flip}")),
                exposure: all.exposure.filter(|_| takes("{exposure}")),
                gain: all.gain.filter(|_| takes("{gain}")),
                white_balance_k: all.white_balance_k.filter(|_| takes("{white_balance_k}")),
                fps: all.fps.filter(|_| takes("{fps}")),
            },
            white_balance: takes("{white_balance_k}"),
            driven: Driven::GivenToCommand,
        }
    }

    /// Whether the exposure or the gain was driven (so that a message about the
    /// picture's brightness can give them).
    pub fn exposes(&self) -> bool {
        self.values.exposure.is_some() || self.values.gain.is_some()
    }

    /// Whether any setting was driven.
    pub fn any(&self) -> bool {
        self.values != SettingsChanges::default() || self.white_balance
    }

    /// A line for `dataset.toml`'s header saying how the camera's settings were applied.
    pub fn note(&self) -> String {
        let table = table_name(self.camera);
        match (self.driven, self.any()) {
            (Driven::ReadBack, _) => format!(
                "[{table}] flip, exposure, gain, white_balance_k (absent: automatic) and fps: \
                 the {} camera's settings as capture wrote and read them back",
                self.camera
            ),
            (Driven::GivenToCommand, true) => format!(
                "[{table}] settings: those the {} camera's command was given (its \
                 placeholders); naocalib cannot read them back",
                self.camera
            ),
            (Driven::GivenToCommand, false) => format!(
                "[{table}]: the {} camera's command took no settings (it set its camera \
                 itself)",
                self.camera
            ),
        }
    }

    /// Checks these settings against those a dataset records for the camera
    /// (`recorded`, its table's keys): every setting driven now must be the one recorded
    /// (a table recording none of them is not checked). `Err` names the control, the
    /// value recorded and the value now.
    pub fn check_same(&self, recorded: &SettingsChanges) -> Result<(), (String, String, String)> {
        if *recorded == SettingsChanges::default() {
            return Ok(());
        }
        let v = &self.values;
        let mut pairs = vec![
            (
                "flip",
                v.flip.map(|f| f.to_string()),
                recorded.flip.map(|f| f.to_string()),
            ),
            (
                "exposure",
                v.exposure.map(|x| x.to_string()),
                recorded.exposure.map(|x| x.to_string()),
            ),
            (
                "gain",
                v.gain.map(|x| x.to_string()),
                recorded.gain.map(|x| x.to_string()),
            ),
            (
                "fps",
                v.fps.map(|x| x.to_string()),
                recorded.fps.map(|x| x.to_string()),
            ),
        ];
        if self.white_balance {
            let auto =
                |k: Option<u32>| k.map_or_else(|| "automatic".to_string(), |k| format!("{k} K"));
            pairs.push((
                "white_balance_k",
                Some(auto(v.white_balance_k)),
                Some(auto(recorded.white_balance_k)),
            ));
        }
        for (control, now, then) in pairs {
            if let Some(now) = now
                && Some(&now) != then.as_ref()
            {
                let then = then.unwrap_or_else(|| "absent".to_string());
                return Err((control.to_string(), then, now));
            }
        }
        Ok(())
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

/// Below this mean grey level a picture is near black: no board's corners can be found
/// (the teams' exposures give a mean near the middle; a V6 camera at too short an exposure
/// gives a nearly black picture).
pub const DARK_MEAN: f64 = 30.0;
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
    /// The settings the camera was driven with, as the dataset records them.
    pub used: UsedSettings,
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
    check_first_size(camera, size, expected)?;
    brightness
        .check(settings)
        .map_err(|e| format!("the {camera} camera's first picture {e}"))
}

/// The size part of [`check_first`]: the camera's first picture (`size`, from its header or
/// decoded) must have the size of its intrinsics (`expected`).
pub fn check_first_size(
    camera: CameraId,
    size: (u32, u32),
    expected: (u32, u32),
) -> Result<(), String> {
    if size != expected {
        return Err(format!(
            "the {camera} camera's first picture is {}×{} pixels; the dataset's intrinsics \
             are for {}×{} (the camera's width and height in dataset.toml)",
            size.0, size.1, expected.0, expected.1
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dataset::settings::parse_setting;

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

    /// A flip against the camera's mounting is refused (upper: flipped, lower: not).
    #[test]
    fn a_flip_that_turns_the_picture_upside_down_is_refused() {
        let upper = CameraSettings::defaults(CameraId::Upper, 640, 480);
        let lower = CameraSettings::defaults(CameraId::Lower, 640, 480);
        assert!(upper.check_upright(CameraId::Upper).is_ok());
        assert!(lower.check_upright(CameraId::Lower).is_ok());
        let e = CameraSettings {
            flip: false,
            ..upper
        }
        .check_upright(CameraId::Upper)
        .unwrap_err();
        assert!(
            e.contains("upper camera's flip is false")
                && e.contains("[upper_camera] flip")
                && e.contains("upside down"),
            "{e}"
        );
        let e = CameraSettings {
            flip: true,
            ..lower
        }
        .check_upright(CameraId::Lower)
        .unwrap_err();
        assert!(
            e.contains("lower camera's flip is true") && e.contains("leave flip at false"),
            "{e}"
        );
    }

    /// A command is given, and a dataset records, the settings whose placeholders it
    /// takes; a V4L2 camera all of them. A resume is checked on what is driven now and
    /// recorded then; a camera whose table records nothing is not checked.
    #[test]
    fn the_settings_used_are_those_a_command_takes_and_resumes_keep_them() {
        let mut s = CameraSettings::defaults(CameraId::Lower, 640, 480);
        let p = s.placeholders();
        assert_eq!(p[0], ("{flip}", "0".to_string()));
        assert_eq!(p[3], ("{white_balance_k}", "auto".to_string()));
        assert_eq!(p[6], ("{height}", "480".to_string()));
        assert!(PLACEHOLDERS.iter().zip(&p).all(|(a, (b, _))| a == b));
        let given = UsedSettings::given_to(CameraId::Lower, &s, "grab -e {exposure} {path}");
        assert_eq!(
            given.values,
            SettingsChanges {
                exposure: Some(1700),
                ..SettingsChanges::default()
            }
        );
        assert!(given.exposes() && given.any() && !given.white_balance);
        let none = UsedSettings::given_to(CameraId::Lower, &s, "grab {path}");
        assert!(!none.any() && !none.exposes());
        assert!(none.note().contains("took no settings"));
        let all = UsedSettings::read_back(CameraId::Lower, &s);
        assert_eq!(all.values, s.as_changes());
        assert!(all.note().contains("[camera]") && all.note().contains("read them back"));
        // Resumed: the same, a table recording nothing, another exposure, another white
        // balance (automatic then).
        assert!(all.check_same(&s.as_changes()).is_ok());
        assert!(all.check_same(&SettingsChanges::default()).is_ok());
        let mut then = s.as_changes();
        then.exposure = Some(900);
        assert_eq!(
            all.check_same(&then).unwrap_err(),
            (
                "exposure".to_string(),
                "900".to_string(),
                "1700".to_string()
            )
        );
        assert!(given.check_same(&then).is_err());
        assert!(
            none.check_same(&then).is_ok(),
            "nothing driven, nothing to check"
        );
        s.white_balance = Some(4000);
        let fixed = UsedSettings::read_back(CameraId::Lower, &s);
        assert_eq!(
            fixed.check_same(&all.values).unwrap_err(),
            (
                "white_balance_k".to_string(),
                "automatic".to_string(),
                "4000 K".to_string()
            )
        );
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
