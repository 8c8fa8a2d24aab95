//! The Ceres backend against the Rust model: residuals, Jacobians, recovery of the truth,
//! held parameters and a rank-deficient problem.
//!
//! Problems are built directly from the model (random stances around docs/MODEL.md §12 poses
//! B and C, random true parameters, noise-free observations), so these tests depend on
//! nothing but `model` and `solve`.

use crate::util::brute_force_jacobian as rust_jacobian;
use crate::util::solve;
use nalgebra::{DMatrix, DVector, Dyn, U1};
use naocalib::model::{
    Camera, FixedSet, JOINT_COUNT, JointAngles, Model, PAPER_PARAMETERS, PARAMETER_COUNT, Param,
    Side, Vertex,
};
use naocalib::solve::ceres::{Ceres, evaluate};
use naocalib::solve::{CaptureTerm, Loss, Observation, Problem, SolveError, Tolerances, Whitening};
use num_dual::{Derivative, DualDVec64};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// docs/MODEL.md §12 pose B (left board in view), in `Joint::ALL` order.
const POSE_B: [f64; JOINT_COUNT] = [
    0.58, 0.422, 0.119, 0.761, -0.503, 1.694, -0.893, 0.647, 0.119, 0.235, -0.888, 1.285, 0.607,
    0.061,
];
/// docs/MODEL.md §12 pose C (right board in view).
const POSE_C: [f64; JOINT_COUNT] = [
    -0.582, 0.222, -0.287, -0.046, -0.457, 1.241, -0.873, 0.292, -0.287, 0.342, -0.462, 0.354,
    -1.096, -0.519,
];

/// Largest joint perturbation around poses B and C [rad]: enough variety for all 21
/// parameters to be well determined, small enough to keep the board in the image.
const STANCE_SPREAD: f64 = 0.15;

/// Random parameters: up to `deg` degrees for angles and `mm` millimetres for lengths, for
/// the paper's 21 parameters (the rest stay zero).
fn random_parameters(rng: &mut ChaCha8Rng, deg: f64, mm: f64) -> [f64; PARAMETER_COUNT] {
    let mut p = [0.0; PARAMETER_COUNT];
    for (i, param) in Param::ALL.iter().take(PAPER_PARAMETERS).enumerate() {
        let limit = match param.unit() {
            naocalib::model::Unit::Deg => deg.to_radians(),
            _ => mm,
        };
        p[i] = rng.random_range(-limit..=limit);
    }
    p
}

/// A stance around `base` whose whole board projects into the image (with a margin) both
/// at zero parameters and at the truth.
fn random_stance(
    rng: &mut ChaCha8Rng,
    model: &Model,
    side: Side,
    base: &[f64; JOINT_COUNT],
    truth: &[f64],
) -> JointAngles {
    let vertices: Vec<Vertex> = model.board.vertices().collect();
    for _ in 0..1000 {
        let joints =
            JointAngles(base.map(|q| q + rng.random_range(-STANCE_SPREAD..=STANCE_SPREAD)));
        let chains = model.chains(side, &joints);
        let visible = |params: &[f64]| {
            model
                .project(&chains, params, &vertices)
                .iter()
                .all(|uv| uv.is_some_and(|uv| model.camera.contains(uv, 10.0)))
        };
        if visible(&[0.0; PARAMETER_COUNT]) && visible(truth) {
            return joints;
        }
    }
    panic!("no stance around the base pose keeps the board in view");
}

/// One capture with all 24 vertices observed exactly where the model at `truth` puts them.
fn capture(model: &Model, id: u64, side: Side, joints: &JointAngles, truth: &[f64]) -> CaptureTerm {
    let chains = model.chains(side, joints);
    let vertices: Vec<Vertex> = model.board.vertices().collect();
    let pixels = model.project(&chains, truth, &vertices);
    let observations = vertices
        .iter()
        .zip(pixels)
        .map(|(v, uv)| Observation {
            vertex: *v,
            point: model.board.vertex_position(*v),
            pixel: uv.expect("vertex in front of the camera"),
        })
        .collect();
    CaptureTerm {
        capture: id,
        chains,
        observations,
        whitening: None,
    }
}

/// A noise-free problem: `per_side` captures of each side in `sides`, all parameters
/// starting at zero.
fn make_problem(
    seed: u64,
    camera: Camera,
    sides: &[Side],
    per_side: usize,
) -> (Problem, [f64; PARAMETER_COUNT]) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let model = Model {
        camera,
        ..Model::default()
    };
    let truth = random_parameters(&mut rng, 3.0, 3.0);
    let mut captures = Vec::new();
    for &side in sides {
        let base = if side == Side::Left { &POSE_B } else { &POSE_C };
        for _ in 0..per_side {
            let joints = random_stance(&mut rng, &model, side, base, &truth);
            captures.push(capture(
                &model,
                captures.len() as u64,
                side,
                &joints,
                &truth,
            ));
        }
    }
    let problem = Problem {
        camera,
        captures,
        initial: [0.0; PARAMETER_COUNT],
        fixed: FixedSet::default(),
        loss: Loss::Squared,
        tolerances: Tolerances::default(),
    };
    (problem, truth)
}

/// A camera with noticeable OpenCV distortion.
fn distorted_camera() -> Camera {
    Camera {
        distortion: [-0.08, 0.03, 0.0015, -0.0008, -0.004],
        ..Camera::default()
    }
}

/// Gives every capture a random, well-conditioned whitening matrix `I + 0.3·N/√m`.
fn add_whitening(problem: &mut Problem, seed: u64) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    for c in &mut problem.captures {
        let m = c.residual_count();
        let scale = 0.3 / (m as f64).sqrt();
        c.whitening = Some(Whitening::Dense(DMatrix::from_fn(m, m, |i, j| {
            f64::from(u8::from(i == j)) + scale * rng.random_range(-1.0..=1.0)
        })));
    }
}

/// Gives every capture a random whitening of the noise model's low-rank form
/// `s·(I − U·diag(shrink)·Uᵀ)`, with 5 orthonormal directions.
fn add_low_rank_whitening(problem: &mut Problem, seed: u64) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    for c in &mut problem.captures {
        let m = c.residual_count();
        let random = DMatrix::from_fn(m, 5, |_, _| rng.random_range(-1.0..=1.0));
        c.whitening = Some(Whitening::LowRank {
            u: random.qr().q(),
            shrink: DVector::from_fn(5, |_, _| rng.random_range(0.0..0.95)),
            scale: rng.random_range(0.5..10.0),
        });
    }
}

/// Random free-parameter values: a few degrees / mm for the paper's parameters, ±0.01 (in
/// internal units) for the extended ones.
fn random_free(problem: &Problem, rng: &mut ChaCha8Rng) -> Vec<f64> {
    let mut all = random_parameters(rng, 4.0, 4.0);
    for x in all.iter_mut().skip(PAPER_PARAMETERS) {
        *x = rng.random_range(-0.01..=0.01);
    }
    problem.free().iter().map(|p| all[p.index()]).collect()
}

/// The Rust residuals at `free_values`, in `f64`.
fn rust_residuals(problem: &Problem, free_values: &[f64]) -> Vec<f64> {
    let all = problem.expand(free_values);
    problem
        .captures
        .iter()
        .flat_map(|c| c.weighted_residuals::<f64>(&all).expect("in front"))
        .collect()
}

fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// max |a − b| / max(1, |b|).
fn max_rel_diff(a: &DMatrix<f64>, b: &DMatrix<f64>) -> f64 {
    assert_eq!(a.shape(), b.shape());
    a.iter()
        .zip(b.iter())
        .map(|(x, y)| (x - y).abs() / y.abs().max(1.0))
        .fold(0.0, f64::max)
}

/// Compares residuals and Jacobians of Ceres and Rust at several random points.
fn check_agreement(problem: &Problem, seed: u64, what: &str) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut worst_r: f64 = 0.0;
    let mut worst_j: f64 = 0.0;
    for _ in 0..5 {
        let x = random_free(problem, &mut rng);
        let (r, j) = evaluate(problem, &x).expect("Ceres evaluates");
        assert_eq!(r.len(), problem.residual_count());
        assert_eq!(j.shape(), (problem.residual_count(), problem.free().len()));
        let plain = rust_residuals(problem, &x);
        let (dual_r, dual_j) = rust_jacobian(problem, &x);
        assert!(
            max_abs_diff(&plain, &dual_r) < 1e-12,
            "{what}: dual values differ from f64"
        );
        worst_r = worst_r.max(max_abs_diff(&r, &plain));
        worst_j = worst_j.max(max_rel_diff(&j, &dual_j));
    }
    println!(
        "{what}: max |residual diff| = {worst_r:.3e} px, max Jacobian rel diff = {worst_j:.3e}"
    );
    assert!(
        worst_r <= 1e-9,
        "{what}: residuals differ by {worst_r:e} px"
    );
    assert!(
        worst_j <= 1e-7,
        "{what}: Jacobians differ by {worst_j:e} (relative)"
    );
}

#[test]
fn residuals_and_jacobians_agree() {
    let (problem, _) = make_problem(1, Camera::default(), &Side::BOTH, 4);
    check_agreement(&problem, 11, "plain");
}

#[test]
fn residuals_and_jacobians_agree_with_whitening_and_distortion() {
    let (mut problem, _) = make_problem(2, Camera::default(), &Side::BOTH, 4);
    add_whitening(&mut problem, 21);
    check_agreement(&problem, 22, "whitened");

    let (problem, _) = make_problem(3, distorted_camera(), &Side::BOTH, 4);
    check_agreement(&problem, 31, "distorted");

    let (mut problem, _) = make_problem(4, distorted_camera(), &Side::BOTH, 4);
    add_whitening(&mut problem, 41);
    check_agreement(&problem, 42, "whitened + distorted");

    let (mut problem, _) = make_problem(6, Camera::default(), &Side::BOTH, 4);
    add_low_rank_whitening(&mut problem, 61);
    check_agreement(&problem, 62, "low-rank whitened");
}

/// Every family free: joint angles of three terms (offset, compliance, play), free
/// intrinsics and distortion, link lengths; whitened. (The lower camera's captures only: the
/// upper camera's intrinsics stay held.)
#[test]
fn residuals_and_jacobians_agree_on_the_extended_model() {
    let (mut problem, _) = make_problem(8, distorted_camera(), &Side::BOTH, 4);
    problem.fixed = FixedSet::from_lists(&crate::util::every_family(), "").expect("families");
    let upper_projection = Param::ALL
        .iter()
        .filter(|p| p.is_upper_projection())
        .count();
    assert_eq!(problem.free().len(), PARAMETER_COUNT - upper_projection);
    check_agreement(&problem, 81, "extended");
    add_low_rank_whitening(&mut problem, 82);
    check_agreement(&problem, 83, "extended + low-rank whitened");
}

#[test]
fn jacobian_agrees_with_held_parameters() {
    let (mut problem, _) = make_problem(5, Camera::default(), &Side::BOTH, 3);
    problem.fixed = FixedSet::with(&[Param::CamYaw, Param::LKneePitch, Param::RBoardTransY]);
    problem.initial[Param::CamYaw.index()] = 0.02;
    problem.initial[Param::LKneePitch.index()] = -0.01;
    problem.initial[Param::RBoardTransY.index()] = 1.5;
    // Free the head joints too: a block that is not part of the paper's parameters.
    problem.fixed.set(Param::HeadYaw, false);
    check_agreement(&problem, 51, "held + head free");
}

/// Asserts that the free parameters of `solution` match `truth` to `tol` (deg / mm).
fn assert_recovered(solution: &naocalib::solve::Solution, truth: &[f64], tol: f64) -> f64 {
    let mut worst: f64 = 0.0;
    for p in Param::ALL.iter().take(PAPER_PARAMETERS) {
        let err = (solution.report_value(*p) - p.unit().to_report(truth[p.index()])).abs();
        assert!(err <= tol, "{p}: off by {err:e} {}", p.unit().name());
        worst = worst.max(err);
    }
    worst
}

#[test]
fn noise_free_solve_recovers_the_truth() {
    let (problem, truth) = make_problem(7, Camera::default(), &Side::BOTH, 8);
    let solution = solve(&problem, &Ceres { verbose: false }).expect("solves");
    assert!(
        solution.summary.converged,
        "{}",
        solution.summary.termination
    );
    assert_eq!(solution.summary.solver, "ceres");
    let worst = assert_recovered(&solution, &truth, 1e-6);
    println!(
        "recovery: max error {worst:.3e} deg|mm after {} iterations, Ceres {:.4} s, solve {:.4} s \
         ({}); cost {:.3e} -> {:.3e}",
        solution.summary.iterations,
        solution.summary.seconds,
        solution.seconds,
        solution.summary.termination,
        solution.summary.initial_cost,
        solution.summary.final_cost
    );

    // The covariance from Ceres' Jacobian at the solution is (JᵀJ)⁻¹ of the Rust Jacobian.
    let free = problem.free();
    let x: Vec<f64> = free.iter().map(|p| solution.values[p.index()]).collect();
    let (_, ceres_j) = evaluate(&problem, &x).expect("ceres evaluates");
    let (cov, _) = naocalib::solve::covariance::from_jacobian(&ceres_j);
    let (_, j) = rust_jacobian(&problem, &x);
    let inv = (j.transpose() * &j).try_inverse().expect("JᵀJ invertible");
    let rel = cov
        .iter()
        .zip(inv.iter())
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max)
        / inv.iter().map(|v| v.abs()).fold(0.0, f64::max);
    println!("covariance vs (JᵀJ)⁻¹: max diff / max entry = {rel:.3e}");
    assert!(rel < 1e-6, "covariance differs from (JᵀJ)⁻¹ by {rel:e}");
}

#[test]
fn held_parameters_stay_put() {
    let (mut problem, truth) = make_problem(8, Camera::default(), &Side::BOTH, 8);
    let held = [Param::CamYaw, Param::LBoardRotZ];
    problem.fixed = FixedSet::with(&held);
    for p in held {
        problem.initial[p.index()] = truth[p.index()];
    }
    let solution = solve(&problem, &Ceres { verbose: false }).expect("solves");
    assert!(
        solution.summary.converged,
        "{}",
        solution.summary.termination
    );
    for p in held {
        assert_eq!(solution.values[p.index()], truth[p.index()], "{p} moved");
        assert_eq!(solution.std[p.index()], 0.0);
    }
    assert_recovered(&solution, &truth, 1e-6);
}

#[test]
fn rank_deficient_problem_does_not_crash() {
    // Left board only: the right leg and board parameters are not observed at all.
    let (problem, _) = make_problem(9, Camera::default(), &[Side::Left], 8);
    let result =
        naocalib::solve::Backend::solve(&Ceres::default(), &problem).expect("backend runs");
    assert!(result.free_values.iter().all(|v| v.is_finite()));
    println!("rank deficient: {}", result.summary.termination);

    let solution = solve(&problem, &Ceres::default()).expect("solves");
    assert!(solution.values.iter().all(|v| v.is_finite()));
    assert!(solution.std.iter().all(|v| v.is_finite()));
    assert!(solution.covariance.iter().all(|v| v.is_finite()));
    // Unobserved parameters keep their start values.
    for p in [Param::RKneePitch, Param::RBoardTransX] {
        assert_eq!(solution.values[p.index()], 0.0, "{p} moved without data");
    }

    // Worse: one stance seen eight times determines only the six degrees of freedom of
    // the board pose, not the twelve parameters of the camera, left leg and left board.
    let (mut problem, _) = make_problem(13, Camera::default(), &[Side::Left], 8);
    let first = problem.captures[0].clone();
    for c in &mut problem.captures {
        c.chains = first.chains.clone();
        c.observations = first.observations.clone();
    }
    let solution = solve(&problem, &Ceres::default()).expect("solves a singular problem");
    assert!(solution.values.iter().all(|v| v.is_finite()));
    assert!(solution.std.iter().all(|v| v.is_finite()));
    assert!(solution.covariance.iter().all(|v| v.is_finite()));
    assert!(
        solution.rms_px[0] < 1e-6 && solution.rms_px[1] < 1e-6,
        "{:?}",
        solution.rms_px
    );
    println!(
        "singular: {}, rms {:?}",
        solution.summary.termination, solution.rms_px
    );
}

#[test]
fn robust_loss_recovers_the_truth_and_rejects_whitening() {
    let (mut problem, truth) = make_problem(10, Camera::default(), &Side::BOTH, 8);
    problem.loss = Loss::Huber(1.0);
    let solution = solve(&problem, &Ceres::default()).expect("solves with Huber");
    assert!(
        solution.summary.converged,
        "{}",
        solution.summary.termination
    );
    assert_recovered(&solution, &truth, 1e-6);

    problem.loss = Loss::Cauchy(2.0);
    let solution = solve(&problem, &Ceres::default()).expect("solves with Cauchy");
    assert_recovered(&solution, &truth, 1e-6);

    add_whitening(&mut problem, 101);
    match solve(&problem, &Ceres::default()) {
        Err(SolveError::Backend { message, .. }) => assert!(message.contains("whitening")),
        other => panic!("whitening with a robust loss must be refused, got {other:?}"),
    }
}

#[test]
fn bad_input_is_an_error_not_a_crash() {
    let (problem, _) = make_problem(12, Camera::default(), &Side::BOTH, 2);
    let n = problem.free().len();
    // Wrong number of values.
    assert!(evaluate(&problem, &vec![0.0; n - 1]).is_err());
    // Not finite.
    let mut x = vec![0.0; n];
    x[0] = f64::NAN;
    assert!(evaluate(&problem, &x).is_err());
    // A camera turned so far that the board lies behind it.
    let mut x = vec![0.0; n];
    x[free_position(&problem, Param::CamPitch)] = std::f64::consts::PI;
    match evaluate(&problem, &x) {
        Err(SolveError::Backend { message, .. }) => assert!(message.contains("behind")),
        other => panic!("expected an error, got {other:?}"),
    }
}

fn free_position(problem: &Problem, p: Param) -> usize {
    problem.free().iter().position(|q| *q == p).expect("free")
}

#[test]
fn dvector_helper_is_consistent() {
    // Guards the dual-number seeding used above against a silent change in num-dual.
    let d: DualDVec64 = DualDVec64::new(2.0, Derivative::derivative_generic(Dyn(3), U1, 1));
    let y = d.clone() * d;
    assert_eq!(y.re, 4.0);
    assert_eq!(
        y.eps.unwrap_generic(Dyn(3), U1),
        DVector::from_vec(vec![0.0, 4.0, 0.0])
    );
}
