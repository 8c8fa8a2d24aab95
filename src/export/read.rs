//! `naocalib import`: a robot's team files read back into a [`Calibration`].

use std::path::{Path, PathBuf};

use super::{
    Calibration, Entry, ExportError, Format, Imported, Posture, names, parse_error, recognised,
    source,
};
use std::collections::BTreeMap;

use crate::calibration::Prior;
use crate::model::{CameraId, Param};

/// One file `naocalib import` read: its path, format name and how many values it held.
pub type FileRead = (PathBuf, &'static str, usize);

/// Reads a robot's team files into a [`Calibration`] (`naocalib import`): every value they
/// hold, as naocalib parameters held at it (`fixed`, the robot's current calibration);
/// every other parameter of the paper's set present but undetermined (never written into
/// a robot file). Returns it with `(file, format name, values read)` per file. The same
/// parameter in two files is an error.
pub fn import_calibration(
    files: &[PathBuf],
    format: Option<&'static dyn Format>,
) -> Result<(Calibration, Vec<FileRead>), ExportError> {
    let mut values: Vec<Option<(f64, usize)>> = vec![None; Param::ALL.len()];
    let mut read = Vec::new();
    let mut cameras: BTreeMap<CameraId, (Prior, usize)> = BTreeMap::new();
    for (k, file) in files.iter().enumerate() {
        let (format, imported) = import(file, format)?;
        // The cameras' intrinsics the file holds, held at them.
        let held = format.read_cameras(&source::read(file)?.text, file)?;
        for (camera, prior) in &held {
            if let Some((_, other)) = cameras.get(camera) {
                return Err(parse_error(
                    file,
                    format!(
                        "the {camera} camera's intrinsics are also in {}",
                        files[*other].display()
                    ),
                ));
            }
            cameras.insert(*camera, (*prior, k));
        }
        let mut imported = imported;
        for (camera, _) in &held {
            for p in crate::calibration::intrinsics::params(*camera) {
                if !imported.iter().any(|(q, _)| *q == p) {
                    imported.push((p, 0.0));
                }
            }
        }
        for (p, v) in &imported {
            if let Some((_, other)) = values[p.index()] {
                return Err(parse_error(
                    file,
                    format!("{p} is also in {}", files[other].display()),
                ));
            }
            values[p.index()] = Some((*v, k));
        }
        read.push((file.clone(), format.name(), imported.len()));
    }
    let parameters = Param::ALL
        .iter()
        .filter_map(|&p| match values[p.index()] {
            Some((value, _)) => Some(Entry {
                param: p,
                value,
                std: Some(0.0),
                fixed: true,
            }),
            None => (p.index() < crate::model::PAPER_PARAMETERS).then_some(Entry {
                param: p,
                value: 0.0,
                std: None,
                fixed: false,
            }),
        })
        .collect();
    let names: Vec<String> = files.iter().map(|f| f.display().to_string()).collect();
    let cal = Calibration {
        origin: crate::calibration::Origin::Imported,
        solver: Some(format!(
            "{} of {}",
            crate::calibration::IMPORT_SOLVER,
            names.join(", ")
        )),
        dataset: None,
        converged: None,
        rms_px: None,
        parameters,
        angles: None,
        posture: Posture::Standing,
        standing: Default::default(),
        cameras: cameras.into_iter().map(|(c, (p, _))| (c, p)).collect(),
    };
    Ok((cal, read))
}

/// Reads a robot's team file: its format (given, or recognised from the content) and the
/// values it holds as naocalib parameters ([`Imported`]: α = −stored for joints). The file
/// must be a regular file ([`source::read`]; a byte-order mark is accepted), in the
/// format's layout, and every value within naocalib's physical bounds
/// ([`crate::model::bounds`]): a value beyond them is refused, naming the file and the
/// parameter, rather than carried into a solve.
pub fn import(
    path: &Path,
    format: Option<&'static dyn Format>,
) -> Result<(&'static dyn Format, Imported), ExportError> {
    let text = source::read(path)?.text;
    let format = match format {
        Some(f) => {
            if f.robot() && !f.matches(&text) {
                return Err(not_in_layout(path, f, &text));
            }
            f
        }
        None => recognised(&text).ok_or_else(|| {
            parse_error(
                path,
                format!(
                    "not a team calibration file naocalib knows (give --format: {})",
                    names()
                ),
            )
        })?,
    };
    let values = format.read(&text, path)?;
    check_bounds(&values, path)?;
    Ok((format, values))
}

/// Refuses values beyond naocalib's physical bounds ([`crate::model::bounds`]), naming the
/// file and the first such parameter.
pub(crate) fn check_bounds(values: &[(Param, f64)], path: &Path) -> Result<(), ExportError> {
    match crate::model::bounds::violations(values.iter().copied()).first() {
        None => Ok(()),
        Some(v) => Err(parse_error(
            path,
            format!("{v}: the file does not hold a value naocalib can use; fix it by hand first"),
        )),
    }
}

/// The error for a file that is not in `format`'s layout: what it looks like instead.
pub(crate) fn not_in_layout(path: &Path, format: &dyn Format, text: &str) -> ExportError {
    let looks = match recognised(text) {
        Some(other) => format!("it looks like a {} file", other.name()),
        None => "its layout is none naocalib knows".to_string(),
    };
    parse_error(
        path,
        format!(
            "not a {} file ({}): {looks}; nothing written",
            format.name(),
            format.description()
        ),
    )
}
