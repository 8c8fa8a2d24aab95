//! The calibration: every parameter with its one-sigma and unit, how the fit went, where
//! it came from ([`Origin`]: solved here, or imported from a robot's team files), and the
//! standing leg offsets robot files carry ([`standing`]). What `solve`, the reports and
//! every export read; [`mod@file`]: the tables naocalib's own calibration file (written
//! and read as one of the exports) shares with the result JSON.

pub mod file;
pub mod intrinsics;
pub mod result_json;
pub mod standing;

use std::collections::BTreeMap;
use std::path::Path;

use crate::dataset::{AngleKind, AngleSource};
use crate::model::{CameraId, Model, Param};
use crate::solve::Solution;

pub use file::{StandingFile, StandingIn, UniqueMap};
pub use intrinsics::{Intrinsics, Prior};
pub use standing::{EXTRAPOLATION_LIMIT, STANDING_TARGET_DEG, Standing, stand_torque};

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

/// How `naocalib import` names itself as a calibration's `solver` (the file's wording;
/// [`Calibration::origin`] says it in the type).
pub const IMPORT_SOLVER: &str = "naocalib import";

/// Where a calibration's values come from.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Origin {
    /// Fitted to a dataset by naocalib's solver (`solve`, `batch`).
    #[default]
    Solved,
    /// A robot's calibration as its team files hold it (`naocalib import`): the values the
    /// robot runs with, nothing fitted, converged or determined by data.
    Imported,
}

/// A calibration as exported: every parameter with its one-sigma and unit, and how the
/// fit went.
#[derive(Debug, Clone, PartialEq)]
pub struct Calibration {
    /// Where its values come from: solved here, or imported from a robot's team files.
    pub origin: Origin,
    /// The solver that produced it (`ceres`, …; for an imported one, what `naocalib
    /// import` read), when known.
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
    /// The a-priori intrinsics of each camera whose intrinsics the calibration carries
    /// (estimated, or imported from a robot's file): what its corrections `Fx` … `Cy`
    /// (`UpperFx` … `UpperCy`) are relative to. Empty when it carries none.
    pub cameras: BTreeMap<CameraId, Prior>,
}

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

impl Calibration {
    /// The calibration of `solution` (from the dataset at `dataset`, if given).
    pub fn from_solution(solution: &Solution, dataset: Option<&Path>) -> Self {
        let mut cal = Calibration {
            origin: Origin::Solved,
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
            cameras: BTreeMap::new(),
        };
        let sigmas: Vec<(Param, f64)> = cal
            .parameters
            .iter()
            .filter_map(|e| Some((e.param, standing::standing_std_of(solution, &cal, e.param)?)))
            .collect();
        for (p, std) in sigmas {
            cal.standing.entry(p).or_default().std = Some(std);
        }
        cal
    }

    /// The calibration with the a-priori intrinsics of `model` for every camera whose
    /// intrinsics it estimated ([`Calibration::cameras`]).
    pub fn with_cameras(mut self, model: &Model) -> Self {
        let estimated = |p: Param| self.get(p).is_some_and(|e| !e.fixed);
        self.cameras = intrinsics::priors_of(model, estimated)
            .into_iter()
            .collect();
        self
    }

    /// `camera`'s calibrated intrinsics: its prior ([`Calibration::cameras`]) plus the
    /// corrections, with their one-sigma (a correction the data do not determine is left
    /// out — its value is arbitrary, and no robot file carries it — and its one-sigma is
    /// `None`); `None` when the calibration carries none for it.
    pub fn intrinsics(&self, camera: CameraId) -> Option<Intrinsics> {
        let prior = *self.cameras.get(&camera)?;
        let params = intrinsics::params(camera);
        let entry = params.map(|p| self.get(p));
        let base = prior.values();
        let correction =
            |e: Option<&Entry>| e.filter(|e| e.is_determined()).map_or(0.0, |e| e.value);
        Some(Intrinsics {
            camera,
            prior,
            value: std::array::from_fn(|k| base[k] + correction(entry[k])),
            std: entry.map(|e| e.map_or(Some(0.0), |e| e.std)),
            calibrated: params.map(|p| self.determined_here(p).is_some()),
        })
    }

    /// The start values this calibration gives a problem of `model` (report units): every
    /// determined parameter, the intrinsics corrections of a camera it carries a prior for
    /// made relative to `model`'s a-priori intrinsics of that camera (scaled to its image
    /// size), as `--start-from` and `plan --around` take them.
    pub fn start_values(&self, model: &Model) -> Vec<(Param, f64)> {
        let mut values: Vec<(Param, f64)> = self
            .parameters
            .iter()
            .filter(|e| e.is_determined())
            .map(|e| (e.param, e.value))
            .collect();
        let (intrinsics, undetermined) = self.intrinsics_relative_to(model);
        values
            .retain(|(p, _)| !undetermined.contains(p) && !intrinsics.iter().any(|(q, _)| q == p));
        values.extend(intrinsics);
        values
    }

    /// The intrinsics corrections (px) of every camera this calibration carries a prior
    /// for, made relative to `model`'s a-priori intrinsics of that camera (scaled to its
    /// image size); and the corrections it carries but does not determine.
    pub fn intrinsics_relative_to(&self, model: &Model) -> (Vec<(Param, f64)>, Vec<Param>) {
        let mut values = Vec::new();
        let mut undetermined = Vec::new();
        for (&camera, prior) in &self.cameras {
            let Some(intrinsics) = self.intrinsics(camera) else {
                continue;
            };
            let own = model.intrinsics(camera);
            let scaled = Prior {
                fx: intrinsics.value[0],
                fy: intrinsics.value[1],
                cx: intrinsics.value[2],
                cy: intrinsics.value[3],
                ..*prior
            }
            .scaled_to(own.width, own.height);
            let base = Prior::of(own).values();
            for (k, p) in intrinsics::params(camera).into_iter().enumerate() {
                if self.get(p).is_none_or(|e| e.is_determined()) {
                    values.push((p, scaled[k] - base[k]));
                } else {
                    undetermined.push(p);
                }
            }
        }
        (values, undetermined)
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

    /// Whether this is a robot's calibration read by `naocalib import` ([`Origin::Imported`])
    /// rather than a fit: the values the robot runs with, no RMS, nothing converged.
    pub fn is_import(&self) -> bool {
        self.origin == Origin::Imported
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
}
