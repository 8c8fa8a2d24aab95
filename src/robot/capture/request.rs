//! What `naocalib capture` is asked for, in the user's units: the run's options, the
//! cameras (each named once) and how each is set up (the team defaults, the robot's
//! dataset.toml, the flags), the dry run of `--check`, and the account printed at the end
//! of a run.

use std::path::{Path, PathBuf};
use std::time::Duration;

use crate::dataset::DatasetError;
use crate::dataset::settings::SettingsChanges;
use crate::model::{CameraId, Model};
use crate::robot::camera::settings::settings_for;
use crate::robot::camera::{Camera, CameraError, CameraSpec, Setup};
use crate::robot::check::{self, CheckReport};

use super::{CaptureError, CaptureOptions, End, Report, cycles_to_seconds};

/// The cameras of a run, opened, each with its name.
pub type OpenCameras = Vec<(CameraId, Box<dyn Camera>)>;

/// A measurement phase to run, as `naocalib capture` is asked for it.
#[derive(Debug, Clone, PartialEq)]
pub struct CaptureRequest {
    /// The stance schedule.
    pub plan: PathBuf,
    /// The robot's dataset.toml (with `resume`, the dataset's own is used).
    pub config: Option<PathBuf>,
    /// LoLA's socket.
    pub lola: PathBuf,
    /// The cameras, `[lower=|upper=]SPEC` each.
    pub cameras: Vec<String>,
    /// Leg joint speed limit (deg/s).
    pub leg_speed_deg: f64,
    /// Head joint speed limit (deg/s).
    pub head_speed_deg: f64,
    /// Stiffness of the head and leg joints while measuring.
    pub stiffness: f64,
    /// Longest a `command:` camera may take for a picture (s).
    pub camera_timeout_s: f64,
    /// Longest wait for one V4L2 frame (s).
    pub frame_timeout_s: f64,
    /// V4L2 settings over the team defaults and dataset.toml's.
    pub camera_settings: Vec<(Vec<CameraId>, SettingsChanges)>,
    /// The program whose `camera-guard` subcommand runs each `command:` picture (naocalib
    /// itself); `None`: a command runs without a guard.
    pub guard: Option<PathBuf>,
}

/// Why a capture could not be set up.
#[derive(Debug, thiserror::Error)]
pub enum CaptureRequestError {
    /// A value is out of range, or missing.
    #[error("{0}")]
    Invalid(String),
    /// A camera is given wrongly, or could not be opened.
    #[error(transparent)]
    Camera(#[from] CameraError),
    /// The robot's dataset.toml could not be read.
    #[error(transparent)]
    Dataset(#[from] DatasetError),
    /// The plan, a camera or the robot failed a check.
    #[error(transparent)]
    Capture(#[from] CaptureError),
}

impl CaptureRequest {
    /// The run's options: the defaults with the speeds and the stiffness asked for.
    pub fn options(&self) -> Result<CaptureOptions, CaptureRequestError> {
        let mut options = CaptureOptions::default();
        options.motion.leg_speed = self.leg_speed_deg.to_radians();
        options.motion.head_speed = self.head_speed_deg.to_radians();
        options.motion.stiffness = self.stiffness;
        options
            .motion
            .validate()
            .map_err(CaptureRequestError::Invalid)?;
        Ok(options)
    }

    /// The cameras, each once.
    pub fn cameras(&self) -> Result<Vec<(CameraId, CameraSpec)>, CaptureRequestError> {
        let mut specs: Vec<(CameraId, CameraSpec)> = Vec::new();
        for text in &self.cameras {
            let (id, spec) = CameraSpec::parse_named(text)?;
            if specs.iter().any(|(c, _)| *c == id) {
                return Err(CaptureRequestError::Invalid(format!(
                    "--camera: the {id} camera is given twice"
                )));
            }
            specs.push((id, spec));
        }
        Ok(specs)
    }

    /// Each camera with how it is set up for the robot `model`: the team defaults,
    /// `config`'s `[camera]`/`[upper_camera]` settings over them, the flags' over those,
    /// the waits, and [`CaptureRequest::guard`] for a `command:` camera.
    pub fn setups(
        &self,
        model: &Model,
        config: &Path,
    ) -> Result<Vec<(CameraId, CameraSpec, Setup)>, CaptureRequestError> {
        let file_settings = crate::dataset::read_camera_settings(config)?;
        self.check_settings_named()?;
        Ok(self
            .cameras()?
            .into_iter()
            .map(|(id, spec)| {
                let setup = Setup {
                    settings: settings_for(id, model, &file_settings, &self.camera_settings),
                    frame_timeout: Duration::from_secs_f64(self.frame_timeout_s),
                    command_timeout: Duration::from_secs_f64(self.camera_timeout_s),
                    guard: self.guard.clone(),
                };
                (id, spec, setup)
            })
            .collect())
    }

    /// Refuses a `--camera-setting` that names a camera the run does not have (a setting
    /// for a camera not given, or a typo of the other camera's name): it would be accepted
    /// and apply to nothing. One without a camera's name is for every camera given.
    pub fn check_settings_named(&self) -> Result<(), CaptureRequestError> {
        let given: Vec<CameraId> = self.cameras()?.iter().map(|(c, _)| *c).collect();
        for (named, _) in &self.camera_settings {
            if named.len() != 1 || given.contains(&named[0]) {
                continue;
            }
            let has: Vec<&str> = given.iter().map(|c| c.name()).collect();
            return Err(CaptureRequestError::Invalid(format!(
                "--camera-setting {camera}.…: this run has no {camera} camera (its cameras: \
                 {}); give the setting for one of them, or the {camera} camera with \
                 --camera {camera}=SPEC",
                has.join(", "),
                camera = named[0].name()
            )));
        }
        Ok(())
    }

    /// The robot's dataset.toml for a run into `dir`: the one given, else the dataset's.
    pub fn config_in(&self, dir: &Path) -> PathBuf {
        match &self.config {
            Some(config) => config.clone(),
            None => dir.join("dataset.toml"),
        }
    }

    /// Opens the cameras of `setups` ([`CaptureRequest::setups`]), each set up (read back
    /// for V4L2) and its first picture checked, before anything moves: the cameras, and a
    /// line for each saying how it is set and what its first picture is.
    pub fn open_cameras(
        setups: &[(CameraId, CameraSpec, Setup)],
        scratch: &Path,
    ) -> Result<(OpenCameras, Vec<String>), CaptureRequestError> {
        let mut cameras = Vec::new();
        let mut said = Vec::new();
        for ((id, spec, setup), (camera, first)) in setups
            .iter()
            .zip(crate::robot::camera::open_all(setups, scratch)?)
        {
            let how = match spec {
                CameraSpec::V4l2(device) => format!(
                    "{}: {} — set and read back",
                    device.display(),
                    setup.settings
                ),
                CameraSpec::Command(_) => "command".to_string(),
            };
            said.push(format!(
                "{id} camera ({how}); first picture {}×{}, mean brightness {:.0} of 255",
                first.size.0, first.size.1, first.brightness.mean
            ));
            cameras.push((*id, camera));
        }
        Ok((cameras, said))
    }

    /// `--check`: checks the plan, each camera (one picture each saved into `save`), LoLA
    /// and the robot, and moves nothing.
    pub fn dry_run(&self, save: &Path) -> Result<CheckReport, CaptureRequestError> {
        let options = self.options()?;
        let Some(config) = &self.config else {
            return Err(CaptureRequestError::Invalid(
                "--check needs --config DATASET_TOML (the robot's cameras)".into(),
            ));
        };
        let model = crate::dataset::read_model(config)?;
        let cameras = self.setups(&model, config)?;
        Ok(check::dry_run(
            &self.plan, &model, &cameras, &self.lola, &options, save,
        )?)
    }
}

/// The last line of a dry run: whether the day can start, or what does not hold.
pub fn verdict(report: &CheckReport) -> String {
    if report.ready() {
        "naocalib: the day can start: every check holds, nothing was moved".to_string()
    } else {
        format!(
            "naocalib: not ready (nothing was moved): {}",
            report.failed()
        )
    }
}

/// The account of a run: what to print, and how it ended.
#[derive(Debug, Clone, PartialEq)]
pub struct Account {
    /// The lines to print: the counts, every capture skipped and why, and how to go on.
    pub lines: Vec<String>,
    /// The exit code of a run that ended without a fault: 0 when the plan was run to its
    /// end, 2 when a signal or a stop ended it.
    pub exit: u8,
    /// The error of a run a fault stopped.
    pub error: Option<String>,
}

/// The account of the run `report` into `out` of a plan of `total` captures (`signalled`:
/// a signal stopped it).
pub fn account(out: &Path, report: &Report, total: usize, signalled: bool) -> Account {
    let done = report.already + report.taken.len();
    let mut lines = vec![format!(
        "{} captures taken in this run ({} before), {} skipped, {done} of {total} in {} \
         ({:.1} s of robot time)",
        report.taken.len(),
        report.already,
        report.skipped(),
        out.display(),
        cycles_to_seconds(report.cycles)
    )];
    for (id, reason) in &report.unreachable {
        lines.push(format!("  skipped capture {id} before moving: {reason}"));
    }
    for (id, reason) in &report.abandoned {
        lines.push(format!("  skipped capture {id} on the way: {reason}"));
    }
    let (exit, error) = match &report.end {
        End::Completed => (0, None),
        End::Interrupted => {
            let signal = if signalled { "a signal" } else { "a stop" };
            lines.push(format!(
                "naocalib: stopped by {signal}: the robot is at rest with its stiffness off; \
                 {} is a valid dataset; go on with --resume",
                out.display()
            ));
            (2, None)
        }
        End::Stopped(e) => (
            1,
            Some(format!(
                "{e}; the run stopped ({} is a valid dataset of the {done} captures taken; \
                 go on with --resume)",
                out.display()
            )),
        ),
    };
    Account { lines, exit, error }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn request() -> CaptureRequest {
        CaptureRequest {
            plan: PathBuf::from("plan.csv"),
            config: None,
            lola: PathBuf::from("/tmp/robocup"),
            cameras: vec!["command:true {path}".into()],
            leg_speed_deg: 30.0,
            head_speed_deg: 90.0,
            stiffness: 0.8,
            camera_timeout_s: 10.0,
            frame_timeout_s: 1.0,
            camera_settings: Vec::new(),
            guard: None,
        }
    }

    #[test]
    fn the_options_are_in_radians_and_checked() {
        let options = request().options().unwrap();
        assert_eq!(options.motion.leg_speed, 30f64.to_radians());
        assert_eq!(options.motion.head_speed, 90f64.to_radians());
        assert_eq!(options.motion.stiffness, 0.8);
        let limp = CaptureRequest {
            stiffness: -1.0,
            ..request()
        };
        assert!(matches!(
            limp.options(),
            Err(CaptureRequestError::Invalid(_))
        ));
    }

    #[test]
    fn each_camera_is_named_once() {
        let both = CaptureRequest {
            cameras: vec!["command:a {path}".into(), "upper=command:b {path}".into()],
            ..request()
        };
        let ids: Vec<CameraId> = both.cameras().unwrap().iter().map(|(c, _)| *c).collect();
        assert_eq!(ids, [CameraId::Lower, CameraId::Upper]);
        let twice = CaptureRequest {
            cameras: vec!["command:a {path}".into(), "lower=command:b {path}".into()],
            ..request()
        };
        assert_eq!(
            twice.cameras().unwrap_err().to_string(),
            "--camera: the lower camera is given twice"
        );
        let bad = CaptureRequest {
            cameras: vec!["usb:0".into()],
            ..request()
        };
        assert!(matches!(bad.cameras(), Err(CaptureRequestError::Camera(_))));
        assert_eq!(
            request().config_in(Path::new("ds")),
            Path::new("ds/dataset.toml")
        );
        let no_config = request().dry_run(Path::new("chk")).unwrap_err();
        assert!(no_config.to_string().starts_with("--check needs --config"));
    }

    #[test]
    fn the_account_tells_how_the_run_ended() {
        let report = |end| Report {
            already: 2,
            taken: Vec::new(),
            unreachable: vec![(7, "blocked".into())],
            abandoned: Vec::new(),
            cycles: 0,
            end,
            limp: true,
        };
        let done = account(Path::new("ds"), &report(End::Completed), 9, false);
        assert_eq!(done.exit, 0);
        assert!(done.error.is_none());
        assert!(
            done.lines[0]
                .starts_with("0 captures taken in this run (2 before), 1 skipped, 2 of 9 in ds"),
            "{:?}",
            done.lines
        );
        assert_eq!(done.lines[1], "  skipped capture 7 before moving: blocked");
        let stopped = account(Path::new("ds"), &report(End::Interrupted), 9, true);
        assert_eq!(stopped.exit, 2);
        assert!(stopped.lines[2].starts_with("naocalib: stopped by a signal:"));
    }
}
