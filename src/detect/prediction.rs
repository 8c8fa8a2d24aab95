//! The parameters a prediction of the boards uses, read from a file: the robot's current
//! calibration (`--start-from`) or the result of a fit (`naocalib solve --json`).

use std::path::{Path, PathBuf};

use crate::dataset::Dataset;
use crate::export::ExportError;
use crate::model::{Model, PARAMETER_COUNT, Param};

/// Why a file's parameters could not be read.
#[derive(Debug, thiserror::Error)]
pub enum PredictionError {
    /// The calibration file could not be read.
    #[error("--start-from {}", .path.display())]
    StartFrom {
        /// The calibration file.
        path: PathBuf,
        /// Why.
        #[source]
        source: ExportError,
    },
    /// The result file could not be read.
    #[error("{}", .path.display())]
    Read {
        /// The result file.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// The result file is not JSON.
    #[error("{}: not JSON", .path.display())]
    NotJson {
        /// The result file.
        path: PathBuf,
        /// Why.
        #[source]
        source: serde_json::Error,
    },
    /// The result file has no parameters.
    #[error("{}: no \"parameters\" object (a `naocalib solve --json` result?)", .0.display())]
    NoParameters(PathBuf),
    /// The result file names a parameter naocalib does not know.
    #[error("{}: unknown parameter {name}", .path.display())]
    UnknownParameter {
        /// The result file.
        path: PathBuf,
        /// The name.
        name: String,
    },
    /// A parameter of the result file has no number for its value.
    #[error("{}: parameter {name} has no numeric value", .path.display())]
    NoValue {
        /// The result file.
        path: PathBuf,
        /// The parameter's name.
        name: String,
    },
}

/// The parameters (internal units) of the calibration file `path` for predicting the
/// boards of a dataset of `model`.
///
/// With `corrected` angles (`[joints] angles = "corrected"`) the robot's joint offsets are
/// already in the logged angles, and the prediction keeps them at zero.
pub fn start_values(
    path: &Path,
    model: &Model,
    corrected: bool,
) -> Result<[f64; PARAMETER_COUNT], PredictionError> {
    let calibration =
        crate::export::read_start_from(path).map_err(|source| PredictionError::StartFrom {
            path: path.to_path_buf(),
            source,
        })?;
    let mut values = [0.0; PARAMETER_COUNT];
    for e in &calibration.parameters {
        let joint = crate::solve::problem::is_joint_offset(e.param);
        if !(corrected && joint) {
            values[e.param.index()] = e.param.unit().from_report(e.value);
        }
    }
    // Intrinsics the calibration carries with their prior, relative to this dataset's.
    for (p, value) in calibration.intrinsics_relative_to(model).0 {
        values[p.index()] = value;
    }
    Ok(values)
}

/// [`start_values`] for `dataset` (its model, and whether its angles are corrected).
pub fn start_values_for(
    path: &Path,
    dataset: &Dataset,
) -> Result<[f64; PARAMETER_COUNT], PredictionError> {
    let corrected = dataset.angles.kind == crate::dataset::AngleKind::Corrected;
    start_values(path, &dataset.model, corrected)
}

/// The parameters of a `naocalib solve --json` result (report units) as internal values;
/// parameters it does not name stay zero.
pub fn solution_values(path: &Path) -> Result<[f64; PARAMETER_COUNT], PredictionError> {
    let text = std::fs::read_to_string(path).map_err(|source| PredictionError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    let json: serde_json::Value =
        serde_json::from_str(&text).map_err(|source| PredictionError::NotJson {
            path: path.to_path_buf(),
            source,
        })?;
    let Some(map) = json.get("parameters").and_then(|p| p.as_object()) else {
        return Err(PredictionError::NoParameters(path.to_path_buf()));
    };
    let mut values = [0.0; PARAMETER_COUNT];
    for (name, entry) in map {
        let named = || (path.to_path_buf(), name.clone());
        let param = Param::from_name(name).ok_or_else(|| {
            let (path, name) = named();
            PredictionError::UnknownParameter { path, name }
        })?;
        let value = entry.get("value").and_then(|v| v.as_f64()).ok_or_else(|| {
            let (path, name) = named();
            PredictionError::NoValue { path, name }
        })?;
        values[param.index()] = param.unit().from_report(value);
    }
    Ok(values)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn file(dir: &Path, name: &str, text: &str) -> PathBuf {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        path
    }

    #[test]
    fn a_result_gives_its_parameters_in_internal_units() {
        let dir = tempfile::tempdir().unwrap();
        let path = file(
            dir.path(),
            "r.json",
            r#"{"parameters": {"CamPitch": {"value": 2.0}, "LBoardTransX": {"value": 1.5}}}"#,
        );
        let values = solution_values(&path).unwrap();
        assert_eq!(values[Param::CamPitch.index()], 2.0f64.to_radians());
        assert_eq!(values[Param::LBoardTransX.index()], 1.5);
        assert_eq!(values[Param::CamYaw.index()], 0.0);
    }

    #[test]
    fn a_bad_result_is_named_with_what_is_wrong() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let error = |name: &str, text: &str| {
            let path = file(d, name, text);
            let e = solution_values(&path).unwrap_err().to_string();
            assert!(e.starts_with(&path.display().to_string()), "{e}");
            e[path.display().to_string().len()..].to_string()
        };
        assert_eq!(error("a", "[1"), ": not JSON");
        assert!(error("b", "{}").starts_with(": no \"parameters\" object"));
        assert_eq!(
            error("c", r#"{"parameters": {"Nope": {"value": 1}}}"#),
            ": unknown parameter Nope"
        );
        assert_eq!(
            error("d", r#"{"parameters": {"CamYaw": {"value": "1"}}}"#),
            ": parameter CamYaw has no numeric value"
        );
        let missing = solution_values(&d.join("none")).unwrap_err();
        assert!(matches!(missing, PredictionError::Read { .. }));
    }

    #[test]
    fn corrected_angles_keep_the_joint_offsets_of_a_calibration_at_zero() {
        let dir = tempfile::tempdir().unwrap();
        let value = |p: Param| match p {
            Param::CamPitch => 1.0,
            Param::LKneePitch => 0.5,
            _ => 0.0,
        };
        let calibration = crate::calibration::Calibration {
            origin: crate::calibration::Origin::Solved,
            solver: Some("test".into()),
            dataset: None,
            converged: Some(true),
            rms_px: Some([0.1, 0.1]),
            parameters: Param::ALL
                .iter()
                .map(|&param| crate::calibration::Entry {
                    param,
                    value: value(param),
                    std: Some(0.01),
                    fixed: false,
                })
                .collect(),
            angles: None,
            posture: crate::calibration::Posture::Standing,
            standing: Default::default(),
            cameras: Default::default(),
        };
        let path = file(dir.path(), "cal.toml", &calibration.to_toml());
        let model = Model::default();
        let raw = start_values(&path, &model, false).unwrap();
        assert_eq!(raw[Param::CamPitch.index()], 1.0f64.to_radians());
        assert_eq!(raw[Param::LKneePitch.index()], 0.5f64.to_radians());
        let corrected = start_values(&path, &model, true).unwrap();
        assert_eq!(corrected[Param::CamPitch.index()], 1.0f64.to_radians());
        assert_eq!(corrected[Param::LKneePitch.index()], 0.0);
        let missing = start_values(&dir.path().join("none.toml"), &model, false).unwrap_err();
        assert!(
            missing.to_string().starts_with("--start-from "),
            "{missing}"
        );
    }
}
