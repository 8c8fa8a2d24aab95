//! `naocalib plan`: design a stance schedule and predict what it will determine.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use clap::Args;

use naocalib::model::{CameraId, Family, FixedSet, Model, Param, Unit};
use naocalib::output::WriteOptions;
use naocalib::plan::{PlanOptions, Prediction, is_angle_offset};
use naocalib::solve::noise::NoiseLevels;

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
    /// The robot's dataset.toml (camera intrinsics, board, robot geometry); the defaults
    /// when not given.
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
    /// its offsets far better, and capture and detection check each picture again.
    #[arg(long, default_value_t = 0.5, value_parser = offset_deg)]
    upper_offset_deg: f64,
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
    let mut out = Vec::new();
    for name in text.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let family = Family::from_name(name).ok_or_else(|| {
            format!(
                "unknown family '{name}' (families: {})",
                Family::names(Family::ALL)
            )
        })?;
        if !out.contains(&family) {
            out.push(family);
        }
    }
    if out.is_empty() {
        return Err("name at least one family".into());
    }
    Ok(Families(out))
}

/// The cameras of `--cameras`.
#[derive(Debug, Clone)]
struct Cameras(Vec<CameraId>);

/// Parses `--cameras`.
fn parse_cameras(text: &str) -> Result<Cameras, String> {
    let mut out = Vec::new();
    for name in text.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let camera = CameraId::from_name(name)
            .ok_or_else(|| format!("unknown camera '{name}' (cameras: lower, upper)"))?;
        if !out.contains(&camera) {
            out.push(camera);
        }
    }
    if out.is_empty() {
        return Err("name at least one camera".into());
    }
    Ok(Cameras(out))
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
    if args.out.is_dir() {
        bail!(
            "{} is a directory; name the CSV file to write",
            args.out.display()
        );
    }
    if !args.force && args.out.symlink_metadata().is_ok() {
        bail!("{} exists (use --force to replace it)", args.out.display());
    }
    // The plan never replaces an input (the --camera file), checked before the planning.
    let write_options = WriteOptions::new(args.force).protecting(args.camera.clone());
    naocalib::output::check_outputs(&[&args.out], &[], &write_options)?;
    let model = match &args.camera {
        Some(path) => naocalib::dataset::read_model(path)?,
        None => Model::default(),
    };
    let cameras = match &args.cameras {
        Some(c) => c.0.clone(),
        None if model.upper_camera.is_some() => vec![CameraId::Lower, CameraId::Upper],
        None => vec![CameraId::Lower],
    };
    if cameras.contains(&CameraId::Upper) && model.upper_camera.is_none() {
        bail!(
            "--cameras names the upper camera, but {} has no [upper_camera] table (its \
             intrinsics)",
            args.camera
                .as_ref()
                .map_or("the default model".to_string(), |p| p.display().to_string())
        );
    }
    let upper = cameras.contains(&CameraId::Upper);
    let mut fixed = FixedSet::with(&Param::ALL);
    for family in &args.families.0 {
        for p in family.params() {
            fixed.set(p, false);
        }
    }
    if upper {
        for p in Family::UpperCamera.params() {
            fixed.set(p, false);
        }
    }
    let mut options = PlanOptions {
        captures: args.captures.unwrap_or(PlanOptions::default().captures),
        fixed,
        levels: NoiseLevels {
            px: args.px_noise,
            joint: args.joint_noise_deg.to_radians(),
        },
        seed: args.seed,
        cameras,
        pool_stances: args.pool,
        upper_pool_stances: args.pool,
        upper_sigma_ratio: args.upper_sigma_ratio,
        ..PlanOptions::default()
    };
    options.feasibility.offset_angle = args.offset_deg.to_radians();
    options.feasibility.offset_length = args.offset_deg;
    options.feasibility.upper_offset = args.upper_offset_deg.to_radians();
    if let Some(path) = &args.around {
        let current = naocalib::export::read_start_from(path)
            .with_context(|| format!("--around {}", path.display()))?;
        for (p, value) in current.start_values(&model) {
            options.feasibility.centre[p.index()] = p.unit().from_report(value);
        }
    }
    let intrinsics_free = options
        .cameras
        .iter()
        .flat_map(|c| c.projection_params())
        .any(|p| !options.fixed.is_fixed(p));
    let start = Instant::now();
    let plan = match args.budget_s {
        Some(budget) => naocalib::plan::plan_within(&model, &options, budget, args.captures)?,
        None => naocalib::plan::plan(&model, &options)?,
    };
    let elapsed = start.elapsed().as_secs_f64();
    if let Some(dir) = args.out.parent().filter(|d| !d.as_os_str().is_empty())
        && !dir.is_dir()
    {
        bail!("the directory {} does not exist", dir.display());
    }
    naocalib::output::write_atomic(
        &args.out,
        &naocalib::plan::render_csv(&plan.captures),
        &write_options,
    )
    .with_context(|| format!("writing the plan {}", args.out.display()))?;
    let mut out = String::new();

    let left = plan
        .captures
        .iter()
        .filter(|c| c.side == naocalib::model::Side::Left)
        .count();
    let f = &options.feasibility;
    let n_upper = plan
        .captures
        .iter()
        .filter(|c| c.camera == CameraId::Upper)
        .count();
    let by_camera = if upper {
        format!(
            ", {} lower camera, {n_upper} upper",
            plan.captures.len() - n_upper
        )
    } else {
        String::new()
    };
    let _ = writeln!(
        out,
        "wrote {}: {} captures ({} left, {} right{by_camera}) in {} leg stances, chosen from \
         {} feasible captures in {elapsed:.1} s",
        args.out.display(),
        plan.captures.len(),
        left,
        plan.captures.len() - left,
        plan.stances,
        plan.pool
    );
    let _ = writeln!(
        out,
        "feasible: every angle at least {:.0}° inside its limits, LHipYawPitch = RHipYawPitch, \
         HeadPitch within its HeadYaw-dependent range, a straight move from rest, no collision (capsules for thighs and tibias; boxes for feet, sandals and torso; the \
         floor), every vertex in plain sight past the resting leg, the whole board at least \
         {} px inside the image and at most {:.0}° off facing the camera for any offsets \
         within ±{}° (sandal translations ±{} mm)",
        f.joint_margin.to_degrees(),
        f.margin_px,
        f.max_view_angle.to_degrees(),
        args.offset_deg,
        args.offset_deg
    );
    if upper {
        let _ = writeln!(
            out,
            "upper camera: the same rules, with offsets within ±{}° (±{} mm) of the --around \
             calibration (zero without it): lying on its back the NAO sees a sandal through \
             its upper camera only from 220–390 mm, where the board spans most of the image and no capture \
             stays in view over ±3°; its imported calibration knows the offsets far better, \
             and capture and detection check every picture again",
            args.upper_offset_deg, args.upper_offset_deg
        );
    }
    let _ = writeln!(
        out,
        "criterion: the worst σ of the 15 camera and leg joint offsets (and the upper camera's \
         3 when planned for), with every other free \
         parameter (families {}) weighed by its column-scaled variance (Σ (w·var)^16); greedy \
         selection, exchange, and refinement around the picked stances",
        args.families
            .0
            .iter()
            .map(|f| f.name())
            .collect::<Vec<_>>()
            .join(", ")
    );
    let _ = writeln!(
        out,
        "\npredicted one-sigma at {} px and {}° joint noise per capture:",
        args.px_noise, args.joint_noise_deg
    );
    out.push_str(&table(&plan.prediction, &plan.baseline));
    report_rank(&mut out, "plan", &plan.prediction);
    report_rank(&mut out, "random stances", &plan.baseline);
    let _ = writeln!(
        out,
        "\nmeasurement phase: predicted {:.0} s for the plan, from rest through every capture \
         and back, every move collision-free ({} through intermediate postures); {:.0} s for \
         the random stances in the simulator's order, {} of whose moves have no collision-free \
         way (the paper's took 590 s)",
        plan.duration, plan.via, plan.baseline_duration, plan.baseline_blocked
    );
    if let Some(budget) = args.budget_s {
        let _ = writeln!(
            out,
            "budget: {} captures fit a measurement phase of {budget} s (predicted {:.1} s{})",
            plan.captures.len(),
            plan.duration,
            match args.captures {
                Some(n) if n == plan.captures.len() => format!(", --captures {n}"),
                _ => String::new(),
            }
        );
    }
    if intrinsics_free {
        for c in &plan.coverage {
            let [lo, hi] = c.centres;
            let _ = writeln!(
                out,
                "{} camera's image: board vertices in {} of the {} cells of a {}×{} grid, \
                 {} of its 4 corners; board centres u {:.0}–{:.0} of {} px, v {:.0}–{:.0} of {} px",
                c.camera.name(),
                c.covered(),
                naocalib::plan::coverage::COLS * naocalib::plan::coverage::ROWS,
                naocalib::plan::coverage::COLS,
                naocalib::plan::coverage::ROWS,
                c.corners(),
                lo[0],
                hi[0],
                c.size[0],
                lo[1],
                hi[1],
                c.size[1]
            );
        }
    }
    super::print_out(out)?;
    Ok(ExitCode::SUCCESS)
}

/// The table of predicted sigmas, plan beside random stances, with the worst angle offset.
fn table(plan: &Prediction, random: &Prediction) -> String {
    let mut out = format!(
        "{:<24} {:>9} {:>11} {:>11} {:>8}\n",
        "parameter", "unit", "plan", "random", "ratio"
    );
    let show = |x: f64, unit: Unit| {
        if x.is_finite() {
            format!("{:.4}", unit.to_report(x))
        } else {
            "undet.".to_string()
        }
    };
    let mut worst = [0.0f64; 2];
    for (k, p) in plan.free.iter().enumerate() {
        let (a, b) = (plan.std[k], random.std_of(*p).unwrap_or(f64::INFINITY));
        let ratio = if a.is_finite() && b.is_finite() && a > 0.0 {
            format!("{:.2}", b / a)
        } else {
            "-".into()
        };
        out.push_str(&format!(
            "{:<24} {:>9} {:>11} {:>11} {:>8}\n",
            p.name(),
            p.unit().name(),
            show(a, p.unit()),
            show(b, p.unit()),
            ratio
        ));
        if is_angle_offset(*p) {
            worst[0] = worst[0].max(a);
            worst[1] = worst[1].max(b);
        }
    }
    if worst[0] > 0.0 && worst[0].is_finite() {
        out.push_str(&format!(
            "worst of the 15 camera and joint offsets: plan {}°, random {}° (random/plan {:.2})\n",
            show(worst[0], Unit::Deg),
            show(worst[1], Unit::Deg),
            worst[1] / worst[0]
        ));
    }
    out
}

/// The rank of a design's information and exactly which parameters it leaves
/// undetermined (those of the named directions and those no capture sees).
fn report_rank(out: &mut String, what: &str, p: &Prediction) {
    let left: Vec<&str> = p.undetermined_params().iter().map(|q| q.name()).collect();
    if p.undetermined.is_empty() && left.is_empty() {
        let _ = writeln!(
            out,
            "{what}: rank {} of {}, every free parameter determined",
            p.rank,
            p.free.len()
        );
    } else if p.undetermined.is_empty() {
        let _ = writeln!(
            out,
            "{what}: rank {} of {}; {} of the free parameters undetermined: {}",
            p.rank,
            p.free.len(),
            left.len(),
            left.join(", ")
        );
    } else {
        let _ = writeln!(
            out,
            "{what}: rank {} of {}; undetermined: {}; {} of the free parameters undetermined: {}",
            p.rank,
            p.free.len(),
            p.undetermined.join("; "),
            left.len(),
            left.join(", ")
        );
    }
}
