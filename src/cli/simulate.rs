//! `naocalib simulate`: write a simulated dataset.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use clap::Args;

use naocalib::model::Family;
use naocalib::sim::camera::CameraPreset;
use naocalib::sim::request::{self, SimRequest, parse_camera};

#[derive(Debug, Args)]
pub struct SimulateArgs {
    /// Directory to write the dataset into.
    out: PathBuf,
    /// Seed of the random generator.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Stances per leg.
    #[arg(long, default_value_t = 24)]
    stances: usize,
    /// Head postures per stance.
    #[arg(long, default_value_t = 3)]
    heads: usize,
    /// Stances per leg photographed with the upper camera (each with --heads postures),
    /// found by search among random stances; the dataset then has an [upper_camera] table
    /// (the --camera preset's intrinsics).
    #[arg(long, default_value_t = 0, value_name = "N")]
    upper_stances: usize,
    /// Draw the true offsets as SPL teams' robot files show them (lower-camera pitch
    /// −3.1…−7.8°, upper-camera pitch −2.2…−10.2° with median −8.5° and roll up to 2.7°,
    /// head offsets up to 6.8° yaw and 4.7° pitch, leg offsets up to 2°) instead of the
    /// paper-sized ones.
    #[arg(long, conflicts_with = "truth")]
    team_offsets: bool,
    /// Pixel noise σ per coordinate (px).
    #[arg(long, default_value_t = 0.1)]
    px_noise: f64,
    /// Joint-angle noise σ per joint and capture (deg).
    #[arg(long, default_value_t = 0.0)]
    joint_noise_deg: f64,
    /// Take the true parameters from this truth.toml instead of drawing them.
    #[arg(long)]
    truth: Option<PathBuf>,
    /// Give the drawn robot effects the paper's model lacks, as families (the help lists
    /// the registry's); their true values go into truth.toml.
    #[arg(long, value_name = "FAMILIES", value_parser = parse_effects, conflicts_with = "truth",
          help = effects_help())]
    effects: Option<Effects>,
    /// Replace files of an existing dataset in OUT.
    #[arg(long)]
    force: bool,
    /// Also render one greyscale PNG per capture into OUT/images (corners.csv is then left
    /// empty, for `naocalib detect`).
    #[arg(long)]
    images: bool,
    /// Image blur σ (px) (with --images).
    #[arg(long, default_value_t = 0.8, requires = "images")]
    blur: f64,
    /// Image grey-level noise σ (with --images).
    #[arg(long, default_value_t = 2.0, requires = "images")]
    grey_noise: f64,
    /// Image vignetting: relative loss of brightness in the corners (with --images).
    #[arg(long, default_value_t = 0.3, requires = "images")]
    vignetting: f64,
    /// The robot's own body in front of the boards (the body model, docs/BODY.md): legs,
    /// each foot standing on its sandal, torso, pelvis and the arms as capture holds them.
    /// A vertex whose refinement window it covers gives no corner; with --images it is
    /// drawn.
    #[arg(long)]
    body: bool,
    /// The simulated lower camera: v4 (the paper's: 640×480, f 562.5 px), v6 (V6 field of
    /// view 56.3°×43.7° at 640×480) or v6-1280x960; its intrinsics go into dataset.toml.
    #[arg(long, default_value = "v4", value_name = "CAMERA", value_parser = parse_camera)]
    camera: CameraPreset,
    /// Photograph the stances of this plan (`naocalib plan`) instead of random ones:
    /// one capture per row, in its order, with the camera of its `camera` column (lower
    /// when absent). Vertices that the true offsets put outside the image are left out, as
    /// a camera would.
    #[arg(long, value_name = "PLAN.csv", conflicts_with_all = ["stances", "heads", "upper_stances"])]
    stance_file: Option<PathBuf>,
    /// Let boards come near and across the image border (to test detection): later head
    /// postures aim anywhere in the image, and a board is kept with 8 vertices in view.
    #[arg(long)]
    near_border: bool,
    /// Lens distortion k1,k2,p1,p2,k3 (OpenCV order) of the simulated camera.
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    distortion: Option<Vec<f64>>,
    /// The sandals of this dataset.toml's [board] (`naocalib sandal --config`'s; default:
    /// naocalib's sandal, 7 × 5 squares of 25 mm with its seven columns across the foot,
    /// centred 200 mm ahead of the ankle; a file without [board] means the paper's).
    #[arg(long, value_name = "DATASET_TOML")]
    board: Option<PathBuf>,
}

/// Runs `naocalib simulate`.
pub fn run(args: &SimulateArgs) -> Result<ExitCode> {
    let request = SimRequest {
        out: args.out.clone(),
        force: args.force,
        seed: args.seed,
        stances: args.stances,
        heads: args.heads,
        upper_stances: args.upper_stances,
        team_offsets: args.team_offsets,
        px_noise: args.px_noise,
        joint_noise_deg: args.joint_noise_deg,
        truth: args.truth.clone(),
        effects: args.effects.clone().map(|e| e.0).unwrap_or_default(),
        images: args.images,
        blur: args.blur,
        grey_noise: args.grey_noise,
        vignetting: args.vignetting,
        body: args.body,
        camera: args.camera,
        stance_file: args.stance_file.clone(),
        near_border: args.near_border,
        distortion: args.distortion.clone(),
        board: args.board.clone(),
    };
    let simulated = request::run(&request)?;
    super::print_out(request::summary(&request, &simulated))?;
    Ok(ExitCode::SUCCESS)
}

/// `--effects`' help, with the registry's families.
fn effects_help() -> String {
    format!(
        "Give the drawn robot effects the paper's model lacks, as families ({}, or `realistic` \
         for {}); their true values go into truth.toml",
        request::effect_families(),
        Family::names(Family::realistic())
    )
}

/// The families of `--effects`.
#[derive(Debug, Clone)]
struct Effects(Vec<Family>);

/// Parses `--effects`: family names, or `realistic`.
fn parse_effects(text: &str) -> Result<Effects, String> {
    request::parse_effects(text).map(Effects)
}
