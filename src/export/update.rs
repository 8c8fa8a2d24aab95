//! `naocalib export --update`: a robot's own file with only what a calibration determined
//! replaced, every other byte kept — and the robot's original never lost.
//!
//! - The file must be in the format's layout ([`super::Format::recognise`]): another
//!   team's file is refused, nothing written.
//! - The previous file is kept as `FILE.bak`; when that exists already (an earlier update),
//!   as `FILE.bak.2`, `FILE.bak.3`, …: a backup is never replaced, so the robot's original
//!   stays in `FILE.bak`.
//! - Nothing is written, and the outcome says why ([`Unchanged`]), when the calibration
//!   determines none of the values the file carries, when the file holds them already, or
//!   — for a calibration of angles already corrected by the file, whose offsets are
//!   changes to it — when the file is a kept backup with this calibration applied: an
//!   update is idempotent.
//! - The file is changed through [`crate::output::rewrite`]: through a symbolic link, with
//!   its mode, owner and hard links kept; a read-only file is refused. The backup gets the
//!   file's mode and owner.

use std::path::{Path, PathBuf};

use super::{
    Calibration, ExportError, Format, check_usable, names, not_in_layout, parse_error, recognised,
    source,
};
use crate::model::Param;
use crate::output::WriteOptions;

/// What [`update()`] did.
#[derive(Debug, Clone, PartialEq)]
pub enum Updated {
    /// The file was changed.
    Written {
        /// The file written (the target of a symbolic link).
        file: PathBuf,
        /// Where its previous content is kept.
        backup: PathBuf,
        /// Whether that backup was written now (`false`: an existing backup already held
        /// the previous content).
        new_backup: bool,
    },
    /// Nothing was written.
    Unchanged(Unchanged),
}

/// Why [`update()`] wrote nothing.
#[derive(Debug, Clone, PartialEq)]
pub enum Unchanged {
    /// The calibration determines none of the values the file carries (all held or
    /// undetermined).
    NothingDetermined,
    /// The file holds this calibration's values already.
    AlreadyHolds,
    /// The calibration (of angles already corrected by the file's values) is already
    /// applied: the file is `backup`, the robot's file before, with this calibration
    /// composed in.
    AlreadyApplied {
        /// The backup holding the file this calibration was applied to.
        backup: PathBuf,
    },
}

impl std::fmt::Display for Unchanged {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Unchanged::NothingDetermined => f.write_str(
                "the calibration determines none of the values this file carries (each is \
                 held or not determined by the data)",
            ),
            Unchanged::AlreadyHolds => f.write_str("the file holds this calibration already"),
            Unchanged::AlreadyApplied { backup } => write!(
                f,
                "this calibration is already applied: the file is {} with it composed in \
                 (its offsets are changes to the robot's previous file)",
                backup.display()
            ),
        }
    }
}

/// The backups of `file`: `FILE.bak`, then `FILE.bak.2`, `FILE.bak.3`, … as far as they
/// exist, and the next free name.
pub fn backups(file: &Path) -> (Vec<PathBuf>, PathBuf) {
    let name = |k: usize| {
        let mut s = file.as_os_str().to_owned();
        if k == 1 {
            s.push(".bak");
        } else {
            s.push(format!(".bak.{k}"));
        }
        PathBuf::from(s)
    };
    let mut existing = Vec::new();
    let mut k = 1;
    loop {
        let path = name(k);
        if path.symlink_metadata().is_err() {
            return (existing, path);
        }
        existing.push(path);
        k += 1;
    }
}

/// `naocalib export --update`: replaces in the robot's file `path` (in `format`'s layout,
/// or the one recognised from its content) only what `cal` determined — the cameras'
/// corrections, the leg joint offsets, the head offsets only when estimated, NomadZ's
/// `jointPlay` only when the play was — and keeps every other byte (a byte-order mark
/// included). See the module's documentation for the backups, the refusals and when
/// nothing is written. A file that cannot be parsed, or holds an implausible value, is
/// refused with its name and line, and nothing is written.
pub fn update(
    cal: &Calibration,
    format: Option<&'static dyn Format>,
    path: &Path,
    inputs: &[PathBuf],
) -> Result<(&'static dyn Format, Updated), ExportError> {
    update_with(cal, format, path, inputs, &mut || {})
}

/// [`update`], with `meanwhile` run just after the file is read (the tests' other program
/// editing it).
fn update_with(
    cal: &Calibration,
    format: Option<&'static dyn Format>,
    path: &Path,
    inputs: &[PathBuf],
    meanwhile: &mut dyn FnMut(),
) -> Result<(&'static dyn Format, Updated), ExportError> {
    check_usable(cal, || path.display().to_string())?;
    let src = source::read(path)?;
    meanwhile();
    let text = &src.text;
    let format = match format {
        Some(f) => f,
        None => recognised(text).ok_or_else(|| {
            parse_error(
                path,
                format!("layout not recognised; give --format ({})", names()),
            )
        })?,
    };
    if !format.robot() {
        return Err(parse_error(
            path,
            format!("--update is not supported for --format {}", format.name()),
        ));
    }
    if !format.matches(text) {
        return Err(not_in_layout(path, format, text));
    }
    let new = format.update(text, path, cal)?;
    if new == *text {
        let held = format.read(text, path).unwrap_or_default();
        // The cameras' intrinsics the file holds, calibrated here.
        let intrinsics = format
            .read_cameras(text, path)
            .unwrap_or_default()
            .iter()
            .any(|(camera, _)| {
                cal.intrinsics(*camera)
                    .is_some_and(|i| i.calibrated.iter().any(|c| *c))
            });
        let why = if intrinsics || held.iter().any(|(p, _)| cal.determined_here(*p).is_some()) {
            Unchanged::AlreadyHolds
        } else {
            Unchanged::NothingDetermined
        };
        return Ok((format, Updated::Unchanged(why)));
    }
    let file = path.canonicalize().map_err(|source| ExportError::Io {
        path: path.to_path_buf(),
        action: "resolve",
        source,
    })?;
    let (existing, next) = backups(&file);
    if cal.corrected_angles()
        && let Some(backup) = applied_to(cal, format, text, &existing)
    {
        return Ok((
            format,
            Updated::Unchanged(Unchanged::AlreadyApplied { backup }),
        ));
    }
    let options = WriteOptions {
        force: false,
        inputs: inputs.to_vec(),
    };
    let meta = std::fs::metadata(&file).map_err(|source| ExportError::Io {
        path: file.clone(),
        action: "read",
        source,
    })?;
    // The previous content is kept: by the newest backup when it holds it, else anew.
    let bytes = src.with_text(text);
    let (backup, new_backup) = match existing.last() {
        Some(last) if std::fs::read(last).is_ok_and(|b| b == bytes.as_bytes()) => {
            (last.clone(), false)
        }
        _ => (next, true),
    };
    // Refuse before writing anything: an input, a read-only file.
    crate::output::check_rewritable(&file, &options)?;
    // The file as read must still be there when its backup is kept and when it is
    // replaced: an edit another program made meanwhile would be lost from both.
    let changed = || {
        (std::fs::read(&file).ok().as_deref() != Some(bytes.as_bytes())).then(|| {
            parse_error(
                path,
                "changed while naocalib was updating it (another program writes it?); \
                 nothing was written: run the update again once it is left alone"
                    .to_string(),
            )
        })
    };
    if let Some(e) = changed() {
        return Err(e);
    }
    if new_backup {
        crate::output::write_new_like(&backup, bytes.as_bytes(), &meta, &options)?;
    }
    if let Some(e) = changed() {
        if new_backup {
            let _ = std::fs::remove_file(&backup);
        }
        return Err(e);
    }
    let file = crate::output::rewrite(&file, src.with_text(&new).as_bytes(), &options)?;
    Ok((
        format,
        Updated::Written {
            file,
            backup,
            new_backup,
        },
    ))
}

/// The kept backup that, updated with `cal`, holds what `text` holds for every parameter
/// `cal` determined (within 1e-9 of the report unit): the file `cal` was already applied
/// to.
fn applied_to(
    cal: &Calibration,
    format: &dyn Format,
    text: &str,
    backups: &[PathBuf],
) -> Option<PathBuf> {
    let here = Path::new("-");
    let now = format.read(text, here).ok()?;
    let determined: Vec<Param> = now
        .iter()
        .map(|(p, _)| *p)
        .filter(|p| cal.determined_here(*p).is_some())
        .collect();
    if determined.is_empty() {
        return None;
    }
    backups.iter().rev().find_map(|b| {
        let old = source::read(b).ok()?.text;
        if !format.matches(&old) {
            return None;
        }
        let applied = format
            .read(&format.update(&old, here, cal).ok()?, here)
            .ok()?;
        let same = determined.iter().all(|p| {
            let value = |v: &[(Param, f64)]| v.iter().find(|(q, _)| q == p).map(|(_, x)| *x);
            matches!((value(&applied), value(&now)), (Some(a), Some(b)) if (a - b).abs() < 1e-9)
        });
        same.then(|| b.clone())
    })
}

impl Calibration {
    /// The value a team file stores for the offset `param` (deg), whose file held
    /// `old_stored` (deg): `−α` for raw angles; for angles the file's calibration already
    /// corrected (true = logged + α with logged = sensor − old), `old_stored − α`.
    pub fn stored_joint_value(
        &self,
        param: Param,
        old_stored: f64,
        path: &Path,
    ) -> Result<f64, ExportError> {
        let alpha = self.determined_here(param).ok_or_else(|| {
            parse_error(
                path,
                format!("{param} was not determined by this calibration"),
            )
        })?;
        Ok(if self.corrected_angles() {
            old_stored - alpha
        } else {
            -alpha
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibration::{Entry, Origin, Posture};

    /// A converged calibration with every parameter at `value` (deg / mm), none held.
    fn calibration(value: f64) -> Calibration {
        Calibration {
            origin: Origin::Solved,
            solver: Some("test".into()),
            dataset: None,
            converged: Some(true),
            rms_px: Some([0.4, 0.5]),
            parameters: Param::ALL
                .into_iter()
                .map(|param| Entry {
                    param,
                    value: if param.name().ends_with("Play") {
                        0.5
                    } else {
                        value
                    },
                    std: Some(0.05),
                    fixed: false,
                })
                .collect(),
            angles: None,
            posture: Posture::Lying,
            standing: Default::default(),
            cameras: Default::default(),
        }
    }

    /// An edit another program makes between naocalib's read and its write is never lost:
    /// the update is refused, the file keeps the other edit, and no backup is left of a
    /// content that was never the file's.
    #[test]
    fn an_update_refuses_a_file_changed_since_it_was_read() {
        let dir = tempfile::tempdir().unwrap();
        let teams = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/teams");
        for name in ["bhuman/cameraCalibration.cfg", "hulks/body.json"] {
            let file = dir.path().join(name.replace('/', "-"));
            std::fs::copy(teams.join(name), &file).unwrap();
            let other = format!("{}\n", std::fs::read_to_string(&file).unwrap());
            let mut edit = || std::fs::write(&file, &other).unwrap();
            let e = update_with(&calibration(1.0), None, &file, &[], &mut edit).unwrap_err();
            assert!(e.to_string().contains("changed while"), "{name}: {e}");
            assert_eq!(std::fs::read_to_string(&file).unwrap(), other, "{name}");
            assert!(backups(&file).0.is_empty(), "{name}: no backup");
            // Left alone, it is updated.
            update(&calibration(1.0), None, &file, &[]).unwrap();
            assert_ne!(std::fs::read_to_string(&file).unwrap(), other, "{name}");
        }
    }
}
