//! The comparison of every solver on one dataset (`naocalib compare`,
//! [`crate::solve::compare`]) as a table and as JSON.

use std::fmt::Write as _;
use std::path::Path;

use serde_json::{Map, Value, json};

use crate::solve::compare::{Comparison, sigma_difference};

/// A number for JSON: `null` when not finite.
fn number(x: f64) -> Value {
    if x.is_finite() { json!(x) } else { Value::Null }
}

/// The comparison of solvers on the dataset in `dataset` as JSON: the dataset, one entry
/// per solver, and every free parameter's values side by side (report units).
pub fn comparison_json(c: &Comparison, dataset: &Path) -> Value {
    let reference = c.reference_run();
    let solvers: Vec<Value> = c
        .runs
        .iter()
        .map(|run| {
            let mut entry = Map::new();
            entry.insert("solver".into(), json!(run.solver));
            entry.insert("ok".into(), json!(run.outcome.is_ok()));
            entry.insert("converged".into(), json!(run.converged()));
            entry.insert("wall_seconds".into(), json!(run.wall_seconds));
            match &run.outcome {
                Err(message) => {
                    entry.insert("error".into(), json!(message));
                }
                Ok(s) => {
                    let summary = &s.summary;
                    entry.insert("iterations".into(), json!(summary.iterations));
                    entry.insert("initial_cost".into(), number(summary.initial_cost));
                    entry.insert("final_cost".into(), number(summary.final_cost));
                    entry.insert("rms_px".into(), json!(s.rms_px.map(number)));
                    entry.insert("solver_seconds".into(), json!(summary.seconds));
                    entry.insert("termination".into(), json!(summary.termination));
                    entry.insert("rank".into(), json!(run.rank));
                    let values: Map<String, Value> = c
                        .free
                        .iter()
                        .map(|p| (p.name().to_string(), number(s.report_value(*p))))
                        .collect();
                    entry.insert("parameters".into(), Value::Object(values));
                }
            }
            entry.insert(
                "max_sigma_difference".into(),
                run.max_sigma.map_or(Value::Null, |(d, _)| number(d)),
            );
            entry.insert(
                "max_sigma_parameter".into(),
                run.max_sigma.map_or(Value::Null, |(_, p)| json!(p.name())),
            );
            Value::Object(entry)
        })
        .collect();
    let parameters: Map<String, Value> = c
        .free
        .iter()
        .map(|p| {
            let values: Map<String, Value> = c
                .runs
                .iter()
                .map(|run| {
                    let v = run.solution().map_or(Value::Null, |s| number(s.report_value(*p)));
                    (run.solver.clone(), v)
                })
                .collect();
            let sigmas: Map<String, Value> = c
                .runs
                .iter()
                .map(|run| {
                    let d = match (run.solution(), reference.solution()) {
                        (Some(s), Some(r)) => number(sigma_difference(s, r, *p)),
                        _ => Value::Null,
                    };
                    (run.solver.clone(), d)
                })
                .collect();
            let entry = json!({
                "unit": p.unit().name(),
                "reference_std": reference.solution().map_or(Value::Null, |s| number(s.report_std(*p))),
                "values": values,
                "sigma_difference": sigmas,
            });
            (p.name().to_string(), entry)
        })
        .collect();
    json!({
        "dataset": dataset.display().to_string(),
        "reference": reference.solver,
        "reference_is_ceres": c.reference_is_ceres,
        "solvers": solvers,
        "parameters": parameters,
    })
}

/// The comparison of solvers on the dataset in `dataset` as text: the dataset, the solver
/// table, then the parameters side by side.
pub fn comparison_text(c: &Comparison, dataset: &Path) -> String {
    let reference = c.reference_run();
    let mut out = format!("{}\n", dataset.display());
    if c.reference_is_ceres {
        let _ = writeln!(
            out,
            "reference: ceres; differences in units of Ceres' one-sigma (σ)"
        );
    } else {
        let _ = writeln!(
            out,
            "reference: {} (no Ceres in this comparison); differences in units of its \
             one-sigma (σ)",
            reference.solver
        );
    }
    if reference.solution().is_none() {
        let _ = writeln!(out, "the reference failed: no differences can be given");
    }
    let _ = writeln!(
        out,
        "\n{:<8} {:<9} {:>5} {:>13} {:>9} {:>9} {:>10} {:>9} {:>5}  max |Δ|/σ",
        "solver",
        "converged",
        "iters",
        "final cost",
        "RMS x px",
        "RMS y px",
        "solver ms",
        "wall ms",
        "rank",
    );
    for run in &c.runs {
        match &run.outcome {
            Err(message) => {
                let _ = writeln!(
                    out,
                    "{:<8} {:<9} {:>5} {:>13} {:>9} {:>9} {:>10} {:>9.1} {:>5}  FAILED: {}",
                    run.solver,
                    "FAILED",
                    "-",
                    "-",
                    "-",
                    "-",
                    "-",
                    1e3 * run.wall_seconds,
                    "-",
                    message
                );
            }
            Ok(s) => {
                let diff = match run.max_sigma {
                    None => "-".to_string(),
                    Some((d, p)) if d > 0.0 => format!("{d:.2e} ({p})"),
                    Some(_) => "0".to_string(),
                };
                let _ = writeln!(
                    out,
                    "{:<8} {:<9} {:>5} {:>13.6e} {:>9.4} {:>9.4} {:>10.1} {:>9.1} {:>5}  {}",
                    run.solver,
                    if s.summary.converged { "yes" } else { "NO" },
                    s.summary.iterations,
                    s.summary.final_cost,
                    s.rms_px[0],
                    s.rms_px[1],
                    1e3 * s.summary.seconds,
                    1e3 * run.wall_seconds,
                    run.rank.map_or("-".to_string(), |r| r.to_string()),
                    diff
                );
            }
        }
    }
    for run in c
        .runs
        .iter()
        .filter(|r| r.solution().is_some() && !r.converged())
    {
        let s = run.solution().expect("filtered");
        let _ = writeln!(
            out,
            "{} did not converge: {}",
            run.solver, s.summary.termination
        );
    }
    let _ = write!(out, "\n{:<14} {:<4}", "parameter", "unit");
    let _ = write!(out, " {:>12}", format!("σ({})", reference.solver));
    for run in &c.runs {
        let _ = write!(out, " {:>12}", run.solver);
    }
    let _ = writeln!(out);
    for p in &c.free {
        let _ = write!(out, "{:<14} {:<4}", p.name(), p.unit().name());
        let sigma = reference
            .solution()
            .map_or("-".to_string(), |s| format!("{:.6}", s.report_std(*p)));
        let _ = write!(out, " {sigma:>12}");
        for run in &c.runs {
            let v = run
                .solution()
                .map_or("-".to_string(), |s| format!("{:.6}", s.report_value(*p)));
            let _ = write!(out, " {v:>12}");
        }
        let _ = writeln!(out);
    }
    out
}
