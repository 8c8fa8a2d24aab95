//! What `naocalib export` and `naocalib import` are asked for: the files to write (each
//! with its format, named or recognised from its name), the robot file to update, what
//! is said before writing, and what was written.

use std::path::{Path, PathBuf};

use super::{
    Calibration, ExportError, FileRead, Format, Posture, Updated, WriteOptions, every_file, export,
    from_path, import_calibration, named, names, read_calibration, update, write_files,
};
use crate::model::Param;

/// Calibration files to write from a result or calibration, as `naocalib export` is asked
/// for them.
#[derive(Debug, Clone, PartialEq)]
pub struct ExportRequest {
    /// The result JSON or calibration TOML/JSON read.
    pub input: PathBuf,
    /// Files to write, each in `format` or the one its name implies.
    pub out: Vec<PathBuf>,
    /// The format of the `out` or `update` files, by name.
    pub format: Option<String>,
    /// A directory to write every format into.
    pub dir: Option<PathBuf>,
    /// A robot's file to update in its team's layout.
    pub update: Option<PathBuf>,
    /// Replace existing files (never the input).
    pub force: bool,
    /// The posture whose leg offsets the robot files carry.
    pub posture: Posture,
    /// Write robot files even for a result that is not a calibration, marked so.
    pub allow_unconverged: bool,
}

/// Why calibration files could not be written or read.
#[derive(Debug, thiserror::Error)]
pub enum ExportRequestError {
    /// No file to write was named.
    #[error("nothing to write: give --out FILE, --dir DIR or --update FILE")]
    Nothing,
    /// The format named is not one of the list.
    #[error("unknown --format '{0}' ({names})", names = names())]
    UnknownFormat(String),
    /// A robot file would be written from a result that is not a calibration.
    #[error("give --allow-unconverged to write it anyway, marked NOT A CALIBRATION")]
    NotACalibration(#[source] ExportError),
    /// The file to import into is no calibration file.
    #[error("{}: --out must be a .toml or .json calibration file", .0.display())]
    NotCalibrationFile(PathBuf),
    /// A file could not be read or written.
    #[error(transparent)]
    Export(#[from] ExportError),
}

/// The format named `name`, if given: a name of the list ([`named`]).
pub fn format_named(name: Option<&str>) -> Result<Option<&'static dyn Format>, ExportRequestError> {
    name.map(|name| named(name).ok_or_else(|| ExportRequestError::UnknownFormat(name.into())))
        .transpose()
}

/// Writes the files of `request` (or updates its robot file) and returns what to print:
/// a line per file written, or what the update did. `note` hears first of a calibration
/// that is not one, of the standing leg offsets the team files get and, for an update of
/// a camera file, of the head offsets the cameras' corrections hold for.
pub fn run(
    request: &ExportRequest,
    note: &mut dyn FnMut(&str),
) -> Result<String, ExportRequestError> {
    if request.out.is_empty() && request.dir.is_none() && request.update.is_none() {
        return Err(ExportRequestError::Nothing);
    }
    let format = format_named(request.format.as_deref())?;
    let mut calibration = read_calibration(&request.input)?;
    calibration.posture = request.posture;
    let problems = calibration.problems();
    if !problems.is_empty() {
        note(&format!(
            "warning: {} is not a calibration: {}",
            request.input.display(),
            problems.join("; ")
        ));
    }
    if calibration.posture == Posture::Standing {
        for line in calibration.standing_notes() {
            note(&line);
        }
    }
    if let Some(file) = &request.update {
        let (format, updated) = update(
            &calibration,
            format,
            file,
            std::slice::from_ref(&request.input),
        )?;
        if !format.joints() {
            note(&head_note(&calibration));
        }
        return Ok(update_message(file, format, &updated));
    }
    let options = WriteOptions {
        force: request.force,
        inputs: vec![request.input.clone()],
    };
    let mut targets: Vec<(&'static dyn Format, PathBuf)> = Vec::new();
    for path in &request.out {
        let format = match format.or_else(|| from_path(path)) {
            Some(f) => f,
            None => return Err(ExportError::UnknownFormat { path: path.clone() }.into()),
        };
        targets.push((format, path.clone()));
    }
    if let Some(dir) = &request.dir {
        targets.extend(every_file(&calibration, dir));
    }
    // The outputs policy: every path is checked before any file is written, a result that
    // is not a calibration becomes no robot file without `allow_unconverged`, and the
    // `dir` set is all or nothing.
    let written = write_files(
        &calibration,
        &targets,
        request.dir.as_deref(),
        &options,
        request.allow_unconverged,
    )
    .map_err(|e| match e {
        e @ ExportError::NotACalibration { .. } => ExportRequestError::NotACalibration(e),
        e => e.into(),
    })?;
    Ok(written
        .iter()
        .map(|path| format!("wrote {}\n", path.display()))
        .collect())
}

/// What an update of a camera file says: the head offsets its corrections hold for.
pub fn head_note(calibration: &Calibration) -> String {
    format!(
        "note: the cameras' corrections hold for head offsets HeadYaw {} deg, HeadPitch {} \
         deg (as this calibration had them); if the robot's joint calibration holds others, \
         solve with --start-from (naocalib import) first",
        calibration.value(Param::HeadYaw),
        calibration.value(Param::HeadPitch)
    )
}

/// What an update of the robot file `file` in `format` did, one line.
pub fn update_message(file: &Path, format: &dyn Format, updated: &Updated) -> String {
    match updated {
        Updated::Written {
            file: written,
            backup,
            new_backup,
        } => {
            let link = file
                .symlink_metadata()
                .is_ok_and(|m| m.file_type().is_symlink());
            let through = if link {
                format!(" through {}", written.display())
            } else {
                String::new()
            };
            let kept = if *new_backup {
                "kept as"
            } else {
                "already kept in"
            };
            format!(
                "updated {}{through} ({}); previous file {kept} {}\n",
                file.display(),
                format.name(),
                backup.display()
            )
        }
        Updated::Unchanged(why) => format!(
            "not updated: {} ({}): {why}; nothing written\n",
            file.display(),
            format.name()
        ),
    }
}

/// A robot's team files to read into a calibration file, as `naocalib import` is asked
/// for them.
#[derive(Debug, Clone, PartialEq)]
pub struct ImportRequest {
    /// The team files.
    pub files: Vec<PathBuf>,
    /// The calibration TOML or JSON to write.
    pub out: PathBuf,
    /// The layout of every file, by name (recognised from each one's content without it).
    pub format: Option<String>,
    /// Replace an existing `out` (never an input).
    pub force: bool,
}

/// Reads the team files of `request` and writes their calibration; returns what each
/// file gave (the file, its format's name, the values read).
pub fn import(request: &ImportRequest) -> Result<Vec<FileRead>, ExportRequestError> {
    let format = format_named(request.format.as_deref())?;
    let (calibration, read) = import_calibration(&request.files, format)?;
    let out_format = match from_path(&request.out) {
        Some(f) if !f.robot() => f,
        _ => return Err(ExportRequestError::NotCalibrationFile(request.out.clone())),
    };
    let options = WriteOptions {
        force: request.force,
        inputs: request.files.clone(),
    };
    export(&calibration, out_format, &request.out, &options)?;
    Ok(read)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn request(input: &Path) -> ExportRequest {
        ExportRequest {
            input: input.to_path_buf(),
            out: Vec::new(),
            format: None,
            dir: None,
            update: None,
            force: false,
            posture: Posture::Standing,
            allow_unconverged: false,
        }
    }

    #[test]
    fn a_format_is_named_from_the_list() {
        assert_eq!(format_named(Some("toml")).unwrap().unwrap().name(), "toml");
        assert!(format_named(None).unwrap().is_none());
        let e = format_named(Some("nope")).err().unwrap().to_string();
        assert!(
            e.starts_with("unknown --format 'nope' (toml, json, "),
            "{e}"
        );
    }

    #[test]
    fn nothing_to_write_and_unknown_names_are_refused_before_reading() {
        let r = request(Path::new("none.json"));
        assert!(matches!(
            run(&r, &mut |_| {}),
            Err(ExportRequestError::Nothing)
        ));
        let unknown = ExportRequest {
            out: vec![PathBuf::from("x.toml")],
            format: Some("nope".into()),
            ..r
        };
        assert!(matches!(
            run(&unknown, &mut |_| {}),
            Err(ExportRequestError::UnknownFormat(_))
        ));
        let import_to_cfg = ImportRequest {
            files: vec![PathBuf::from("none.cfg")],
            out: PathBuf::from("cal.cfg"),
            format: Some("bhuman-camera".into()),
            force: false,
        };
        // The team file is read first: it does not exist.
        assert!(matches!(
            import(&import_to_cfg),
            Err(ExportRequestError::Export(_))
        ));
    }

    #[test]
    fn an_update_says_what_it_did() {
        let format = named("bhuman-camera").unwrap();
        let written = Updated::Written {
            file: PathBuf::from("cam.cfg"),
            backup: PathBuf::from("cam.cfg.bak"),
            new_backup: true,
        };
        assert_eq!(
            update_message(Path::new("cam.cfg"), format, &written),
            "updated cam.cfg (bhuman-camera); previous file kept as cam.cfg.bak\n"
        );
        let again = Updated::Written {
            file: PathBuf::from("cam.cfg"),
            backup: PathBuf::from("cam.cfg.bak"),
            new_backup: false,
        };
        assert!(
            update_message(Path::new("cam.cfg"), format, &again)
                .ends_with("previous file already kept in cam.cfg.bak\n")
        );
    }
}
