//! naocalib's own calibration file, TOML or JSON: every parameter with its one-sigma and
//! unit, whether the solver converged and the RMS residual it reached. Written and read
//! with serde (unknown keys refused), so that what is written is what is read.
//!
//! ```toml
//! format = "naocalib-calibration"
//! version = 1
//! solver = "ceres"
//! converged = true
//! rms_px = [0.94, 1.23]
//!
//! [parameters.CamYaw]
//! value = 0.5835      # report units: deg, mm, px, 1, deg/(N·m)
//! std = 0.0292        # one sigma, same unit; absent when the data do not determine it
//! unit = "deg"
//!
//! [parameters.HeadYaw]
//! value = 0.0
//! std = 0.0
//! unit = "deg"
//! fixed = true        # held at `value`, not estimated
//!
//! [parameters.RKneePitch]
//! value = 0.12
//! unit = "deg"
//! undetermined = true # the data do not determine it: no sigma, an arbitrary value
//! ```
//!
//! The JSON form has the same keys; [`Calibration::from_json`] also reads the result JSON
//! of `naocalib solve --json`, whose `parameters` object has the same entries (a `null`
//! `std` or `"determined": false` marks a parameter the data do not determine).

use std::collections::BTreeMap;
use std::path::Path;

use serde::ser::SerializeMap;
use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::dataset::{AngleKind, AngleSource};
use crate::export::{ExportError, parse_error};
use crate::model::{PAPER_PARAMETERS, Param};
use crate::report::ResultJson;
use crate::solve::Solution;

/// The `format` key of the TOML and JSON calibration files.
pub const FORMAT: &str = "naocalib-calibration";
/// The `version` key of the TOML and JSON calibration files.
pub const VERSION: i64 = 1;

/// The meaning of the offsets, as stated in every exported file.
pub const COMPENSATION: &str = "joint offset alpha: true joint angle = logged (sensor) angle + \
     alpha; team frameworks compute true = sensor - stored and command request + stored, so \
     their files store -alpha; camera offsets are rotation corrections of the lower camera \
     in the camera matrix, after the head joints";

/// A final RMS residual beyond this (px) is no plausible detection noise: such a fit is
/// not a calibration (the same bound as [`Solution::is_calibration`]).
pub const MAX_PLAUSIBLE_RMS_PX: f64 = crate::solve::misfit::IMPLAUSIBLE_RMS_PX;

/// One calibrated parameter, in report units (deg, mm, px, 1, deg/(N·m)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Entry {
    /// The parameter.
    pub param: Param,
    /// Its estimate (or the value it was held at).
    pub value: f64,
    /// Its one-sigma uncertainty; `Some(0)` when held fixed, `None` when the data do not
    /// determine it.
    pub std: Option<f64>,
    /// Whether it was held fixed (at `value`).
    pub fixed: bool,
}

impl Entry {
    /// Whether the value means something: held fixed, or determined by the data.
    pub fn is_determined(&self) -> bool {
        self.fixed || self.std.is_some()
    }

    /// `value ± std unit`, `value unit (fixed)` or `value unit (NOT determined)`.
    pub fn describe(&self) -> String {
        let unit = self.param.unit().name();
        match (self.fixed, self.std) {
            (true, _) => format!("{} {unit} (held fixed)", self.value),
            (false, Some(s)) => format!("{} ± {s} {unit}", self.value),
            (false, None) => format!("{} {unit} (NOT determined by the data)", self.value),
        }
    }
}

/// How `naocalib import` names itself as a calibration's `solver`.
pub const IMPORT_SOLVER: &str = "naocalib import";

/// A calibration as exported: every parameter with its one-sigma and unit, and how the
/// fit went.
#[derive(Debug, Clone, PartialEq)]
pub struct Calibration {
    /// The solver that produced it (`ceres`, …), when known.
    pub solver: Option<String>,
    /// The dataset it was calibrated from, when known.
    pub dataset: Option<String>,
    /// Whether the solver converged, when known.
    pub converged: Option<bool>,
    /// The final RMS residual `[x, y]` (px), when known.
    pub rms_px: Option<[f64; 2]>,
    /// The parameters, in the order of [`Param::ALL`].
    pub parameters: Vec<Entry>,
    /// Whether the dataset's joint angles were raw or already corrected by a joint
    /// calibration (`None`: not recorded, read as raw, the dataset default).
    pub angles: Option<AngleSource>,
    /// The posture whose leg offsets robot files carry (standing unless asked otherwise);
    /// it matters only when compliance or play have values.
    pub posture: Posture,
    /// What each standing leg offset rests on (its one-sigma, the lying torques its
    /// compliance was estimated from), by leg offset; empty when not known.
    pub standing: BTreeMap<Param, Standing>,
}

/// What a standing leg offset ([`Calibration::standing_offset`]) rests on.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Standing {
    /// Its one-sigma (deg): `√(gᵀ C g)` with `g = (1, τ_stand, ½·sgn τ_stand)` and `C` the
    /// covariance of `α`, `κ` and `π` of the joint, correlations included; `None` when
    /// not known.
    pub std: Option<f64>,
    /// The largest |gravity torque| (N·m) about the joint in the lying captures its
    /// compliance was estimated from; `None` when not known.
    pub lying_torque: Option<f64>,
}

/// The accuracy a standing leg offset should reach (deg, one sigma): beyond it the report
/// and `export` name the joint and the reason.
pub const STANDING_TARGET_DEG: f64 = 0.05;

/// A compliance applied at more than this many times the largest torque it was estimated
/// from is an extrapolation the report names.
pub const EXTRAPOLATION_LIMIT: f64 = 3.0;

/// The posture a robot file's leg offsets are for (`naocalib export --posture`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Posture {
    /// The standard stand the robot plays in ([`crate::model::gravity::STAND_DEG`]): leg
    /// offsets `α + κ·τ_stand + ½π·sgn τ_stand`.
    #[default]
    Standing,
    /// Lying on its back as calibrated: the offsets `α` themselves.
    Lying,
}

/// The standing gravity torque (N·m) about the leg joint whose offset is `param`, in the
/// standard stand with the default geometry; `None` for other parameters.
pub fn stand_torque(param: Param) -> Option<f64> {
    use crate::model::{RobotGeometry, Side, gravity};
    let side = match param.group() {
        crate::model::ParamGroup::LeftLeg => Side::Left,
        crate::model::ParamGroup::RightLeg => Side::Right,
        _ => return None,
    };
    let k = side.leg_joints().iter().position(|j| j.offset() == param)?;
    let torques =
        gravity::standing_leg_torques(&RobotGeometry::default(), side, &gravity::stand_joints());
    Some(torques[k])
}

/// The one-sigma (deg) of the standing offset of `param` in `cal` from the covariance of
/// `solution`: `√(gᵀ C g)` over the offset, and the compliance and play `cal` estimated
/// (held or undetermined ones enter with zero weight, as in the offset itself).
fn standing_std_of(solution: &Solution, cal: &Calibration, param: Param) -> Option<f64> {
    cal.standing_offset(param)?;
    let tau = stand_torque(param)?;
    let estimated = |suffix: &str| {
        Param::from_name(&format!("{}{suffix}", param.name()))
            .filter(|p| cal.get(*p).is_some_and(|e| !e.fixed && e.std.is_some()))
    };
    let mut g = vec![(param, 1.0)];
    g.extend(estimated("Compliance").map(|p| (p, tau)));
    let sign = if tau == 0.0 { 0.0 } else { tau.signum() };
    g.extend(estimated("Play").map(|p| (p, 0.5 * sign)));
    let c = &solution.covariance;
    let variance: f64 = g
        .iter()
        .flat_map(|&(a, ga)| {
            g.iter()
                .map(move |&(b, gb)| ga * gb * c[(a.index(), b.index())])
        })
        .sum();
    Some(param.unit().to_report(variance.max(0.0).sqrt()))
}

impl Calibration {
    /// The calibration of `solution` (from the dataset at `dataset`, if given).
    pub fn from_solution(solution: &Solution, dataset: Option<&Path>) -> Self {
        let mut cal = Calibration {
            solver: Some(solution.summary.solver.clone()),
            dataset: dataset.map(|d| d.display().to_string()),
            converged: Some(solution.summary.converged),
            rms_px: Some(solution.rms_px),
            parameters: Param::ALL
                .iter()
                .filter(|&&p| solution.fixed.in_model(p))
                .map(|&p| {
                    let fixed = solution.fixed.is_fixed(p);
                    let std = if fixed {
                        Some(0.0)
                    } else if solution.is_determined(p) {
                        Some(solution.report_std(p))
                    } else {
                        None
                    };
                    Entry {
                        param: p,
                        value: solution.report_value(p),
                        std,
                        fixed,
                    }
                })
                .collect(),
            angles: None,
            posture: Posture::Standing,
            standing: BTreeMap::new(),
        };
        let sigmas: Vec<(Param, f64)> = cal
            .parameters
            .iter()
            .filter_map(|e| Some((e.param, standing_std_of(solution, &cal, e.param)?)))
            .collect();
        for (p, std) in sigmas {
            cal.standing.entry(p).or_default().std = Some(std);
        }
        cal
    }

    /// Records, for every leg offset, the largest |gravity torque| about its joint in the
    /// captures of `dataset` (lying, the board of that leg in view): how far the standing
    /// torque extrapolates the compliance estimated from them.
    pub fn with_lying_torques(mut self, dataset: &crate::dataset::Dataset) -> Self {
        use crate::model::{Side, gravity};
        for side in [Side::Left, Side::Right] {
            let mut largest = [0.0f64; 6];
            for c in dataset.captures.iter().filter(|c| c.side == side) {
                let tau = gravity::leg_torques(
                    &dataset.model.robot,
                    &dataset.model.board,
                    side,
                    &c.joints,
                );
                for (m, t) in largest.iter_mut().zip(tau) {
                    *m = m.max(t.abs());
                }
            }
            for (joint, m) in side.leg_joints().into_iter().zip(largest) {
                if self.standing_offset(joint.offset()).is_some() {
                    self.standing
                        .entry(joint.offset())
                        .or_default()
                        .lying_torque = Some(m);
                }
            }
        }
        self
    }

    /// The one-sigma (deg) of [`Calibration::standing_offset`] of `param`, when known.
    pub fn standing_std(&self, param: Param) -> Option<f64> {
        self.standing_offset(param)?;
        self.standing.get(&param)?.std
    }

    /// Why the standing offset of `param` is less certain than [`STANDING_TARGET_DEG`], or
    /// rests on a compliance extrapolated beyond [`EXTRAPOLATION_LIMIT`] times its lying
    /// torques (`None` when neither): the joint, the reason and its one-sigma.
    pub fn standing_caveat(&self, param: Param) -> Option<String> {
        self.standing_offset(param)?;
        let tau = stand_torque(param)?;
        let info = self.standing.get(&param).copied().unwrap_or_default();
        let compliance = Param::from_name(&format!("{}Compliance", param.name()))
            .and_then(|p| self.get(p))
            .is_some_and(|e| !e.fixed && e.std.is_some());
        // σ falls as 1/√captures: how many times the captures would reach the target.
        let sigma = match info.std {
            None => "σ unknown".to_string(),
            Some(s) if s > STANDING_TARGET_DEG => format!(
                "±{s:.3}° (about {:.1}× the captures would reach ±{STANDING_TARGET_DEG}°)",
                (s / STANDING_TARGET_DEG).powi(2)
            ),
            Some(s) => format!("±{s:.3}°"),
        };
        let extrapolated = info
            .lying_torque
            .filter(|&m| compliance && tau.abs() > EXTRAPOLATION_LIMIT * m);
        if let Some(m) = extrapolated {
            let factor = if m > 0.0 {
                format!("×{:.0}", tau.abs() / m)
            } else {
                "from no torque at all".to_string()
            };
            return Some(format!(
                "{param}: compliance determined only up to {m:.3} N·m lying, extrapolated \
                 {factor} to the stand's {:.2} N·m: standing offset {sigma}",
                tau.abs()
            ));
        }
        match info.std {
            Some(s) if s > STANDING_TARGET_DEG => Some(format!(
                "{param}: standing offset {sigma}, beyond the {STANDING_TARGET_DEG}° target"
            )),
            _ => None,
        }
    }

    /// Every standing leg offset with what it rests on, in registry order: what the
    /// calibration file's `[standing]` table and the result JSON's `standing` carry.
    pub fn standing_files(&self) -> Vec<(Param, StandingFile)> {
        self.parameters
            .iter()
            .filter_map(|e| {
                let value = self.standing_offset(e.param)?;
                let info = self.standing.get(&e.param).copied().unwrap_or_default();
                Some((
                    e.param,
                    StandingFile {
                        value,
                        std: info.std,
                        tau_stand: stand_torque(e.param),
                        tau_lying_max: info.lying_torque,
                    },
                ))
            })
            .collect()
    }

    /// [`Calibration::standing_caveat`] of every leg offset that has one.
    pub fn standing_caveats(&self) -> Vec<String> {
        self.parameters
            .iter()
            .filter_map(|e| self.standing_caveat(e.param))
            .collect()
    }

    /// The effective offset (deg) of the leg joint whose offset is `param` for a robot in
    /// the standard stand: `α + κ·τ_stand + ½π·sgn τ_stand` with the compliance `κ` and
    /// play `π` this calibration estimated (zero when held or not determined) — `None` when
    /// `param` is no leg offset, or when neither compliance nor play was estimated (the
    /// standing offset is then `α` itself).
    pub fn standing_offset(&self, param: Param) -> Option<f64> {
        let tau = stand_torque(param)?;
        let alpha = self.get(param)?.value;
        // Only compliance and play this calibration estimated: held values (a robot's
        // imported jointPlay, say) are already in the offsets its file holds.
        let other = |suffix: &str| {
            Param::from_name(&format!("{}{suffix}", param.name()))
                .and_then(|p| self.get(p))
                .filter(|e| !e.fixed && e.std.is_some())
                .map_or(0.0, |e| e.value)
        };
        let (kappa, play) = (other("Compliance"), other("Play"));
        if kappa == 0.0 && play == 0.0 {
            return None;
        }
        let sign = if tau > 0.0 {
            1.0
        } else if tau < 0.0 {
            -1.0
        } else {
            0.0
        };
        Some(alpha + kappa * tau + 0.5 * play * sign)
    }

    /// The value a robot file carries for `param` in [`Calibration::posture`]: the standing
    /// offset of a leg joint when compliance or play have values, otherwise the value.
    fn posture_value(&self, param: Param, value: f64) -> f64 {
        match self.posture {
            Posture::Standing => self.standing_offset(param).unwrap_or(value),
            Posture::Lying => value,
        }
    }

    /// The entry of `param`, if present.
    pub fn get(&self, param: Param) -> Option<&Entry> {
        self.parameters.iter().find(|e| e.param == param)
    }

    /// The value of `param` in report units; 0 when absent.
    pub fn value(&self, param: Param) -> f64 {
        self.get(param).map_or(0.0, |e| e.value)
    }

    /// The value of `param` a fresh robot file carries (report units): its value when it is
    /// determined (estimated, or held at a known value); `None` when absent or not
    /// determined by the data (a robot file never carries an arbitrary value).
    pub fn robot_value(&self, param: Param) -> Option<f64> {
        self.get(param)
            .filter(|e| e.is_determined())
            .map(|e| self.posture_value(param, e.value))
    }

    /// The value of `param` when this calibration estimated it and the data determine it
    /// (report units): what `--update` writes into a robot's file. Held parameters and
    /// undetermined ones are `None`: the robot's file keeps its value.
    pub fn determined_here(&self, param: Param) -> Option<f64> {
        self.get(param)
            .filter(|e| !e.fixed && e.std.is_some())
            .map(|e| self.posture_value(param, e.value))
    }

    /// Whether the joint angles the calibration was fitted to were already corrected by
    /// the robot's joint calibration (dataset `[joints] angles = "corrected"`).
    pub fn corrected_angles(&self) -> bool {
        self.angles
            .as_ref()
            .is_some_and(|a| a.kind == AngleKind::Corrected)
    }

    /// The value a team file stores for the offset `param` (deg), whose file held
    /// `old_stored` (deg): `−α` for raw angles; for angles the file's calibration already
    /// corrected (true = logged + α with logged = sensor − old), `old_stored − α`.
    pub fn stored_joint_value(
        &self,
        param: Param,
        old_stored: f64,
        path: &Path,
    ) -> Result<f64, ExportError> {
        let alpha = self.determined_here(param).ok_or_else(|| {
            parse_error(
                path,
                format!("{param} was not determined by this calibration"),
            )
        })?;
        Ok(if self.corrected_angles() {
            old_stored - alpha
        } else {
            -alpha
        })
    }

    /// Whether this is a robot's calibration read by `naocalib import` (its `solver` starts
    /// with [`IMPORT_SOLVER`]) rather than a fit: the values the robot runs with, no RMS,
    /// nothing converged.
    pub fn is_import(&self) -> bool {
        self.converged.is_none()
            && self.rms_px.is_none()
            && self
                .solver
                .as_deref()
                .is_some_and(|s| s.starts_with(IMPORT_SOLVER))
    }

    /// Why this result is not a calibration a robot should load (empty when it is one):
    /// the solver did not converge, a value or sigma is not finite, or the residuals are
    /// far beyond any plausible noise ([`MAX_PLAUSIBLE_RMS_PX`]).
    pub fn problems(&self) -> Vec<String> {
        let mut out = Vec::new();
        if self.converged == Some(false) {
            out.push("the solver did not converge".to_string());
        }
        let bad: Vec<&str> = self
            .parameters
            .iter()
            .filter(|e| !e.value.is_finite() || e.std.is_some_and(|s| !s.is_finite()))
            .map(|e| e.param.name())
            .collect();
        if !bad.is_empty() {
            out.push(format!("non-finite values or sigmas: {}", bad.join(", ")));
        }
        // A robot's imported calibration is not a fit: nothing converged or was determined
        // by data, and its values are what the robot already runs with (the bounds hold).
        let imported = self.is_import();
        if self.converged.is_none() && !imported {
            out.push("it does not say whether the solver converged".to_string());
        }
        // Physical bounds (crate::model::bounds) and a determined rank.
        let outside = crate::model::bounds::violations_of_estimates(
            self.parameters
                .iter()
                .filter(|e| e.value.is_finite())
                .map(|e| (e.param, e.value, e.std.unwrap_or(0.0))),
        );
        if !outside.is_empty() {
            let list: Vec<String> = outside.iter().map(|v| v.to_string()).collect();
            out.push(format!("outside the physical bounds: {}", list.join("; ")));
        }
        let free: Vec<&Entry> = self.parameters.iter().filter(|e| !e.fixed).collect();
        if !imported && !free.is_empty() && free.iter().all(|e| e.std.is_none()) {
            out.push("the data determine none of the free parameters (rank 0)".to_string());
        }
        if let Some(rms) = self.rms_px {
            if rms.iter().any(|r| !r.is_finite()) {
                out.push("the RMS residual is not finite".to_string());
            } else if rms.iter().any(|&r| r > MAX_PLAUSIBLE_RMS_PX) {
                out.push(format!(
                    "RMS residual ({:.2}, {:.2}) px is far beyond any plausible detection \
                     noise ({MAX_PLAUSIBLE_RMS_PX} px): the model does not explain the data",
                    rms[0], rms[1]
                ));
            }
        }
        out
    }

    fn file(&self, json: bool) -> CalibrationOut<'_> {
        CalibrationOut {
            format: FORMAT,
            version: VERSION,
            solver: self.solver.as_deref(),
            dataset: self.dataset.as_deref(),
            converged: self.converged,
            rms_px: self.rms_px,
            units: json.then(|| {
                BTreeMap::from([
                    ("angles".to_string(), "deg".to_string()),
                    ("lengths".to_string(), "mm".to_string()),
                ])
            }),
            compensation: COMPENSATION,
            angles: self.angles.as_ref().map(|a| a.kind),
            corrected_by: self.angles.as_ref().and_then(|a| a.corrected_by.as_deref()),
            parameters: Entries(&self.parameters),
            standing: self
                .standing_files()
                .into_iter()
                .map(|(p, f)| (p.name(), f))
                .collect(),
        }
    }

    /// The calibration as TOML, with a header stating units and the compensation rule.
    pub fn to_toml(&self) -> String {
        let mut s = String::new();
        crate::export::header(
            &mut s,
            "#",
            self,
            "angles in degrees (deg), lengths in millimetres (mm), intrinsics in pixels \
             (px); std is the one-sigma uncertainty in the same unit",
        );
        s.push('\n');
        s.push_str(&toml::to_string(&self.file(false)).expect("TOML of plain values"));
        s
    }

    /// The calibration as JSON (the same keys as the TOML).
    pub fn to_json(&self) -> Value {
        serde_json::to_value(self.file(true)).expect("JSON of plain values")
    }

    /// Reads a calibration TOML written by [`Calibration::to_toml`]; `path` names the
    /// source in errors (with the line).
    pub fn from_toml(text: &str, path: &Path) -> Result<Self, ExportError> {
        let file: CalibrationIn = toml::from_str(text).map_err(|e| {
            let line = e
                .span()
                .map(|s| format!("line {}: ", text[..s.start].matches('\n').count() + 1))
                .unwrap_or_default();
            parse_error(path, format!("{line}{}", e.message()))
        })?;
        file.into_calibration(path)
    }

    /// Reads a calibration JSON written by [`Calibration::to_json`], or the result JSON of
    /// `naocalib solve --json` (a run of `naocalib batch --out`).
    pub fn from_json(text: &str, path: &Path) -> Result<Self, ExportError> {
        let json_error = |e: serde_json::Error| {
            // serde says "sequence" and "map" for what a JSON file calls array and object.
            let text = e
                .to_string()
                .replace("invalid type: sequence", "found a JSON array")
                .replace("invalid type: map", "found a JSON object");
            parse_error(path, format!("line {}: {text}", e.line()))
        };
        let probe: Value = serde_json::from_str(text).map_err(json_error)?;
        if probe.get("format").is_some() {
            let file: CalibrationIn = serde_json::from_str(text).map_err(json_error)?;
            file.into_calibration(path)
        } else {
            let result: ResultJson = serde_json::from_str(text).map_err(json_error)?;
            Calibration::from_result(result, path)
        }
    }
}

/// Reads a calibration file: TOML by the `.toml` extension, otherwise JSON (a calibration
/// JSON or the result JSON of `naocalib solve --json`).
pub fn read_calibration(path: &Path) -> Result<Calibration, ExportError> {
    let text = crate::export::source::read(path)?.text;
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("toml"))
    {
        Calibration::from_toml(&text, path)
    } else {
        Calibration::from_json(&text, path)
    }
}

/// Reads the calibration a solve or a detection starts from (`--start-from`: a robot's
/// calibration from `naocalib import`, or an earlier result) and refuses it when a value it
/// holds is beyond the physical bounds ([`crate::model::bounds`]), naming the file and the
/// parameter: a start value beyond them (a play of −3°, an offset of 50°) would move the
/// model's joints by it without a word.
pub fn read_start_from(path: &Path) -> Result<Calibration, ExportError> {
    let cal = read_calibration(path)?;
    let held: Vec<(Param, f64)> = cal
        .parameters
        .iter()
        .filter(|e| e.is_determined())
        .map(|e| (e.param, e.value))
        .collect();
    match crate::model::bounds::violations(held).first() {
        None => Ok(cal),
        Some(v) => Err(parse_error(
            path,
            format!(
                "{v}: not a calibration to start from; fix the file (or the robot's file it was imported from) first"
            ),
        )),
    }
}

fn is_false(b: &bool) -> bool {
    !*b
}

/// The file as written.
#[derive(Serialize)]
struct CalibrationOut<'a> {
    format: &'a str,
    version: i64,
    #[serde(skip_serializing_if = "Option::is_none")]
    solver: Option<&'a str>,
    #[serde(skip_serializing_if = "Option::is_none")]
    dataset: Option<&'a str>,
    #[serde(skip_serializing_if = "Option::is_none")]
    converged: Option<bool>,
    #[serde(skip_serializing_if = "Option::is_none")]
    rms_px: Option<[f64; 2]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    units: Option<BTreeMap<String, String>>,
    compensation: &'a str,
    #[serde(skip_serializing_if = "Option::is_none")]
    angles: Option<AngleKind>,
    #[serde(skip_serializing_if = "Option::is_none")]
    corrected_by: Option<&'a str>,
    parameters: Entries<'a>,
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    standing: BTreeMap<&'a str, StandingFile>,
}

/// One standing leg offset as written (`[standing.<offset>]`): its value (derived from the
/// parameters, deg), one-sigma (deg), the stand's torque and the largest lying torque its
/// compliance was estimated from (N·m).
#[derive(Serialize, Deserialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct StandingFile {
    /// The standing offset (deg).
    pub value: f64,
    /// Its one-sigma (deg).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub std: Option<f64>,
    /// The stand's gravity torque about the joint (N·m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tau_stand: Option<f64>,
    /// The largest lying torque the compliance was estimated from (N·m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tau_lying_max: Option<f64>,
}

/// A standing offset as read: a table, or a bare value (files of earlier versions).
#[derive(Serialize, Deserialize, Debug, Clone, PartialEq)]
#[serde(untagged)]
pub enum StandingIn {
    /// `{value, std, tau_stand, tau_lying_max}`.
    Table(StandingFile),
    /// A bare value (deg), as earlier versions wrote.
    Value(f64),
}

/// The [`Standing`] entries of a `standing` table read (values are derived from the
/// parameters and not kept); unknown offsets or bad numbers are errors.
fn standing_from(
    table: Option<BTreeMap<String, StandingIn>>,
    path: &Path,
) -> Result<BTreeMap<Param, Standing>, ExportError> {
    let mut out = BTreeMap::new();
    for (name, entry) in table.unwrap_or_default() {
        let Some(p) = Param::from_name(&name).filter(|p| stand_torque(*p).is_some()) else {
            return Err(parse_error(
                path,
                format!("standing.{name}: not a leg joint offset"),
            ));
        };
        let StandingIn::Table(t) = entry else {
            continue;
        };
        for (key, x) in [("std", t.std), ("tau_lying_max", t.tau_lying_max)] {
            if let Some(x) = x
                && !(x.is_finite() && x >= 0.0)
            {
                return Err(parse_error(
                    path,
                    format!("standing.{name}.{key}: {x} is not a finite, non-negative number"),
                ));
            }
        }
        out.insert(
            p,
            Standing {
                std: t.std,
                lying_torque: t.tau_lying_max,
            },
        );
    }
    Ok(out)
}

/// The parameters as a map in registry order.
struct Entries<'a>(&'a [Entry]);

impl Serialize for Entries<'_> {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let mut map = serializer.serialize_map(Some(self.0.len()))?;
        for e in self.0 {
            map.serialize_entry(
                e.param.name(),
                &EntryFile {
                    value: e.value,
                    std: e.std,
                    unit: Some(e.param.unit().name().to_string()),
                    fixed: e.fixed,
                    undetermined: !e.is_determined(),
                },
            )?;
        }
        map.end()
    }
}

/// One parameter as written and read.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct EntryFile {
    value: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    std: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    unit: Option<String>,
    #[serde(default, skip_serializing_if = "is_false")]
    fixed: bool,
    #[serde(default, skip_serializing_if = "is_false")]
    undetermined: bool,
}

/// The file as read.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CalibrationIn {
    format: String,
    version: i64,
    solver: Option<String>,
    dataset: Option<String>,
    converged: Option<bool>,
    rms_px: Option<[f64; 2]>,
    #[allow(dead_code)]
    units: Option<BTreeMap<String, String>>,
    #[allow(dead_code)]
    compensation: Option<String>,
    angles: Option<AngleKind>,
    corrected_by: Option<String>,
    parameters: UniqueMap<EntryFile>,
    /// Values derived from the parameters on writing ([`Calibration::standing_offset`]);
    /// their one-sigma and lying torques are kept.
    standing: Option<BTreeMap<String, StandingIn>>,
}

impl CalibrationIn {
    fn into_calibration(self, path: &Path) -> Result<Calibration, ExportError> {
        if self.format != FORMAT {
            return Err(parse_error(
                path,
                format!("format is \"{}\", expected \"{FORMAT}\"", self.format),
            ));
        }
        if self.version != VERSION {
            return Err(parse_error(
                path,
                format!(
                    "version {} is not supported (expected {VERSION})",
                    self.version
                ),
            ));
        }
        let entries = self.parameters.0.into_iter().map(|(name, e)| {
            let determined = !e.undetermined;
            (name, e.value, e.std, e.unit, e.fixed, determined)
        });
        let fit = (self.solver, self.dataset, self.converged, self.rms_px);
        assemble(
            fit,
            (self.angles, self.corrected_by),
            entries.collect(),
            self.standing,
            path,
        )
    }
}

/// What a calibration or result file says of the fit: solver, dataset, converged, RMS.
type FitRead = (
    Option<String>,
    Option<String>,
    Option<bool>,
    Option<[f64; 2]>,
);

/// The calibration a file holds: its fit, its `angles`/`corrected_by` and its parameters,
/// each checked.
fn assemble(
    (solver, dataset, converged, rms_px): FitRead,
    (kind, corrected_by): (Option<AngleKind>, Option<String>),
    entries: Vec<RawEntry>,
    standing: Option<BTreeMap<String, StandingIn>>,
    path: &Path,
) -> Result<Calibration, ExportError> {
    let angles = angle_source(kind, corrected_by, path)?;
    check_rms(rms_px, path)?;
    Ok(Calibration {
        solver,
        dataset,
        converged,
        rms_px,
        parameters: entries_from(entries, path)?,
        angles,
        posture: Posture::Standing,
        standing: standing_from(standing, path)?,
    })
}

/// The `angles` / `corrected_by` keys as an [`AngleSource`] (`None` when absent).
fn angle_source(
    kind: Option<AngleKind>,
    corrected_by: Option<String>,
    path: &Path,
) -> Result<Option<AngleSource>, ExportError> {
    match (kind, corrected_by) {
        (None, None) => Ok(None),
        (None, Some(_)) => Err(parse_error(path, "corrected_by without angles")),
        (Some(AngleKind::Raw), Some(_)) => Err(parse_error(
            path,
            "corrected_by is only meaningful with angles = \"corrected\"",
        )),
        (Some(kind), corrected_by) => Ok(Some(AngleSource { kind, corrected_by })),
    }
}

impl Calibration {
    /// The calibration a result JSON ([`ResultJson`]) holds; `path` names the source in
    /// errors.
    pub fn from_result(result: ResultJson, path: &Path) -> Result<Self, ExportError> {
        let entries = result.parameters.0.into_iter().map(|(name, e)| {
            let determined = e.is_determined();
            (name, e.value, e.std, e.unit, e.fixed, determined)
        });
        let fit = (
            result.solver,
            result.dataset,
            result.converged,
            result.rms_px,
        );
        let angles = (result.angles, result.corrected_by);
        assemble(fit, angles, entries.collect(), result.standing, path)
    }
}

/// An RMS residual read must be a non-negative number.
fn check_rms(rms: Option<[f64; 2]>, path: &Path) -> Result<(), ExportError> {
    if let Some(r) = rms.iter().flatten().find(|r| **r < 0.0) {
        return Err(parse_error(
            path,
            format!("rms_px: {r} is negative; an RMS residual is never below zero"),
        ));
    }
    Ok(())
}

/// The `parameters` table of a calibration or result file, by name: read, its keys must be
/// unique (serde's maps keep the last of a repeated key, so a parameter given twice would
/// pass unnoticed); written, in alphabetical order.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(transparent)]
pub struct UniqueMap<V>(pub BTreeMap<String, V>);

impl<'de, V: Deserialize<'de>> Deserialize<'de> for UniqueMap<V> {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Visit<V>(std::marker::PhantomData<V>);
        impl<'de, V: Deserialize<'de>> serde::de::Visitor<'de> for Visit<V> {
            type Value = UniqueMap<V>;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a table of parameters")
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                mut map: A,
            ) -> Result<Self::Value, A::Error> {
                let mut out = BTreeMap::new();
                while let Some(key) = map.next_key::<String>()? {
                    if out.contains_key(&key) {
                        return Err(serde::de::Error::custom(format!(
                            "parameters.{key} is given twice"
                        )));
                    }
                    let value = map.next_value()?;
                    out.insert(key, value);
                }
                Ok(UniqueMap(out))
            }
        }
        d.deserialize_map(Visit(std::marker::PhantomData))
    }
}

type RawEntry = (String, f64, Option<f64>, Option<String>, bool, bool);

/// Checks the entries read (names, units, numbers) and orders them as [`Param::ALL`].
fn entries_from(raw: Vec<RawEntry>, path: &Path) -> Result<Vec<Entry>, ExportError> {
    let mut by_param = BTreeMap::new();
    for (name, value, std, unit, fixed, determined) in raw {
        let Some(p) = Param::from_name(&name) else {
            return Err(parse_error(
                path,
                format!("parameters.{name}: unknown parameter"),
            ));
        };
        let at = |key: &str| format!("parameters.{name}.{key}");
        if !value.is_finite() {
            return Err(parse_error(
                path,
                format!("{}: {value} is not a finite number", at("value")),
            ));
        }
        if let Some(u) = &unit
            && u != p.unit().name()
        {
            return Err(parse_error(
                path,
                format!(
                    "{}: \"{u}\", but {name} is in {}",
                    at("unit"),
                    p.unit().name()
                ),
            ));
        }
        if fixed && !determined {
            return Err(parse_error(
                path,
                format!("parameters.{name}: both fixed and undetermined"),
            ));
        }
        let std = match (fixed, determined, std) {
            (true, _, s) => Some(s.unwrap_or(0.0)),
            (false, false, _) => None,
            (false, true, s) => s,
        };
        if let Some(s) = std
            && !(s.is_finite() && s >= 0.0)
        {
            return Err(parse_error(
                path,
                format!("{}: {s} is not a finite, non-negative number", at("std")),
            ));
        }
        by_param.insert(
            p,
            Entry {
                param: p,
                value,
                std,
                fixed,
            },
        );
    }
    for p in &Param::ALL[..PAPER_PARAMETERS] {
        if !by_param.contains_key(p) {
            return Err(parse_error(
                path,
                format!("parameters.{}: missing", p.name()),
            ));
        }
    }
    Ok(by_param.into_values().collect())
}
