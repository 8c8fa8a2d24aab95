//! The least-squares backends: the [`Backend`] contract, the registry of the available ones
//! ([`backend_names`], [`backend`]), the checked run of one ([`fit`]) that every stage of the
//! pipeline uses, and the allocator tuning that makes repeated fits cheap.

use super::{Problem, SolveError, Summary};
use crate::model::PARAMETER_COUNT;

/// What a backend returns.
#[derive(Debug, Clone, PartialEq)]
pub struct BackendResult {
    /// Final values of the free parameters (order of [`Problem::free`]), internal units.
    pub free_values: Vec<f64>,
    /// The run's summary.
    pub summary: Summary,
}

/// A least-squares solver that can run a [`Problem`]: from the problem's start values
/// ([`Problem::initial`]), minimise `½‖r‖²` of its weighted residuals over its free
/// parameters ([`Problem::free`]) and return their values with an account of the run.
/// Everything else — outliers, the misfit tests, the noise model, the uncertainty — is the
/// pipeline's ([`super::calibrate`]), the same for every backend. A problem reaches a
/// backend only after [`super::validate`]: it has more residuals than free parameters, and
/// every vertex lies in front of the camera at the start values.
///
/// A backend in a few lines — undamped Gauss–Newton steps on the Jacobian that
/// [`super::jacobian::Evaluator`] provides — and a calibration with it:
///
/// ```
/// use naocalib::model::{FixedSet, Model, Param};
/// use naocalib::sim::{SimOptions, simulate};
/// use naocalib::solve::jacobian::Evaluator;
/// use naocalib::solve::{
///     Backend, BackendResult, Problem, SolveError, Summary, UncertaintyOptions, calibrate,
/// };
///
/// /// Eight Gauss–Newton steps from the start values.
/// struct GaussNewton;
///
/// impl Backend for GaussNewton {
///     fn name(&self) -> &'static str {
///         "gauss-newton"
///     }
///
///     fn solve(&self, problem: &Problem) -> Result<BackendResult, SolveError> {
///         let fail = |message: &str| SolveError::Backend {
///             solver: self.name().into(),
///             message: message.into(),
///         };
///         let eval = Evaluator::new(problem);
///         let mut x: Vec<f64> = eval.free().iter().map(|p| problem.initial[p.index()]).collect();
///         let behind = || fail("a vertex is behind the camera");
///         let initial_cost = eval.cost(&x).ok_or_else(behind)?;
///         for _ in 0..8 {
///             let (r, j) = eval.residuals_and_jacobian(&x).ok_or_else(behind)?;
///             let normal = (j.transpose() * &j).cholesky().ok_or_else(|| fail("singular"))?;
///             let step = normal.solve(&(j.transpose() * r));
///             x.iter_mut().zip(step.iter()).for_each(|(xi, s)| *xi -= s);
///         }
///         let final_cost = eval.cost(&x).ok_or_else(behind)?;
///         Ok(BackendResult {
///             free_values: x,
///             summary: Summary {
///                 solver: self.name().into(),
///                 converged: true,
///                 iterations: 8,
///                 initial_cost,
///                 final_cost,
///                 termination: "8 Gauss–Newton steps".into(),
///                 seconds: 0.0,
///             },
///         })
///     }
/// }
///
/// let options = SimOptions { stances: 6, heads: 2, ..SimOptions::default() };
/// let dataset = simulate(&Model::default(), &options).unwrap();
/// let problem = Problem::from_dataset(&dataset, FixedSet::default()).unwrap();
/// let solution = calibrate(&problem, &GaussNewton, &UncertaintyOptions::default()).unwrap();
/// let truth = &dataset.truth.as_ref().unwrap().values;
/// let error = solution.values[Param::CamPitch.index()] - truth[Param::CamPitch.index()];
/// assert!(error.abs() < 4.0 * solution.std[Param::CamPitch.index()]);
/// ```
pub trait Backend {
    /// Short name, as in `--solver` and the result JSON.
    fn name(&self) -> &'static str;
    /// Solves the problem from its initial values: the values and the run's summary. The
    /// uncertainty is not the backend's: [`super::calibrate`] computes it from the Jacobian
    /// at the final fit, the same for every backend.
    fn solve(&self, problem: &Problem) -> Result<BackendResult, SolveError>;
}

/// Names of the available backends, the default first.
pub fn backend_names() -> Vec<&'static str> {
    let mut names = Vec::new();
    if cfg!(feature = "ceres") {
        names.push("ceres");
    }
    names.extend(["lm", "tiny"]);
    names
}

/// The backend called `name` (see [`backend_names`]); `verbose` lets it log progress.
pub fn backend(name: &str, verbose: bool) -> Option<Box<dyn Backend>> {
    let _ = verbose;
    match name {
        #[cfg(feature = "ceres")]
        "ceres" => Some(Box::new(super::ceres::Ceres { verbose })),
        "lm" => Some(Box::new(super::lm::MinpackLm)),
        "tiny" => Some(Box::new(super::tiny::Tiny)),
        _ => None,
    }
}

/// Lets the C allocator keep freed memory for reuse instead of handing it back to the
/// operating system: every fit allocates and frees the same large buffers (Ceres' dense
/// Jacobian and factorisation, the Rust Jacobians), and mapping them afresh each time costs
/// page faults (docs/MODEL.md §13). Affects the whole process, which keeps up to 256 MB of
/// freed memory; the CLI calls it at start, and a program that solves many problems may
/// too. It also grows the main heap once by 32 MB and asks the kernel to back that
/// part with transparent huge pages (`madvise(MADV_HUGEPAGE)`, what glibc's
/// `glibc.malloc.hugetlb=1` tunable does): one solve touches some 10 MB of fresh heap,
/// which costs about 2500 page faults in 4 KiB pages and a handful in 2 MiB ones. Memory
/// that is never touched is not backed. Does nothing outside glibc.
pub fn retain_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only changes glibc malloc's tuning; it may be called at any time.
    // The block is allocated and freed here, never read or written; sbrk(0) only reads
    // the break; madvise only advises the kernel on pages of the heap that the allocator
    // owns (it does not change their contents or mapping).
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 64 << 20);
        libc::mallopt(libc::M_TRIM_THRESHOLD, 256 << 20);
        // Below the mmap threshold: the block comes from the main heap, which grows by it.
        let block = libc::malloc(HUGE_HEAP);
        if !block.is_null() {
            const HUGE_PAGE: usize = 2 << 20;
            let start = (block as usize).next_multiple_of(HUGE_PAGE);
            let end = libc::sbrk(0) as usize / HUGE_PAGE * HUGE_PAGE;
            if end > start {
                libc::madvise(start as *mut libc::c_void, end - start, libc::MADV_HUGEPAGE);
            }
            libc::free(block);
        }
    }
}

/// How much the main heap grows at once in [`retain_freed_memory`] (bytes): a paper-sized
/// solve's working memory with room to spare.
const HUGE_HEAP: usize = 32 << 20;

/// One optimiser run, as the pipeline's stages pass it on.
#[derive(Debug, Clone)]
pub(crate) struct Fit {
    /// All parameter values, internal units.
    pub values: [f64; PARAMETER_COUNT],
    /// The backend's summary.
    pub summary: Summary,
}

/// Runs `backend` on `problem` after [`super::validate`], and checks what it returns: one
/// value per free parameter, all finite. The covariance is not computed here: the pipeline
/// computes it once, from the Jacobian its statistics evaluate at the final fit.
pub(crate) fn fit(problem: &Problem, backend: &dyn Backend) -> Result<Fit, SolveError> {
    super::validate(problem)?;
    let result = backend.solve(problem)?;
    let free = problem.free();
    if result.free_values.len() != free.len() {
        return Err(SolveError::Backend {
            solver: backend.name().into(),
            message: format!(
                "returned {} values for {} free parameters",
                result.free_values.len(),
                free.len()
            ),
        });
    }
    let values = problem.expand(&result.free_values);
    let mut summary = result.summary;
    if values.iter().any(|v| !v.is_finite()) {
        // Nothing downstream (residuals, covariance, tests) means anything there, and an
        // eigen-decomposition of non-finite numbers does not end.
        return Err(SolveError::Backend {
            solver: backend.name().into(),
            message: "the fit diverged to non-finite parameter values".into(),
        });
    }
    // A NaN gradient can end a search "converged" at a non-finite cost.
    summary.converged &= summary.final_cost.is_finite();
    Ok(Fit { values, summary })
}
