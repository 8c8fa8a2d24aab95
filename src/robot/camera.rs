//! Taking the picture: the V6's cameras through Video4Linux2 (`v4l2:DEVICE`, with the
//! `v4l2` feature; the `v4l2` module) set as [`settings`] says, or any command that writes a PNG or
//! JPEG (`command:CMD {path}`).
//!
//! A `command:` camera is given its camera's settings through placeholders (`{flip}`,
//! `{exposure}`, `{gain}`, … [`settings::PLACEHOLDERS`]) and runs under a guard (the
//! [`guard`] module, `naocalib camera-guard`) that kills every process the command starts
//! when capture dies, by whatever signal.
//!
//! A picture belongs to its stance only if its exposure began after the stance settled:
//! V4L2 frames are checked by their buffer timestamps; a `command:` grabber must itself
//! deliver a frame whose exposure began after it was started (a framework that streams
//! continuously must wait for the next frame, not hand over one it already holds).

pub mod guard;
pub mod picture;
pub mod settings;
#[cfg(feature = "v4l2")]
pub mod v4l2;

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use crate::model::CameraId;
pub use picture::{check_picture, decode_grey, header_size, image_kind};
use settings::UsedSettings;

/// A picture as taken: the encoded image and its extension (`png` or `jpg`).
#[derive(Debug, Clone, PartialEq)]
pub struct Picture {
    /// The encoded image file.
    pub bytes: Vec<u8>,
    /// `png` or `jpg`.
    pub extension: &'static str,
}

/// Why no picture was taken.
#[derive(Debug, thiserror::Error)]
pub enum CameraError {
    /// The `--camera` text is not a known kind.
    #[error(
        "--camera '{0}': expected [lower=|upper=]SPEC, SPEC 'v4l2:DEVICE' (e.g. \
         v4l2:/dev/video-bottom) or 'command:CMD {{path}}' (CMD writes a PNG or JPEG to \
         {{path}}; {{camera}} is the camera's name)"
    )]
    Spec(String),
    /// V4L2 was asked for but this build lacks it.
    #[error(
        "--camera v4l2:… needs naocalib built with the `v4l2` feature (cargo build --release \
         --no-default-features --features v4l2); use 'command:…' with your own grabber \
         otherwise"
    )]
    NoV4l2,
    /// The command failed.
    #[error("camera command '{command}' {status}: {stderr}")]
    Command {
        /// The command run.
        command: String,
        /// How it ended.
        status: String,
        /// What it wrote to stderr (shortened).
        stderr: String,
    },
    /// The command took too long.
    #[error("camera command '{command}' took longer than {seconds} s; stopped")]
    Timeout {
        /// The command run.
        command: String,
        /// The limit (s).
        seconds: f64,
    },
    /// A picture that does not decode or does not have the camera's size.
    #[error("the picture of capture {id} {message}")]
    Unreadable {
        /// The capture.
        id: u64,
        /// What is wrong.
        message: String,
    },
    /// No camera was given for a capture's camera.
    #[error("no {0} camera given (--camera {0}=SPEC)")]
    Missing(crate::model::CameraId),
    /// The run stopped while the picture was being taken.
    #[error("camera command '{0}' stopped: the run is over")]
    Cancelled(String),
    /// The picture is not a PNG or JPEG.
    #[error("{}: {message}", path.display())]
    Image {
        /// The file the picture was read from.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// The camera device failed.
    #[error("camera {device}: {message}")]
    Device {
        /// The device.
        device: String,
        /// What went wrong.
        message: String,
    },
    /// A camera setting written did not read back the same; nothing was moved.
    #[error(
        "the {camera} camera ({device}): {control} was set to {wrote} but reads back {read}; \
         nothing was moved (is it a NAO V6 camera, and is another program using it?)"
    )]
    Setting {
        /// The camera.
        camera: CameraId,
        /// Its device.
        device: String,
        /// The control (its name in dataset.toml where it has one).
        control: String,
        /// The value written.
        wrote: String,
        /// The value read back.
        read: String,
    },
    /// The camera's stream delivered no frame, even after a restart.
    #[error(
        "the {camera} camera ({device}) stalled: no frame within {seconds} s, {restarts} \
         stream restart(s) did not help; unplugging is not needed — restart naocalib (the \
         camera is opened afresh) or reboot the robot if it stalls again"
    )]
    Stalled {
        /// The camera.
        camera: CameraId,
        /// Its device.
        device: String,
        /// The frame timeout (s).
        seconds: f64,
        /// The restarts tried.
        restarts: u32,
    },
    /// A camera's first picture is not fit to calibrate with (size, near black, saturated).
    #[error("{0}; nothing was moved")]
    FirstPicture(String),
    /// A camera's flip would turn its pictures upside down.
    #[error("{0}; nothing was moved")]
    UpsideDown(String),
    /// A file could not be read or a process started.
    #[error("camera: {0}")]
    Io(#[from] std::io::Error),
}

/// A camera: takes one picture per call.
pub trait Camera: Send {
    /// Takes a picture now; `scratch` is a directory for temporary files.
    fn take(&mut self, scratch: &Path) -> Result<Picture, CameraError>;

    /// A flag that, once set, makes a [`Camera::take`] under way give up at once (and
    /// every later one fail), when the camera can be interrupted.
    fn cancel_flag(&self) -> Option<Arc<AtomicBool>> {
        None
    }
}

/// What `--camera` names.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum CameraSpec {
    /// A Video4Linux2 device (the V6's lower camera is `/dev/video-bottom`).
    V4l2(PathBuf),
    /// A shell command with `{path}` where the picture is to be written.
    Command(String),
}

impl CameraSpec {
    /// Parses `lower=SPEC`, `upper=SPEC` or `SPEC` alone (the lower camera).
    pub fn parse_named(text: &str) -> Result<(CameraId, CameraSpec), CameraError> {
        for camera in CameraId::ALL {
            if let Some(spec) = text
                .strip_prefix(camera.name())
                .and_then(|t| t.strip_prefix('='))
            {
                return CameraSpec::parse(spec)
                    .map(|s| (camera, s))
                    .map_err(|_| CameraError::Spec(text.into()));
            }
        }
        CameraSpec::parse(text).map(|s| (CameraId::Lower, s))
    }

    /// Parses `v4l2:DEVICE` or `command:CMD` (CMD must contain `{path}`).
    pub fn parse(text: &str) -> Result<CameraSpec, CameraError> {
        if let Some(device) = text.strip_prefix("v4l2:") {
            if device.is_empty() {
                return Err(CameraError::Spec(text.into()));
            }
            return Ok(CameraSpec::V4l2(PathBuf::from(device)));
        }
        if let Some(command) = text.strip_prefix("command:") {
            if !command.contains("{path}") || command.trim().is_empty() {
                return Err(CameraError::Spec(text.into()));
            }
            return Ok(CameraSpec::Command(command.to_string()));
        }
        Err(CameraError::Spec(text.into()))
    }

    /// Opens `camera` (`{camera}` in a command stands for its name): a V4L2 device is set
    /// to `setup.settings`, every value read back; a command is only remembered, with the
    /// settings its placeholders stand for. Settings whose flip would turn the pictures
    /// upside down are refused ([`settings::CameraSettings::check_upright`]).
    pub fn open(&self, camera: CameraId, setup: &Setup) -> Result<Box<dyn Camera>, CameraError> {
        setup
            .settings
            .check_upright(camera)
            .map_err(CameraError::UpsideDown)?;
        match self {
            CameraSpec::Command(command) => Ok(Box::new(CommandCamera {
                command: command.clone(),
                name: camera.name().to_string(),
                settings: setup.settings,
                guard: setup.guard.clone(),
                timeout: setup.command_timeout,
                count: 0,
                cancel: Arc::new(AtomicBool::new(false)),
            })),
            #[cfg(feature = "v4l2")]
            CameraSpec::V4l2(device) => Ok(Box::new(v4l2::V4l2Camera::open(
                device,
                camera,
                &setup.settings,
                v4l2::FrameWait {
                    timeout: setup.frame_timeout,
                    restarts: 1,
                },
            )?)),
            #[cfg(not(feature = "v4l2"))]
            CameraSpec::V4l2(_) => Err(CameraError::NoV4l2),
        }
    }

    /// The settings `camera` is driven with when opened with `settings`: all of them,
    /// read back, for a V4L2 device; those its placeholders take for a command.
    pub fn used(&self, camera: CameraId, settings: &settings::CameraSettings) -> UsedSettings {
        match self {
            CameraSpec::V4l2(_) => UsedSettings::read_back(camera, settings),
            CameraSpec::Command(command) => UsedSettings::given_to(camera, settings, command),
        }
    }

    /// Opens `camera` as [`CameraSpec::open`] does, takes one picture and checks it
    /// ([`settings::check_first`]: the size of `setup.settings`, neither near black nor
    /// saturated), for a V4L2 device and a command alike: the camera and its first picture
    /// (with the settings applied and read back for a V4L2 device), or why it is not fit —
    /// before anything moves.
    pub fn open_checked(
        &self,
        camera: CameraId,
        setup: &Setup,
        scratch: &Path,
    ) -> Result<(Box<dyn Camera>, settings::FirstPicture), CameraError> {
        let mut cam = self.open(camera, setup)?;
        let picture = cam.take(scratch)?;
        let s = &setup.settings;
        let first = |message| {
            CameraError::FirstPicture(format!("the {camera} camera's first picture {message}"))
        };
        // Its size by its header first: nothing is allocated for a picture of another size.
        let (_, claimed) = header_size(&picture.bytes).map_err(first)?;
        settings::check_first_size(camera, claimed, (s.width, s.height))
            .map_err(CameraError::FirstPicture)?;
        let (size, grey) = decode_grey(&picture.bytes, (s.width, s.height)).map_err(first)?;
        let brightness = settings::Brightness::of_grey(&grey);
        let applied = matches!(self, CameraSpec::V4l2(_)).then_some(setup.settings);
        let used = self.used(camera, s);
        settings::check_first(
            camera,
            size,
            (s.width, s.height),
            &brightness,
            used.exposes().then_some(s),
        )
        .map_err(CameraError::FirstPicture)?;
        Ok((
            cam,
            settings::FirstPicture {
                camera,
                settings: applied,
                used,
                size,
                brightness,
                picture,
            },
        ))
    }
}

/// A camera opened and checked, with its first picture.
pub type Opened = (Box<dyn Camera>, settings::FirstPicture);

/// Every camera of a run opened ([`CameraSpec::open_checked`]: set up, read back, its
/// first picture checked), in order, before anything moves; the first that is not fit
/// stops it.
pub fn open_all(
    cameras: &[(CameraId, CameraSpec, Setup)],
    scratch: &Path,
) -> Result<Vec<Opened>, CameraError> {
    cameras
        .iter()
        .map(|(id, spec, setup)| spec.open_checked(*id, setup, scratch))
        .collect()
}

/// How a camera is opened: its settings and how long a picture may take.
#[derive(Debug, Clone, PartialEq)]
pub struct Setup {
    /// What a V4L2 camera is set to, and what a command's placeholders stand for (its size
    /// is also what every picture must have).
    pub settings: settings::CameraSettings,
    /// The longest wait for one V4L2 frame (a stalled stream is restarted once after it).
    pub frame_timeout: Duration,
    /// The longest a `command:` camera may take for a picture.
    pub command_timeout: Duration,
    /// The program whose `camera-guard` subcommand ([`guard`]) runs each `command:`
    /// picture (naocalib itself); `None`: the command runs without a guard, and what it
    /// starts in the background may outlive a capture killed by SIGKILL.
    pub guard: Option<PathBuf>,
}

impl Setup {
    /// The team defaults of `camera` at `width`×`height` ([`settings::CameraSettings::defaults`]),
    /// a 1 s frame timeout, 10 s for a command, no guard.
    pub fn defaults(camera: CameraId, width: u32, height: u32) -> Setup {
        Setup {
            settings: settings::CameraSettings::defaults(camera, width, height),
            frame_timeout: Duration::from_secs(1),
            command_timeout: Duration::from_secs(10),
            guard: None,
        }
    }
}

/// Quotes `text` for `sh` (single quotes).
fn shell_quote(text: &str) -> String {
    format!("'{}'", text.replace('\'', r"'\''"))
}

/// `command:CMD {path}`: runs CMD with `sh -c`, `{path}` replaced by a fresh file name,
/// `{camera}` by the camera's name (`lower`, `upper`) and the settings' placeholders
/// ([`settings::PLACEHOLDERS`]) by their values, and reads the PNG or JPEG it wrote there.
/// CMD runs in a process group of its own (under the [`guard`] when one is given), which
/// is killed as a whole when it takes too long, when the run stops, when CMD is done, and
/// (through the guard) when capture dies.
#[derive(Debug)]
pub struct CommandCamera {
    command: String,
    name: String,
    settings: settings::CameraSettings,
    guard: Option<PathBuf>,
    timeout: Duration,
    count: u64,
    cancel: Arc<AtomicBool>,
}

/// Makes the process `command` starts die with the thread that starts it (Linux's
/// `PR_SET_PDEATHSIG`) — used for a command run without a guard: a camera command that
/// is one process (the shell exec'd it) is killed by the kernel even when capture itself
/// is killed and cannot kill its group.
fn die_with_parent(command: &mut std::process::Command) {
    #[cfg(target_os = "linux")]
    {
        use std::os::unix::process::CommandExt as _;
        // SAFETY: getpid before the fork; prctl and getppid are async-signal-safe.
        let parent = unsafe { libc::getpid() };
        unsafe {
            command.pre_exec(move || {
                if libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL) != 0 {
                    return Err(std::io::Error::last_os_error());
                }
                // The parent died before the prctl: no signal would come.
                if libc::getppid() != parent {
                    return Err(std::io::Error::other("capture is gone"));
                }
                Ok(())
            });
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = command;
}

/// Kills the process group `child` leads, and reaps `child`.
fn kill_group(child: &mut std::process::Child) {
    // The group's id is the child's pid (`process_group(0)`).
    unsafe {
        libc::kill(-(child.id() as libc::pid_t), libc::SIGKILL);
    }
    let _ = child.kill();
    let _ = child.wait();
}

/// Reads what is in `pipe` now, without waiting for more (a process that left the group
/// may hold it open).
fn read_available(pipe: Option<impl std::io::Read + std::os::fd::AsRawFd>) -> String {
    let Some(mut pipe) = pipe else {
        return String::new();
    };
    // SAFETY: fcntl on an open descriptor this process owns.
    unsafe {
        let fd = pipe.as_raw_fd();
        let flags = libc::fcntl(fd, libc::F_GETFL);
        libc::fcntl(fd, libc::F_SETFL, flags | libc::O_NONBLOCK);
    }
    let mut bytes = Vec::new();
    let mut buf = [0u8; 4096];
    while bytes.len() < 65536 {
        match std::io::Read::read(&mut pipe, &mut buf) {
            Ok(n) if n > 0 => bytes.extend_from_slice(&buf[..n]),
            _ => break,
        }
    }
    String::from_utf8_lossy(&bytes).into_owned()
}

impl CommandCamera {
    /// The command line of picture `path`: `{path}`, `{camera}` and the settings'
    /// placeholders replaced (each value quoted for `sh`).
    fn line(&self, path: &Path) -> String {
        let mut line = self
            .command
            .replace("{path}", &shell_quote(&path.to_string_lossy()))
            .replace("{camera}", &shell_quote(&self.name));
        for (placeholder, value) in self.settings.placeholders() {
            line = line.replace(placeholder, &shell_quote(&value));
        }
        line
    }

    /// Starts `line`: under the guard (`naocalib camera-guard`, which reports how the
    /// command ended on its standard output) when there is one, else `sh -c` itself; in a
    /// process group of its own either way.
    fn spawn(&self, line: &str) -> std::io::Result<std::process::Child> {
        use std::os::unix::process::CommandExt as _;
        use std::process::Stdio;
        let mut command = match &self.guard {
            Some(program) => {
                let mut c = std::process::Command::new(program);
                c.arg(guard::SUBCOMMAND)
                    .arg("--parent")
                    .arg(std::process::id().to_string())
                    .arg("--")
                    .arg(line)
                    .stdout(Stdio::piped());
                c
            }
            None => {
                let mut c = std::process::Command::new("sh");
                c.arg("-c").arg(line).stdout(Stdio::null());
                die_with_parent(&mut c);
                c
            }
        };
        command
            .process_group(0)
            .stdin(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
    }
}

impl Camera for CommandCamera {
    fn take(&mut self, scratch: &Path) -> Result<Picture, CameraError> {
        self.count += 1;
        let path = scratch.join(format!("picture-{}", self.count));
        let _ = std::fs::remove_file(&path);
        let line = self.line(&path);
        if self.cancel.load(Ordering::Relaxed) {
            return Err(CameraError::Cancelled(self.command.clone()));
        }
        let mut child = self.spawn(&line)?;
        let start = Instant::now();
        let status = loop {
            if let Some(status) = child.try_wait()? {
                break status;
            }
            if self.cancel.load(Ordering::Relaxed) {
                kill_group(&mut child);
                return Err(CameraError::Cancelled(self.command.clone()));
            }
            if start.elapsed() > self.timeout {
                kill_group(&mut child);
                return Err(CameraError::Timeout {
                    command: self.command.clone(),
                    seconds: self.timeout.as_secs_f64(),
                });
            }
            std::thread::sleep(Duration::from_millis(2));
        };
        // Whatever CMD left running in its group goes with it (the guard has killed the
        // group already).
        unsafe {
            libc::kill(-(child.id() as libc::pid_t), libc::SIGKILL);
        }
        let ended = match &self.guard {
            Some(_) => guard::Ended::read(&read_available(child.stdout.take())),
            None => Some(guard::Ended::of(status)),
        };
        if ended != Some(guard::Ended::Exit(0)) {
            let stderr = read_available(child.stderr.take());
            let stderr: String = stderr.trim().chars().take(400).collect();
            return Err(CameraError::Command {
                command: self.command.clone(),
                status: ended.map_or_else(
                    || format!("was stopped from outside ({status})"),
                    |e| e.to_string(),
                ),
                stderr,
            });
        }
        let bytes = std::fs::read(&path).map_err(|e| CameraError::Image {
            path: path.clone(),
            message: format!("the camera command wrote no picture here: {e}"),
        })?;
        let _ = std::fs::remove_file(&path);
        // Only the kind here: the run decodes every picture in full and checks its size.
        let extension = image_kind(&bytes).ok_or_else(|| CameraError::Image {
            path,
            message: "is neither a PNG nor a JPEG".into(),
        })?;
        Ok(Picture { bytes, extension })
    }

    fn cancel_flag(&self) -> Option<Arc<AtomicBool>> {
        Some(self.cancel.clone())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn specs_parse() {
        assert_eq!(
            CameraSpec::parse("v4l2:/dev/video-bottom").unwrap(),
            CameraSpec::V4l2("/dev/video-bottom".into())
        );
        assert_eq!(
            CameraSpec::parse("command:grab --out {path}").unwrap(),
            CameraSpec::Command("grab --out {path}".into())
        );
        for bad in ["", "v4l2:", "command:grab", "usb:0"] {
            assert!(CameraSpec::parse(bad).is_err(), "{bad}");
        }
        assert_eq!(
            CameraSpec::parse_named("upper=v4l2:/dev/video-top").unwrap(),
            (CameraId::Upper, CameraSpec::V4l2("/dev/video-top".into()))
        );
        assert_eq!(
            CameraSpec::parse_named("lower=command:grab {camera} {path}").unwrap(),
            (
                CameraId::Lower,
                CameraSpec::Command("grab {camera} {path}".into())
            )
        );
        assert_eq!(
            CameraSpec::parse_named("command:grab a=b {path}")
                .unwrap()
                .0,
            CameraId::Lower
        );
        for bad in ["upper=", "upper=usb:0", "top=v4l2:/dev/video-top"] {
            assert!(CameraSpec::parse_named(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn a_command_camera_reads_the_png_it_wrote_and_refuses_other_files() {
        let setup = Setup::defaults(CameraId::Lower, 640, 480);
        let dir = tempfile::tempdir().unwrap();
        let image = crate::sim::render::GreyImage {
            width: 4,
            height: 2,
            pixels: vec![7; 8],
        };
        let src = dir.path().join("src.png");
        std::fs::write(&src, image.to_png().unwrap()).unwrap();
        let spec = CameraSpec::parse(&format!("command:cp '{}' {{path}}", src.display())).unwrap();
        let mut camera = spec.open(CameraId::Lower, &setup).unwrap();
        let picture = camera.take(dir.path()).unwrap();
        assert_eq!(picture.extension, "png");
        assert_eq!(picture.bytes, std::fs::read(&src).unwrap());

        let text = dir.path().join("x.txt");
        std::fs::write(&text, "hello").unwrap();
        let spec = CameraSpec::parse(&format!("command:cp '{}' {{path}}", text.display())).unwrap();
        let e = spec.open(CameraId::Lower, &setup).unwrap().take(dir.path());
        assert!(e.unwrap_err().to_string().contains("neither a PNG"));
        let spec = CameraSpec::parse("command:echo oops >&2; false {path}").unwrap();
        let e = spec.open(CameraId::Lower, &setup).unwrap().take(dir.path());
        assert!(e.unwrap_err().to_string().contains("oops"));
    }

    /// A command is given its camera's settings through the placeholders it takes (each
    /// quoted); a flip that turns the picture upside down is refused at opening.
    #[test]
    fn a_command_camera_is_given_its_settings_and_a_wrong_flip_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let image = crate::sim::render::GreyImage {
            width: 4,
            height: 2,
            pixels: vec![7; 8],
        };
        let src = dir.path().join("src.png");
        std::fs::write(&src, image.to_png().unwrap()).unwrap();
        let log = dir.path().join("given.txt");
        let spec = CameraSpec::parse(&format!(
            "command:echo {{camera}} {{flip}} {{exposure}} {{gain}} {{white_balance_k}} {{fps}} \
             {{width}}x{{height}} > '{}'; cp '{}' {{path}}",
            log.display(),
            src.display()
        ))
        .unwrap();
        let mut setup = Setup::defaults(CameraId::Upper, 1280, 960);
        setup.settings.gain = 300;
        spec.open(CameraId::Upper, &setup)
            .unwrap()
            .take(dir.path())
            .unwrap();
        assert_eq!(
            std::fs::read_to_string(&log).unwrap(),
            "upper 1 700 300 auto 30 1280x960\n"
        );
        setup.settings.flip = false;
        let e = spec
            .open(CameraId::Upper, &setup)
            .err()
            .unwrap()
            .to_string();
        assert!(
            e.contains("upside down") && e.contains("nothing was moved"),
            "{e}"
        );
    }

    /// A command camera's first picture: size and brightness measured, a dark one and one
    /// of another size refused before anything moves.
    #[test]
    fn first_pictures_are_checked_for_size_and_brightness() {
        let dir = tempfile::tempdir().unwrap();
        let write = |name: &str, w: u32, h: u32, level: u8| {
            let image = crate::sim::render::GreyImage {
                width: w,
                height: h,
                pixels: (0..w * h).map(|i| level + (i % 2) as u8).collect(),
            };
            let path = dir.path().join(name);
            std::fs::write(&path, image.to_png().unwrap()).unwrap();
            CameraSpec::parse(&format!("command:cp '{}' {{path}}", path.display())).unwrap()
        };
        let setup = Setup::defaults(CameraId::Upper, 64, 48);
        let (_, first) = write("ok.png", 64, 48, 100)
            .open_checked(CameraId::Upper, &setup, dir.path())
            .unwrap();
        assert_eq!(first.size, (64, 48));
        assert!((first.brightness.mean - 100.5).abs() < 1e-9);
        assert_eq!(first.settings, None);
        let e = write("dark.png", 64, 48, 5)
            .open_checked(CameraId::Upper, &setup, dir.path())
            .err()
            .unwrap()
            .to_string();
        assert!(
            e.contains("upper camera") && e.contains("near black"),
            "{e}"
        );
        assert!(e.contains("nothing was moved"), "{e}");
        let e = write("big.png", 128, 96, 100)
            .open_checked(CameraId::Upper, &setup, dir.path())
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("128×96"), "{e}");
    }
}
