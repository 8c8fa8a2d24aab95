//! The result JSON of a run ([`ResultJson::from_run`]; its keys are
//! [`crate::calibration::result_json`]), written by `solve --json` and for every run of
//! `batch` (`--json`, `--out`).
//!
//! Printed through [`ResultJson::to_value`], its keys are in alphabetical order at every
//! level; a number that is not finite is written as `null`.

use serde_json::Value;

use crate::calibration::result_json::{
    ChangeJson, ChosenJson, CorrelatedJson, DirectionJson, FamilyTestJson, IdentifiabilityJson,
    MisfitJson, NoiseJson, OutlierJson, ParameterJson, ResultJson, UndeterminedJson,
};
use crate::calibration::{StandingIn, UniqueMap};
use crate::model::Param;
use crate::run::{Change, Run};
use crate::solve::Solution;

fn names<'a>(names: impl IntoIterator<Item = &'a str>) -> Vec<String> {
    names.into_iter().map(String::from).collect()
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

    /// Adds the standing leg offsets of `cal` ([`crate::calibration::Calibration::standing_rows`]), if any.
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
    use crate::dataset::AngleKind;
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
