//! Exports of a calibration — the paper's compensation step: the joint offsets and camera
//! corrections in forms that people read and robots load.
//!
//! - [`own`]: naocalib's own calibration TOML/JSON of a [`Calibration`], which carries
//!   every parameter with its one-sigma ([`read_calibration`] reads it, and the result
//!   JSON of `naocalib solve --json` as well).
//! - a format is one [`Format`] — name, file, description, recognise, write, read,
//!   update — implemented by a unit struct in its team's module with its units and axis
//!   conventions, and one line of [`FORMATS`], from which the CLI's `--format` and help,
//!   [`from_path`], [`recognised`] and docs/EXPORTS.md's table ([`table`]) follow:
//!   [`bhuman`] (`cameraCalibration.cfg` in the 2019+ and the older layout,
//!   `jointCalibration.cfg`), [`hulks`] (per-head and per-body parameter JSON), [`naoth`]
//!   (`CameraMatrixOffset.cfg`), [`nomadz`] (`cameraCalibration.cfg`, `jointCalibration.cfg`
//!   with `jointPlay`), [`runswift`] (`[kinematics]`). [`camera`] turns naocalib's camera
//!   offsets into each team's parameterisation of the same rotation and back.
//! - [`update()`]: a robot's own file with only what a calibration determined replaced, every
//!   other byte kept ([`mod@cfg`], [`jsonedit`], [`ini`] read the files with the span of every
//!   value); [`import`] / [`import_calibration`]: a robot's files read back.
//! - files are written through [`crate::output`], the one writer (atomically, never over an
//!   input); [`write_files`] holds the outputs policy for a calibration's files.
//!
//! The sign of the joint offsets: naocalib's α means true angle = logged angle + α. Every
//! team framework computes true = sensor − stored and commands request + stored, so the
//! team files store **−α** (docs/EXPORTS.md cites each team's code; `tests/it/
//! export_signs.rs` proves it through that code). The camera offsets go into the camera
//! matrix, after the head joints. Every exported file says so in its header, with its
//! units.
//!
//! A result that is not a calibration — not converged, non-finite, or with residuals far
//! beyond any plausible noise ([`Calibration::problems`]) — is never written into a file a
//! robot loads: one policy, [`check_files`] (through [`write_files`], which [`export`],
//! [`export_all`], `naocalib export` and `solve --export` ([`dir_files`]) all use), refuses
//! it with [`ExportError::NotACalibration`]. naocalib's own TOML/JSON carry `converged` and
//! `rms_px`, so they say what the result is; and the rendered team files of such a result
//! (for those who insist, `naocalib export --allow-unconverged`) start with a
//! `NOT A CALIBRATION` marker.
//!
//! ```
//! use naocalib::export::{Calibration, WriteOptions, export, own};
//! # use naocalib::model::{FixedSet, Model};
//! # use naocalib::sim::{SimOptions, simulate};
//! # use naocalib::solve::{Problem, UncertaintyOptions, backend, calibrate};
//! # let options = SimOptions { stances: 4, heads: 2, ..SimOptions::default() };
//! # let dataset = simulate(&Model::default(), &options).unwrap();
//! # let problem = Problem::from_dataset(&dataset, FixedSet::default()).unwrap();
//! # let solution = calibrate(&problem, backend("lm", false).unwrap().as_ref(), &UncertaintyOptions::plain()).unwrap();
//! let calibration = Calibration::from_solution(&solution, None);
//! let dir = tempfile::tempdir().unwrap();
//! let path = dir.path().join("calibration.toml");
//! export(&calibration, &own::Toml, &path, &WriteOptions::default()).unwrap();
//! let back = naocalib::export::read_calibration(&path).unwrap();
//! assert_eq!(back.parameters, calibration.parameters);
//! ```

pub mod bhuman;
pub mod camera;
pub mod cfg;
pub mod format;
pub mod hulks;
pub mod ini;
pub mod jsonedit;
pub mod naoth;
pub mod nomadz;
pub mod own;
mod read;
pub mod request;
pub mod runswift;
pub mod source;
pub mod tree;
pub mod update;
mod write;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::model::{CameraId, Param};
use read::not_in_layout;
use write::check_usable;

pub use crate::calibration::{COMPENSATION, Calibration, Entry, Posture};
pub use bhuman::BHUMAN_JOINTS;
pub use format::{
    DocRow, Format, NameRule, from_path, help, name_hints, name_patterns, named, names, recognised,
    table,
};
pub use own::{FORMAT, VERSION, read_calibration, read_start_from};
pub use read::{FileRead, import, import_calibration};
pub use update::{Unchanged, Updated, update};
pub use write::{
    Withheld, check_files, check_fresh, dir_files, every_file, export, export_all, write_files,
};
// `WriteOptions` belongs to the export API.
pub use crate::output::WriteOptions;

/// Every format, one line each, in `--dir` order: the `--format` names and help,
/// [`from_path`], [`recognised`], `--dir` and docs/EXPORTS.md's table follow this list.
/// Adding a format is a unit struct implementing [`Format`] in its team's module and one
/// line here.
pub static FORMATS: &[&dyn Format] = &[
    &own::Toml,
    &own::Json,
    &bhuman::Camera,
    &bhuman::Camera2016,
    &bhuman::Joints,
    &bhuman::Intrinsics,
    &hulks::Head,
    &hulks::Body,
    &naoth::Camera,
    &naoth::CameraInfo(CameraId::Upper),
    &naoth::CameraInfo(CameraId::Lower),
    &nomadz::Camera,
    &nomadz::Joints,
    &nomadz::CameraInfo(CameraId::Upper),
    &nomadz::CameraInfo(CameraId::Lower),
    &runswift::Camera,
];

/// Everything that can go wrong exporting or reading an export.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// Reading or writing a file failed.
    #[error("{}: cannot {action}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What was attempted.
        action: &'static str,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// Writing a file failed or was refused ([`crate::output`], the one writer): it exists
    /// and `force` was not given, it is an input, something is in the way.
    #[error(transparent)]
    Write(#[from] crate::output::WriteError),
    /// A calibration file could not be understood.
    #[error("{}: {message}", path.display())]
    Parse {
        /// The file (or `-` for text not read from a file).
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// The output format cannot be told from the file name ([`from_path`]).
    #[error("{}: unknown export format (use {}, or give --format)", path.display(), name_hints())]
    UnknownFormat {
        /// The file.
        path: PathBuf,
    },
    /// A joint file from a calibration of corrected angles needs the robot's file.
    #[error(
        "not writing {}: {format}: the calibration was fitted to joint angles already \
             corrected by the robot's joint calibration, so its offsets are changes to that \
             file: give the robot's file with --update FILE", path.display()
    )]
    NeedsUpdate {
        /// The file not written.
        path: PathBuf,
        /// The format's name.
        format: &'static str,
    },
    /// A file of the cameras' intrinsics for a calibration that carries none.
    #[error(
        "not writing {}: {format}: the calibration carries no camera intrinsics for it (solve \
         with --free intrinsics; a camera's need captures of it)", path.display()
    )]
    NoIntrinsics {
        /// The file not written.
        path: PathBuf,
        /// The format's name.
        format: &'static str,
    },
    /// The result is not a calibration a robot should load.
    #[error("not a calibration, refusing to write {what}: {}", reasons.join("; "))]
    NotACalibration {
        /// The file or files that were not written.
        what: String,
        /// Why ([`Calibration::problems`]).
        reasons: Vec<String>,
    },
}

pub(crate) fn parse_error(path: &Path, message: impl Into<String>) -> ExportError {
    ExportError::Parse {
        path: path.to_path_buf(),
        message: message.into(),
    }
}

/// What a robot's team file holds, as naocalib parameters in report units (deg): joint
/// offsets as α = −stored, camera corrections converted to naocalib's offsets.
pub type Imported = Vec<(Param, f64)>;

/// The header every exported file starts with (each line behind `comment`): what wrote
/// it, from what, the units and the compensation rule — and a loud marker when the result
/// is not a calibration.
pub(crate) fn header(s: &mut String, comment: &str, cal: &Calibration, units: &str) {
    for problem in cal.problems() {
        let _ = writeln!(s, "{comment} NOT A CALIBRATION — do not load: {problem}");
    }
    let _ = writeln!(
        s,
        "{comment} NAO kinematic calibration written by naocalib {}",
        env!("CARGO_PKG_VERSION")
    );
    if let Some(d) = &cal.dataset {
        let _ = writeln!(s, "{comment} dataset: {d}");
    }
    if let Some(solver) = &cal.solver {
        let converged = match cal.converged {
            Some(true) => ", converged",
            Some(false) => ", NOT converged",
            None => "",
        };
        let _ = writeln!(s, "{comment} solver: {solver}{converged}");
    }
    let _ = writeln!(s, "{comment} Units: {units}.");
    let _ = writeln!(
        s,
        "{comment} Joint offsets: naocalib's alpha means true angle = logged angle + alpha."
    );
    let _ = writeln!(
        s,
        "{comment} Team frameworks compute true = sensor - stored and command request + stored,"
    );
    let _ = writeln!(
        s,
        "{comment} so their files store -alpha. Camera offsets are rotation corrections of the"
    );
    let cameras = if camera::known(cal, crate::model::CameraId::Upper) {
        "cameras"
    } else {
        "lower camera"
    };
    let _ = writeln!(
        s,
        "{comment} {cameras} in the camera matrix, applied after the head joints."
    );
    let undetermined: Vec<&str> = cal
        .parameters
        .iter()
        .filter(|e| !e.is_determined())
        .map(|e| e.param.name())
        .collect();
    if !undetermined.is_empty() {
        let _ = writeln!(
            s,
            "{comment} NOT determined by the data (not written into robot files, see the report): {}",
            undetermined.join(", ")
        );
    }
}

/// A camera correction beyond this (deg) in a robot's file is no plausible correction: the
/// file is refused as corrupt (e.g. a tilt of 3.38 written in radians, 194°).
pub const CAMERA_LIMIT_DEG: f64 = 30.0;
/// A joint offset beyond this (deg) in a robot's file is refused as corrupt.
pub const JOINT_LIMIT_DEG: f64 = 30.0;

/// Refuses a value read from a robot's file beyond `limit_deg`, naming file, line and key.
pub(crate) fn check_plausible(
    path: &Path,
    line: usize,
    key: &str,
    value_deg: f64,
    limit_deg: f64,
) -> Result<(), ExportError> {
    if value_deg.abs() <= limit_deg {
        Ok(())
    } else {
        Err(parse_error(
            path,
            format!(
                "line {line}: {key} = {value_deg:.3} deg is no plausible correction (beyond \
                 ±{limit_deg} deg): the file looks corrupt; fix it by hand first"
            ),
        ))
    }
}

/// A number as team files carry it: the shortest text that reads back to the same `f64`
/// (so exports round-trip exactly), `-0` as `0`.
pub(crate) fn num(x: f64) -> String {
    if x == 0.0 { "0".into() } else { format!("{x}") }
}
