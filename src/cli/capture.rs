//! `naocalib capture`: the measurement phase on a NAO V6 over LoLA (docs/CAPTURE.md).

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::Ordering;
use std::sync::mpsc;

use anyhow::{Context, Result, bail};
use clap::Args;

use naocalib::dataset::settings::{self, SettingsChanges};
use naocalib::model::CameraId;
use naocalib::robot::camera::guard;
use naocalib::robot::capture::request::{self, CaptureRequest};
use naocalib::robot::capture::{self, CaptureError, Forecast};
use naocalib::robot::check::{self, CheckReport};
use naocalib::robot::lola::{self, Connection, Replay};
use naocalib::robot::{Event, Session, Start};

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
    /// The library's request of these flags.
    fn request(&self) -> CaptureRequest {
        CaptureRequest {
            plan: self.plan.clone(),
            config: self.config.clone(),
            lola: self.lola.clone(),
            cameras: self.camera.clone(),
            leg_speed_deg: self.leg_speed,
            head_speed_deg: self.head_speed,
            stiffness: self.stiffness,
            camera_timeout_s: self.camera_timeout,
            frame_timeout_s: self.frame_timeout,
            camera_settings: self.camera_setting.clone(),
            guard: std::env::current_exe().ok(),
        }
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

/// `naocalib rest-guard --lola SOCKET …` (hidden): the process capture starts before it
/// connects to LoLA, that takes the robot to rest when capture dies without doing so
/// (`naocalib::robot::capture::guard`); capture's pipe is its standard input.
#[derive(Debug, Args)]
pub struct RestGuardArgs {
    /// LoLA's socket.
    #[arg(long, value_name = "SOCKET")]
    lola: PathBuf,
    /// Leg joint speed limit (deg/s).
    #[arg(long, value_parser = within(1.0, 60.0, " deg/s"))]
    leg_speed: f64,
    /// Head joint speed limit (deg/s).
    #[arg(long, value_parser = within(1.0, 180.0, " deg/s"))]
    head_speed: f64,
    /// Cycles of the stiffness ramp-down.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    ramp_cycles: u32,
}

/// Runs the rest guard: ignores the signals a terminal sends (they are capture's to act
/// on), watches capture's pipe, and takes the robot to rest when capture is gone.
pub fn rest_guard(args: &RestGuardArgs) -> Result<ExitCode> {
    // SIGTTOU too: in a group of its own it may be in the background of capture's
    // terminal, and must not be stopped for writing there.
    for signal in capture::STOP_SIGNALS.into_iter().chain([libc::SIGTTOU]) {
        // SAFETY: ignoring a signal in this single-threaded process.
        unsafe {
            libc::signal(signal, libc::SIG_IGN);
        }
    }
    let motion = naocalib::robot::motion::MotionOptions {
        leg_speed: args.leg_speed.to_radians(),
        head_speed: args.head_speed.to_radians(),
        ramp_cycles: args.ramp_cycles,
        ..Default::default()
    };
    let stdin = std::io::stdin().lock();
    let taken = capture::guard::run(&args.lola, &motion, stdin, &mut std::io::stdout())
        .context("capture ended without taking the robot to rest, and the rest guard could not")?;
    if let Some(t) = taken {
        note!(
            "naocalib: capture ended without taking the robot to rest: the rest guard took \
             it over at stiffness {:.2}, commanded the rest posture and ramped the stiffness \
             to 0 in {} cycles ({:.2} s){}",
            t.stiffness,
            t.cycles,
            capture::cycles_to_seconds(u64::from(t.cycles)),
            if t.answered {
                ""
            } else {
                ", the last ones blind (LoLA stopped answering)"
            }
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// Runs `naocalib capture --check DIR`: prints the table; exit 1 when something does not
/// hold.
fn dry_run(request: &CaptureRequest, save: &Path) -> Result<ExitCode> {
    let report = request.dry_run(save)?;
    super::print_out(report.table())?;
    note!("{}", request::verdict(&report));
    Ok(if report.ready() {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}

/// Runs `naocalib capture`.
pub fn run(args: &CaptureArgs) -> Result<ExitCode> {
    let request = args.request();
    if let Some(save) = &args.check {
        return dry_run(&request, save);
    }
    let Some(dir) = &args.out else {
        bail!("OUT is needed (the dataset directory to write)");
    };
    let options = request.options()?;
    let given: Vec<CameraId> = request.cameras()?.iter().map(|(c, _)| *c).collect();
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
    let setups = request.setups(&start.model, &request.config_in(dir))?;
    let used: Vec<_> = setups
        .iter()
        .map(|(id, spec, setup)| spec.used(*id, &setup.settings))
        .collect();
    start.check_settings(&used)?;
    let scratch = tempfile::tempdir().context("cannot create a scratch directory")?;
    let (cameras, opened) = CaptureRequest::open_cameras(&setups, scratch.path())?;
    said.extend(opened);
    let stop = capture::stop_on_signals().context("cannot watch for Ctrl-C, SIGTERM or SIGHUP")?;
    // The rest guard watches before LoLA is reached: whatever ends capture once it holds
    // the robot, the robot ends at rest and limp.
    let mut guard = request
        .guard
        .as_deref()
        .map(|program| capture::guard::Guard::spawn(program, &args.lola, &options.motion))
        .transpose()?;
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
    if let Some(guard) = &mut guard {
        guard.arm()?;
    }
    let report = Session::new(model, rows, &options)
        .observe(&mut events)
        .stop_on(&stop)
        .run(out, cameras, &mut link);
    // The robot is limp (or gone): let LoLA go before anything may wait for the terminal.
    drop(connection);
    // Limp, or never commanded: the guard is done; else it takes the robot to rest now.
    if let Some(guard) = guard {
        match &report {
            Ok(r) if !r.limp => guard.hand_over(),
            _ => guard.release(),
        }
    }
    terminal.close();
    let account = request::account(dir, &report?, rows.len(), stop.load(Ordering::Relaxed));
    for line in &account.lines {
        note!("{line}");
    }
    match account.error {
        Some(e) => Err(anyhow::Error::msg(e)),
        None => Ok(ExitCode::from(account.exit)),
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
