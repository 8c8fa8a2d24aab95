//! The Ceres backend: the one `cxx` bridge to the C++ shim in `cpp/ceres_shim.{h,cc}`.
//!
//! Rust ships each capture's chains as data (elementary transforms, with the held parameters
//! already frozen) plus the observed vertices; the shim evaluates the transform list on Jets
//! in an autodiff cost function. Everything that could trip a glog CHECK is validated in
//! Rust first (see [`super::validate`]); C++ exceptions come back as `Err`.

#[cxx::bridge(namespace = "naocalib")]
pub mod ffi {
    /// One elementary transform of a chain.
    /// `kind`: 0 = fixed transform (`rotation`, `translation`), 1 = rotation about `axis`,
    /// 2 = translation along `axis`; for 1 and 2 the amount is
    /// `constant + scale · free[param]` (`param` = −1: constant only).
    /// `axis`: 0 = x, 1 = y, 2 = z.
    #[derive(Debug, Clone)]
    struct FfiStep {
        kind: u8,
        axis: u8,
        constant: f64,
        param: i32,
        scale: f64,
        rotation: [f64; 9],
        translation: [f64; 3],
    }

    /// One capture: its camera chain is `steps[first_step .. first_step + camera_steps]`,
    /// its board chain the `board_steps` steps after that; its vertices are
    /// `points[3·first_vertex ..]` / `pixels[2·first_vertex ..]`, `vertex_count` of them.
    /// `first_weight` indexes `weights` for a row-major (2·vertex_count)² whitening matrix,
    /// or is −1 for none.
    #[derive(Debug, Clone)]
    struct FfiCapture {
        first_step: u32,
        camera_steps: u32,
        board_steps: u32,
        first_vertex: u32,
        vertex_count: u32,
        first_weight: i64,
    }

    /// The whole problem over the free parameters.
    #[derive(Debug, Clone)]
    struct FfiProblem {
        /// Start values of the free parameters.
        params: Vec<f64>,
        /// Parameter block of each free parameter (parameters sharing an id form one block).
        param_block: Vec<u32>,
        steps: Vec<FfiStep>,
        captures: Vec<FfiCapture>,
        /// Board-frame vertex positions, 3 per vertex [mm].
        points: Vec<f64>,
        /// Observed pixels, 2 per vertex.
        pixels: Vec<f64>,
        /// Whitening matrices, concatenated.
        weights: Vec<f64>,
        /// fx, fy, cx, cy, k1, k2, p1, p2, k3.
        camera: [f64; 9],
    }

    /// Solver settings. `loss`: 0 = none, 1 = Huber, 2 = Cauchy (per vertex, `loss_scale` px).
    #[derive(Debug, Clone)]
    struct FfiOptions {
        max_iterations: u32,
        function_tolerance: f64,
        gradient_tolerance: f64,
        parameter_tolerance: f64,
        loss: u8,
        loss_scale: f64,
        covariance: bool,
        verbose: bool,
    }

    /// What a solve returns. `covariance` is row-major n×n over the free parameters,
    /// `(JᵀJ)⁺` of the weighted problem, unscaled; empty when `covariance_ok` is false.
    #[derive(Debug, Clone)]
    struct FfiSolution {
        params: Vec<f64>,
        covariance: Vec<f64>,
        covariance_ok: bool,
        iterations: u32,
        initial_cost: f64,
        final_cost: f64,
        converged: bool,
        termination: String,
        seconds: f64,
    }

    /// Residuals (weighted as in the solve) and the dense row-major Jacobian over the free
    /// parameters, at given values.
    #[derive(Debug, Clone)]
    struct FfiEvaluation {
        cost: f64,
        residuals: Vec<f64>,
        jacobian: Vec<f64>,
    }

    unsafe extern "C++" {
        include!("naocalib/cpp/ceres_shim.h");

        /// Runs Levenberg–Marquardt (dense QR) from `problem.params`.
        fn solve(problem: &FfiProblem, options: &FfiOptions) -> Result<FfiSolution>;

        /// Evaluates residuals and Jacobian at `params` (free parameters).
        fn evaluate(problem: &FfiProblem, params: &[f64]) -> Result<FfiEvaluation>;
    }
}
