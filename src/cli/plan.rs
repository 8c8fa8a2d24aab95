//! `naocalib plan`: design a stance schedule and predict what it will determine.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use clap::Args;

use naocalib::model::{CameraId, Family};
use naocalib::plan::report;
use naocalib::plan::request::{self, PlanRequest};

use super::options::{joint_sigma_deg_or_zero, px_sigma};

#[derive(Debug, Args)]
pub struct PlanArgs {
    /// The stance schedule to write (CSV: capture,board,HeadYaw,…,RAnkleRoll in radians,
    /// and a camera column, lower or upper, when some capture is by the upper camera).
    out: PathBuf,
    /// Number of captures, both legs together [default: 144; with --budget-s, as many as
    /// fit, at most this].
    #[arg(long,
          value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(2..=5000))]
    captures: Option<usize>,
    /// The robot time the measurement phase may take (s, 1 … 36000): the plan takes as many
    /// captures as fit, its predicted duration from rest through every capture and back,
    /// every move included (at most --captures when given).
    #[arg(long, value_name = "SECONDS", value_parser = budget_s)]
    budget_s: Option<f64>,
    /// Parameter families the calibration will free, comma-separated; the plan is made for
    /// them (the help lists the registry's families).
    #[arg(long, value_name = "FAMILIES", default_value = "paper", value_parser = parse_families,
          help = families_help())]
    families: Families,
    /// Pixel noise σ per coordinate the prediction assumes (px, 0.001 … 100).
    #[arg(long, default_value_t = 0.1, value_parser = px_sigma)]
    px_noise: f64,
    /// Joint-angle noise σ per joint and capture the prediction assumes (deg, 0 … 10).
    #[arg(long, default_value_t = 0.1, value_parser = joint_sigma_deg_or_zero)]
    joint_noise_deg: f64,
    /// Seed of the random candidate pool.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// The robot's dataset.toml (camera intrinsics, board, robot geometry); without it the
    /// defaults with naocalib's sandal (docs/SANDALS.md; a dataset.toml without [board]
    /// means the paper's).
    #[arg(long, value_name = "DATASET_TOML")]
    camera: Option<PathBuf>,
    /// The board must stay in view for every angle offset within ± this (deg, 0 … 30) (and
    /// sandal translations within ± this in mm).
    #[arg(long, default_value_t = 3.0, value_parser = offset_deg)]
    offset_deg: f64,
    /// Cameras to plan captures for, comma-separated (lower, upper); both by default when
    /// the --camera dataset has an [upper_camera] table, else lower. Planning for the upper
    /// camera frees its rotation offsets (UpperCamYaw, UpperCamPitch, UpperCamRoll).
    #[arg(long, value_name = "CAMERAS", value_parser = parse_cameras)]
    cameras: Option<Cameras>,
    /// The box of offsets for upper-camera captures (deg, 0 … 30; sandal translations in
    /// mm), centred on the --around calibration. Lying on its back the NAO sees a sandal
    /// through its upper camera only from 220–390 mm, where the board spans most of the
    /// image, so no capture stays in view over ±3°; the robot's imported calibration knows
    /// its offsets far better, and capture and detection check each picture again
    /// [default: 0.5, halved down to 0.125 when no upper-camera capture of a leg stays in
    /// view over it].
    #[arg(long, value_parser = offset_deg)]
    upper_offset_deg: Option<f64>,
    /// The σ the design aims at for the upper camera's rotation offsets, as a fraction of
    /// the worst σ of the lower camera's and legs' 15 angle offsets (0.1 … 10). Lower puts
    /// more of the captures on the upper camera: its offsets get smaller σ, the 15 larger.
    #[arg(long, default_value_t = 0.88, value_parser = sigma_ratio)]
    upper_sigma_ratio: f64,
    /// Leg stances drawn into the candidate pool per leg, for each camera planned for.
    #[arg(long, default_value_t = 300,
          value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..=100_000))]
    pool: usize,
    /// Replace an existing OUT.
    #[arg(long)]
    force: bool,
    /// Design the stances around the robot's current calibration (a calibration TOML/JSON,
    /// e.g. from `naocalib import`) instead of zero: the board must stay in view for every
    /// offset within ±--offset-deg of the robot's values (for captures whose logged angles
    /// are raw, as LoLA reports them).
    #[arg(long, value_name = "CAL.toml")]
    around: Option<PathBuf>,
    /// Plan as though the robot's body hid nothing and touched nothing (the paper's
    /// planner). Without it the plan sees past the body (docs/BODY.md): a capture is kept
    /// only when at least half of its board's vertices have their window in plain sight
    /// past the body model, its posture and every move to it touch nothing, and the design
    /// weighs those vertices alone.
    #[arg(long)]
    ignore_body: bool,
}

/// `--families`' help, with the registry's families.
fn families_help() -> String {
    format!(
        "Parameter families the calibration will free (paper, {}), comma-separated; the \
         plan is made for them",
        super::options::extended_families()
    )
}

/// The families of `--families`.
#[derive(Debug, Clone)]
struct Families(Vec<Family>);

/// Parses `--families`.
fn parse_families(text: &str) -> Result<Families, String> {
    request::parse_families(text).map(Families)
}

/// The cameras of `--cameras`.
#[derive(Debug, Clone)]
struct Cameras(Vec<CameraId>);

/// Parses `--cameras`.
fn parse_cameras(text: &str) -> Result<Cameras, String> {
    request::parse_cameras(text).map(Cameras)
}

/// An offset range: 0 … 30 (the physical bound of an angle offset,
/// [`naocalib::model::bounds`]).
fn offset_deg(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(v) if (0.0..=30.0).contains(&v) => Ok(v),
        _ => Err(format!("must be a number from 0 to 30, got '{text}'")),
    }
}

/// A measurement phase's budget: 1 … 36000 s.
fn budget_s(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(v) if (1.0..=36000.0).contains(&v) => Ok(v),
        _ => Err(format!(
            "must be a number of seconds from 1 to 36000, got '{text}'"
        )),
    }
}

fn sigma_ratio(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(v) if (0.1..=10.0).contains(&v) => Ok(v),
        _ => Err(format!("must be a number from 0.1 to 10, got '{text}'")),
    }
}

/// Runs `naocalib plan`.
pub fn run(args: &PlanArgs) -> Result<ExitCode> {
    let request = PlanRequest {
        out: args.out.clone(),
        force: args.force,
        captures: args.captures,
        budget_s: args.budget_s,
        families: args.families.0.clone(),
        px_noise: args.px_noise,
        joint_noise_deg: args.joint_noise_deg,
        seed: args.seed,
        camera: args.camera.clone(),
        offset_deg: args.offset_deg,
        cameras: args.cameras.as_ref().map(|c| c.0.clone()),
        upper_offset_deg: args.upper_offset_deg,
        upper_sigma_ratio: args.upper_sigma_ratio,
        pool: args.pool,
        around: args.around.clone(),
        sight: !args.ignore_body,
    };
    let planned = request::run(&request)?;
    super::print_out(report::summary(&request, &planned))?;
    Ok(ExitCode::SUCCESS)
}
