//! naocalib's own calibration files, the TOML and the JSON ([`Calibration::to_toml`],
//! [`Calibration::to_json`]): every parameter with its one-sigma and unit, whether the
//! solver converged and the RMS residual it reached. Written and read with serde (unknown
//! keys refused), so that what is written is what is read. No robot loads them: they are
//! read with [`read_calibration`] (`--start-from`, `naocalib export`), not imported, and
//! never updated.
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
//! `std` or `"determined": false` marks a parameter the data do not determine) and whose
//! `cameras` object is the same table of a-priori intrinsics.

use std::collections::BTreeMap;
use std::path::Path;

use serde::ser::SerializeMap;
use serde::{Deserialize, Serialize};
use serde_json::Value;

use super::format::{DocRow, Format, NameRule};
use super::{ExportError, parse_error};
use crate::calibration::result_json::ResultJson;
use crate::calibration::{
    COMPENSATION, Calibration, Entry, IMPORT_SOLVER, Origin, Posture, Prior, Standing,
    StandingFile, StandingIn, UniqueMap, stand_torque,
};
use crate::dataset::{AngleKind, AngleSource};
use crate::model::{CameraId, PAPER_PARAMETERS, Param};

/// The `format` key of the TOML and JSON calibration files.
pub const FORMAT: &str = "naocalib-calibration";
/// The `version` key of the TOML and JSON calibration files.
pub const VERSION: i64 = 1;

/// Whether `code` is one of naocalib's calibration files.
fn is_naocalib(code: &str) -> bool {
    code.contains(FORMAT)
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

impl Calibration {
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
            cameras: &self.cameras,
        }
    }

    /// The calibration as TOML, with a header stating units and the compensation rule.
    pub fn to_toml(&self) -> String {
        let mut s = String::new();
        super::header(
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
/// A robot's file (a team's format) is no calibration: the error points to `naocalib
/// import`, which reads it.
pub fn read_calibration(path: &Path) -> Result<Calibration, ExportError> {
    let text = super::source::read(path)?.text;
    let read = if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("toml"))
    {
        Calibration::from_toml(&text, path)
    } else {
        Calibration::from_json(&text, path)
    };
    read.map_err(|e| match super::format::recognised(&text) {
        // Neither a calibration nor a robot's file naocalib knows: what the reader said,
        // and what a calibration is.
        None if !looks_like_a_calibration(&text) => match e {
            ExportError::Parse { path, message } => parse_error(
                &path,
                format!(
                    "{message}: not a calibration (a TOML or JSON of `naocalib import`, \
                         `solve --export` or `solve --json`); a robot's file is read with \
                         `naocalib import`"
                ),
            ),
            e => e,
        },
        Some(format) => parse_error(
            path,
            format!(
                "is a robot's file ({}), not a calibration: read it with `naocalib import {} \
                 --out current.toml` (with the robot's other calibration file, if any) and \
                 give current.toml",
                format.name(),
                path.display()
            ),
        ),
        None => e,
    })
}

/// Whether `text` is TOML or JSON with a calibration's `format` or `parameters` (a
/// calibration, if perhaps a broken one), not some other file.
fn looks_like_a_calibration(text: &str) -> bool {
    let has = |key: &str| key == "format" || key == "parameters";
    if let Ok(table) = text.parse::<toml::Table>() {
        return table.keys().any(|k| has(k));
    }
    match serde_json::from_str::<Value>(text) {
        Ok(Value::Object(map)) => map.keys().any(|k| has(k)),
        _ => false,
    }
}

/// Reads the calibration a solve, a detection or a plan starts from (`solve --start-from`,
/// `detect --start-from`, `plan --around`: a robot's calibration from `naocalib import`,
/// or an earlier result) — the one plausibility rule of them all — and refuses it when a value it
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
    /// The a-priori intrinsics of the cameras whose intrinsics it carries.
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    cameras: &'a BTreeMap<CameraId, Prior>,
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
    /// The a-priori intrinsics of the cameras whose intrinsics it carries.
    cameras: Option<BTreeMap<CameraId, Prior>>,
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
        let cameras = checked_cameras(self.cameras, path)?;
        let mut cal = assemble(
            fit,
            (self.angles, self.corrected_by),
            entries.collect(),
            self.standing,
            path,
        )?;
        cal.cameras = cameras;
        Ok(cal)
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
    // The file says "imported" in words: a solver named as `naocalib import` names itself,
    // and nothing of a fit.
    let imported = converged.is_none()
        && rms_px.is_none()
        && solver
            .as_deref()
            .is_some_and(|s| s.starts_with(IMPORT_SOLVER));
    Ok(Calibration {
        origin: if imported {
            Origin::Imported
        } else {
            Origin::Solved
        },
        solver,
        dataset,
        converged,
        rms_px,
        parameters: entries_from(entries, path)?,
        angles,
        posture: Posture::Standing,
        standing: standing_from(standing, path)?,
        cameras: BTreeMap::new(),
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
        let cameras = checked_cameras(result.cameras, path)?;
        let mut cal = assemble(fit, angles, entries.collect(), result.standing, path)?;
        cal.cameras = cameras;
        Ok(cal)
    }
}

/// The `cameras` table of a calibration or result file, each camera's prior checked
/// usable ([`Prior::is_valid`]); empty when absent.
fn checked_cameras(
    cameras: Option<BTreeMap<CameraId, Prior>>,
    path: &Path,
) -> Result<BTreeMap<CameraId, Prior>, ExportError> {
    let cameras = cameras.unwrap_or_default();
    if let Some(camera) = cameras.iter().find(|(_, p)| !p.is_valid()) {
        return Err(parse_error(
            path,
            format!(
                "cameras.{}: the image size and focal lengths must be positive and every \
                 number finite",
                camera.0
            ),
        ));
    }
    Ok(cameras)
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
