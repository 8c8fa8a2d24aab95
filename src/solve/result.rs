//! What a calibration returns: the [`Solution`] with its uncertainty and diagnosis, the
//! optimiser's [`Summary`], and why a solve could not be done ([`SolveError`]).

use nalgebra::DMatrix;

use super::{FamilyTest, Misfit, Undetermined, noise, uncertainty};
use crate::model::{Family, FixedSet, PARAMETER_COUNT, Param};

/// Why a solve could not be done.
#[derive(Debug, thiserror::Error)]
pub enum SolveError {
    /// The problem cannot be solved as posed (checked before any backend runs).
    #[error("{0}")]
    Invalid(String),
    /// The backend itself failed (a C++ exception, a numerical failure).
    #[error("{solver} failed: {message}")]
    Backend {
        /// Which backend.
        solver: String,
        /// What it said.
        message: String,
    },
}

/// The optimiser's account of a run.
#[derive(Debug, Clone, PartialEq)]
pub struct Summary {
    /// Backend name (`ceres`, …).
    pub solver: String,
    /// Whether the backend reports convergence.
    pub converged: bool,
    /// Iterations taken.
    pub iterations: usize,
    /// `½‖r‖²` at the start (weighted residuals, robust loss applied).
    pub initial_cost: f64,
    /// `½‖r‖²` at the end.
    pub final_cost: f64,
    /// The backend's termination reason, in its words.
    pub termination: String,
    /// Wall time of the optimisation and covariance (s).
    pub seconds: f64,
}

/// A calibration result: parameters with their uncertainty, and how well the model fits.
#[derive(Debug, Clone, PartialEq)]
pub struct Solution {
    /// The optimiser's summary.
    pub summary: Summary,
    /// All parameter values, internal units (rad / mm).
    pub values: [f64; PARAMETER_COUNT],
    /// One-sigma uncertainty of every parameter, internal units; 0 for held parameters.
    pub std: [f64; PARAMETER_COUNT],
    /// Covariance of all parameters (PARAMETER_COUNT²), internal units; zero rows and
    /// columns for held parameters.
    pub covariance: DMatrix<f64>,
    /// Which parameters were held fixed.
    pub fixed: FixedSet,
    /// RMS of the unweighted residuals in u and v (px) at the solution.
    pub rms_px: [f64; 2],
    /// RMS in u and v at the start values (px).
    pub initial_rms_px: [f64; 2],
    /// Number of observed vertices.
    pub observations: usize,
    /// Number of captures with at least one vertex.
    pub captures: usize,
    /// Estimated residual variance `σ̂² = 2·cost / (m − n)` of the weighted residuals.
    pub residual_variance: f64,
    /// Wall time of the whole solve including the statistics (s).
    pub seconds: f64,
    /// Every observed vertex's residual (projection − observation) before and after.
    pub residuals: Vec<VertexResidual>,
    /// The noise levels the uncertainty is based on (estimated or given); `None` when the
    /// plain `σ̂²(JᵀJ)⁻¹` was used.
    pub noise: Option<noise::NoiseLevels>,
    /// One-sigma from the capture-clustered sandwich (internal units), beside `std`.
    pub sandwich_std: Option<[f64; PARAMETER_COUNT]>,
    /// One-sigma from the capture bootstrap, when asked for.
    pub bootstrap: Option<BootstrapStd>,
    /// What the data determine, and what not.
    pub identifiability: uncertainty::Identifiability,
    /// Vertices the robust first fit flagged as outliers and left out (with `--loss`).
    pub outliers: Vec<Outlier>,
    /// The families with free parameters in this fit.
    pub families: Vec<Family>,
    /// Free parameters the data cannot tell apart from others: held at their nominal value
    /// (zero std, `undetermined` in the JSON), with the combination they form.
    pub undetermined: Vec<Undetermined>,
    /// Whether the model explains the data, and what to free if not.
    pub misfit: Misfit,
    /// With [`ModelChoice::Auto`](super::ModelChoice::Auto): the tests of the families that were freed, in the order
    /// they were chosen.
    pub chosen: Vec<FamilyTest>,
}

/// A vertex whose residual after the robust fit is far beyond the noise.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Outlier {
    /// The capture id.
    pub capture: u64,
    /// Which vertex.
    pub vertex: crate::model::Vertex,
    /// Its `(u, v)` residual at the robust fit (px).
    pub residual: [f64; 2],
}

/// The capture bootstrap's one-sigma.
#[derive(Debug, Clone, PartialEq)]
pub struct BootstrapStd {
    /// One-sigma of every parameter, internal units.
    pub std: [f64; PARAMETER_COUNT],
    /// Refits done.
    pub replicates: usize,
    /// Refits that failed or did not converge (left out).
    pub failed: usize,
}

impl Solution {
    /// The held (undetermined) parameters whose direction moves the reported parameter `p`
    /// by more than its σ per unit (px, deg, mm) they are off, each with how much: `p`'s
    /// estimate is off by `ratio × (held value − truth)` (report units of `p` per report
    /// unit of the held one). `p`'s σ assumes each held at its nominal value and leaves
    /// that error out: it is not honest unless the held one is known. Empty for a fixed
    /// or undetermined `p`.
    pub fn held_trade_offs(&self, p: Param) -> Vec<(Param, f64)> {
        if self.fixed.is_fixed(p) || !self.is_determined(p) {
            return Vec::new();
        }
        let sigma = self.report_std(p);
        self.undetermined
            .iter()
            .filter(|u| u.param != p)
            .filter_map(|u| {
                let terms = &u.direction.terms;
                let own = terms.iter().find(|t| t.0 == u.param)?.1;
                let c = terms.iter().find(|t| t.0 == p)?.1;
                let ratio = c / own;
                (own != 0.0 && ratio.abs() > sigma).then_some((u.param, ratio))
            })
            .collect()
    }

    /// Whether the data determine `p` (a held parameter counts as determined).
    pub fn is_determined(&self, p: Param) -> bool {
        !self.undetermined.iter().any(|u| u.param == p)
            && self
                .identifiability
                .determined
                .get(p.index())
                .copied()
                .unwrap_or(true)
    }

    /// Whether this is a calibration one may use: the optimiser converged to finite
    /// values within the physical bounds ([`Solution::out_of_bounds`]) and the residuals
    /// are within any plausible noise ([`super::misfit::IMPLAUSIBLE_RMS_PX`]).
    pub fn is_calibration(&self) -> bool {
        self.summary.converged
            && self.values.iter().all(|v| v.is_finite())
            && self
                .rms_px
                .iter()
                .all(|r| *r <= super::misfit::IMPLAUSIBLE_RMS_PX)
            && self.out_of_bounds().is_empty()
    }

    /// The parameters whose value is outside its physical bound
    /// ([`crate::model::bounds`]): such a fit is no calibration, whatever its residuals.
    pub fn out_of_bounds(&self) -> Vec<crate::model::bounds::Violation> {
        crate::model::bounds::violations_internal(&self.values, Some(&self.std), Param::ALL)
    }
}

/// The residual of one observed vertex at the start values and at the solution (px).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VertexResidual {
    /// The capture id.
    pub capture: u64,
    /// Which vertex.
    pub vertex: crate::model::Vertex,
    /// `(u, v)` residual at the start values.
    pub initial: [f64; 2],
    /// `(u, v)` residual at the solution.
    pub solved: [f64; 2],
}

impl Solution {
    /// Value of one parameter in report units (deg / mm).
    pub fn report_value(&self, p: Param) -> f64 {
        p.unit().to_report(self.values[p.index()])
    }

    /// One-sigma of one parameter in report units (deg / mm).
    pub fn report_std(&self, p: Param) -> f64 {
        p.unit().to_report(self.std[p.index()])
    }
}
