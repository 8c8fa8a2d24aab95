//! `naocalib capture`: the measurement phase on a NAO V6 over LoLA (docs/CAPTURE.md).

use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::Ordering;
use std::time::Duration;

use anyhow::{Context, Result, bail};
use clap::Args;

use naocalib::model::CameraId;
use naocalib::robot::camera::CameraSpec;
use naocalib::robot::capture::{self, check_plan, predicted_steps, read_plan};
use naocalib::robot::lola::{self, Connection};
use naocalib::robot::{CaptureOptions, DatasetOut, End, Event};

use super::options::within;

#[derive(Debug, Args)]
pub struct CaptureArgs {
    /// The stance schedule (`naocalib plan`'s CSV: capture,board,HeadYaw,…,RAnkleRoll and
    /// an optional camera column, lower or upper).
    plan: PathBuf,
    /// The dataset directory to write (dataset.toml, captures.csv, images/).
    out: PathBuf,
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
    /// Longest a picture may take (s, 0.1 … 120).
    #[arg(long, default_value_t = 10.0, value_parser = within(0.1, 120.0, " s"))]
    camera_timeout: f64,
}

/// What the printer thread writes to the terminal.
enum Print {
    /// Captures in the dataset, and the bar's message.
    Progress(u64, String),
    /// A line above the bar.
    Line(String),
}

/// Runs `naocalib capture`.
pub fn run(args: &CaptureArgs) -> Result<ExitCode> {
    let mut options = CaptureOptions::default();
    options.motion.leg_speed = args.leg_speed.to_radians();
    options.motion.head_speed = args.head_speed.to_radians();
    options.motion.stiffness = args.stiffness;
    options
        .motion
        .validate()
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    let mut specs: Vec<(CameraId, CameraSpec)> = Vec::new();
    for text in &args.camera {
        let (id, spec) = CameraSpec::parse_named(text)?;
        if specs.iter().any(|(c, _)| *c == id) {
            bail!("--camera: the {id} camera is given twice");
        }
        specs.push((id, spec));
    }
    let rows = read_plan(&args.plan)?;
    let config_model = match &args.config {
        Some(path) => Some(naocalib::dataset::read_model(path)?),
        None => None,
    };
    let (out, model) = if args.resume {
        let (out, model) = DatasetOut::resume(&args.out, &args.plan, &rows)?;
        if config_model.is_some_and(|m| m != model) {
            bail!(
                "{}: its camera, sandals or geometry differ from {}'s dataset.toml; resume \
                 with the same robot configuration",
                args.config.as_ref().expect("given").display(),
                args.out.display()
            );
        }
        (Some(out), model)
    } else {
        let Some(model) = config_model else {
            bail!("--config DATASET.toml is needed (the robot's camera intrinsics and sandals)");
        };
        DatasetOut::check_new(&args.out)?;
        (None, model)
    };
    // Every row checked before anything is written or moved.
    check_plan(&args.plan, &model, &rows, options.joint_margin)?;
    if let Some(out) = &out {
        for (id, why) in out.retake() {
            note!("capture {id} will be taken again ({why})");
        }
    }
    let plan_bytes = std::fs::read(&args.plan)
        .with_context(|| format!("{}: cannot read", args.plan.display()))?;
    if let Some(row) = rows
        .iter()
        .find(|r| !specs.iter().any(|(c, _)| *c == r.camera))
    {
        bail!(
            "{} line {}: capture {} is for the {} camera; give it with --camera {}=SPEC \
             (nothing was moved)",
            args.plan.display(),
            row.line,
            row.id,
            row.camera,
            row.camera
        );
    }
    let timeout = Duration::from_secs_f64(args.camera_timeout);
    let mut cameras = Vec::new();
    for (id, spec) in &specs {
        cameras.push((*id, spec.open(id.name(), timeout)?));
    }
    let stop = capture::stop_on_signals().context("cannot watch for Ctrl-C, SIGTERM or SIGHUP")?;
    let mut link = Connection::connect(&args.lola, options.safety.silent_cycles)?;
    let out = match out {
        Some(out) => out,
        None => DatasetOut::create(&args.out, &model, &plan_bytes)?,
    };
    let todo: Vec<_> = rows.iter().filter(|r| !out.has(r.id)).copied().collect();
    let total = rows.len();
    let bar = super::progress_bar(total as u64 as usize, "captures");
    let steps = predicted_steps(&model, &todo, &options);
    let predicted = |from: usize| steps[from.min(todo.len())..].iter().sum::<f64>();
    // The terminal is written from a thread of its own: a terminal that stops reading (a
    // stalled or silently lost ssh session) blocks that thread, never the robot's cycles.
    let (print, printed) = std::sync::mpsc::channel::<Print>();
    let printer = {
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
    let _ = print.send(Print::Progress(
        out.len() as u64,
        format!(", {:.0} s of robot time planned", predicted(0)),
    ));
    let mut visited = 0usize;
    let mut events = |event: Event| {
        let p = match event {
            Event::Started => return,
            Event::Taken { done, .. } => {
                visited += 1;
                Print::Progress(
                    done as u64,
                    format!(", ~{:.0} s left by the plan", predicted(visited)),
                )
            }
            Event::Skipped { id, reason } => {
                visited += 1;
                Print::Line(format!(
                    "capture {id} skipped: {reason}; the leg returns to rest"
                ))
            }
            Event::Cooling { joint, temperature } => Print::Line(format!(
                "{} at {temperature:.1} °C: resting until the motors cool",
                joint.name()
            )),
        };
        let _ = print.send(p);
    };
    let report = capture::run(
        &model,
        &rows,
        out,
        cameras,
        &mut link,
        &options,
        &stop,
        &mut events,
    );
    // The robot is limp (or gone): let LoLA go before anything may wait for the terminal.
    drop(link);
    drop(print);
    let _ = printer.join();
    let report = report?;
    bar.finish_and_clear();
    let done = report.already + report.taken.len();
    note!(
        "{} captures taken in this run ({} before), {} skipped, {done} of {total} in {} \
         ({:.1} s of robot time)",
        report.taken.len(),
        report.already,
        report.skipped.len(),
        args.out.display(),
        capture::cycles_to_seconds(report.cycles)
    );
    for (id, reason) in &report.skipped {
        note!("  skipped capture {id}: {reason}");
    }
    match report.end {
        End::Completed => Ok(ExitCode::SUCCESS),
        End::Interrupted => {
            let signal = if stop.load(Ordering::Relaxed) {
                "a signal"
            } else {
                "a stop"
            };
            note!(
                "naocalib: stopped by {signal}: the robot is at rest with its stiffness off; \
                 {} is a valid dataset; go on with --resume",
                args.out.display()
            );
            Ok(ExitCode::from(2))
        }
        End::Stopped(e) => {
            bail!(
                "{e}; the run stopped ({} is a valid dataset of the {done} captures taken; \
                 go on with --resume)",
                args.out.display()
            )
        }
    }
}
