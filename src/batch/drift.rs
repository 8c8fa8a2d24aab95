//! Drift between calibration runs of the same robot: per parameter the change between two
//! runs and its z-score `z = Δ / √(σ₁² + σ₂²)`, with the one-sigma each run reported. Two
//! runs are independent measurements, so their uncertainties add; a change with
//! `|z| > threshold` (3 by default) is more than the noise explains — that joint (or the
//! camera, or a sandal) really changed.
//!
//! ```
//! # use naocalib::model::{FixedSet, Model};
//! # use naocalib::sim::{SimOptions, simulate};
//! # use naocalib::solve::{Problem, UncertaintyOptions, backend, calibrate};
//! use naocalib::batch::drift;
//! # let solve_seed = |seed| {
//! #     let options = SimOptions { seed, stances: 4, heads: 2, ..SimOptions::default() };
//! #     let dataset = simulate(&Model::default(), &options).unwrap();
//! #     let problem = Problem::from_dataset(&dataset, FixedSet::default()).unwrap();
//! #     calibrate(&problem, backend("lm", false).unwrap().as_ref(), &UncertaintyOptions::plain()).unwrap()
//! # };
//! let (before, after) = (solve_seed(1), solve_seed(2));
//! for d in drift(&before, &after, 3.0).iter().filter(|d| d.flagged) {
//!     println!("{} changed by {:.3} {} (z = {:.1})", d.param, d.delta, d.param.unit().name(), d.z.unwrap());
//! }
//! ```

use std::path::{Path, PathBuf};

use crate::model::Param;
use crate::solve::Solution;

use super::Run;

/// The change of one parameter between two runs, in report units (deg / mm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParamDrift {
    /// The parameter.
    pub param: Param,
    /// `value(b) − value(a)`.
    pub delta: f64,
    /// `√(σ_a² + σ_b²)`.
    pub sigma: f64,
    /// `delta / sigma`; `None` when the combined sigma is zero.
    pub z: Option<f64>,
    /// `|z| > threshold`.
    pub flagged: bool,
}

/// The drift of every parameter both runs determined ([`super::stats::determined`]: the
/// paper's 21 and any further one), from `a` to `b`; `|z| > threshold` is flagged. A
/// parameter either run held or left undetermined has no drift: its value there is a start
/// value, not a measurement.
pub fn drift(a: &Solution, b: &Solution, threshold: f64) -> Vec<ParamDrift> {
    use super::stats::determined;
    Param::ALL
        .iter()
        .copied()
        .filter(|&p| a.fixed.is_shown(p) || b.fixed.is_shown(p))
        .filter(|&p| determined(a, p) && determined(b, p))
        .map(|p| {
            let delta = b.report_value(p) - a.report_value(p);
            let sigma = a.report_std(p).hypot(b.report_std(p));
            let z = (sigma > 0.0 && sigma.is_finite()).then(|| delta / sigma);
            ParamDrift {
                param: p,
                delta,
                sigma,
                z,
                flagged: z.is_some_and(|z| z.abs() > threshold),
            }
        })
        .collect()
}

/// Which pairs of runs of one robot are compared.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum DriftMode {
    /// Each run with the one before it.
    #[default]
    Consecutive,
    /// Each run with the first.
    First,
}

/// Which runs belong to the same robot.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Grouping {
    /// Datasets in the same parent directory (`robots/nao12/2024-07-*`) are one robot's.
    #[default]
    Parent,
    /// Every run of the batch is of one robot.
    All,
    /// No drift.
    None,
}

/// How drift is computed in a batch.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DriftOptions {
    /// Pairs compared.
    pub mode: DriftMode,
    /// `|z|` above which a change is flagged.
    pub threshold: f64,
    /// Which runs are of one robot.
    pub grouping: Grouping,
}

impl Default for DriftOptions {
    fn default() -> Self {
        DriftOptions {
            mode: DriftMode::Consecutive,
            threshold: 3.0,
            grouping: Grouping::Parent,
        }
    }
}

/// The drift between two runs of a batch.
#[derive(Debug, Clone, PartialEq)]
pub struct DriftPair {
    /// The robot (the parent directory, or `*` when every run is one robot's).
    pub robot: String,
    /// Index of the earlier run in [`super::Batch::runs`].
    pub from: usize,
    /// Index of the later run.
    pub to: usize,
    /// Per parameter.
    pub params: Vec<ParamDrift>,
}

impl DriftPair {
    /// The flagged parameters.
    pub fn flagged(&self) -> impl Iterator<Item = &ParamDrift> {
        self.params.iter().filter(|d| d.flagged)
    }
}

fn robot_of(dataset: &Path, grouping: Grouping) -> String {
    match grouping {
        Grouping::Parent => dataset
            .parent()
            .map(Path::to_path_buf)
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or_else(|| PathBuf::from("."))
            .display()
            .to_string(),
        Grouping::All | Grouping::None => "*".into(),
    }
}

/// The drift between the runs of each robot (grouped by `options.grouping`), in the order
/// of the runs (sort the runs by time, e.g. by dataset name, before).
pub fn batch_drift(runs: &[Run], options: &DriftOptions) -> Vec<DriftPair> {
    if options.grouping == Grouping::None {
        return Vec::new();
    }
    let mut groups: Vec<(String, Vec<usize>)> = Vec::new();
    for (i, run) in runs.iter().enumerate() {
        let robot = robot_of(run.dataset(), options.grouping);
        match groups.iter_mut().find(|(r, _)| *r == robot) {
            Some((_, members)) => members.push(i),
            None => groups.push((robot, vec![i])),
        }
    }
    let mut pairs = Vec::new();
    for (robot, members) in groups {
        for k in 1..members.len() {
            let from = match options.mode {
                DriftMode::Consecutive => members[k - 1],
                DriftMode::First => members[0],
            };
            let to = members[k];
            pairs.push(DriftPair {
                robot: robot.clone(),
                from,
                to,
                params: drift(&runs[from].solution, &runs[to].solution, options.threshold),
            });
        }
    }
    pairs
}
