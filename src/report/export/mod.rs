//! Exports of a calibration — the paper's compensation step: the joint offsets and camera
//! corrections in forms that people read and robots load.
//!
//! - [`calibration`]: naocalib's own calibration TOML/JSON ([`Calibration`]), which carries
//!   every parameter with its one-sigma, and reads back the result JSON of
//!   `naocalib solve --json` as well.
//! - the formats SPL teams load, each in its own module with its units and axis
//!   conventions: [`bhuman`] (`cameraCalibration.cfg`, `jointCalibration.cfg`), [`hulks`]
//!   (per-head and per-body parameter JSON), [`naoth`] (`CameraMatrixOffset.cfg`),
//!   [`nomadz`] (`jointCalibration.cfg` with `jointPlay`), [`runswift`] (`[kinematics]`).
//!   [`camera`] turns naocalib's camera offsets into each team's parameterisation of the
//!   same rotation.
//! - [`io`]: where files may be written and how (atomically, never over an input).
//!
//! Compensation (as in the paper): joint offsets are **added to requested angles and
//! subtracted from measured ones**; the camera offsets go into the camera matrix. Every
//! exported file says so in its header, with its units.
//!
//! A result that is not a calibration — not converged, non-finite, or with residuals far
//! beyond any plausible noise ([`Calibration::problems`]) — is never written into a file a
//! robot loads: [`export`] and [`export_all`] refuse it with
//! [`ExportError::NotACalibration`]. naocalib's own TOML/JSON carry `converged` and
//! `rms_px`, so they say what the result is; and the rendered team files of such a result
//! (for those who insist, `naocalib export --allow-unconverged`) start with a
//! `NOT A CALIBRATION` marker.
//!
//! ```
//! use naocalib::report::export::{Calibration, ExportFormat, WriteOptions, export};
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
//! export(&calibration, ExportFormat::Toml, &path, &WriteOptions::default()).unwrap();
//! let back = naocalib::report::export::read_calibration(&path).unwrap();
//! assert_eq!(back.parameters, calibration.parameters);
//! ```

pub mod bhuman;
pub mod calibration;
pub mod camera;
pub mod hulks;
pub mod io;
pub mod naoth;
pub mod nomadz;
pub mod runswift;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

pub use bhuman::{
    BHUMAN_JOINTS, bhuman_camera_cfg, bhuman_joint_cfg, read_bhuman_camera_cfg,
    read_bhuman_joint_cfg,
};
pub use calibration::{COMPENSATION, Calibration, Entry, FORMAT, VERSION, read_calibration};
pub use io::{WriteOptions, check_writable, dataset_files, write_atomic, write_atomic_with};

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
    /// The file exists and `force` was not given.
    #[error("{}: already exists; use --force to overwrite", path.display())]
    Exists {
        /// The existing file.
        path: PathBuf,
    },
    /// The output path is one of the inputs (a dataset file, the file being converted).
    #[error("{}: is an input file; refusing to overwrite it", path.display())]
    Input {
        /// The input file.
        path: PathBuf,
    },
    /// A calibration file could not be understood.
    #[error("{}: {message}", path.display())]
    Parse {
        /// The file (or `-` for text not read from a file).
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// The output format cannot be told from the file name.
    #[error("{}: unknown export format (use .toml, .json, cameraCalibration.cfg or \
             jointCalibration.cfg, or give --format)", path.display())]
    UnknownFormat {
        /// The file.
        path: PathBuf,
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
        "{comment} Compensation: joint offsets are ADDED to requested joint angles and"
    );
    let _ = writeln!(
        s,
        "{comment} SUBTRACTED from measured joint angles; the camera offsets are rotation"
    );
    let _ = writeln!(
        s,
        "{comment} corrections of the lower camera that go into the camera matrix."
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
            "{comment} NOT determined by the data (arbitrary values, see the report): {}",
            undetermined.join(", ")
        );
    }
}

/// The output formats of [`export`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ExportFormat {
    /// Calibration TOML ([`Calibration::to_toml`]).
    Toml,
    /// Calibration JSON ([`Calibration::to_json`]).
    Json,
    /// B-Human `cameraCalibration.cfg` ([`bhuman_camera_cfg`]).
    BHumanCamera,
    /// B-Human `jointCalibration.cfg` ([`bhuman_joint_cfg`]).
    BHumanJoints,
    /// HULKs per-head parameter JSON ([`hulks::head_json`]).
    HulksHead,
    /// HULKs per-body parameter JSON ([`hulks::body_json`]).
    HulksBody,
    /// NaoTH `CameraMatrixOffset.cfg` ([`naoth::camera_matrix_offset_cfg`]).
    NaothCamera,
    /// NomadZ `jointCalibration.cfg` ([`nomadz::joint_calibration_cfg`]).
    NomadzJoints,
    /// rUNSWift `[kinematics]` camera entries ([`runswift::kinematics_cfg`]).
    RunswiftCamera,
}

impl ExportFormat {
    /// Every format, with its `--format` name and the file name [`export_all`] gives it.
    pub const ALL: [(ExportFormat, &'static str, &'static str); 9] = [
        (ExportFormat::Toml, "toml", "calibration.toml"),
        (ExportFormat::Json, "json", "calibration.json"),
        (
            ExportFormat::BHumanCamera,
            "bhuman-camera",
            "cameraCalibration.cfg",
        ),
        (
            ExportFormat::BHumanJoints,
            "bhuman-joints",
            "jointCalibration.cfg",
        ),
        (ExportFormat::HulksHead, "hulks-head", "hulks/head.json"),
        (ExportFormat::HulksBody, "hulks-body", "hulks/body.json"),
        (
            ExportFormat::NaothCamera,
            "naoth-camera",
            "naoth/CameraMatrixOffset.cfg",
        ),
        (
            ExportFormat::NomadzJoints,
            "nomadz-joints",
            "nomadz/jointCalibration.cfg",
        ),
        (
            ExportFormat::RunswiftCamera,
            "runswift-camera",
            "runswift/kinematics.cfg",
        ),
    ];

    /// The `--format` names, comma-separated (for messages).
    pub fn names() -> String {
        Self::ALL.map(|(_, name, _)| name).join(", ")
    }

    /// The format named `name` (`toml`, `json`, `bhuman-camera`, …; see [`Self::ALL`]).
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL
            .iter()
            .find(|(_, n, _)| *n == name)
            .map(|(f, _, _)| *f)
    }

    /// The format's `--format` name.
    pub fn name(self) -> &'static str {
        Self::ALL
            .iter()
            .find(|(f, _, _)| *f == self)
            .map_or("", |(_, n, _)| n)
    }

    /// Whether a robot loads files of this format (all but naocalib's TOML and JSON).
    pub fn is_robot_format(self) -> bool {
        !matches!(self, ExportFormat::Toml | ExportFormat::Json)
    }

    /// The format a file name implies: `*.toml`, `*.json`, `*camera*.cfg` (B-Human),
    /// `*joint*.cfg` (B-Human), `CameraMatrixOffset.cfg` (NaoTH).
    pub fn from_path(path: &Path) -> Option<Self> {
        let name = path.file_name()?.to_string_lossy().to_lowercase();
        if name.ends_with(".toml") {
            Some(ExportFormat::Toml)
        } else if name.ends_with(".json") {
            Some(ExportFormat::Json)
        } else if name == "cameramatrixoffset.cfg" {
            Some(ExportFormat::NaothCamera)
        } else if name.ends_with(".cfg") && name.contains("camera") {
            Some(ExportFormat::BHumanCamera)
        } else if name.ends_with(".cfg") && name.contains("joint") {
            Some(ExportFormat::BHumanJoints)
        } else {
            None
        }
    }

    /// The calibration rendered in this format (with the `NOT A CALIBRATION` marker when
    /// [`Calibration::problems`] finds any).
    pub fn render(self, cal: &Calibration) -> String {
        match self {
            ExportFormat::Toml => cal.to_toml(),
            ExportFormat::Json => {
                let mut s =
                    serde_json::to_string_pretty(&cal.to_json()).expect("JSON of plain values");
                s.push('\n');
                s
            }
            ExportFormat::BHumanCamera => bhuman_camera_cfg(cal),
            ExportFormat::BHumanJoints => bhuman_joint_cfg(cal),
            ExportFormat::HulksHead => hulks::head_json(cal),
            ExportFormat::HulksBody => hulks::body_json(cal),
            ExportFormat::NaothCamera => naoth::camera_matrix_offset_cfg(cal),
            ExportFormat::NomadzJoints => nomadz::joint_calibration_cfg(cal),
            ExportFormat::RunswiftCamera => runswift::kinematics_cfg(cal),
        }
    }
}

/// Refuses a result that is not a calibration for the files robots load.
fn check_usable(cal: &Calibration, what: impl FnOnce() -> String) -> Result<(), ExportError> {
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

/// Writes `cal` to `path` in `format`, atomically (see [`write_atomic`]). A result that
/// is not a calibration is refused for robot formats ([`ExportError::NotACalibration`]);
/// naocalib's TOML and JSON are written, carrying `converged` and `rms_px`.
pub fn export(
    cal: &Calibration,
    format: ExportFormat,
    path: &Path,
    options: &WriteOptions,
) -> Result<(), ExportError> {
    if format.is_robot_format() {
        check_usable(cal, || path.display().to_string())?;
    }
    write_atomic(path, format.render(cal).as_bytes(), options)
}

/// Writes `cal` into `dir` in every format (file names in [`ExportFormat::ALL`]) and
/// returns the paths written. Checks every path before writing any, so that nothing is
/// written when one is refused; refuses a result that is not a calibration.
pub fn export_all(
    cal: &Calibration,
    dir: &Path,
    options: &WriteOptions,
) -> Result<Vec<PathBuf>, ExportError> {
    check_usable(cal, || {
        format!("the calibration files into {}", dir.display())
    })?;
    let paths: Vec<PathBuf> = ExportFormat::ALL
        .iter()
        .map(|(_, _, name)| dir.join(name))
        .collect();
    for path in &paths {
        io::check_writable(path, options)?;
    }
    // All or nothing: written into a stage beside `dir`, published at the end.
    let stage = crate::output::Staged::new(dir, options)?;
    for (format, _, name) in ExportFormat::ALL.iter() {
        export(cal, *format, &stage.dir().join(name), &stage.options())?;
    }
    stage.publish()?;
    Ok(paths)
}

/// A number as team files carry it: the shortest text that reads back to the same `f64`
/// (so exports round-trip exactly), `-0` as `0`.
pub(crate) fn num(x: f64) -> String {
    if x == 0.0 { "0".into() } else { format!("{x}") }
}
