//! The result JSON of `naocalib solve --json` (docs/MODEL.md §8) as one type, [`ResultJson`]:
//! written for every run (`crate::report` makes it from a run), read back by `naocalib
//! export` and `solve --start-from` ([`crate::calibration::Calibration::from_json`]), so that
//! what is written and what is read are the same keys.
//!
//! Printed, its keys are in alphabetical order at every level. JSON has no NaN or infinity:
//! a number that is not finite is written as `null`, so the numbers of the fit's statistics
//! are `Option<f64>` (`None` for `null`) when read. The keys a calibration needs are the only
//! ones a reader must find; the others default when absent (a result written by hand, or by
//! an older naocalib).

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::{Prior, StandingIn, UniqueMap};
use crate::dataset::AngleKind;
use crate::model::CameraId;
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

/// A parameter's change since the previous calibration (a run's `Change`).
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
