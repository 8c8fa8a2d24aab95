//! Reports of a run ([`crate::run::Run`]) and its [`Solution`]: the paper's Table 2 as text
//! ([`run_text`], [`table`]), the result JSON of docs/MODEL.md §8 ([`ResultJson`]), the HTML
//! report ([`html`]), plots, the comparison of solvers ([`compare`]), and the files
//! `naocalib solve` writes beside its printout ([`RunFiles`]). A report sees a run or a
//! solution, never a solver.

pub mod compare;
pub(crate) mod files;
pub mod html;
pub mod misfit_plot;
pub mod plot;
pub mod printed;
pub mod result_json;

pub use crate::calibration::result_json::ResultJson;
pub use files::{FilesError, RunFiles};

use std::fmt::Write as _;

use serde_json::Value;

use crate::model::Param;
use crate::run::{Change, Run};
use crate::solve::Solution;

/// Parameters shown in reports: the paper's 21, the upper camera's when the dataset has
/// upper-camera captures, plus any further one that was estimated.
pub fn shown_parameters(solution: &Solution) -> Vec<Param> {
    Param::ALL
        .iter()
        .copied()
        .filter(|p| solution.fixed.is_shown(*p))
        .collect()
}

/// A one-sigma cell: the value, `fixed`, or `undet.` when the data do not determine it;
/// marked `†` when it assumes a held parameter at its nominal value
/// ([`Solution::held_trade_offs`]).
fn sigma_cell(solution: &Solution, p: Param, std: Option<f64>) -> String {
    if solution.fixed.is_fixed(p) {
        "fixed".into()
    } else if !solution.is_determined(p) {
        "undet.".into()
    } else {
        let mark = if solution.held_trade_offs(p).is_empty() {
            ""
        } else {
            "†"
        };
        std.map_or_else(
            || "-".into(),
            |s| format!("{:.4}{mark}", p.unit().to_report(s)),
        )
    }
}

/// The lines saying which reported σ assume a held parameter at its nominal value, and how
/// far its error moves them ([`Solution::held_trade_offs`]).
pub fn held_trade_off_lines(solution: &Solution) -> Vec<String> {
    let mut lines = Vec::new();
    for p in Param::ALL {
        let held = solution.held_trade_offs(p);
        if held.is_empty() {
            continue;
        }
        let names: Vec<String> = held.iter().map(|(q, _)| q.to_string()).collect();
        let moves: Vec<String> = held
            .iter()
            .map(|(q, ratio)| {
                format!(
                    "{:.3} {} per {} of {q}",
                    ratio.abs(),
                    p.unit().name(),
                    q.unit().name()
                )
            })
            .collect();
        lines.push(format!(
            "  † {p}: its σ {:.4} {} is not honest: it assumes {} at nominal (held, \
             undetermined), whose error moves {p} by {} — more than its σ; give {} a known \
             value, or fix {p} too",
            solution.report_std(p),
            p.unit().name(),
            names.join(" and "),
            moves.join(", "),
            names.join(" and ")
        ));
    }
    lines
}

/// The human-readable table: value ± one sigma per parameter, the sandwich and bootstrap
/// one-sigma beside it, truth and error when the truth is known; then fit statistics, the
/// noise model and what the data cannot determine.
pub fn table(solution: &Solution, truth: Option<&[f64]>) -> String {
    let mut out = String::new();
    let boot = solution.bootstrap.as_ref();
    let shown = shown_parameters(solution);
    let name_width = shown.iter().map(|p| p.name().len()).fold(14, usize::max);
    let unit_width = shown
        .iter()
        .map(|p| p.unit().name().chars().count())
        .fold(4, usize::max);
    let _ = write!(
        out,
        "{:<name_width$} {:>10} {:>9}  {:<unit_width$} {:>9}",
        "parameter", "value", "±1σ", "unit", "sandwich"
    );
    if boot.is_some() {
        let _ = write!(out, " {:>9}", "bootstrap");
    }
    if truth.is_some() {
        let _ = write!(out, " {:>10} {:>9} {:>6}", "truth", "error", "err/σ");
    }
    out.push('\n');
    for p in shown {
        let unit = p.unit();
        let value = solution.report_value(p);
        let std = sigma_cell(solution, p, Some(solution.std[p.index()]));
        let sandwich = sigma_cell(solution, p, solution.sandwich_std.map(|s| s[p.index()]));
        let _ = write!(
            out,
            "{:<name_width$} {:>10.4} {:>9}  {:<unit_width$} {:>9}",
            p.name(),
            value,
            std,
            unit.name(),
            sandwich
        );
        if let Some(b) = boot {
            let _ = write!(
                out,
                " {:>9}",
                sigma_cell(solution, p, Some(b.std[p.index()]))
            );
        }
        if let Some(truth) = truth {
            let t = unit.to_report(truth[p.index()]);
            let err = value - t;
            let usable = !solution.fixed.is_fixed(p)
                && solution.is_determined(p)
                && solution.std[p.index()] > 0.0;
            let z = if usable {
                format!("{:.2}", err / solution.report_std(p))
            } else {
                String::from("-")
            };
            let _ = write!(out, " {:>10.4} {:>9.4} {:>6}", t, err, z);
        }
        out.push('\n');
    }
    out.push('\n');
    for line in diagnosis(solution) {
        let _ = writeln!(out, "{line}");
    }
    let s = &solution.summary;
    let _ = writeln!(
        out,
        "time {:.1} ms (optimiser {:.1} ms)",
        solution.seconds * 1e3,
        s.seconds * 1e3
    );
    out
}

/// The text report of a run, as `naocalib solve` prints it: the dataset, the [`table`], the
/// standing leg offsets ([`standing_table`]) and the change since the previous calibration
/// ([`changes_table`]).
pub fn run_text(run: &Run) -> String {
    let mut out = format!("{}\n", run.dataset().display());
    out.push_str(&table(&run.solution, run.truth()));
    out.push_str(&standing_table(&run.calibration));
    out.push_str(&intrinsics_table(&run.intrinsics));
    if let Some(changes) = &run.changes {
        out.push_str(&changes_table(changes));
    }
    out
}

/// One quantity of a camera's intrinsics as the teams read them
/// ([`crate::calibration::intrinsics::TeamsView`]), as the table and the HTML report show
/// it.
#[derive(Debug, Clone, PartialEq)]
pub struct IntrinsicsRow {
    /// What it is (`opening angle width`, …).
    pub quantity: &'static str,
    /// Its value.
    pub value: f64,
    /// Its one-sigma cell: the number, `held` or `undet.`.
    pub sigma: String,
    /// The previous calibration's value, when known.
    pub previous: Option<f64>,
    /// The unit (`deg`, `px`).
    pub unit: &'static str,
}

impl IntrinsicsRow {
    /// `value − previous`, when the previous value is known.
    pub fn change(&self) -> Option<f64> {
        self.previous.map(|p| self.value - p)
    }
}

/// The rows of one calibrated camera's intrinsics as the teams read them: opening angles
/// (deg), focal lengths (px) and the centre's offset from the image's middle (px), each with
/// its one-sigma and the previous calibration's value.
pub fn intrinsics_rows(camera: &crate::run::CameraIntrinsics) -> Vec<IntrinsicsRow> {
    use crate::calibration::intrinsics::{TEAMS_QUANTITIES, TeamsView};
    let now = camera.now.teams_view();
    let previous = camera
        .previous
        .map(|v| TeamsView::of_values(v, camera.now.prior.width, camera.now.prior.height));
    TEAMS_QUANTITIES
        .iter()
        .enumerate()
        .map(|(k, &(quantity, unit))| IntrinsicsRow {
            quantity,
            value: now.values[k],
            sigma: match now.std[k] {
                None => "undet.".into(),
                Some(_) if !now.calibrated[k] => "held".into(),
                Some(s) => format!("{s:.4}"),
            },
            previous: previous.map(|p| p.values[k]),
            unit,
        })
        .collect()
}

/// The heading of one camera's intrinsics table: the camera and the image size.
pub fn intrinsics_heading(camera: &crate::run::CameraIntrinsics) -> String {
    format!(
        "Intrinsics of the {} camera at {}×{} px as the teams read them (±1σ from the fit)",
        camera.now.camera, camera.now.prior.width, camera.now.prior.height
    )
}

/// The calibrated cameras' intrinsics ([`intrinsics_rows`]) as text tables, one per camera,
/// with the previous calibration's values and the change when the run started from one
/// (empty when the run calibrated no intrinsics).
pub fn intrinsics_table(cameras: &[crate::run::CameraIntrinsics]) -> String {
    let mut out = String::new();
    for camera in cameras {
        let with_previous = camera.previous.is_some();
        let _ = writeln!(out, "\n{}:", intrinsics_heading(camera));
        let _ = write!(out, "{:<22} {:>10} {:>9}", "quantity", "value", "±1σ");
        if with_previous {
            let _ = write!(out, " {:>10} {:>9}", "previous", "change");
        }
        let _ = writeln!(out, "  unit");
        for row in intrinsics_rows(camera) {
            let _ = write!(
                out,
                "{:<22} {:>10.4} {:>9}",
                row.quantity, row.value, row.sigma
            );
            if let (Some(previous), Some(change)) = (row.previous, row.change()) {
                let _ = write!(out, " {previous:>10.4} {change:>+9.4}");
            }
            let _ = writeln!(out, "  {}", row.unit);
        }
    }
    out
}

/// What the fit says about itself, one line each (sub-items indented by two spaces):
/// convergence, the residuals, the noise model, the model fitted and the misfit verdict,
/// the captures that stand out, outliers, and identifiability (rank, strongly correlated
/// pairs, weakly and not determined combinations, what to hold fixed). Used by [`table`]
/// and the HTML report.
pub fn diagnosis(solution: &Solution) -> Vec<String> {
    let mut lines = Vec::new();
    let s = &solution.summary;
    lines.push(format!(
        "solver {}: {} after {} iterations ({})",
        s.solver,
        if s.converged {
            "converged"
        } else {
            "NOT converged"
        },
        s.iterations,
        s.termination
    ));
    lines.push(format!(
        "captures {}, vertices {}; rms x {:.4} px, y {:.4} px (before: x {:.2} px, y {:.2} px)",
        solution.captures,
        solution.observations,
        solution.rms_px[0],
        solution.rms_px[1],
        solution.initial_rms_px[0],
        solution.initial_rms_px[1]
    ));
    if let Some(noise) = solution.noise {
        let sandwich = if solution.misfit.detected {
            "; σ from the capture-clustered sandwich (a misfit is flagged)"
        } else {
            ""
        };
        lines.push(format!(
            "noise model: pixel σ {:.3} px, joint σ {:.3}° per capture; χ²/dof {:.2}{sandwich}",
            noise.px,
            noise.joint.to_degrees(),
            solution.residual_variance
        ));
    } else if solution.misfit.noise_model_set_aside {
        lines.push(
            "uncertainty: capture-clustered sandwich (the noise model is set aside: the \
             residuals are not noise)"
                .into(),
        );
    } else {
        lines.push("uncertainty: plain σ̂²(JᵀJ)⁻¹ (no noise model)".into());
    }
    lines.extend(model_text(solution).lines().map(String::from));
    if let Some(b) = &solution.bootstrap {
        lines.push(format!(
            "bootstrap: {} refits over resampled captures ({} failed)",
            b.replicates, b.failed
        ));
    }
    let rms = plot::capture_rms_values(solution);
    let mut sorted: Vec<f64> = rms.iter().map(|r| r.1).filter(|r| r.is_finite()).collect();
    sorted.sort_by(f64::total_cmp);
    if let Some(&median) = sorted.get(sorted.len() / 2) {
        let threshold = plot::OUTLIER_FACTOR * median;
        let standing: Vec<String> = rms
            .iter()
            .filter(|r| r.1 > threshold || r.1.is_nan())
            .map(|(id, r)| format!("{id} ({r:.2} px)"))
            .collect();
        if !standing.is_empty() {
            lines.push(format!(
                "captures standing out (RMS above {}× the median {median:.3} px): {}",
                plot::OUTLIER_FACTOR,
                standing.join(", ")
            ));
        }
    }
    if !solution.outliers.is_empty() {
        lines.push(format!(
            "outliers left out: {} vertices (capture row,col: residual px)",
            solution.outliers.len()
        ));
        for o in solution.outliers.iter().take(20) {
            lines.push(format!(
                "  capture {} ({},{}): ({:+.2}, {:+.2})",
                o.capture, o.vertex.row, o.vertex.col, o.residual[0], o.residual[1]
            ));
        }
        if solution.outliers.len() > 20 {
            lines.push(format!(
                "  … and {} more (see --json)",
                solution.outliers.len() - 20
            ));
        }
    }
    lines.extend(identifiability_text(solution).lines().map(String::from));
    lines
}

/// The result JSON of docs/MODEL.md §8 ([`ResultJson`]) as a value, keys in alphabetical
/// order.
pub fn json(solution: &Solution, truth: Option<&[f64]>) -> Value {
    ResultJson::new(solution, truth).to_value()
}

/// The model part of the text report: the families fitted (and chosen, with
/// `--model auto`), undetermined parameters with the combination they form, and the misfit
/// verdict in one plain line.
pub fn model_text(solution: &Solution) -> String {
    let mut out = String::new();
    let families: Vec<&str> = solution.families.iter().map(|f| f.name()).collect();
    let _ = writeln!(out, "model: {}", families.join(", "));
    for t in &solution.chosen {
        let _ = writeln!(
            out,
            "  freed {} (misfit test F = {:.1} on {} directions, p = {:.1e})",
            t.family, t.statistic, t.df, t.p_value
        );
    }
    for u in &solution.undetermined {
        let _ = writeln!(
            out,
            "  {} undetermined, held at nominal: the data cannot see a change along {}",
            u.param,
            u.direction.describe()
        );
    }
    let held = held_trade_off_lines(solution);
    for line in &held {
        let _ = writeln!(out, "{line}");
    }
    let _ = writeln!(out, "diagnosis: {}", solution.misfit.message);
    if !held.is_empty() && solution.misfit.detected {
        let _ = writeln!(
            out,
            "  † the misfit may come from the parameters held at nominal (†) rather than from \
             a missing family: what it points to is no remedy until they are known"
        );
    }
    out
}

/// The identifiability part of the text report.
pub fn identifiability_text(solution: &Solution) -> String {
    let id = &solution.identifiability;
    let mut out = String::new();
    let condition = id
        .condition_number
        .map_or_else(|| "infinite".to_string(), |c| format!("{c:.0}"));
    let _ = writeln!(
        out,
        "identifiability: rank {} of {} free parameters, condition number {} (column-scaled)",
        id.rank, id.free, condition
    );
    if !id.correlated.is_empty() {
        let pairs: Vec<String> = id
            .correlated
            .iter()
            .take(6)
            .map(|(a, b, r)| format!("{a}/{b} {r:+.2}"))
            .collect();
        let _ = writeln!(out, "  strongly correlated: {}", pairs.join(", "));
    }
    for d in &id.weak {
        let _ = writeln!(
            out,
            "  weakly determined: {} (relative singular value {:.1e})",
            d.describe(),
            d.relative_singular_value
        );
    }
    for p in &id.unobserved {
        let _ = writeln!(out, "  NOT observed by any capture: {p}");
    }
    for d in &id.undetermined {
        let _ = writeln!(out, "  NOT determined: {}", d.describe());
    }
    if !id.suggest_fix.is_empty() {
        let names: Vec<&str> = id.suggest_fix.iter().map(|p| p.name()).collect();
        let _ = writeln!(
            out,
            "  the data cannot determine every parameter; hold some fixed, e.g. --fix {}",
            names.join(",")
        );
    }
    out
}

/// The change since the previous calibration ([`crate::run::changes`]) as a text table
/// (`parameter previous now change z unit`), largest |z| marked.
pub fn changes_table(changes: &[Change]) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "\nChange since the previous calibration (z = change / sigma):"
    );
    let _ = writeln!(
        out,
        "{:<24} {:>10} {:>10} {:>10} {:>7}  unit",
        "parameter", "previous", "now", "change", "z"
    );
    for c in changes {
        let mark = if c.z.abs() > 3.0 { "  <- |z| > 3" } else { "" };
        let _ = writeln!(
            out,
            "{:<24} {:>10.4} {:>10.4} {:>+10.4} {:>+7.2}  {}{mark}",
            c.param.name(),
            c.previous,
            c.value,
            c.change,
            c.z,
            c.param.unit().name()
        );
    }
    out
}

/// [`crate::calibration::Calibration::standing_rows`] as a text table (empty when there
/// are none), with the joints whose standing offset is uncertain beyond the target or
/// extrapolated named below it ([`crate::calibration::Calibration::standing_caveats`]).
pub fn standing_table(cal: &crate::calibration::Calibration) -> String {
    let rows = cal.standing_rows();
    if rows.is_empty() {
        return String::new();
    }
    let mut out = String::new();
    let _ = writeln!(
        out,
        "\nLeg offsets lying (as calibrated) and standing (alpha + kappa*tau_stand + \
         play/2*sgn tau_stand, sigma of alpha, kappa, play jointly; team files carry the \
         standing ones unless --posture lying):"
    );
    let _ = writeln!(
        out,
        "{:<24} {:>10} {:>10} {:>8} {:>10} {:>10}  unit",
        "parameter", "lying", "standing", "sigma", "tau_stand", "tau_lying"
    );
    for (p, lying, standing, std) in rows {
        let tau = crate::calibration::stand_torque(p).unwrap_or(f64::NAN);
        let sigma = std.map_or_else(|| "-".to_string(), |s| format!("{s:.4}"));
        let lying_tau = cal
            .standing
            .get(&p)
            .and_then(|s| s.lying_torque)
            .map_or_else(|| "-".to_string(), |m| format!("{m:.4}"));
        let _ = writeln!(
            out,
            "{:<24} {lying:>10.4} {standing:>10.4} {sigma:>8} {tau:>+10.4} {lying_tau:>10}  deg, N·m",
            p.name()
        );
    }
    let caveats = cal.standing_caveats();
    if !caveats.is_empty() {
        let _ = writeln!(
            out,
            "Standing offsets less certain than {}° (one sigma) or resting on an extrapolated \
             compliance:",
            crate::calibration::STANDING_TARGET_DEG
        );
        for c in caveats {
            let _ = writeln!(out, "  {c}");
        }
    }
    out
}
