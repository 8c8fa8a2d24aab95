//! Taking the picture: the V6's lower camera through Video4Linux2 (`v4l2:DEVICE`, with the
//! `v4l2` feature) or any command that writes a PNG or JPEG (`command:CMD {path}`).

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use crate::model::CameraId;

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

    /// Opens the camera named `name` (`lower` or `upper`: what `{camera}` stands for in a
    /// command).
    pub fn open(&self, name: &str, timeout: Duration) -> Result<Box<dyn Camera>, CameraError> {
        match self {
            CameraSpec::Command(command) => Ok(Box::new(CommandCamera {
                command: command.clone(),
                name: name.to_string(),
                timeout,
                count: 0,
                cancel: Arc::new(AtomicBool::new(false)),
            })),
            #[cfg(feature = "v4l2")]
            CameraSpec::V4l2(device) => Ok(Box::new(v4l2::V4l2Camera::open(
                device,
                &v4l2::V4l2Options::default(),
            )?)),
            #[cfg(not(feature = "v4l2"))]
            CameraSpec::V4l2(_) => Err(CameraError::NoV4l2),
        }
    }
}

/// The extension of an encoded PNG or JPEG image, from its first bytes.
pub fn image_kind(bytes: &[u8]) -> Option<&'static str> {
    if bytes.starts_with(b"\x89PNG\r\n\x1a\n") {
        Some("png")
    } else if bytes.starts_with(&[0xff, 0xd8, 0xff]) {
        Some("jpg")
    } else {
        None
    }
}

/// Quotes `text` for `sh` (single quotes).
fn shell_quote(text: &str) -> String {
    format!("'{}'", text.replace('\'', r"'\''"))
}

/// `command:CMD {path}`: runs CMD with `sh -c`, `{path}` replaced by a fresh file name and
/// `{camera}` by the camera's name (`lower`, `upper`), and reads the PNG or JPEG it wrote
/// there. CMD runs in a process group of its own, which is
/// killed as a whole when it takes too long or the run stops.
#[derive(Debug)]
pub struct CommandCamera {
    command: String,
    name: String,
    timeout: Duration,
    count: u64,
    cancel: Arc<AtomicBool>,
}

/// Makes the process `command` starts die with the thread that starts it (Linux's
/// `PR_SET_PDEATHSIG`): a camera command that is one process (the shell exec'd it) is
/// killed by the kernel even when capture itself is killed and cannot kill its group.
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

impl Camera for CommandCamera {
    fn take(&mut self, scratch: &Path) -> Result<Picture, CameraError> {
        self.count += 1;
        let path = scratch.join(format!("picture-{}", self.count));
        let _ = std::fs::remove_file(&path);
        let line = self
            .command
            .replace("{path}", &shell_quote(&path.to_string_lossy()))
            .replace("{camera}", &shell_quote(&self.name));
        if self.cancel.load(Ordering::Relaxed) {
            return Err(CameraError::Cancelled(self.command.clone()));
        }
        use std::os::unix::process::CommandExt as _;
        let mut command = std::process::Command::new("sh");
        command.arg("-c").arg(&line).process_group(0);
        die_with_parent(&mut command);
        let mut child = command
            .stdin(std::process::Stdio::null())
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::piped())
            .spawn()?;
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
        // Whatever CMD left running in its group goes with it.
        unsafe {
            libc::kill(-(child.id() as libc::pid_t), libc::SIGKILL);
        }
        if !status.success() {
            let mut stderr = String::new();
            if let Some(mut e) = child.stderr.take() {
                use std::io::Read as _;
                let _ = e.read_to_string(&mut stderr);
            }
            let stderr: String = stderr.trim().chars().take(400).collect();
            return Err(CameraError::Command {
                command: self.command.clone(),
                status: status.to_string(),
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

/// Decodes a PNG or JPEG image in full; its extension and size (width, height).
pub fn decode_size(bytes: &[u8]) -> Result<(&'static str, (u32, u32)), String> {
    match image_kind(bytes) {
        Some("png") => {
            let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
            let mut reader = decoder
                .read_info()
                .map_err(|e| format!("is not a readable PNG: {e}"))?;
            let size = reader
                .output_buffer_size()
                .ok_or("is not a readable PNG: too large")?;
            let mut buf = vec![0; size];
            let info = reader
                .next_frame(&mut buf)
                .map_err(|e| format!("is not a readable PNG: {e}"))?;
            Ok(("png", (info.width, info.height)))
        }
        Some(_) => {
            let mut decoder = jpeg_decoder::Decoder::new(std::io::Cursor::new(bytes));
            let pixels = decoder
                .decode()
                .map_err(|e| format!("is not a readable JPEG: {e}"))?;
            let info = decoder.info().ok_or("is not a readable JPEG: no frame")?;
            let (w, h) = (info.width as usize, info.height as usize);
            if pixels.len() < w * h {
                return Err("is not a readable JPEG: its image data is short".into());
            }
            Ok(("jpg", (info.width.into(), info.height.into())))
        }
        None => Err("is neither a PNG nor a JPEG".into()),
    }
}

/// Checks that a picture decodes in full and has the camera's size (`width`×`height`
/// from the dataset's camera intrinsics): what `detect` will need of it.
pub fn check_picture(bytes: &[u8], width: u32, height: u32) -> Result<&'static str, String> {
    let (extension, size) = decode_size(bytes)?;
    if size != (width, height) {
        return Err(format!(
            "is {}×{} pixels; the camera's intrinsics are for {width}×{height}",
            size.0, size.1
        ));
    }
    Ok(extension)
}

/// The V6's lower camera through Video4Linux2 (the `v4l` crate).
#[cfg(feature = "v4l2")]
pub mod v4l2 {
    use std::path::Path;

    use v4l::buffer::Type;
    use v4l::io::traits::CaptureStream;
    use v4l::prelude::*;
    use v4l::video::Capture;

    use super::{Camera, CameraError, Picture};

    /// How the camera is set up (docs/CAPTURE.md §4): YUYV at 640×480 or 1280×960, fixed
    /// exposure and gain so that every picture is exposed alike.
    #[derive(Debug, Clone, Copy, PartialEq)]
    pub struct V4l2Options {
        /// Width (640 or 1280).
        pub width: u32,
        /// Height (480 or 960).
        pub height: u32,
        /// Exposure in the driver's units (100 µs on the V6's OV5640).
        pub exposure: i64,
        /// Analogue gain in the driver's units.
        pub gain: i64,
        /// Frames dropped after opening and before each picture (the stream's queue).
        pub skip_frames: u32,
    }

    impl Default for V4l2Options {
        /// 640×480, exposure 100 (10 ms), gain 32, 3 frames skipped.
        fn default() -> Self {
            V4l2Options {
                width: 640,
                height: 480,
                exposure: 100,
                gain: 32,
                skip_frames: 3,
            }
        }
    }

    /// An open V4L2 device streaming YUYV.
    pub struct V4l2Camera {
        device: Device,
        name: String,
        options: V4l2Options,
    }

    // The device is used from one thread at a time (the camera worker).
    unsafe impl Send for V4l2Camera {}

    fn device_error(name: &str, message: impl std::fmt::Display) -> CameraError {
        CameraError::Device {
            device: name.to_string(),
            message: message.to_string(),
        }
    }

    /// V4L2 control ids (linux/v4l2-controls.h).
    const V4L2_CID_EXPOSURE_AUTO: u32 = 0x009a0901;
    const V4L2_CID_EXPOSURE_ABSOLUTE: u32 = 0x009a0902;
    const V4L2_CID_GAIN: u32 = 0x00980913;
    const V4L2_CID_AUTO_WHITE_BALANCE: u32 = 0x0098090c;
    /// `V4L2_EXPOSURE_MANUAL`.
    const EXPOSURE_MANUAL: i64 = 1;

    impl V4l2Camera {
        /// Opens `path`, sets YUYV at the size and the fixed exposure.
        pub fn open(path: &Path, options: &V4l2Options) -> Result<V4l2Camera, CameraError> {
            let name = path.display().to_string();
            let device = Device::with_path(path).map_err(|e| device_error(&name, e))?;
            let mut format = device.format().map_err(|e| device_error(&name, e))?;
            format.width = options.width;
            format.height = options.height;
            format.fourcc = v4l::FourCC::new(b"YUYV");
            let set = device
                .set_format(&format)
                .map_err(|e| device_error(&name, e))?;
            if set.fourcc != v4l::FourCC::new(b"YUYV")
                || set.width != options.width
                || set.height != options.height
            {
                return Err(device_error(
                    &name,
                    format!(
                        "does not stream YUYV {}×{} (it offers {} {}×{})",
                        options.width, options.height, set.fourcc, set.width, set.height
                    ),
                ));
            }
            for (id, value) in [
                (V4L2_CID_EXPOSURE_AUTO, EXPOSURE_MANUAL),
                (V4L2_CID_EXPOSURE_ABSOLUTE, options.exposure),
                (V4L2_CID_GAIN, options.gain),
                (V4L2_CID_AUTO_WHITE_BALANCE, 0),
            ] {
                let control = v4l::Control {
                    id,
                    value: v4l::control::Value::Integer(value),
                };
                device
                    .set_control(control)
                    .map_err(|e| device_error(&name, format!("control {id:#x}: {e}")))?;
            }
            Ok(V4l2Camera {
                device,
                name,
                options: *options,
            })
        }
    }

    impl Camera for V4l2Camera {
        fn take(&mut self, _scratch: &Path) -> Result<Picture, CameraError> {
            let name = self.name.clone();
            let mut stream = MmapStream::with_buffers(&self.device, Type::VideoCapture, 4)
                .map_err(|e| device_error(&name, e))?;
            for _ in 0..self.options.skip_frames {
                stream.next().map_err(|e| device_error(&name, e))?;
            }
            let (buf, _meta) = stream.next().map_err(|e| device_error(&name, e))?;
            let (w, h) = (self.options.width as usize, self.options.height as usize);
            if buf.len() < 2 * w * h {
                return Err(device_error(&name, "short YUYV frame"));
            }
            // YUYV: Y0 U Y1 V; the grey image is every other byte.
            let grey: Vec<u8> = buf[..2 * w * h].iter().step_by(2).copied().collect();
            let image = crate::sim::render::GreyImage {
                width: self.options.width,
                height: self.options.height,
                pixels: grey,
            };
            let bytes = image.to_png().map_err(|e| device_error(&name, e))?;
            Ok(Picture {
                bytes,
                extension: "png",
            })
        }
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
        let dir = tempfile::tempdir().unwrap();
        let image = crate::sim::render::GreyImage {
            width: 4,
            height: 2,
            pixels: vec![7; 8],
        };
        let src = dir.path().join("src.png");
        std::fs::write(&src, image.to_png().unwrap()).unwrap();
        let spec = CameraSpec::parse(&format!("command:cp '{}' {{path}}", src.display())).unwrap();
        let mut camera = spec.open("lower", Duration::from_secs(10)).unwrap();
        let picture = camera.take(dir.path()).unwrap();
        assert_eq!(picture.extension, "png");
        assert_eq!(picture.bytes, std::fs::read(&src).unwrap());

        let text = dir.path().join("x.txt");
        std::fs::write(&text, "hello").unwrap();
        let spec = CameraSpec::parse(&format!("command:cp '{}' {{path}}", text.display())).unwrap();
        let e = spec
            .open("lower", Duration::from_secs(10))
            .unwrap()
            .take(dir.path());
        assert!(e.unwrap_err().to_string().contains("neither a PNG"));
        let spec = CameraSpec::parse("command:echo oops >&2; false {path}").unwrap();
        let e = spec
            .open("lower", Duration::from_secs(10))
            .unwrap()
            .take(dir.path());
        assert!(e.unwrap_err().to_string().contains("oops"));
    }
}
