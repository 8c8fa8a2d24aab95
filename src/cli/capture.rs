//! `naocalib capture`: the measurement phase on a NAO V6 over LoLA (docs/CAPTURE.md).

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::Ordering;
use std::sync::mpsc;
use std::time::Duration;

use anyhow::{Context, Result, bail};
use clap::Args;

use naocalib::model::{CameraId, Model};
use naocalib::robot::camera::settings::{self, SettingsChanges, settings_for};
use naocalib::robot::camera::{CameraSpec, Setup, guard};
use naocalib::robot::capture::{self, CaptureError, Forecast};
use naocalib::robot::check::{self, CheckReport};
use naocalib::robot::lola::{self, Connection, Replay};
use naocalib::robot::{CaptureOptions, End, Event, Report, Session, Start};

use super::options::within;

#[derive(Debug, Args)]
pub struct CaptureArgs {
    /// The stance schedule (`naocalib plan`'s CSV: capture,board,HeadYaw,…,RAnkleRoll and
    /// an optional camera column, lower or upper).
    plan: PathBuf,
    /// The dataset directory to write (dataset.toml, captures.csv, images/); not with
    /// --check.
    #[arg(required_unless_present = "check")]
    out: Option<PathBuf>,
    /// The robot's dataset.toml (camera intrinsics, [upper_camera] for upper rows, sandals,
    /// geometry), copied into OUT; with --resume, OUT's own is used (and this one must
    /// agree).
    #[arg(long, value_name = "DATASET_TOML")]
    config: Option<PathBuf>,
    /// LoLA's socket.
    #[arg(long, value_name = "SOCKET", default_value = lola::DEFAULT_SOCKET)]
    lola: PathBuf,
    /// A camera, once per camera: [lower=|upper=]SPEC, SPEC 'v4l2:DEVICE' (the V6's
    /// /dev/video-bottom and /dev/video-top; needs the `v4l2` feature) or 'command:CMD
    /// {path}' (CMD writes a PNG or JPEG to {path}; {camera} is 'lower' or 'upper'). Without
    /// a name: the lower camera. Each plan row's picture comes from its `camera`.
    #[arg(long, value_name = "[CAMERA=]SPEC", required = true)]
    camera: Vec<String>,
    /// Go on with the dataset in OUT at the first capture of the plan not yet taken.
    #[arg(long)]
    resume: bool,
    /// Leg joint speed limit (deg/s, 1 … 60).
    #[arg(long, default_value_t = 30.0, value_parser = within(1.0, 60.0, " deg/s"))]
    leg_speed: f64,
    /// Head joint speed limit (deg/s, 1 … 180).
    #[arg(long, default_value_t = 90.0, value_parser = within(1.0, 180.0, " deg/s"))]
    head_speed: f64,
    /// Stiffness of the head and leg joints while measuring (0.1 … 1).
    #[arg(long, default_value_t = 0.8, value_parser = within(0.1, 1.0, ""))]
    stiffness: f64,
    /// Longest a `command:` camera may take for a picture (s, 0.1 … 120).
    #[arg(long, default_value_t = 10.0, value_parser = within(0.1, 120.0, " s"))]
    camera_timeout: f64,
    /// Move nothing: check the plan, each camera (one picture each saved into DIR, with
    /// its size and brightness), LoLA and the robot (on its back, battery, temperatures,
    /// stiffness off); print what holds; exit 0 only when a capture can start.
    #[arg(long, value_name = "DIR", conflicts_with_all = ["out", "resume"])]
    check: Option<PathBuf>,
    /// Longest wait for one V4L2 frame (s, 0.01 … 10); a stalled stream is restarted once,
    /// then the run ends at rest.
    #[arg(long, default_value_t = 1.0, value_parser = within(0.01, 10.0, " s"))]
    frame_timeout: f64,
    /// A V4L2 camera's setting, over the team defaults and dataset.toml's: [CAMERA.]KEY=VALUE
    /// with KEY flip, exposure, gain, white_balance_k or fps (e.g. upper.exposure=1000;
    /// without CAMERA: both cameras). Repeatable.
    #[arg(long, value_name = "[CAMERA.]KEY=VALUE", value_parser = parse_setting)]
    camera_setting: Vec<(Vec<CameraId>, SettingsChanges)>,
}

/// `--camera-setting`'s parser.
fn parse_setting(text: &str) -> Result<(Vec<CameraId>, SettingsChanges), String> {
    settings::parse_setting(text)
}

impl CaptureArgs {
    /// The run's options from the flags.
    fn options(&self) -> Result<CaptureOptions> {
        let mut options = CaptureOptions::default();
        options.motion.leg_speed = self.leg_speed.to_radians();
        options.motion.head_speed = self.head_speed.to_radians();
        options.motion.stiffness = self.stiffness;
        options
            .motion
            .validate()
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        Ok(options)
    }

    /// The cameras of `--camera`, each once.
    fn cameras(&self) -> Result<Vec<(CameraId, CameraSpec)>> {
        let mut specs: Vec<(CameraId, CameraSpec)> = Vec::new();
        for text in &self.camera {
            let (id, spec) = CameraSpec::parse_named(text)?;
            if specs.iter().any(|(c, _)| *c == id) {
                bail!("--camera: the {id} camera is given twice");
            }
            specs.push((id, spec));
        }
        Ok(specs)
    }

    /// Each camera of `--camera` with how it is set up for the robot `model`: the team
    /// defaults, `config`'s `[camera]`/`[upper_camera]` settings over them,
    /// `--camera-setting` over those, the waits, and naocalib itself as the guard of a
    /// `command:` camera.
    fn setups(&self, model: &Model, config: &Path) -> Result<Vec<(CameraId, CameraSpec, Setup)>> {
        let file_settings = naocalib::dataset::read_camera_settings(config)?;
        let guard = std::env::current_exe().ok();
        Ok(self
            .cameras()?
            .into_iter()
            .map(|(id, spec)| {
                let setup = Setup {
                    settings: settings_for(id, model, &file_settings, &self.camera_setting),
                    frame_timeout: Duration::from_secs_f64(self.frame_timeout),
                    command_timeout: Duration::from_secs_f64(self.camera_timeout),
                    guard: guard.clone(),
                };
                (id, spec, setup)
            })
            .collect())
    }
}

/// `naocalib camera-guard --parent PID -- LINE` (hidden): the guard capture runs each
/// `command:` camera's picture under (`naocalib::robot::camera::guard`).
#[derive(Debug, Args)]
pub struct CameraGuardArgs {
    /// The capture process the guard belongs to.
    #[arg(long)]
    parent: u32,
    /// The command line, for `sh -c`.
    #[arg(last = true, required = true)]
    line: String,
}

/// Runs the guard; it returns only when it could not kill its group.
pub fn guard(args: &CameraGuardArgs) -> Result<ExitCode> {
    Err(guard::run(args.parent, &args.line).into())
}

/// Runs `naocalib capture --check DIR`: prints the table; exit 1 when something does not
/// hold.
fn dry_run(args: &CaptureArgs, save: &Path) -> Result<ExitCode> {
    let options = args.options()?;
    let Some(config) = &args.config else {
        bail!("--check needs --config DATASET_TOML (the robot's cameras)");
    };
    let model = naocalib::dataset::read_model(config)?;
    let cameras = args.setups(&model, config)?;
    let report = check::dry_run(&args.plan, &model, &cameras, &args.lola, &options, save)?;
    print!("{}", report.table());
    if report.ready() {
        note!("naocalib: the day can start: every check holds, nothing was moved");
        Ok(ExitCode::SUCCESS)
    } else {
        note!(
            "naocalib: not ready (nothing was moved): {}",
            report.failed()
        );
        Ok(ExitCode::from(1))
    }
}

/// Runs `naocalib capture`.
pub fn run(args: &CaptureArgs) -> Result<ExitCode> {
    if let Some(save) = &args.check {
        return dry_run(args, save);
    }
    let Some(dir) = &args.out else {
        bail!("OUT is needed (the dataset directory to write)");
    };
    let options = args.options()?;
    let given: Vec<CameraId> = args.cameras()?.iter().map(|(c, _)| *c).collect();
    // Every row checked before anything is written or moved.
    let mut start = Start::new(
        &args.plan,
        dir,
        args.config.as_deref(),
        args.resume,
        &given,
        options.joint_margin,
    )?;
    // What is said before the robot is reached goes through the terminal's thread once
    // there is one: a terminal that stops reading must not hold up the run.
    let mut said: Vec<String> = start
        .retake()
        .iter()
        .map(|(id, why)| format!("capture {id} will be taken again ({why})"))
        .collect();
    // Every camera set up (read back for V4L2), its settings those the dataset records
    // (with --resume), and its first picture checked before anything moves.
    let config = match &args.config {
        Some(config) => config.clone(),
        None => dir.join("dataset.toml"),
    };
    let setups = args.setups(&start.model, &config)?;
    let used: Vec<_> = setups
        .iter()
        .map(|(id, spec, setup)| spec.used(*id, &setup.settings))
        .collect();
    start.check_settings(&used)?;
    let scratch = tempfile::tempdir().context("cannot create a scratch directory")?;
    let mut cameras = Vec::new();
    for ((id, spec, setup), (camera, first)) in setups
        .iter()
        .zip(naocalib::robot::camera::open_all(&setups, scratch.path())?)
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
    let stop = capture::stop_on_signals().context("cannot watch for Ctrl-C, SIGTERM or SIGHUP")?;
    let mut connection = Connection::connect(&args.lola, options.safety.silent_cycles)?;
    // The robot's checks on LoLA's first message, before anything is written or sent.
    let (first, checks) = check::first_message(&mut connection, &options.safety)?;
    let report = CheckReport { checks };
    if !report.can_move() {
        return Err(CaptureError::NotReady(report.blocking()).into());
    }
    let mut link = Replay::new(first, &mut connection);
    let out = start.open(&used)?;
    let (model, rows) = (&start.model, &start.rows);
    let mut forecast = Forecast::new(model, &out.todo(rows), &options);
    let terminal = Terminal::spawn(rows.len());
    for line in said {
        terminal.send(Print::Line(line));
    }
    terminal.send(Print::Progress(
        out.len() as u64,
        format!(", {:.0} s of robot time planned", forecast.left()),
    ));
    let mut events = |event: &Event| {
        forecast.observe(event);
        terminal.send(match event {
            Event::Started => return,
            Event::Taken { done, .. } => Print::Progress(
                *done as u64,
                format!(", ~{:.0} s left by the plan", forecast.left()),
            ),
            _ => Print::Line(event.to_string()),
        });
    };
    let report = Session::new(model, rows, &options)
        .observe(&mut events)
        .stop_on(&stop)
        .run(out, cameras, &mut link);
    // The robot is limp (or gone): let LoLA go before anything may wait for the terminal.
    drop(connection);
    terminal.close();
    summary(dir, &report?, rows.len(), stop.load(Ordering::Relaxed))
}

/// The account of the run, and the exit code: 0 when the plan was run to its end, 2 when
/// a signal stopped it, an error when a fault did.
fn summary(out: &Path, report: &Report, total: usize, signalled: bool) -> Result<ExitCode> {
    let done = report.already + report.taken.len();
    note!(
        "{} captures taken in this run ({} before), {} skipped, {done} of {total} in {} \
         ({:.1} s of robot time)",
        report.taken.len(),
        report.already,
        report.skipped(),
        out.display(),
        capture::cycles_to_seconds(report.cycles)
    );
    for (id, reason) in &report.unreachable {
        note!("  skipped capture {id} before moving: {reason}");
    }
    for (id, reason) in &report.abandoned {
        note!("  skipped capture {id} on the way: {reason}");
    }
    match &report.end {
        End::Completed => Ok(ExitCode::SUCCESS),
        End::Interrupted => {
            let signal = if signalled { "a signal" } else { "a stop" };
            note!(
                "naocalib: stopped by {signal}: the robot is at rest with its stiffness off; \
                 {} is a valid dataset; go on with --resume",
                out.display()
            );
            Ok(ExitCode::from(2))
        }
        End::Stopped(e) => {
            bail!(
                "{e}; the run stopped ({} is a valid dataset of the {done} captures taken; \
                 go on with --resume)",
                out.display()
            )
        }
    }
}

/// What the terminal thread writes.
enum Print {
    /// Captures in the dataset, and the bar's message.
    Progress(u64, String),
    /// A line above the bar.
    Line(String),
}

/// The progress bar and the lines above it, written from a thread of its own: a terminal
/// that stops reading (a stalled or silently lost ssh session) blocks that thread, never the
/// robot's cycles.
struct Terminal {
    bar: indicatif::ProgressBar,
    print: mpsc::Sender<Print>,
    thread: std::thread::JoinHandle<()>,
}

impl Terminal {
    /// The bar of a plan of `total` captures, and its thread.
    fn spawn(total: usize) -> Terminal {
        let bar = super::progress_bar(total, "captures");
        let (print, printed) = mpsc::channel::<Print>();
        let thread = {
            let bar = bar.clone();
            std::thread::spawn(move || {
                for p in printed {
                    match p {
                        Print::Progress(done, message) => {
                            bar.set_position(done);
                            bar.set_message(message);
                        }
                        Print::Line(line) if bar.is_hidden() => note!("{line}"),
                        Print::Line(line) => bar.println(line),
                    }
                }
            })
        };
        Terminal { bar, print, thread }
    }

    /// Hands `p` to the thread, without waiting.
    fn send(&self, p: Print) {
        let _ = self.print.send(p);
    }

    /// Waits until everything is written, then clears the bar.
    fn close(self) {
        drop(self.print);
        let _ = self.thread.join();
        self.bar.finish_and_clear();
    }
}
