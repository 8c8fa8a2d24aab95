//! Flags shared by several commands, each defined once and flattened where it is used
//! (`solve`, `batch`, `compare`), with their checks in clap's value parsers.

use anyhow::Result;
use clap::Args;

use naocalib::model::FixedSet;
use naocalib::run::RunOptions;
use naocalib::solve::{self, Loss, ModelChoice, UncertaintyOptions, noise::NoiseOptions};

/// The backend used when `--solver` is not given.
pub const DEFAULT_SOLVER: &str = if cfg!(feature = "ceres") {
    "ceres"
} else {
    "lm"
};

/// Most bootstrap refits a run may ask for (each is a whole fit).
pub const MAX_BOOTSTRAP: usize = 10_000;

/// What is fitted: which parameters are free, and the loss.
#[derive(Debug, Clone, Args)]
pub struct ProblemArgs {
    /// Parameters or families to hold fixed at zero, comma-separated (CamYaw,LBoardRotZ).
    #[arg(long, value_name = "NAMES")]
    pub fix: Option<String>,
    /// Parameters or families to estimate beyond the paper's, comma-separated (the help
    /// lists the families of the registry).
    #[arg(long, value_name = "NAMES", help = free_help())]
    pub free: Option<String>,
    /// Robust first fit: huber or cauchy, optionally with a scale in px (huber:2);
    /// outlier vertices are listed and left out of the final fit.
    #[arg(long, value_name = "LOSS[:PX]", value_parser = parse_loss)]
    pub loss: Option<Loss>,
}

impl ProblemArgs {
    /// The held parameters for `--fix` and `--free` (family or parameter names).
    pub fn fixed_set(&self) -> Result<FixedSet> {
        naocalib::model::held::held(self.free.as_deref(), self.fix.as_deref())
            .map_err(anyhow::Error::msg)
    }

    /// The loss (plain least squares without `--loss`).
    pub fn loss(&self) -> Loss {
        self.loss.unwrap_or(Loss::Squared)
    }
}

/// The library's options for one run (`solve`, and every run of `batch`) from the flags
/// both share: the problem's, the backend and the uncertainty's.
pub fn run_options(
    problem: &ProblemArgs,
    solver: &SolverArgs,
    uncertainty: &UncertaintyArgs,
    verbose: bool,
) -> Result<RunOptions> {
    Ok(RunOptions {
        solver: solver.solver.clone(),
        fixed: problem.fixed_set()?,
        loss: problem.loss(),
        uncertainty: uncertainty.options(),
        verbose,
        start_from: None,
    })
}

/// Which backend solves.
#[derive(Debug, Clone, Args)]
pub struct SolverArgs {
    /// Least-squares backend: ceres (default), lm (levenberg-marquardt crate), tiny
    /// (tiny-solver).
    #[arg(long, default_value = DEFAULT_SOLVER, value_parser = parse_solver)]
    pub solver: String,
}

/// Which families `--model` fits.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ModelArg {
    /// The paper's 21 parameters, with `--free`/`--fix` applied.
    Paper,
    /// Also free, one at a time, the families the data support and can determine.
    Auto,
}

/// How the model is chosen and the reported uncertainty obtained.
#[derive(Debug, Clone, Args)]
pub struct UncertaintyArgs {
    /// Families to fit: paper (the paper's model with --free/--fix), or auto (free the
    /// families the misfit tests point to, one at a time, until none is significant).
    #[arg(long, value_enum, default_value = "paper")]
    pub model: ModelArg,
    /// Pixel noise σ (px, 0.001 … 100) for the noise model; estimated from the residuals
    /// if not given.
    #[arg(long, value_name = "PX", value_parser = px_sigma)]
    pub px_noise: Option<f64>,
    /// Joint-angle noise σ per joint and capture (deg, above 0 and at most 10); estimated if
    /// not given.
    #[arg(long, value_name = "DEG", value_parser = joint_sigma_deg)]
    pub joint_noise_deg: Option<f64>,
    /// Report the plain σ̂²(JᵀJ)⁻¹ instead of the noise model (over-confident under joint
    /// noise).
    #[arg(long)]
    pub plain_std: bool,
    /// Also estimate the uncertainty by a capture bootstrap with N refits (at most 10000).
    #[arg(long, value_name = "N", default_value_t = 0,
          value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(0..=MAX_BOOTSTRAP as u64))]
    pub bootstrap: usize,
}

impl UncertaintyArgs {
    /// The library's options for these flags.
    pub fn options(&self) -> UncertaintyOptions {
        UncertaintyOptions {
            noise_model: !self.plain_std,
            noise: NoiseOptions {
                px: self.px_noise,
                joint: self.joint_noise_deg.map(f64::to_radians),
            },
            bootstrap: self.bootstrap,
            model: match self.model {
                ModelArg::Paper => ModelChoice::Given,
                ModelArg::Auto => ModelChoice::Auto,
            },
            ..UncertaintyOptions::default()
        }
    }
}

/// The smallest pixel noise σ a flag takes (px): below it, σ² and its inverse leave the
/// range of floating-point numbers' useful precision (a detector's corners are never better
/// than a thousandth of a pixel).
pub const MIN_PX_SIGMA: f64 = 1e-3;
/// The largest pixel noise σ a flag takes (px): beyond it corners are no measurement.
pub const MAX_PX_SIGMA: f64 = 100.0;
/// The largest joint-angle noise σ a flag takes (deg): a NAO's encoders are far better.
pub const MAX_JOINT_SIGMA_DEG: f64 = 10.0;

/// A pixel noise σ: MIN_PX_SIGMA … MAX_PX_SIGMA px.
pub fn px_sigma(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(v) if (MIN_PX_SIGMA..=MAX_PX_SIGMA).contains(&v) => Ok(v),
        _ => Err(format!(
            "must be a pixel noise σ from {MIN_PX_SIGMA} to {MAX_PX_SIGMA} px, got '{text}'"
        )),
    }
}

/// A joint-angle noise σ: above 0 and at most MAX_JOINT_SIGMA_DEG degrees.
pub fn joint_sigma_deg(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(v) if v > 0.0 && v <= MAX_JOINT_SIGMA_DEG => Ok(v),
        _ => Err(format!(
            "must be a joint noise σ above 0 and at most {MAX_JOINT_SIGMA_DEG}°, got '{text}'"
        )),
    }
}

/// A joint-angle noise σ that may be zero: 0 … MAX_JOINT_SIGMA_DEG degrees.
pub fn joint_sigma_deg_or_zero(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(v) if (0.0..=MAX_JOINT_SIGMA_DEG).contains(&v) => Ok(v),
        _ => Err(format!(
            "must be a joint noise σ from 0 to {MAX_JOINT_SIGMA_DEG}°, got '{text}'"
        )),
    }
}

/// A solver this build has.
fn parse_solver(name: &str) -> Result<String, String> {
    if solve::backend_names().contains(&name) {
        Ok(name.to_string())
    } else {
        Err(format!(
            "unknown solver '{name}' (available: {})",
            solve::backend_names().join(", ")
        ))
    }
}

/// Parses `huber`, `cauchy`, `huber:2.5`.
pub fn parse_loss(text: &str) -> Result<Loss, String> {
    let (name, scale) = match text.split_once(':') {
        Some((n, s)) => match s.parse::<f64>() {
            Ok(v) if v.is_finite() && v > 0.0 => (n, v),
            _ => return Err(format!("the scale of '{text}' must be a positive number")),
        },
        None => (text, 1.0),
    };
    match name {
        "huber" => Ok(Loss::Huber(scale)),
        "cauchy" => Ok(Loss::Cauchy(scale)),
        _ => Err(format!("unknown loss '{name}' (huber or cauchy)")),
    }
}

/// A number from `lo` to `hi` (inclusive), in `unit`: a flag's physical range.
pub fn within(
    lo: f64,
    hi: f64,
    unit: &'static str,
) -> impl Fn(&str) -> Result<f64, String> + Clone + Send + Sync + 'static {
    move |text: &str| match text.parse::<f64>() {
        Ok(v) if (lo..=hi).contains(&v) => Ok(v),
        _ => Err(format!("must be from {lo} to {hi}{unit}, got '{text}'")),
    }
}

/// The families of the registry beyond the paper's, comma-separated, for help texts.
pub fn extended_families() -> String {
    use naocalib::model::Family;
    Family::names(Family::ALL.into_iter().filter(|f| *f != Family::Paper))
}

/// `--free`'s help, with the registry's families.
fn free_help() -> String {
    format!(
        "Parameters or families to estimate beyond the paper's, comma-separated ({}, or names \
         such as Fx)",
        extended_families()
    )
}
