//! `naocalib simulate`: write a simulated dataset.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Result, bail};
use clap::Args;

use naocalib::model::{CameraId, Family, Model};
use naocalib::output::{Staged, WriteOptions};
use naocalib::sim::SimOptions;
use naocalib::sim::camera::CameraPreset;

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
}

/// The most captures `simulate` writes (as many as a dataset may have).
const MAX_CAPTURES: usize = 100_000;

/// Checks the counts and noise levels before anything is simulated or written.
fn check_bounds(args: &SimulateArgs) -> Result<()> {
    if args.stances == 0 || args.heads == 0 {
        bail!(
            "--stances and --heads must be at least 1 (got {} and {})",
            args.stances,
            args.heads
        );
    }
    let captures = args
        .stances
        .checked_add(args.upper_stances)
        .and_then(|n| n.checked_mul(args.heads))
        .and_then(|n| n.checked_mul(2));
    if captures.is_none_or(|n| n > MAX_CAPTURES) {
        let count = captures.map_or("more than 2⁶⁴".to_string(), |n| n.to_string());
        bail!(
            "--stances {} --upper-stances {} --heads {} would make 2 × ({} + {}) × {} = \
             {count} captures; at most {MAX_CAPTURES} are allowed",
            args.stances,
            args.upper_stances,
            args.heads,
            args.stances,
            args.upper_stances,
            args.heads
        );
    }
    let within = |flag: &str, x: f64, hi: f64, unit: &str| {
        if x.is_finite() && (0.0..=hi).contains(&x) {
            Ok(())
        } else {
            Err(anyhow::anyhow!("{flag} must be 0 … {hi} {unit}, got {x}"))
        }
    };
    within("--px-noise", args.px_noise, 100.0, "px")?;
    within("--joint-noise-deg", args.joint_noise_deg, 10.0, "°")?;
    if let Some(d) = &args.distortion
        && let Some(k) = d.iter().find(|k| !(k.is_finite() && k.abs() <= 100.0))
    {
        bail!("--distortion coefficients must be finite and within ±100, got {k}");
    }
    Ok(())
}

/// Runs `naocalib simulate`.
pub fn run(args: &SimulateArgs) -> Result<ExitCode> {
    check_bounds(args)?;
    let truth = match &args.truth {
        Some(path) => {
            // With --force the dataset's truth.toml would be replaced: never the input.
            let written = args.out.join(naocalib::dataset::TRUTH_TOML);
            if let (Ok(a), Ok(b)) = (path.canonicalize(), written.canonicalize())
                && a == b
            {
                bail!(
                    "--truth {} is the truth.toml this would write; copy it out of {} first",
                    path.display(),
                    args.out.display()
                );
            }
            Some(naocalib::dataset::read_truth(path)?.values)
        }
        None => None,
    };
    let (schedule, schedule_cameras) = match &args.stance_file {
        Some(path) => {
            let plan = naocalib::plan::read_csv(path)?;
            if plan.is_empty() {
                bail!("{}: the plan has no captures", path.display());
            }
            // The camera of each row (the plan's `camera` column; lower when absent).
            let cameras = naocalib::dataset::read_captures(path)?
                .iter()
                .map(|c| c.camera)
                .collect();
            (Some(naocalib::plan::to_stances(&plan)), cameras)
        }
        None => (None, Vec::new()),
    };
    // Every output against every input, and the dataset files against --force, before
    // anything is simulated or written.
    let inputs: Vec<PathBuf> = args
        .truth
        .iter()
        .chain(&args.stance_file)
        .cloned()
        .collect();
    let write_options = WriteOptions::new(args.force).protecting(inputs);
    let dataset_files = naocalib::output::dataset_files(&args.out);
    let files: Vec<&std::path::Path> = dataset_files.iter().map(PathBuf::as_path).collect();
    naocalib::output::check_outputs(&files, &[&args.out], &write_options)?;
    naocalib::dataset::check_writable(&args.out, true, args.force)?;
    // The dataset is written into a stage beside OUT and published at the end: a failure
    // (a full disk) or a kill part-way leaves OUT as it was.
    let stage = Staged::new(&args.out, &write_options)?;
    let options = SimOptions {
        seed: args.seed,
        stances: args.stances,
        heads: args.heads,
        px_noise: args.px_noise,
        joint_noise: args.joint_noise_deg.to_radians(),
        truth,
        effects: args.effects.clone().map(|e| e.0).unwrap_or_default(),
        noise_seed: None,
        near_border: args.near_border,
        images: args.images.then(|| naocalib::sim::render::ImageOutput {
            dir: stage.dir().to_path_buf(),
            options: naocalib::sim::render::RenderOptions {
                blur: args.blur,
                noise: args.grey_noise,
                vignetting: args.vignetting,
                seed: args.seed,
                ..Default::default()
            },
            force: true,
        }),
        upper_stances: args.upper_stances,
        team_offsets: args.team_offsets,
        schedule_cameras,
        schedule,
    };
    let mut model = Model {
        camera: args.camera.camera(),
        ..Model::default()
    };
    if let Some(d) = &args.distortion {
        anyhow::ensure!(
            d.len() == 5,
            "--distortion takes five numbers: k1,k2,p1,p2,k3"
        );
        model.camera.distortion = std::array::from_fn(|i| d[i]);
    }
    let upper = args.upper_stances > 0 || options.schedule_cameras.contains(&CameraId::Upper);
    if upper {
        // The V6's two cameras are the same model: the upper one gets the same intrinsics.
        model.upper_camera = Some(model.camera);
    }
    let mut dataset = naocalib::sim::simulate(&model, &options)?;
    if args.images {
        dataset.corners.clear();
    }
    let mut outside = 0;
    if let Some(path) = &args.stance_file {
        // A planned stance may show part of the board outside the image for offsets beyond
        // the plan's bounds: those vertices are not seen.
        let camera_of: std::collections::HashMap<u64, CameraId> =
            dataset.captures.iter().map(|c| (c.id, c.camera)).collect();
        let before = dataset.corners.len();
        dataset.corners.retain(|c| {
            let camera = camera_of.get(&c.capture).copied().unwrap_or_default();
            model.intrinsics(camera).contains(c.pixel, 0.0)
        });
        outside = before - dataset.corners.len();
        if let Some(truth) = &mut dataset.truth {
            for key in ["stances_per_leg", "head_postures"] {
                truth.simulation.remove(key);
            }
            truth.simulation.insert(
                "stance_file".into(),
                toml::Value::String(path.display().to_string()),
            );
        }
    }
    dataset.dir = args.out.clone();
    dataset.write(stage.dir(), true)?;
    stage.publish()?;
    let upper = dataset
        .captures
        .iter()
        .filter(|c| c.camera == CameraId::Upper)
        .count();
    if args.images {
        super::print_out(format!(
            "wrote {}: {} captures{} with images in {} (seed {}, blur {} px, grey noise {}, \
             vignetting {}, {}° joint noise); corners.csv is empty: run `naocalib detect`\n",
            args.out.display(),
            dataset.captures.len(),
            upper_note(upper),
            args.out.join("images").display(),
            args.seed,
            args.blur,
            args.grey_noise,
            args.vignetting,
            args.joint_noise_deg
        ))?;
    } else {
        super::print_out(format!(
            "wrote {}: {} captures{}, {} vertices (seed {}, {} px, {}° joint noise)\n",
            args.out.display(),
            dataset.captures.len(),
            upper_note(upper),
            dataset.corners.len(),
            args.seed,
            args.px_noise,
            args.joint_noise_deg
        ))?;
        if outside > 0 {
            super::print_out(format!(
                "{outside} vertices fell outside the image at the true offsets and were left \
                 out\n"
            ))?;
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// ` (N with the upper camera)` when there are upper-camera captures, else nothing.
fn upper_note(upper: usize) -> String {
    if upper == 0 {
        String::new()
    } else {
        format!(" ({upper} with the upper camera)")
    }
}

/// `--effects`' help, with the registry's families.
fn effects_help() -> String {
    format!(
        "Give the drawn robot effects the paper's model lacks, as families ({}, or `realistic` \
         for {}); their true values go into truth.toml",
        effect_families(),
        Family::names(Family::realistic())
    )
}

/// The families `--effects` draws: every one beyond the paper's but the upper camera's
/// (drawn with the paper's whenever there are upper-camera captures).
fn effect_families() -> String {
    Family::names(
        Family::ALL
            .into_iter()
            .filter(|f| !matches!(f, Family::Paper | Family::UpperCamera)),
    )
}

/// The families of `--effects`.
#[derive(Debug, Clone)]
struct Effects(Vec<Family>);

/// Parses `--effects`: family names, or `realistic`.
fn parse_effects(text: &str) -> Result<Effects, String> {
    let mut out = Vec::new();
    for name in text.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let named: Vec<Family> = match (name, Family::from_name(name)) {
            ("realistic", _) => Family::realistic(),
            (_, Some(Family::Paper | Family::UpperCamera)) | (_, None) => {
                return Err(format!(
                    "unknown effect '{name}' ({}, realistic = {})",
                    effect_families(),
                    Family::names(Family::realistic())
                ));
            }
            (_, Some(f)) => vec![f],
        };
        for f in named {
            if !out.contains(&f) {
                out.push(f);
            }
        }
    }
    Ok(Effects(out))
}

/// Parses `--camera`.
fn parse_camera(text: &str) -> Result<CameraPreset, String> {
    CameraPreset::from_name(text).ok_or_else(|| {
        let names: Vec<&str> = CameraPreset::ALL.iter().map(|(_, n)| *n).collect();
        format!("unknown camera '{text}' ({})", names.join(", "))
    })
}
