//! One calibration run — the paper's unit of work (its Table 2 lists three runs of one
//! robot): a dataset solved with [`RunOptions`] into a [`Run`], which holds everything said
//! of the run afterwards. The solution, the calibration robot files carry (standing leg
//! offsets and the dataset's joint-angle source included), the change since the robot's
//! previous calibration (`--start-from`) and the run's [`Provenance`].
//!
//! Every output reads the run: the table, the result JSON, the HTML report, plots, the
//! calibration files and the policy of `naocalib solve`'s files (all in `report`, which
//! reads this module, never the other way), and `batch`, whose runs are these.
//!
//! ```
//! use std::path::Path;
//! use naocalib::dataset::Dataset;
//! use naocalib::model::Param;
//! use naocalib::run::{self, Origin, RunOptions};
//!
//! let dataset = Dataset::load(Path::new("data/sample"))?;
//! let run = run::calibrate(&dataset, &RunOptions::default())?;
//! assert_eq!(run.provenance.origin, Origin::Solved);
//! assert_eq!(run.dataset(), Path::new("data/sample"));
//! let knee = run.calibration.get(Param::LKneePitch).expect("a leg offset");
//! println!("LKneePitch {}", knee.describe());
//! println!("{}", naocalib::report::run_text(&run));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod change;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use crate::calibration::Calibration;
pub use crate::calibration::Origin;
use crate::dataset::{AngleKind, Dataset};
use crate::model::{FixedSet, PARAMETER_COUNT, Side};
use crate::solve::{Loss, Problem, Solution, SolveError, UncertaintyOptions};

pub use change::{CameraIntrinsics, Change, changes, intrinsics_of};

/// How a run solves its dataset: what `naocalib solve` and `naocalib batch` take from their
/// flags.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// The least-squares backend ([`crate::solve::backend_names`]).
    pub solver: String,
    /// The parameters held fixed (`--fix`, `--free`).
    pub fixed: FixedSet,
    /// The loss: a robust first fit with outliers left out (`--loss`), or plain least
    /// squares ([`Loss::Squared`]).
    pub loss: Loss,
    /// How the model is chosen and the uncertainty obtained.
    pub uncertainty: UncertaintyOptions,
    /// Let the backend log its progress.
    pub verbose: bool,
    /// The robot's previous calibration (`--start-from`): its values are the start values,
    /// the head offsets are held at them unless freed, and the run records the change since
    /// it.
    pub start_from: Option<Calibration>,
}

impl Default for RunOptions {
    /// The first backend of this build, the paper's model, plain least squares, the noise
    /// model: `naocalib solve` without options.
    fn default() -> Self {
        RunOptions {
            solver: crate::solve::backend_names()[0].to_string(),
            fixed: FixedSet::default(),
            loss: Loss::Squared,
            uncertainty: UncertaintyOptions::default(),
            verbose: false,
            start_from: None,
        }
    }
}

impl RunOptions {
    /// The least-squares problem of `dataset` under these options: the free parameters, the
    /// loss, and the start values of [`RunOptions::start_from`].
    pub fn problem(&self, dataset: &Dataset) -> Result<Problem, RunError> {
        let mut problem =
            Problem::from_dataset(dataset, self.fixed.clone()).map_err(RunError::Problem)?;
        problem.loss = self.loss;
        if let Some(previous) = &self.start_from {
            let values = previous.start_values(&dataset.model);
            problem.start_from(&values, corrected(dataset));
        }
        Ok(problem)
    }
}

/// Why a run has no result.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The dataset does not make a least-squares problem (too few corners, …).
    #[error(transparent)]
    Problem(SolveError),
    /// The solve failed.
    #[error(transparent)]
    Solve(SolveError),
    /// No backend of that name in this build.
    #[error("unknown solver '{0}'")]
    UnknownSolver(String),
}

/// Where a run comes from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Provenance {
    /// The dataset directory, as named.
    pub dataset: PathBuf,
    /// The naocalib version that made the run.
    pub version: &'static str,
    /// How the run's calibration came to be: [`Origin::Solved`] for a run solved here.
    pub origin: Origin,
}

/// One calibration run: the solution of a dataset and all that is said of it.
#[derive(Debug, Clone)]
pub struct Run {
    /// Where it comes from.
    pub provenance: Provenance,
    /// The fit: values, uncertainty, residuals, diagnosis.
    pub solution: Solution,
    /// The calibration robot files carry: the solution's, with the dataset's joint-angle
    /// source and the lying torques its standing leg offsets rest on.
    pub calibration: Calibration,
    /// The robot's previous calibration it started from (`--start-from`); its
    /// [`Calibration::origin`] says whether it was imported from the robot's files.
    pub start_from: Option<Calibration>,
    /// The change since [`Run::start_from`], parameter by parameter.
    pub changes: Option<Vec<Change>>,
    /// Each camera whose intrinsics the run calibrated, with the previous calibration's
    /// ([`Run::start_from`]); empty with the intrinsics held.
    pub intrinsics: Vec<CameraIntrinsics>,
    /// The dataset's true parameters (simulated datasets), internal units.
    pub truth: Option<[f64; PARAMETER_COUNT]>,
    /// Which board each capture shows (for plots).
    pub sides: BTreeMap<u64, Side>,
}

/// Whether the dataset's joint angles were already corrected by the robot's joint
/// calibration.
fn corrected(dataset: &Dataset) -> bool {
    dataset.angles.kind == AngleKind::Corrected
}

/// Solves `dataset` with `options` into its run: the library's `naocalib solve`.
pub fn calibrate(dataset: &Dataset, options: &RunOptions) -> Result<Run, RunError> {
    let backend = crate::solve::backend(&options.solver, options.verbose)
        .ok_or_else(|| RunError::UnknownSolver(options.solver.clone()))?;
    let problem = options.problem(dataset)?;
    let solution = crate::solve::calibrate(&problem, backend.as_ref(), &options.uncertainty)
        .map_err(RunError::Solve)?;
    Ok(Run::new(dataset, solution, options.start_from.clone()))
}

impl Run {
    /// The run of `solution`, fitted to `dataset` (from `start_from`, when given).
    pub fn new(dataset: &Dataset, solution: Solution, start_from: Option<Calibration>) -> Self {
        let mut calibration = Calibration::from_solution(&solution, Some(&dataset.dir))
            .with_lying_torques(dataset)
            .with_cameras(&dataset.model);
        calibration.angles = Some(dataset.angles.clone());
        let changes = start_from
            .as_ref()
            .map(|previous| changes(&solution, previous, corrected(dataset), &dataset.model));
        let intrinsics = intrinsics_of(&calibration, start_from.as_ref(), &dataset.model);
        Run {
            provenance: Provenance {
                dataset: dataset.dir.clone(),
                version: env!("CARGO_PKG_VERSION"),
                origin: calibration.origin,
            },
            calibration,
            start_from,
            changes,
            intrinsics,
            truth: dataset.truth.as_ref().map(|t| t.values),
            sides: dataset.captures.iter().map(|c| (c.id, c.side)).collect(),
            solution,
        }
    }

    /// The dataset directory.
    pub fn dataset(&self) -> &Path {
        &self.provenance.dataset
    }

    /// The true parameters (internal units), when the dataset has them.
    pub fn truth(&self) -> Option<&[f64]> {
        self.truth.as_ref().map(|t| &t[..])
    }
}
