//! The pure-Rust backends (`lm`, `tiny`) against Ceres on simulated datasets: the same
//! answer within 0.01 sigma, the same recovery of the truth, the same covariance and rank,
//! the same robust fit; and `compare` reporting solvers that fail or stop early.

use crate::util::brute_force_jacobian as brute_force;
use nalgebra::DMatrix;
use naocalib::model::{FixedSet, Model, PARAMETER_COUNT, Side};
use naocalib::sim::{SimOptions, simulate};
use naocalib::solve::covariance::{from_jacobian, rank_of_covariance};
use naocalib::solve::jacobian::Evaluator;
use naocalib::solve::{Loss, Problem, Whitening, backend_names, compare::compare};

/// A small simulated problem: `stances` stances × `heads` head postures per leg.
fn simulated(seed: u64, stances: usize, heads: usize) -> (Problem, [f64; PARAMETER_COUNT]) {
    let options = SimOptions {
        seed,
        stances,
        heads,
        ..SimOptions::default()
    };
    let dataset = simulate(&Model::default(), &options).expect("simulated");
    let truth = dataset.truth.as_ref().expect("truth").values;
    let problem = Problem::from_dataset(&dataset, FixedSet::default()).expect("problem");
    (problem, truth)
}

/// max |a − b| / max(1, |b|).
fn max_rel_diff(a: &DMatrix<f64>, b: &DMatrix<f64>) -> f64 {
    assert_eq!(a.shape(), b.shape());
    a.iter()
        .zip(b.iter())
        .map(|(x, y)| (x - y).abs() / y.abs().max(1.0))
        .fold(0.0, f64::max)
}

/// The structural Jacobian (prefix poses, no duals through the chains) on the extended
/// model: every family free, including the head, link lengths and the compliance and play
/// that share a joint's step with its offset, away from the nominal values.
#[test]
fn fast_jacobian_equals_brute_force_duals_on_the_extended_model() {
    use naocalib::model::Family;
    let options = SimOptions {
        seed: 9,
        stances: 4,
        heads: 2,
        upper_stances: 1,
        effects: vec![
            Family::Head,
            Family::Intrinsics,
            Family::Links,
            Family::Compliance,
            Family::Play,
        ],
        ..SimOptions::default()
    };
    let two_cameras = Model {
        upper_camera: Some(Model::default().camera),
        ..Model::default()
    };
    let dataset = simulate(&two_cameras, &options).expect("simulated");
    let truth = dataset.truth.as_ref().expect("truth").values;
    let mut problem = Problem::from_dataset(&dataset, FixedSet::default()).expect("problem");
    problem.fixed = FixedSet::from_lists(&crate::util::every_family(), "")
        .expect("families")
        .for_upper_camera(true);
    let free = problem.free();
    assert_eq!(free.len(), PARAMETER_COUNT);
    let x: Vec<f64> = free
        .iter()
        .enumerate()
        .map(|(i, p)| 0.8 * truth[p.index()] + 1e-3 * (i as f64 - 30.0))
        .collect();
    let eval = Evaluator::new(&problem);
    let (r, j) = eval.residuals_and_jacobian(&x).expect("in front");
    let (br, bj) = brute_force(&problem, &x);
    let r_diff = r
        .iter()
        .zip(&br)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    let j_diff = max_rel_diff(&j, &bj);
    println!("extended: residuals {r_diff:.2e}, Jacobian {j_diff:.2e}");
    assert!(r_diff < 1e-9, "residuals differ by {r_diff:e}");
    assert!(j_diff < 1e-9, "Jacobians differ by {j_diff:e}");
    // Every column is exercised: none is zero throughout.
    for (k, p) in free.iter().enumerate() {
        assert!(bj.column(k).amax() > 0.0, "{p} has no derivative");
    }
}

#[test]
fn fast_jacobian_equals_brute_force_duals() {
    let (mut problem, truth) = simulated(3, 4, 2);
    let free = problem.free();
    let x: Vec<f64> = free.iter().map(|p| 0.7 * truth[p.index()]).collect();
    for loss in [Loss::Squared, Loss::Huber(0.5), Loss::Cauchy(1.0)] {
        problem.loss = loss;
        let eval = Evaluator::new(&problem);
        let (r, j) = eval.residuals_and_jacobian(&x).expect("in front");
        let (br, bj) = brute_force(&problem, &x);
        let r_diff = r
            .iter()
            .zip(&br)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        let j_diff = max_rel_diff(&j, &bj);
        println!("{loss:?}: residuals {r_diff:.2e}, Jacobian {j_diff:.2e}");
        assert!(r_diff < 1e-9, "{loss:?}: residuals differ by {r_diff:e}");
        assert!(j_diff < 1e-9, "{loss:?}: Jacobians differ by {j_diff:e}");
        let plain = eval.residuals(&x).expect("in front");
        assert!((plain - r).amax() < 1e-12);
    }
}

#[test]
fn covariance_is_finite_and_ranks_zero_columns_out() {
    // Left board only: the right leg and board leave nine columns at zero.
    let options = SimOptions {
        stances: 6,
        heads: 2,
        ..SimOptions::default()
    };
    let mut dataset = simulate(&Model::default(), &options).expect("simulated");
    dataset.captures.retain(|c| c.side == Side::Left);
    let problem = Problem::from_dataset(&dataset, FixedSet::default()).expect("problem");
    let eval = Evaluator::new(&problem);
    let x = vec![0.0; eval.free().len()];
    let (_, j) = eval.residuals_and_jacobian(&x).expect("in front");
    let (cov, rank) = from_jacobian(&j);
    assert_eq!(rank, 12);
    assert!(cov.iter().all(|v| v.is_finite()));
    assert_eq!(rank_of_covariance(&cov), 12);
}

#[test]
fn compare_reports_solvers_that_stop_early() {
    let (mut problem, _) = simulated(5, 4, 2);
    problem.tolerances.max_iterations = 1;
    let comparison = compare(&problem, &[]).expect("compares");
    assert_eq!(comparison.runs.len(), backend_names().len());
    for run in &comparison.runs {
        println!(
            "{}: converged {}, {:?}",
            run.solver,
            run.converged(),
            run.solution().map(|s| &s.summary.termination)
        );
        assert!(run.solution().is_some(), "{} failed", run.solver);
        assert!(
            !run.converged(),
            "{} converged in one iteration",
            run.solver
        );
        assert!(run.solution().unwrap().summary.iterations <= 2);
    }
    assert_eq!(comparison.reference_is_ceres, cfg!(feature = "ceres"));
    // A solver that fails outright (a robust loss with whitening is refused by all).
    let mut bad = problem.clone();
    bad.loss = Loss::Huber(1.0);
    for c in &mut bad.captures {
        c.whitening = Some(Whitening::Dense(DMatrix::identity(
            c.residual_count(),
            c.residual_count(),
        )));
    }
    let comparison = compare(&bad, &[]).expect("compares");
    for run in &comparison.runs {
        let message = run.outcome.as_ref().expect_err("refused");
        assert!(message.contains("whitening"), "{message}");
        assert!(run.max_sigma.is_none());
    }
    assert!(compare(&problem, &["nonsense"]).is_err());
}

#[cfg(feature = "ceres")]
mod with_ceres {
    use super::*;
    use crate::util::solve;
    use naocalib::model::Param;
    use naocalib::solve::{Backend, backend};

    /// The pure-Rust backends of this build.
    fn rust_backends() -> Vec<Box<dyn Backend>> {
        ["lm", "tiny"]
            .iter()
            .map(|n| backend(n, false).expect("pure-Rust backend"))
            .collect()
    }
    use naocalib::solve::ceres::{Ceres, evaluate};
    use naocalib::solve::compare::max_sigma_difference;

    /// Solves with Ceres and every pure-Rust backend; checks agreement within `tol_sigma`
    /// of Ceres' sigma and that the truth is recovered as well as Ceres recovers it.
    fn check_agreement(problem: &Problem, truth: &[f64], tol_sigma: f64, what: &str) {
        let reference = solve(problem, &Ceres::default()).expect("ceres solves");
        assert!(
            reference.summary.converged,
            "{what}: ceres did not converge"
        );
        let free = problem.free();
        let ceres_truth = max_error_sigma(&reference, truth, &free);
        for b in rust_backends() {
            let s = solve(problem, b.as_ref()).expect("solves");
            assert!(
                s.summary.converged,
                "{what}: {} did not converge: {}",
                b.name(),
                s.summary.termination
            );
            let (d, p) = max_sigma_difference(&s, &reference, &free);
            let own_truth = max_error_sigma(&s, truth, &free);
            println!(
                "{what}: {} within {d:.2e} sigma of Ceres ({p}); truth within {own_truth:.3} \
                 sigma (Ceres {ceres_truth:.3}); cost {:.6e} vs {:.6e}",
                b.name(),
                s.summary.final_cost,
                reference.summary.final_cost
            );
            assert!(
                d <= tol_sigma,
                "{what}: {} differs by {d} sigma in {p}",
                b.name()
            );
            assert!(
                (own_truth - ceres_truth).abs() <= tol_sigma,
                "{what}: {} recovers the truth differently",
                b.name()
            );
            let rel = (s.summary.final_cost - reference.summary.final_cost).abs()
                / reference.summary.final_cost;
            assert!(rel < 1e-8, "{what}: final costs differ by {rel:e}");
        }
    }

    /// The largest |estimate − truth| / std over the free parameters.
    fn max_error_sigma(s: &naocalib::solve::Solution, truth: &[f64], free: &[Param]) -> f64 {
        free.iter()
            .map(|p| (s.values[p.index()] - truth[p.index()]).abs() / s.std[p.index()])
            .fold(0.0, f64::max)
    }

    #[test]
    fn small_simulations_agree_with_ceres() {
        for seed in [1, 2, 3] {
            let (problem, truth) = simulated(seed, 8, 2);
            check_agreement(&problem, &truth, 0.01, &format!("8x2 seed {seed}"));
        }
    }

    #[test]
    fn paper_sized_simulation_agrees_with_ceres() {
        let (problem, truth) = simulated(1, 24, 3);
        check_agreement(&problem, &truth, 0.01, "paper-sized");
    }

    #[test]
    fn robust_losses_agree_with_ceres() {
        let options = SimOptions {
            seed: 4,
            stances: 8,
            heads: 2,
            ..SimOptions::default()
        };
        let mut dataset = simulate(&Model::default(), &options).expect("simulated");
        let truth = dataset.truth.as_ref().expect("truth").values;
        // A few gross outliers for the loss to down-weight.
        for (k, corner) in dataset
            .corners
            .iter_mut()
            .enumerate()
            .filter(|(k, _)| k % 97 == 0)
        {
            corner.pixel[0] += 3.0 + (k % 5) as f64;
            corner.pixel[1] -= 2.0;
        }
        let mut problem = Problem::from_dataset(&dataset, FixedSet::default()).expect("problem");
        for loss in [Loss::Huber(0.3), Loss::Cauchy(0.5)] {
            problem.loss = loss;
            let reference = solve(&problem, &Ceres::default()).expect("ceres solves");
            let free = problem.free();
            for b in rust_backends() {
                let s = solve(&problem, b.as_ref()).expect("solves");
                assert!(
                    s.summary.converged,
                    "{loss:?}: {} did not converge",
                    b.name()
                );
                let (d, p) = max_sigma_difference(&s, &reference, &free);
                let rel = (s.summary.final_cost - reference.summary.final_cost).abs()
                    / reference.summary.final_cost;
                println!(
                    "{loss:?}: {} within {d:.2e} sigma ({p}), cost rel diff {rel:.1e}",
                    b.name()
                );
                assert!(
                    d <= 0.01,
                    "{loss:?}: {} differs by {d} sigma in {p}",
                    b.name()
                );
                assert!(rel < 1e-8, "{loss:?}: {} cost differs by {rel:e}", b.name());
            }
            // The robust fit still finds the truth despite the outliers.
            let worst = free
                .iter()
                .map(|p| {
                    (reference.values[p.index()] - truth[p.index()]).abs()
                        / reference.std[p.index()]
                })
                .fold(0.0, f64::max);
            assert!(worst < 6.0, "{loss:?}: truth {worst} sigma away");
        }
    }

    #[test]
    fn rust_jacobian_matches_ceres() {
        let (problem, truth) = simulated(6, 4, 2);
        let free = problem.free();
        let x: Vec<f64> = free.iter().map(|p| 0.5 * truth[p.index()]).collect();
        let (r, j) = evaluate(&problem, &x).expect("ceres evaluates");
        let (rr, rj) = Evaluator::new(&problem)
            .residuals_and_jacobian(&x)
            .expect("in front");
        let r_diff = r
            .iter()
            .zip(rr.iter())
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        let j_diff = max_rel_diff(&rj, &j);
        println!("vs Ceres: residuals {r_diff:.2e}, Jacobian {j_diff:.2e}");
        assert!(r_diff < 1e-9 && j_diff < 1e-7);
    }

    /// Max |a − b| / √(b_ii·b_jj) over the matrix.
    fn correlation_scaled_diff(a: &DMatrix<f64>, b: &DMatrix<f64>) -> f64 {
        let n = b.nrows();
        let mut worst: f64 = 0.0;
        for i in 0..n {
            for j in 0..n {
                let scale = (b[(i, i)] * b[(j, j)]).sqrt();
                if scale > 0.0 {
                    worst = worst.max((a[(i, j)] - b[(i, j)]).abs() / scale);
                }
            }
        }
        worst
    }

    /// The covariance [`from_jacobian`] makes of a backend's Jacobian at a fit.
    fn covariance_at(problem: &Problem, free_values: &[f64]) -> (DMatrix<f64>, usize) {
        let (_, j) = Evaluator::new(problem)
            .residuals_and_jacobian(free_values)
            .expect("in front");
        from_jacobian(&j)
    }

    #[test]
    fn covariance_agrees_across_backends() {
        // Backends return values only; the pipeline computes the covariance from the
        // Jacobian at the fit. Ceres' own Jacobian there gives the same covariance, and so
        // does every pure-Rust backend's fit.
        let (problem, _) = simulated(2, 8, 2);
        let ceres = Ceres::default().solve(&problem).expect("ceres solves");
        let (_, ceres_j) = evaluate(&problem, &ceres.free_values).expect("ceres evaluates");
        let (ceres_cov, ceres_rank) = from_jacobian(&ceres_j);
        let (cov, rank) = covariance_at(&problem, &ceres.free_values);
        let scaled = correlation_scaled_diff(&cov, &ceres_cov);
        let plain = (&cov - &ceres_cov).amax() / ceres_cov.amax();
        println!("covariance: max diff / max entry {plain:.2e}, scaled {scaled:.2e}");
        assert!(plain < 1e-6 && scaled < 1e-6);
        assert_eq!(rank, problem.free().len());
        assert_eq!(ceres_rank, rank);
        assert_eq!(rank_of_covariance(&ceres_cov), rank);
        for b in rust_backends() {
            let own = b.solve(&problem).expect("solves");
            let (own_cov, _) = covariance_at(&problem, &own.free_values);
            let d = correlation_scaled_diff(&own_cov, &ceres_cov);
            println!("{}: covariance scaled diff {d:.2e}", b.name());
            assert!(d < 1e-6, "{}: {d:e}", b.name());
        }
    }

    #[test]
    fn ranks_agree_on_rank_deficient_problems() {
        // (a) Left board only: nine parameters are not observed at all.
        let options = SimOptions {
            stances: 8,
            heads: 2,
            ..SimOptions::default()
        };
        let mut dataset = simulate(&Model::default(), &options).expect("simulated");
        dataset.captures.retain(|c| c.side == Side::Left);
        let left_only = Problem::from_dataset(&dataset, FixedSet::default()).expect("problem");
        // (b) One stance, seen again and again: only the board pose (six degrees of
        // freedom) is determined.
        let (mut one_stance, _) = simulated(8, 8, 2);
        one_stance
            .captures
            .retain(|c| c.chains.board.params().contains(&Param::LKneePitch));
        let first = one_stance.captures[0].clone();
        for c in &mut one_stance.captures {
            c.chains = first.chains.clone();
        }
        for (problem, expected, what) in
            [(left_only, 12, "left only"), (one_stance, 6, "one stance")]
        {
            let ceres = Ceres::default().solve(&problem).expect("ceres runs");
            let (_, ceres_j) = evaluate(&problem, &ceres.free_values).expect("evaluates");
            let (ceres_cov, _) = from_jacobian(&ceres_j);
            let ceres_rank = rank_of_covariance(&ceres_cov);
            let (_, rank) = covariance_at(&problem, &ceres.free_values);
            let mut ranks = vec![("ceres".to_string(), ceres_rank), ("rust".into(), rank)];
            for b in rust_backends() {
                let own = b.solve(&problem).expect("runs");
                let (cov, _) = covariance_at(&problem, &own.free_values);
                assert!(cov.iter().all(|v| v.is_finite()));
                ranks.push((b.name().into(), rank_of_covariance(&cov)));
            }
            println!("{what}: ranks {ranks:?}");
            for (name, r) in ranks {
                assert_eq!(r, expected, "{what}: {name} rank {r}");
            }
        }
    }
}
