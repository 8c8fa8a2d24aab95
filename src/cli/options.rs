//! Flags shared by several commands, each defined once and flattened where it is used
//! (`solve`, `batch`, `compare`), with their checks in clap's value parsers.

use anyhow::{Context, Result};
use clap::Args;

use naocalib::model::FixedSet;
use naocalib::solve::{self, Backend, Loss, ModelChoice, UncertaintyOptions, noise::NoiseOptions};

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
    /// Parameters or families to estimate beyond the paper's, comma-separated
    /// (head, intrinsics, distortion, links, compliance, play, or names such as Fx).
    #[arg(long, value_name = "NAMES")]
    pub free: Option<String>,
    /// Robust first fit: huber or cauchy, optionally with a scale in px (huber:2);
    /// outlier vertices are listed and left out of the final fit.
    #[arg(long, value_name = "LOSS[:PX]", value_parser = parse_loss)]
    pub loss: Option<Loss>,
}

impl ProblemArgs {
    /// The held parameters for `--fix` and `--free` (family or parameter names).
    pub fn fixed_set(&self) -> Result<FixedSet> {
        FixedSet::from_lists(
            self.free.as_deref().unwrap_or(""),
            self.fix.as_deref().unwrap_or(""),
        )
        .map_err(anyhow::Error::msg)
    }

    /// The loss (plain least squares without `--loss`).
    pub fn loss(&self) -> Loss {
        self.loss.unwrap_or(Loss::Squared)
    }
}

/// Which backend solves.
#[derive(Debug, Clone, Args)]
pub struct SolverArgs {
    /// Least-squares backend: ceres (default), lm (levenberg-marquardt crate), tiny
    /// (tiny-solver).
    #[arg(long, default_value = DEFAULT_SOLVER, value_parser = parse_solver)]
    pub solver: String,
}

impl SolverArgs {
    /// The chosen backend.
    pub fn backend(&self, verbose: bool) -> Result<Box<dyn Backend>> {
        solve::backend(&self.solver, verbose)
            .with_context(|| format!("unknown solver '{}'", self.solver))
    }
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
    /// Pixel noise σ (px) for the noise model; estimated from the residuals if not given.
    #[arg(long, value_name = "PX", value_parser = positive)]
    pub px_noise: Option<f64>,
    /// Joint-angle noise σ per joint and capture (deg); estimated if not given.
    #[arg(long, value_name = "DEG", value_parser = positive)]
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

/// A finite number greater than zero.
pub fn positive(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("must be a positive number, got '{text}'")),
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
