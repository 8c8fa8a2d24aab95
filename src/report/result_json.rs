//! The result JSON of `naocalib solve --json` (docs/MODEL.md §8) as one type, [`ResultJson`]:
//! the JSON of a run ([`ResultJson::from_run`]), written by `solve --json` and for every run
//! of `batch` (`--json`, `--out`), read back by `naocalib export` and
//! `solve --start-from` ([`crate::calibration::Calibration::from_json`]), so that what is
//! written and what is read are the same keys.
//!
//! Printed through [`ResultJson::to_value`], its keys are in alphabetical order at every
//! level. JSON has no NaN or infinity: a number that is not finite is written as `null`, so
//! the numbers of the fit's statistics are `Option<f64>` (`None` for `null`) when read. The
//! keys a calibration needs are the only ones a reader must find; the others default when
//! absent (a result written by hand, or by an older naocalib).

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::calibration::{Prior, StandingIn, UniqueMap};
use crate::dataset::AngleKind;
use crate::model::{CameraId, Param};
use crate::run::{Change, Run};
use crate::solve::Solution;
use crate::solve::uncertainty::Direction;

/// The result of one calibration, as `naocalib solve --json` prints it. Fields are in the
/// order of the printed keys (alphabetical).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ResultJson {
    /// Whether the dataset's joint angles were raw or already corrected (`solve`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub angles: Option<AngleKind>,
    /// The a-priori intrinsics of each camera whose intrinsics were estimated (`solve
    /// --free intrinsics`), as naocalib's calibration files carry them: what the
    /// corrections `Fx` … `Cy` (`UpperFx` … `UpperCy`) are relative to, so that `export`
    /// writes the cameras' intrinsics from the result. Absent with the intrinsics held.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cameras: Option<BTreeMap<CameraId, Prior>>,
    /// Captures used.
    #[serde(default)]
    pub captures: usize,
    /// The change since the robot's previous calibration (`solve --start-from`), by
    /// parameter name.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub changes: Option<BTreeMap<String, ChangeJson>>,
    /// The families `--model auto` freed, with their misfit test.
    #[serde(default)]
    pub chosen: Vec<ChosenJson>,
    /// Whether the solver converged.
    pub converged: Option<bool>,
    /// The joint calibration that corrected the angles, when they were (`solve`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub corrected_by: Option<String>,
    /// The dataset directory (`solve`, `batch`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dataset: Option<String>,
    /// The families fitted (`paper`, `compliance`, …).
    #[serde(default)]
    pub families: Vec<String>,
    /// The final cost.
    #[serde(default)]
    pub final_cost: Option<f64>,
    /// Rank, conditioning and undetermined directions.
    #[serde(default)]
    pub identifiability: IdentifiabilityJson,
    /// The cost at the start values.
    #[serde(default)]
    pub initial_cost: Option<f64>,
    /// The RMS residual `[x, y]` at the start values (px).
    #[serde(default)]
    pub initial_rms_px: [Option<f64>; 2],
    /// Solver iterations.
    #[serde(default)]
    pub iterations: usize,
    /// The misfit tests and their verdict.
    #[serde(default)]
    pub misfit: MisfitJson,
    /// The noise model (`null` without one).
    #[serde(default)]
    pub noise: Option<NoiseJson>,
    /// The vertices left out as outliers by a robust first fit.
    #[serde(default)]
    pub outliers: Vec<OutlierJson>,
    /// Every parameter, by name.
    pub parameters: UniqueMap<ParameterJson>,
    /// The residual standard deviation (px).
    #[serde(default)]
    pub residual_sigma_px: Option<f64>,
    /// The final RMS residual `[x, y]` (px).
    pub rms_px: Option<[f64; 2]>,
    /// Wall time of the calibration (s).
    #[serde(default)]
    pub seconds: Option<f64>,
    /// The solver (`ceres`, `lm`, `tiny`).
    pub solver: Option<String>,
    /// The standing leg offsets when compliance or play have values (`solve`): value and
    /// one-sigma (deg), the stand's and the largest lying torque (N·m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub standing: Option<BTreeMap<String, StandingIn>>,
    /// How the solver ended.
    #[serde(default)]
    pub termination: String,
    /// The parameters the data do not determine, each with the combination it forms.
    #[serde(default)]
    pub undetermined: Vec<UndeterminedJson>,
    /// Vertices used.
    #[serde(default)]
    pub vertices: usize,
}

/// One parameter of the result, in report units.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParameterJson {
    /// `false` when the data do not determine it (absent otherwise).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub determined: Option<bool>,
    /// Held fixed (absent when not).
    #[serde(default, skip_serializing_if = "is_false")]
    pub fixed: bool,
    /// One sigma: 0 when held, `null` when the data do not determine it.
    #[serde(default)]
    pub std: Option<f64>,
    /// The bootstrap's one sigma (`--bootstrap`), when estimated and determined.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub std_bootstrap: Option<f64>,
    /// The sandwich one sigma, when estimated and determined.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub std_sandwich: Option<f64>,
    /// The held (undetermined) parameters its σ assumes at their nominal value, each with
    /// how far its error moves this one (this one's unit per the held one's): when present,
    /// the σ is not honest (absent otherwise).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub std_assumes_held: Option<std::collections::BTreeMap<String, f64>>,
    /// The true value, when the dataset has one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub truth: Option<f64>,
    /// `true` when the data do not determine it (absent otherwise).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub undetermined: Option<bool>,
    /// The unit (`deg`, `mm`, `px`, `1`, `deg/(N·m)`).
    #[serde(default)]
    pub unit: Option<String>,
    /// The estimate, or the value it was held at.
    pub value: f64,
}

impl ParameterJson {
    /// Whether the entry says the data determine its value: not marked undetermined, and
    /// held fixed or with a sigma.
    pub fn is_determined(&self) -> bool {
        self.determined.unwrap_or(true)
            && !self.undetermined.unwrap_or(false)
            && (self.fixed || self.std.is_some())
    }
}

/// The noise model's levels.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NoiseJson {
    /// The joint-angle σ per joint and capture (deg).
    pub joint_deg: Option<f64>,
    /// The pixel σ (px).
    pub px: Option<f64>,
}

/// Identifiability: docs/MODEL.md §8.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct IdentifiabilityJson {
    /// The column-scaled condition number (`null` when infinite).
    pub condition_number: Option<f64>,
    /// Strongly correlated pairs.
    pub correlated: Vec<CorrelatedJson>,
    /// Free parameters.
    pub free: usize,
    /// Numerical rank.
    pub rank: usize,
    /// Singular values of the column-scaled Jacobian.
    pub singular_values: Vec<Option<f64>>,
    /// What to hold fixed.
    pub suggest_fix: Vec<String>,
    /// Directions the data do not determine.
    pub undetermined: Vec<DirectionJson>,
    /// Parameters no capture observes.
    pub unobserved: Vec<String>,
    /// Weakly determined directions.
    pub weak: Vec<DirectionJson>,
}

/// A strongly correlated pair.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CorrelatedJson {
    /// One parameter.
    pub a: String,
    /// The other.
    pub b: String,
    /// Their correlation.
    pub r: Option<f64>,
}

/// A direction in parameter space.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DirectionJson {
    /// As text (`0.71·LHipPitch − 0.70·LKneePitch`).
    pub combination: String,
    /// Its singular value relative to the largest.
    pub relative_singular_value: Option<f64>,
    /// `[parameter, coefficient]` pairs.
    pub terms: Vec<(String, Option<f64>)>,
}

/// The misfit tests and verdict.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct MisfitJson {
    /// Whether a misfit was detected.
    pub detected: bool,
    /// The verdict in one line.
    pub message: String,
    /// Whether the noise model was set aside (the residuals are not noise).
    pub noise_model_set_aside: bool,
    /// The families the tests point to.
    pub suggest: Vec<String>,
    /// One test per family.
    pub tests: Vec<FamilyTestJson>,
}

/// One family's misfit test.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FamilyTestJson {
    /// Degrees of freedom.
    pub df: usize,
    /// The family.
    pub family: String,
    /// The p-value.
    pub p_value: Option<f64>,
    /// The family's parameters.
    pub parameters: Vec<String>,
    /// Whether it is significant.
    pub significant: bool,
    /// The test statistic.
    pub statistic: Option<f64>,
}

/// A family `--model auto` freed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ChosenJson {
    /// The family.
    pub family: String,
    /// Its test's p-value.
    pub p_value: Option<f64>,
    /// Its test statistic.
    pub statistic: Option<f64>,
}

/// A parameter the data do not determine.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct UndeterminedJson {
    /// The combination it forms.
    pub combination: String,
    /// The parameter.
    pub parameter: String,
}

/// A vertex left out as an outlier.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OutlierJson {
    /// The capture id.
    pub capture: u64,
    /// The vertex column.
    pub col: u32,
    /// Its `(u, v)` residual at the robust fit (px).
    pub residual_px: [Option<f64>; 2],
    /// The vertex row.
    pub row: u32,
}

/// A parameter's change since the previous calibration ([`Change`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ChangeJson {
    /// `value − previous`.
    pub change: Option<f64>,
    /// The previous value.
    pub previous: Option<f64>,
    /// The value now.
    pub value: Option<f64>,
    /// `change / σ` (`null` when σ is zero).
    pub z: Option<f64>,
}

fn is_false(b: &bool) -> bool {
    !*b
}

fn names<'a>(names: impl IntoIterator<Item = &'a str>) -> Vec<String> {
    names.into_iter().map(String::from).collect()
}

impl From<&Direction> for DirectionJson {
    fn from(d: &Direction) -> Self {
        DirectionJson {
            combination: d.describe(),
            relative_singular_value: Some(d.relative_singular_value),
            terms: d
                .terms
                .iter()
                .map(|(p, c)| (p.name().to_string(), Some(*c)))
                .collect(),
        }
    }
}

impl ResultJson {
    /// The result JSON of `run`: its solution (with the truth, when known), dataset, the
    /// dataset's joint-angle source, standing leg offsets, the change since the previous
    /// calibration and the a-priori intrinsics of the cameras whose intrinsics it
    /// estimated.
    pub fn from_run(run: &Run) -> Self {
        let mut result =
            ResultJson::new(&run.solution, run.truth()).with_standing(&run.calibration);
        result.dataset = Some(run.dataset().display().to_string());
        if let Some(angles) = &run.calibration.angles {
            result.angles = Some(angles.kind);
            result.corrected_by = angles.corrected_by.clone();
        }
        if let Some(changes) = &run.changes {
            result = result.with_changes(changes);
        }
        let cameras = &run.calibration.cameras;
        result.cameras = (!cameras.is_empty()).then(|| cameras.clone());
        result
    }

    /// The result of `solution` (with each parameter's `truth` when given), without the
    /// keys only a dataset or a command knows (`dataset`, `angles`, `changes`, …).
    pub fn new(solution: &Solution, truth: Option<&[f64]>) -> Self {
        let s = &solution.summary;
        let id = &solution.identifiability;
        let parameters = Param::ALL
            .iter()
            .filter(|&&p| solution.fixed.in_model(p))
            .map(|&p| (p.name().to_string(), parameter(solution, p, truth)))
            .collect();
        ResultJson {
            angles: None,
            cameras: None,
            captures: solution.captures,
            changes: None,
            chosen: solution
                .chosen
                .iter()
                .map(|t| ChosenJson {
                    family: t.family.name().to_string(),
                    p_value: Some(t.p_value),
                    statistic: Some(t.statistic),
                })
                .collect(),
            converged: Some(s.converged),
            corrected_by: None,
            dataset: None,
            families: names(solution.families.iter().map(|f| f.name())),
            final_cost: Some(s.final_cost),
            identifiability: IdentifiabilityJson {
                condition_number: id.condition_number,
                correlated: id
                    .correlated
                    .iter()
                    .map(|(a, b, r)| CorrelatedJson {
                        a: a.name().to_string(),
                        b: b.name().to_string(),
                        r: Some(*r),
                    })
                    .collect(),
                free: id.free,
                rank: id.rank,
                singular_values: id.singular_values.iter().copied().map(Some).collect(),
                suggest_fix: names(id.suggest_fix.iter().map(|p| p.name())),
                undetermined: id.undetermined.iter().map(DirectionJson::from).collect(),
                unobserved: names(id.unobserved.iter().map(|p| p.name())),
                weak: id.weak.iter().map(DirectionJson::from).collect(),
            },
            initial_cost: Some(s.initial_cost),
            initial_rms_px: solution.initial_rms_px.map(Some),
            iterations: s.iterations,
            misfit: MisfitJson {
                detected: solution.misfit.detected,
                message: solution.misfit.message.clone(),
                noise_model_set_aside: solution.misfit.noise_model_set_aside,
                suggest: names(solution.misfit.suggest.iter().map(|f| f.name())),
                tests: solution
                    .misfit
                    .tests
                    .iter()
                    .map(|t| FamilyTestJson {
                        df: t.df,
                        family: t.family.name().to_string(),
                        p_value: Some(t.p_value),
                        parameters: names(t.params.iter().map(|p| p.name())),
                        significant: t.significant,
                        statistic: Some(t.statistic),
                    })
                    .collect(),
            },
            noise: solution.noise.map(|n| NoiseJson {
                joint_deg: Some(n.joint.to_degrees()),
                px: Some(n.px),
            }),
            outliers: solution
                .outliers
                .iter()
                .map(|o| OutlierJson {
                    capture: o.capture,
                    col: o.vertex.col,
                    residual_px: o.residual.map(Some),
                    row: o.vertex.row,
                })
                .collect(),
            parameters: UniqueMap(parameters),
            residual_sigma_px: Some(solution.residual_variance.sqrt()),
            rms_px: Some(solution.rms_px),
            seconds: Some(solution.seconds),
            solver: Some(s.solver.clone()),
            standing: None,
            termination: s.termination.clone(),
            undetermined: solution
                .undetermined
                .iter()
                .map(|u| UndeterminedJson {
                    combination: u.direction.describe(),
                    parameter: u.param.name().to_string(),
                })
                .collect(),
            vertices: solution.observations,
        }
    }

    /// Adds the change since the previous calibration ([`crate::run::changes`]).
    pub fn with_changes(mut self, changes: &[Change]) -> Self {
        self.changes = Some(
            changes
                .iter()
                .map(|c| {
                    (
                        c.param.name().to_string(),
                        ChangeJson {
                            change: Some(c.change),
                            previous: Some(c.previous),
                            value: Some(c.value),
                            z: Some(c.z),
                        },
                    )
                })
                .collect(),
        );
        self
    }

    /// Adds the standing leg offsets of `cal` ([`super::standing_offsets`]), if any.
    pub fn with_standing(mut self, cal: &crate::calibration::Calibration) -> Self {
        let files = cal.standing_files();
        self.standing = (!files.is_empty()).then(|| {
            files
                .into_iter()
                .map(|(p, f)| (p.name().to_string(), StandingIn::Table(f)))
                .collect()
        });
        self
    }

    /// The result as a JSON value: keys in alphabetical order at every level, numbers that
    /// are not finite as `null`.
    pub fn to_value(&self) -> Value {
        serde_json::to_value(self).expect("JSON of plain values")
    }
}

/// One parameter's entry: value, sigma (0 when held, `null` when undetermined), unit,
/// the sandwich and bootstrap sigma when estimated and determined, and the truth.
fn parameter(solution: &Solution, p: Param, truth: Option<&[f64]>) -> ParameterJson {
    let fixed = solution.fixed.is_fixed(p);
    let determined = solution.is_determined(p);
    let estimated = !fixed && determined;
    let undetermined = (!fixed && !determined).then_some(true);
    ParameterJson {
        determined: undetermined.map(|_| false),
        fixed,
        std: if fixed {
            Some(0.0)
        } else if determined {
            Some(solution.report_std(p))
        } else {
            None
        },
        std_bootstrap: solution
            .bootstrap
            .as_ref()
            .filter(|_| estimated)
            .map(|b| p.unit().to_report(b.std[p.index()])),
        std_sandwich: solution
            .sandwich_std
            .filter(|_| estimated)
            .map(|sw| p.unit().to_report(sw[p.index()])),
        std_assumes_held: Some(
            solution
                .held_trade_offs(p)
                .into_iter()
                .map(|(held, ratio)| (held.name().to_string(), ratio))
                .collect::<std::collections::BTreeMap<String, f64>>(),
        )
        .filter(|m| !m.is_empty()),
        truth: truth.map(|t| p.unit().to_report(t[p.index()])),
        undetermined,
        unit: Some(p.unit().name().to_string()),
        value: solution.report_value(p),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{FixedSet, Model};
    use crate::sim::{SimOptions, simulate};
    use crate::solve::{Problem, UncertaintyOptions, backend, calibrate};

    fn solution() -> (Solution, Vec<f64>) {
        let options = SimOptions {
            stances: 3,
            heads: 1,
            seed: 3,
            ..SimOptions::default()
        };
        let dataset = simulate(&Model::default(), &options).unwrap();
        let truth = dataset.truth.as_ref().unwrap().values.to_vec();
        // Link lengths freed: the data of 6 captures cannot determine all of them.
        let fixed = FixedSet::from_lists("links", "").unwrap();
        let problem = Problem::from_dataset(&dataset, fixed).unwrap();
        let lm = backend("lm", false).unwrap();
        let solution = calibrate(&problem, lm.as_ref(), &UncertaintyOptions::default()).unwrap();
        (solution, truth)
    }

    #[test]
    fn what_is_written_is_what_is_read() {
        let (solution, truth) = solution();
        let mut result = ResultJson::new(&solution, Some(&truth));
        result.dataset = Some("d".into());
        result.angles = Some(AngleKind::Raw);
        let text = serde_json::to_string_pretty(&result.to_value()).unwrap();
        let back: ResultJson = serde_json::from_str(&text).unwrap();
        assert_eq!(back, result);
        // The keys docs/MODEL.md §8 names, in alphabetical order.
        let value = result.to_value();
        let keys: Vec<&String> = value.as_object().unwrap().keys().collect();
        let mut sorted = keys.clone();
        sorted.sort();
        assert_eq!(keys, sorted);
        for key in [
            "solver",
            "converged",
            "rms_px",
            "parameters",
            "misfit",
            "noise",
        ] {
            assert!(value.get(key).is_some(), "{key} missing");
        }
        // A parameter the data do not determine says so twice, with a null sigma.
        let undetermined: Vec<&ParameterJson> = result
            .parameters
            .0
            .values()
            .filter(|e| !e.is_determined())
            .collect();
        assert!(!undetermined.is_empty());
        assert_eq!(undetermined.len(), solution.undetermined.len());
        assert!(
            undetermined
                .iter()
                .all(|e| e.std.is_none() && e.undetermined == Some(true))
        );
    }

    #[test]
    fn numbers_that_are_not_finite_are_null_and_read_back_as_none() {
        let (solution, _) = solution();
        let mut result = ResultJson::new(&solution, None);
        result.final_cost = Some(f64::NAN);
        result.misfit.tests[0].p_value = Some(f64::INFINITY);
        let value = result.to_value();
        assert!(value["final_cost"].is_null());
        assert!(value["misfit"]["tests"][0]["p_value"].is_null());
        let back: ResultJson = serde_json::from_value(value).unwrap();
        assert_eq!(back.final_cost, None);
        assert_eq!(back.misfit.tests[0].p_value, None);
    }
}
