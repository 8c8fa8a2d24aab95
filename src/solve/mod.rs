//! Solving the calibration: the [`Problem`], the backends, and the [`Solution`] with its
//! uncertainty and diagnosis. docs/MODEL.md §13 maps these files to the model's sections.
//!
//! - [`problem`]: the least-squares [`Problem`] a backend sees, made from a dataset;
//! - `check`: whether a problem can be solved ([`validate`]), one wording per error;
//! - `backend`: the [`Backend`] contract and registry ([`backend`], [`backend_names`]),
//!   the checked run of a backend that every fit goes through, [`retain_freed_memory`];
//!   the backends themselves in `ceres` (C++ Ceres, feature `ceres`), [`lm`] and [`tiny`];
//! - `pipeline`: [`calibrate`], the one pipeline, as named stages — hold the undetermined
//!   parameters ([`identify`]), the robust fit, the plain fit, the misfit tests
//!   ([`misfit`]), the noise model's rounds ([`noise`]), the statistics ([`uncertainty`],
//!   [`covariance`]) — and `--model auto`'s choice of families ([`ModelChoice::Auto`]);
//! - `result`: the [`Solution`], its [`Summary`] and [`SolveError`];
//! - [`jacobian`]: residuals and exact Jacobians in Rust, for the pure-Rust backends and
//!   the statistics; [`linearisation`]: one evaluation of every capture at a fit, which the
//!   misfit tests, the noise model and the statistics share, and their normal equations;
//!   [`compare`]: every backend on one problem.

mod backend;
#[cfg(feature = "ceres")]
pub mod ceres;
mod check;
pub mod compare;
pub mod covariance;
pub mod identify;
pub mod jacobian;
pub mod linearisation;
pub mod lm;
pub mod misfit;
pub mod noise;
mod pipeline;
pub mod problem;
mod result;
pub mod tiny;
pub mod uncertainty;

pub(crate) use backend::fit;
pub use backend::{Backend, BackendResult, backend, backend_names, retain_freed_memory};
pub use check::validate;
pub use identify::Undetermined;
pub use misfit::{FamilyTest, Misfit};
pub use pipeline::{ModelChoice, OUTLIER_SIGMAS, UncertaintyOptions, calibrate};
pub use problem::{CaptureTerm, Loss, Observation, Problem, Tolerances, Whitening};
pub use result::{BootstrapStd, Outlier, Solution, SolveError, Summary, VertexResidual};
