//! Reports of a [`Solution`]: the paper's Table 2 as text, and the result JSON of SPEC
//! section 7. A report sees a solution (and optionally the truth), never a solver.

pub mod export;
pub mod plot;

use std::fmt::Write as _;

use serde_json::{Map, Value, json};

use crate::model::{PAPER_PARAMETERS, Param};
use crate::solve::Solution;

/// Parameters shown in reports: the paper's 21, plus any further one that was estimated.
pub fn shown_parameters(solution: &Solution) -> Vec<Param> {
    Param::ALL
        .iter()
        .copied()
        .filter(|p| p.index() < PAPER_PARAMETERS || !solution.fixed.is_fixed(*p))
        .collect()
}

/// The human-readable table: value ± one sigma per parameter (and truth / error when the
/// truth is known), then RMS, iterations and time.
pub fn table(solution: &Solution, truth: Option<&[f64]>) -> String {
    let mut out = String::new();
    let _ = write!(
        out,
        "{:<14} {:>10} {:>9}  {:<4}",
        "parameter", "value", "±1σ", "unit"
    );
    if truth.is_some() {
        let _ = write!(out, " {:>10} {:>9} {:>6}", "truth", "error", "err/σ");
    }
    out.push('\n');
    for p in shown_parameters(solution) {
        let unit = p.unit();
        let value = solution.report_value(p);
        let fixed = solution.fixed.is_fixed(p);
        let std = if fixed {
            "fixed".to_string()
        } else {
            format!("{:.4}", solution.report_std(p))
        };
        let _ = write!(
            out,
            "{:<14} {:>10.4} {:>9}  {:<4}",
            p.name(),
            value,
            std,
            unit.name()
        );
        if let Some(truth) = truth {
            let t = unit.to_report(truth[p.index()]);
            let err = value - t;
            let z = if fixed || solution.std[p.index()] == 0.0 {
                String::from("-")
            } else {
                format!("{:.2}", err / solution.report_std(p))
            };
            let _ = write!(out, " {:>10.4} {:>9.4} {:>6}", t, err, z);
        }
        out.push('\n');
    }
    let s = &solution.summary;
    let _ = writeln!(
        out,
        "\nsolver {}: {} after {} iterations ({})",
        s.solver,
        if s.converged {
            "converged"
        } else {
            "NOT converged"
        },
        s.iterations,
        s.termination
    );
    let _ = writeln!(
        out,
        "captures {}, vertices {}; rms x {:.4} px, y {:.4} px (before: x {:.2} px, y {:.2} px)",
        solution.captures,
        solution.observations,
        solution.rms_px[0],
        solution.rms_px[1],
        solution.initial_rms_px[0],
        solution.initial_rms_px[1]
    );
    if let Some(noise) = solution.noise {
        let _ = writeln!(
            out,
            "noise model: pixel σ {:.3} px, joint σ {:.3}° per capture; χ²/dof {:.2}",
            noise.px,
            noise.joint.to_degrees(),
            solution.residual_variance
        );
    } else {
        let _ = writeln!(out, "uncertainty: plain σ̂²(JᵀJ)⁻¹ (no noise model)");
    }
    let _ = writeln!(
        out,
        "time {:.1} ms (optimiser and covariance {:.1} ms)",
        solution.seconds * 1e3,
        s.seconds * 1e3
    );
    out
}

/// The result JSON of SPEC section 7 (plus a few extra keys).
pub fn json(solution: &Solution, truth: Option<&[f64]>) -> Value {
    let mut params = Map::new();
    for p in Param::ALL {
        let fixed = solution.fixed.is_fixed(p);
        let mut entry = json!({
            "value": solution.report_value(p),
            "std": if fixed { 0.0 } else { solution.report_std(p) },
            "unit": p.unit().name(),
        });
        if fixed {
            entry["fixed"] = Value::Bool(true);
        }
        if let Some(truth) = truth {
            entry["truth"] = json!(p.unit().to_report(truth[p.index()]));
        }
        params.insert(p.name().to_string(), entry);
    }
    let s = &solution.summary;
    json!({
        "solver": s.solver,
        "converged": s.converged,
        "iterations": s.iterations,
        "termination": s.termination,
        "initial_cost": s.initial_cost,
        "final_cost": s.final_cost,
        "rms_px": solution.rms_px,
        "initial_rms_px": solution.initial_rms_px,
        "captures": solution.captures,
        "vertices": solution.observations,
        "residual_sigma_px": solution.residual_variance.sqrt(),
        "seconds": solution.seconds,
        "noise": solution.noise.map(|n| json!({
            "px": n.px,
            "joint_deg": n.joint.to_degrees(),
        })),
        "parameters": Value::Object(params),
    })
}
