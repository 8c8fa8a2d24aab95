//! `naocalib capture`: the measurement phase on a NAO V6 over LoLA (docs/CAPTURE.md).

use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::Ordering;
use std::time::Duration;

use anyhow::{Context, Result, bail};
use clap::Args;

use naocalib::robot::camera::CameraSpec;
use naocalib::robot::capture::{self, check_plan, predicted_steps, read_plan};
use naocalib::robot::lola::{self, Connection};
use naocalib::robot::{CaptureOptions, DatasetOut, End, Event};

use super::options::within;

#[derive(Debug, Args)]
pub struct CaptureArgs {
    /// The stance schedule (`naocalib plan`'s CSV: capture,board,HeadYaw,…,RAnkleRoll).
    plan: PathBuf,
    /// The dataset directory to write (dataset.toml, captures.csv, images/).
    out: PathBuf,
    /// The robot's dataset.toml (lower camera intrinsics, sandals, geometry), copied into
    /// OUT; with --resume, OUT's own is used (and this one must agree).
    #[arg(long, value_name = "DATASET_TOML")]
    config: Option<PathBuf>,
    /// LoLA's socket.
    #[arg(long, value_name = "SOCKET", default_value = lola::DEFAULT_SOCKET)]
    lola: PathBuf,
    /// The camera: 'v4l2:/dev/video-bottom' (the V6's lower camera; needs the `v4l2`
    /// feature) or 'command:CMD {path}' (CMD writes a PNG or JPEG to {path}).
    #[arg(long, value_name = "SPEC")]
    camera: String,
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
    let spec = CameraSpec::parse(&args.camera)?;
    let rows = read_plan(&args.plan)?;
    let config_model = match &args.config {
        Some(path) => Some(naocalib::dataset::read_model(path)?),
        None => None,
    };
    let (out, model) = if args.resume {
        let (out, model) = DatasetOut::resume(&args.out)?;
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
        (None, model)
    };
    // Every row checked before anything is written or moved.
    check_plan(&args.plan, &model, &rows, options.joint_margin)?;
    if let Some(out) = &out
        && let Some(id) = out.ids().find(|id| !rows.iter().any(|r| r.id == *id))
    {
        bail!(
            "{}: capture {id} is not in the plan {}; --resume needs the plan the run began \
             with",
            args.out.display(),
            args.plan.display()
        );
    }
    let camera = spec.open(Duration::from_secs_f64(args.camera_timeout))?;
    let stop = capture::stop_on_signals().context("cannot watch for Ctrl-C / SIGTERM")?;
    let mut link = Connection::connect(&args.lola, options.safety.silent_cycles)?;
    let out = match out {
        Some(out) => out,
        None => DatasetOut::create(&args.out, &model)?,
    };
    let todo: Vec<_> = rows.iter().filter(|r| !out.has(r.id)).copied().collect();
    let total = rows.len();
    let bar = super::progress_bar(total as u64 as usize, "captures");
    bar.set_position(out.len() as u64);
    let steps = predicted_steps(&model, &todo, &options);
    let predicted = |from: usize| steps[from.min(todo.len())..].iter().sum::<f64>();
    bar.set_message(format!(", {:.0} s of robot time planned", predicted(0)));
    let say = |line: String| {
        if bar.is_hidden() {
            note!("{line}");
        } else {
            bar.println(line);
        }
    };
    let mut visited = 0usize;
    let mut events = |event: Event| match event {
        Event::Started => {}
        Event::Taken { done, .. } => {
            visited += 1;
            bar.set_position(done as u64);
            bar.set_message(format!(", ~{:.0} s left by the plan", predicted(visited)));
        }
        Event::Skipped { id, reason } => {
            visited += 1;
            say(format!(
                "capture {id} skipped: {reason}; the leg returns to rest"
            ));
        }
        Event::Cooling { joint, temperature } => say(format!(
            "{} at {temperature:.1} °C: resting until the motors cool",
            joint.name()
        )),
    };
    let report = capture::run(
        &model,
        &rows,
        out,
        camera,
        &mut link,
        &options,
        &stop,
        &mut events,
    )?;
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
