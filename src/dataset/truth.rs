//! `truth.toml`: the true parameters of a simulated dataset (docs/MODEL.md §7), read with
//! serde ([`TruthToml`]).

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use serde::Deserialize;

use crate::model::{Family, PARAMETER_COUNT, Param};

use super::Truth;
use super::error::{DatasetError, Location};
use super::toml_doc::TomlDoc;
use super::units::{report_value, toml_float};

/// The content of `truth.toml`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct TruthToml {
    /// Parameter name → true value in report units (deg / mm / px / 1). Required; an
    /// `Option` so that a missing table gets its own message.
    parameters: Option<BTreeMap<String, f64>>,
    /// Free-form keys (noise levels, seed, …).
    #[serde(default)]
    simulation: toml::Table,
}

/// Reads the truth from the content of `truth.toml` at `path`.
pub(crate) fn parse(path: &Path, bytes: &[u8]) -> Result<Truth, DatasetError> {
    let doc = TomlDoc::new(path, bytes)?;
    let file: TruthToml = doc.deserialize()?;
    let Some(parameters) = file.parameters else {
        return Err(DatasetError::invalid(
            Location::file(path).field("parameters"),
            "missing table [parameters] (the true parameter values in deg / mm)",
        ));
    };
    let mut values = [0.0; PARAMETER_COUNT];
    let mut unknown = Vec::new();
    for (name, value) in &parameters {
        match Param::from_name(name) {
            Some(param) => values[param.index()] = param.unit().from_report(*value),
            None => unknown.push(doc.at(&format!("parameters.{name}"))),
        }
    }
    // The first unknown name in file order.
    if let Some(at) = unknown.into_iter().min_by_key(|at| at.line) {
        let name = at.field.as_deref().unwrap_or_default();
        let name = name.strip_prefix("parameters.").unwrap_or(name).to_string();
        let known: Vec<_> = Param::ALL.iter().map(|p| p.name()).collect();
        return Err(DatasetError::invalid(
            at,
            format!("unknown parameter '{name}' (known: {})", known.join(", ")),
        ));
    }
    let truth = Truth {
        values,
        simulation: file.simulation,
    };
    validate(path, &truth).map_err(|e| match e {
        DatasetError::Invalid { at, message } => {
            let located = at.field.as_deref().map(|f| doc.at(f)).unwrap_or(at);
            DatasetError::Invalid {
                at: located,
                message,
            }
        }
        e => e,
    })?;
    Ok(truth)
}

/// Checks a truth in memory: finite values everywhere.
pub(crate) fn validate(path: &Path, truth: &Truth) -> Result<(), DatasetError> {
    for param in Param::ALL {
        let x = truth.values[param.index()];
        if !x.is_finite() {
            return Err(DatasetError::invalid(
                Location::file(path).field(format!("parameters.{param}")),
                format!("{x} is not a finite number"),
            ));
        }
    }
    for (key, value) in &truth.simulation {
        non_finite(&format!("simulation.{key}"), value).map_err(|(field, x)| {
            DatasetError::invalid(
                Location::file(path).field(field),
                format!("{x} is not a finite number"),
            )
        })?;
    }
    Ok(())
}

fn non_finite(key: &str, value: &toml::Value) -> Result<(), (String, f64)> {
    match value {
        toml::Value::Float(x) if !x.is_finite() => Err((key.to_string(), *x)),
        toml::Value::Array(items) => items
            .iter()
            .enumerate()
            .try_for_each(|(i, item)| non_finite(&format!("{key}[{i}]"), item)),
        toml::Value::Table(table) => table
            .iter()
            .try_for_each(|(k, item)| non_finite(&format!("{key}.{k}"), item)),
        _ => Ok(()),
    }
}

/// `truth.toml` for `truth` (already validated): every parameter in [`Param::ALL`] order,
/// in report units, then the `[simulation]` table. The upper camera's rotation offsets are
/// written only for a dataset with upper-camera captures (`upper`) or when one is not zero,
/// its intrinsics (`UpperFx` … `UpperK2`) only when one is not zero (a parameter left out
/// reads as zero).
pub(crate) fn render(truth: &Truth, upper: bool) -> Result<String, toml::ser::Error> {
    let upper = upper
        || Family::UpperCamera
            .params()
            .any(|p| truth.values[p.index()] != 0.0);
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# The true parameters of this simulated dataset, in report units (deg / mm)."
    );
    let _ = writeln!(s);
    let _ = writeln!(s, "[parameters]");
    // The upper camera's intrinsics: only when one is not zero.
    let upper_projection = Param::ALL
        .into_iter()
        .any(|p| p.is_upper_projection() && truth.values[p.index()] != 0.0);
    for param in Param::ALL {
        if (param.family() == Family::UpperCamera && !upper)
            || (param.is_upper_projection() && !upper_projection)
        {
            continue;
        }
        let value = report_value(param.unit(), truth.values[param.index()]);
        let _ = writeln!(
            s,
            "{param} = {}   # {}",
            toml_float(value),
            param.unit().name()
        );
    }
    let _ = writeln!(s);
    let mut wrapper = toml::Table::new();
    wrapper.insert(
        "simulation".into(),
        toml::Value::Table(truth.simulation.clone()),
    );
    s.push_str(&toml::to_string(&wrapper)?);
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse_str(text: &str) -> Result<Truth, String> {
        parse(Path::new("d/truth.toml"), text.as_bytes()).map_err(|e| e.to_string())
    }

    #[test]
    fn reads_report_units() {
        let t = parse_str(
            "[parameters]\nCamYaw = 0.4764\nLBoardTransX = -2\nHeadYaw = 1.5\n\n\
             [simulation]\nseed = 7\npx_noise = 0.5\nnote = 'x'\nsub = { a = [1, 2] }\n",
        )
        .unwrap();
        assert_eq!(t.values[Param::CamYaw.index()], 0.4764f64.to_radians());
        assert_eq!(t.values[Param::LBoardTransX.index()], -2.0);
        assert_eq!(t.values[Param::HeadYaw.index()], 1.5f64.to_radians());
        assert_eq!(t.values[Param::CamPitch.index()], 0.0);
        assert_eq!(t.simulation["seed"].as_integer(), Some(7));
        assert_eq!(t.simulation["px_noise"].as_float(), Some(0.5));
        assert_eq!(t.simulation.len(), 4);
        let t = parse_str("[parameters]\n").unwrap();
        assert!(t.simulation.is_empty());
    }

    #[test]
    fn errors() {
        let cases = [
            (
                "[parameters]\nCamYaw = 1\nCamYow = 2\n",
                "d/truth.toml line 3, field parameters.CamYow: unknown parameter 'CamYow' (known: CamYaw, CamPitch",
            ),
            (
                "[parameters]\nCamYaw = nan\n",
                "d/truth.toml line 2, field parameters.CamYaw: nan is not a finite number",
            ),
            (
                "[parameters]\nCamYaw = '1'\n",
                "d/truth.toml line 2, field parameters.CamYaw: expected a number, found a string",
            ),
            (
                "[simulation]\nseed = 1\n",
                "d/truth.toml, field parameters: missing table [parameters]",
            ),
            (
                "[parameters]\n[simulation]\nnoise = -inf\n",
                "d/truth.toml line 3, field simulation.noise: -inf is not a finite number",
            ),
            (
                "[parameters]\n[other]\n",
                "d/truth.toml line 2, field other: unknown key 'other' at the top level",
            ),
            (
                "[parameters]\nsimulation = 3\n",
                "unknown parameter 'simulation'",
            ),
            (
                "simulation = 3\n[parameters]\n",
                "d/truth.toml line 1, field simulation: expected a table, found an integer",
            ),
        ];
        for (text, expected) in cases {
            let e = parse_str(text).unwrap_err();
            assert!(e.contains(expected), "{e:?} should contain {expected:?}");
        }
    }

    #[test]
    fn render_round_trips() {
        let mut values = [0.0; PARAMETER_COUNT];
        let report = [
            0.4764, -4.5627, -1.7991, -2.2938, 0.9692, 0.2299, -1.1442, 1.6708, 0.0267,
        ];
        for (i, r) in report.iter().enumerate() {
            values[i] = Param::ALL[i].unit().from_report(*r);
        }
        values[Param::RBoardTransY.index()] = 2.2007;
        let mut simulation = toml::Table::new();
        simulation.insert("seed".into(), toml::Value::Integer(42));
        simulation.insert("px_noise".into(), toml::Value::Float(0.1));
        let truth = Truth { values, simulation };
        let text = render(&truth, false).unwrap();
        assert!(text.contains("\nCamYaw = 0.4764   # deg\n"), "{text}");
        assert!(text.contains("\nRBoardTransY = 2.2007   # mm\n"), "{text}");
        assert_eq!(parse(Path::new("t"), text.as_bytes()).unwrap(), truth);
    }

    #[test]
    fn validate_in_memory() {
        let mut truth = Truth {
            values: [0.0; PARAMETER_COUNT],
            simulation: toml::Table::new(),
        };
        assert!(validate(Path::new("t.toml"), &truth).is_ok());
        truth.simulation.insert(
            "n".into(),
            toml::Value::Array(vec![toml::Value::Float(f64::NAN)]),
        );
        let e = validate(Path::new("t.toml"), &truth).unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.toml, field simulation.n[0]: NaN is not a finite number"
        );
        truth.values[Param::CamRoll.index()] = f64::INFINITY;
        let e = validate(Path::new("t.toml"), &truth).unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.toml, field parameters.CamRoll: inf is not a finite number"
        );
    }
}
