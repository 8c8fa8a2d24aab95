//! naocalib's own calibration files, the TOML and the JSON ([`Calibration::to_toml`],
//! [`Calibration::to_json`]): every parameter with its one-sigma and unit, `converged` and
//! `rms_px`. No robot loads them: they are read with [`crate::calibration::read_calibration`]
//! (`--start-from`, `naocalib export`), not imported, and never updated.

use super::Calibration;
use super::format::{DocRow, Format, NameRule};

/// Whether `code` is one of naocalib's calibration files.
fn is_naocalib(code: &str) -> bool {
    code.contains(crate::calibration::FORMAT)
}

/// naocalib's calibration TOML ([`Calibration::to_toml`]).
#[derive(Debug, Clone, Copy)]
pub struct Toml;

impl Format for Toml {
    fn name(&self) -> &'static str {
        "toml"
    }
    fn file(&self) -> &'static str {
        "calibration.toml"
    }
    fn description(&self) -> &'static str {
        "naocalib's calibration TOML: every parameter with sigma and unit"
    }
    fn doc_row(&self) -> DocRow {
        DocRow {
            carries: "every parameter: value, σ, unit, `fixed` / `undetermined`; `converged`, \
                      `rms_px`; `angles` (raw / corrected)",
            units: "report units (deg, mm, px, 1, deg/(N·m))",
            axes: "naocalib's",
        }
    }
    fn recognise(&self, code: &str) -> bool {
        is_naocalib(code)
    }
    fn write(&self, cal: &Calibration) -> String {
        cal.to_toml()
    }
    fn robot(&self) -> bool {
        false
    }
    fn file_names(&self) -> NameRule {
        NameRule::Ending(".toml")
    }
}

/// naocalib's calibration JSON ([`Calibration::to_json`], the keys of the TOML).
#[derive(Debug, Clone, Copy)]
pub struct Json;

impl Format for Json {
    fn name(&self) -> &'static str {
        "json"
    }
    fn file(&self) -> &'static str {
        "calibration.json"
    }
    fn description(&self) -> &'static str {
        "naocalib's calibration JSON (same keys as the TOML)"
    }
    fn doc_row(&self) -> DocRow {
        DocRow {
            carries: "the same keys as the TOML",
            units: "report units",
            axes: "naocalib's",
        }
    }
    fn recognise(&self, code: &str) -> bool {
        is_naocalib(code)
    }
    fn write(&self, cal: &Calibration) -> String {
        let mut s = serde_json::to_string_pretty(&cal.to_json()).expect("JSON of plain values");
        s.push('\n');
        s
    }
    fn robot(&self) -> bool {
        false
    }
    fn file_names(&self) -> NameRule {
        NameRule::Ending(".json")
    }
}
