//! The one `cxx` bridge to the C++ shim in `cpp/ceres_shim.{h,cc}`: the shared structs and
//! the two entry points, nothing else. It is alone in this file because `build.rs` compiles
//! the C++ translation unit again whenever the bridge's file changes; the Rust around it
//! (`super`) can change without that.
//!
//! Everything that could trip a glog CHECK is validated in Rust first; C++ exceptions come
//! back as `Err`.

#[cxx::bridge(namespace = "naocalib")]
pub mod ffi {
    /// What an elementary transform does.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    enum StepKind {
        /// A constant transform (`rotation`, `translation`).
        Fixed,
        /// A rotation about `axis` by `amount` (rad).
        Rotate,
        /// A translation along `axis` by `amount` (mm).
        Translate,
    }

    /// A local coordinate axis.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    enum StepAxis {
        /// x.
        X,
        /// y.
        Y,
        /// z.
        Z,
    }

    /// How each Levenberg–Marquardt step's linear least-squares problem is solved.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    enum LinearSolver {
        /// Householder QR of the dense Jacobian (never squares its condition number).
        DenseQr,
        /// Cholesky of the normal equations `JᵀJ` (about half the flops of QR).
        DenseNormalCholesky,
    }

    /// The robust loss per vertex.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    enum LossKind {
        /// Plain least squares.
        Squared,
        /// Huber with `loss_scale` (px).
        Huber,
        /// Cauchy with `loss_scale` (px).
        Cauchy,
    }

    /// `constant + Σ scales[k] · free[params[k]]` over the entries with `params[k] ≥ 0`
    /// (−1: unused).
    #[derive(Debug, Clone, Copy)]
    struct FfiAmount {
        constant: f64,
        params: [i32; 3],
        scales: [f64; 3],
    }

    /// One elementary transform of a chain.
    #[derive(Debug, Clone)]
    struct FfiStep {
        kind: StepKind,
        axis: StepAxis,
        amount: FfiAmount,
        rotation: [f64; 9],
        translation: [f64; 3],
    }

    /// The projection: `u = cx + fx·a'`, `v = cy + fy·b'` with OpenCV distortion of the
    /// normalised coordinates when `distorted`.
    #[derive(Debug, Clone)]
    struct FfiProjection {
        fx: FfiAmount,
        fy: FfiAmount,
        cx: FfiAmount,
        cy: FfiAmount,
        k1: FfiAmount,
        k2: FfiAmount,
        p1: f64,
        p2: f64,
        k3: f64,
        distorted: bool,
    }

    /// One capture: its camera chain is `steps[first_step .. first_step + camera_steps]`,
    /// its board chain the `board_steps` steps after that; its camera's projection is
    /// `projections[projection]`; its vertices are
    /// `points[3·first_vertex ..]` / `pixels[2·first_vertex ..]`, `vertex_count` of them.
    /// `first_weight` indexes `weights` for the capture's whitening `W` (m = 2·vertex_count
    /// rows), or is −1 for none. With `whitening_rank` −1, `W` is dense: m² numbers, row
    /// major. With `whitening_rank` q ≥ 0, `W = scale·(I − U·diag(shrink)·Uᵀ)`, stored as
    /// `scale`, then `U` (m × q, row major), then `shrink` (q): 1 + m·q + q numbers.
    #[derive(Debug, Clone)]
    struct FfiCapture {
        first_step: u32,
        camera_steps: u32,
        board_steps: u32,
        projection: u32,
        first_vertex: u32,
        vertex_count: u32,
        first_weight: i64,
        whitening_rank: i32,
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
        /// Board-frame vertex positions, 3 per vertex (mm).
        points: Vec<f64>,
        /// Observed pixels, 2 per vertex.
        pixels: Vec<f64>,
        /// Whitenings, concatenated (see `FfiCapture`).
        weights: Vec<f64>,
        /// The cameras' projections (one per distinct projection of the captures).
        projections: Vec<FfiProjection>,
    }

    /// Solver settings.
    #[derive(Debug, Clone)]
    struct FfiOptions {
        max_iterations: u32,
        function_tolerance: f64,
        gradient_tolerance: f64,
        parameter_tolerance: f64,
        loss: LossKind,
        loss_scale: f64,
        linear_solver: LinearSolver,
        verbose: bool,
    }

    /// What a solve returns: the free parameters' values and the run's summary.
    #[derive(Debug, Clone)]
    struct FfiSolution {
        params: Vec<f64>,
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

        /// Runs Levenberg–Marquardt from `problem.params`.
        fn solve(problem: &FfiProblem, options: &FfiOptions) -> Result<FfiSolution>;

        /// Evaluates residuals and Jacobian at `params` (free parameters).
        fn evaluate(problem: &FfiProblem, params: &[f64]) -> Result<FfiEvaluation>;
    }
}
