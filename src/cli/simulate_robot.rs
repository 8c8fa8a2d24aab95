//! `naocalib simulate-robot`: a simulated NAO V6 (on its back unless `--lying` says
//! otherwise) that serves LoLA, and
//! `simulate-robot snap`, its cameras (for `capture --camera 'lower=command:…'`).

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use clap::{Args, Subcommand};

use naocalib::model::CameraId;
use naocalib::robot::body::Lying;
use naocalib::robot::simulated::request::{self, RobotRequest};
use naocalib::robot::simulated::{self, SnapSettings};
use naocalib::sim::render::RenderOptions;

use super::options::within;

#[derive(Debug, Args)]
#[command(args_conflicts_with_subcommands = true)]
pub struct SimulateRobotArgs {
    #[command(subcommand)]
    snap: Option<SnapCommand>,
    /// The socket to serve LoLA on.
    #[arg(long, value_name = "SOCKET")]
    lola: Option<PathBuf>,
    /// The robot's dataset.toml (camera, sandals, geometry); the defaults with naocalib's
    /// sandal when not given.
    #[arg(long, value_name = "DATASET_TOML")]
    config: Option<PathBuf>,
    /// Seed of the true offsets drawn (camera ±3°, leg joints σ 1°, sandals).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Also give the robot these effects beyond the paper's model (e.g. compliance,play).
    #[arg(long, value_name = "FAMILIES", value_delimiter = ',')]
    effects: Vec<String>,
    /// Take the true parameters from this truth.toml instead of drawing them.
    #[arg(long, value_name = "TRUTH_TOML", conflicts_with_all = ["seed", "effects"])]
    truth: Option<PathBuf>,
    /// Speed relative to real time (10: cycles of 1.2 ms); 0 runs as fast as the client
    /// answers.
    #[arg(long, default_value_t = 1.0)]
    speed: f64,
    /// Write the robot's state here (true parameters and joints) for `snap`.
    #[arg(long, value_name = "FILE")]
    state: Option<PathBuf>,
    /// Write every actuator message received (CSV, LoLA's joint order) here at exit.
    #[arg(long, value_name = "FILE")]
    record: Option<PathBuf>,
    /// Fault: JOINT cannot move beyond DEG degrees (e.g. LKneePitch=40).
    #[arg(long, value_name = "JOINT=DEG")]
    block: Option<String>,
    /// Fault: this joint's motor heats up fast under load.
    #[arg(long, value_name = "JOINT")]
    overheat: Option<String>,
    /// Fault: close the connection and exit after this many cycles.
    #[arg(long, value_name = "CYCLES")]
    drop_after: Option<u64>,
    /// Fault: close the connection and exit on SIGUSR1.
    #[arg(long)]
    drop_on_sigusr1: bool,
    /// Fault: stop sending (connection kept open) after this many cycles.
    #[arg(long, value_name = "CYCLES")]
    silent_after: Option<u64>,
    /// Fault: send a message that does not parse in this cycle.
    #[arg(long, value_name = "CYCLE")]
    garbage_at: Option<u64>,
    /// How the robot lies: back (the default), front, left-side, right-side, standing,
    /// upside-down or tilted (its IMU says so).
    #[arg(long, default_value = "back", value_parser = lying)]
    lying: Lying,
    /// Its battery's charge (%, 0 … 100).
    #[arg(long, default_value_t = 90.0, value_parser = within(0.0, 100.0, " %"))]
    battery: f64,
    /// Fault: roll over onto the right side from this cycle on.
    #[arg(long, value_name = "CYCLE")]
    roll_at: Option<u64>,
    /// Fault: the chest button pressed from this cycle on.
    #[arg(long, value_name = "CYCLE")]
    chest_at: Option<u64>,
    /// Fault: a motor reports this temperature status (1 … 3) from this cycle on, up to
    /// END if given (e.g. LKneePitch=2@300, LKneePitch=1@300..1800).
    #[arg(long, value_name = "JOINT=STATUS@CYCLE[..END]")]
    status: Option<String>,
    /// Fault: the battery down to 3 % from this cycle on.
    #[arg(long, value_name = "CYCLE")]
    low_battery_at: Option<u64>,
    /// Serve this many clients one after the other before exiting (at least 1).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    clients: u32,
}

#[derive(Debug, Subcommand)]
enum SnapCommand {
    /// Render a camera's view of a simulated robot into PATH (PNG).
    Snap {
        /// The picture to write.
        path: PathBuf,
        /// The state file the robot writes (`--state`).
        #[arg(long, value_name = "FILE")]
        state: PathBuf,
        /// The camera: lower or upper (which needs [upper_camera] in the robot's
        /// dataset.toml).
        #[arg(long, default_value = "lower", value_parser = camera_id)]
        camera: CameraId,
        /// The sensor's flip (1 or 0): the upper camera's picture is upright only
        /// flipped, the lower's only unflipped; not given: unflipped, as the sensor
        /// starts (capture gives `--flip {flip}`).
        #[arg(long, value_parser = flip)]
        flip: Option<bool>,
        /// Manual exposure (driver units, with --gain): the picture's brightness scales
        /// with exposure × gain, the scene as rendered at the team settings (upper 700 ×
        /// 800, lower 1700 × 250); not given: automatic exposure.
        #[arg(long, requires = "gain", value_parser = clap::value_parser!(u32).range(0..=1_048_575))]
        exposure: Option<u32>,
        /// Gain (driver units, with --exposure).
        #[arg(long, requires = "exposure", value_parser = clap::value_parser!(u32).range(0..=1023))]
        gain: Option<u32>,
    },
}

fn flip(text: &str) -> Result<bool, String> {
    match text {
        "1" | "true" => Ok(true),
        "0" | "false" => Ok(false),
        _ => Err(format!("'{text}': expected 1 or 0")),
    }
}

fn camera_id(name: &str) -> Result<CameraId, String> {
    CameraId::from_name(name).ok_or_else(|| format!("'{name}': expected lower or upper"))
}

fn lying(name: &str) -> Result<Lying, String> {
    Lying::from_name(name).ok_or_else(|| {
        let names: Vec<&str> = Lying::NAMED.iter().map(|(_, n, _)| *n).collect();
        format!("'{name}': expected one of {}", names.join(", "))
    })
}

/// Runs `naocalib simulate-robot`.
pub fn run(args: &SimulateRobotArgs) -> Result<ExitCode> {
    if let Some(SnapCommand::Snap {
        path,
        state: file,
        camera,
        flip,
        exposure,
        gain,
    }) = &args.snap
    {
        let state = simulated::read_state(file)?;
        let settings = SnapSettings {
            flip: flip.unwrap_or(false),
            manual: exposure.zip(*gain),
        };
        simulated::snap(
            &state,
            file,
            *camera,
            &settings,
            path,
            &RenderOptions::default(),
        )?;
        return Ok(ExitCode::SUCCESS);
    }
    let cycles = request::run(&RobotRequest {
        lola: args.lola.clone(),
        config: args.config.clone(),
        seed: args.seed,
        effects: args.effects.clone(),
        truth: args.truth.clone(),
        speed: args.speed,
        state: args.state.clone(),
        record: args.record.clone(),
        block: args.block.clone(),
        overheat: args.overheat.clone(),
        status: args.status.clone(),
        drop_after: args.drop_after,
        drop_on_signal: args.drop_on_sigusr1,
        silent_after: args.silent_after,
        garbage_at: args.garbage_at,
        lying: args.lying,
        battery_percent: args.battery,
        roll_at: args.roll_at,
        chest_at: args.chest_at,
        low_battery_at: args.low_battery_at,
        clients: args.clients,
    })?;
    note!("simulated robot: {cycles} cycles served");
    Ok(ExitCode::SUCCESS)
}
