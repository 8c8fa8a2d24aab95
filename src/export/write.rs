//! The outputs policy of a calibration's files, and writing them: [`check_files`] before
//! any is written, [`write_files`] through the one writer ([`crate::output`]).

use std::path::{Path, PathBuf};

use super::{Calibration, ExportError, FORMATS, Format, WriteOptions};
use crate::output::{check_writable, write_atomic};

/// Refuses a fresh joint file (at `path`) for a calibration fitted to angles the robot's
/// joint calibration had already corrected: its offsets are changes to that calibration,
/// which only `--update` of the robot's file can compose (stored_new = stored_old − α).
pub fn check_fresh(cal: &Calibration, format: &dyn Format, path: &Path) -> Result<(), ExportError> {
    if format.joints() && cal.corrected_angles() {
        Err(ExportError::NeedsUpdate {
            path: path.to_path_buf(),
            format: format.name(),
        })
    } else {
        Ok(())
    }
}

/// Refuses a result that is not a calibration for the files robots load.
pub(crate) fn check_usable(
    cal: &Calibration,
    what: impl FnOnce() -> String,
) -> Result<(), ExportError> {
    let reasons = cal.problems();
    if reasons.is_empty() {
        Ok(())
    } else {
        Err(ExportError::NotACalibration {
            what: what(),
            reasons,
        })
    }
}

/// The outputs policy of a calibration's files, checked for every file before any is
/// written: a result that is not a calibration ([`Calibration::problems`]) never becomes a
/// file a robot loads ([`ExportError::NotACalibration`], naming the first such file) unless
/// `allow_not_calibration` (`naocalib export --allow-unconverged`: the files then start
/// with a `NOT A CALIBRATION` marker); a joint file of a calibration fitted to corrected
/// angles is refused ([`check_fresh`]); and no file may replace an input, nor an existing
/// file without `options.force`.
pub fn check_files(
    cal: &Calibration,
    files: &[(&'static dyn Format, PathBuf)],
    options: &WriteOptions,
    allow_not_calibration: bool,
) -> Result<(), ExportError> {
    if !allow_not_calibration && let Some((_, path)) = files.iter().find(|(f, _)| f.robot()) {
        check_usable(cal, || path.display().to_string())?;
    }
    for (format, path) in files {
        check_fresh(cal, *format, path)?;
        if format.intrinsics() && !format.has_intrinsics_for(cal) {
            return Err(ExportError::NoIntrinsics {
                path: path.clone(),
                format: format.name(),
            });
        }
        check_writable(path, options)?;
    }
    Ok(())
}

/// Writes `cal` as `files` (each a format and its path) after [`check_files`], atomically,
/// and returns the paths in the order given. The files inside `dir` are written all or
/// nothing: into a stage beside `dir`, published after the others.
pub fn write_files(
    cal: &Calibration,
    files: &[(&'static dyn Format, PathBuf)],
    dir: Option<&Path>,
    options: &WriteOptions,
    allow_not_calibration: bool,
) -> Result<Vec<PathBuf>, ExportError> {
    check_files(cal, files, options, allow_not_calibration)?;
    let stage = dir
        .map(|d| crate::output::Staged::new(d, options))
        .transpose()?;
    for (format, path) in files {
        let text = format.write(cal);
        match (&stage, dir.and_then(|d| path.strip_prefix(d).ok())) {
            (Some(stage), Some(rel)) => stage.write(rel, text.as_bytes())?,
            _ => write_atomic(path, text.as_bytes(), options)?,
        }
    }
    if let Some(stage) = stage {
        stage.publish()?;
    }
    Ok(files.iter().map(|(_, path)| path.clone()).collect())
}

/// Writes `cal` to `path` in `format`, atomically, under the outputs policy of
/// [`check_files`]: a result that is not a calibration is refused for robot formats
/// ([`ExportError::NotACalibration`]); naocalib's TOML and JSON are written, carrying
/// `converged` and `rms_px`.
pub fn export(
    cal: &Calibration,
    format: &'static dyn Format,
    path: &Path,
    options: &WriteOptions,
) -> Result<(), ExportError> {
    write_files(cal, &[(format, path.to_path_buf())], None, options, false).map(|_| ())
}

/// What a directory export ([`dir_files`]) leaves out, and why.
#[derive(Debug, Clone, PartialEq)]
pub enum Withheld {
    /// Nothing: every format.
    Nothing,
    /// The joint files: the calibration was fitted to angles the robot's joint calibration
    /// had already corrected, so its offsets are changes to the robot's file
    /// ([`super::update()`]).
    JointFiles,
    /// Every robot file: the result is not a calibration (these reasons); only naocalib's
    /// own TOML and JSON, which say so.
    RobotFiles(Vec<String>),
}

/// Every format of [`FORMATS`] with its file in `dir` ([`Format::file`]) that `cal` has
/// something for: the files of the cameras' intrinsics ([`Format::intrinsics`]) only when
/// it carries the intrinsics they hold ([`Format::has_intrinsics_for`]).
pub fn every_file(cal: &Calibration, dir: &Path) -> Vec<(&'static dyn Format, PathBuf)> {
    FORMATS
        .iter()
        .filter(|f| !f.intrinsics() || f.has_intrinsics_for(cal))
        .map(|&f| (f, dir.join(f.file())))
        .collect()
}

/// The files a directory export of `cal` into `dir` writes under the outputs policy
/// (`naocalib solve --export`), with the file names of [`Format::file`], and what it
/// leaves out.
pub fn dir_files(cal: &Calibration, dir: &Path) -> (Vec<(&'static dyn Format, PathBuf)>, Withheld) {
    let problems = cal.problems();
    let withheld = if !problems.is_empty() {
        Withheld::RobotFiles(problems)
    } else if cal.corrected_angles() {
        Withheld::JointFiles
    } else {
        Withheld::Nothing
    };
    let files = every_file(cal, dir)
        .into_iter()
        .filter(|(format, _)| match withheld {
            Withheld::Nothing => true,
            Withheld::JointFiles => !format.joints(),
            Withheld::RobotFiles(_) => !format.robot(),
        })
        .collect();
    (files, withheld)
}

/// Writes `cal` into `dir` in every format (file names of [`Format::file`]) and returns
/// the paths written ([`write_files`]): every path is checked before any is written, so
/// that nothing is written when one is refused; a result that is not a calibration is
/// refused.
pub fn export_all(
    cal: &Calibration,
    dir: &Path,
    options: &WriteOptions,
) -> Result<Vec<PathBuf>, ExportError> {
    write_files(cal, &every_file(cal, dir), Some(dir), options, false)
}
