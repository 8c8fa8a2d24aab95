//! Exports of a calibration — the paper's compensation step: the joint offsets and camera
//! corrections in forms that people read and robots load.
//!
//! - [`crate::calibration`]: naocalib's own calibration TOML/JSON ([`Calibration`]), which carries
//!   every parameter with its one-sigma, and reads back the result JSON of
//!   `naocalib solve --json` as well.
//! - the formats SPL teams load, each in its own module with its units and axis
//!   conventions, one row each in [`REGISTRY`] (name, file, description, reader, writer,
//!   updater): [`bhuman`] (`cameraCalibration.cfg` in the 2019+ and the older layout,
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
//! use naocalib::export::{Calibration, ExportFormat, WriteOptions, export};
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
//! let back = naocalib::export::read_calibration(&path).unwrap();
//! assert_eq!(back.parameters, calibration.parameters);
//! ```

pub mod bhuman;
pub mod camera;
pub mod cfg;
pub mod hulks;
pub mod ini;
pub mod jsonedit;
pub mod naoth;
pub mod nomadz;
pub mod runswift;
pub mod source;
pub mod tree;
pub mod update;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::model::Param;

pub use crate::calibration::{
    COMPENSATION, Calibration, Entry, FORMAT, Posture, VERSION, read_calibration, read_start_from,
};
pub use bhuman::{
    BHUMAN_JOINTS, bhuman_camera_cfg, bhuman_joint_cfg, read_bhuman_camera_cfg,
    read_bhuman_joint_cfg,
};
pub use update::{Unchanged, Updated, update};
// `WriteOptions` belongs to the export API.
pub use crate::output::WriteOptions;
use crate::output::{check_writable, write_atomic};

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
    /// The output format cannot be told from the file name.
    #[error("{}: unknown export format (use .toml, .json, cameraCalibration.cfg or \
             jointCalibration.cfg, or give --format)", path.display())]
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

/// The output formats of [`export`]; each has one row in [`REGISTRY`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ExportFormat {
    /// Calibration TOML ([`Calibration::to_toml`]).
    Toml,
    /// Calibration JSON ([`Calibration::to_json`]).
    Json,
    /// B-Human `cameraCalibration.cfg`, 2019+ layout ([`bhuman_camera_cfg`]).
    BHumanCamera,
    /// B-Human `cameraCalibration.cfg`, layout up to 2018 ([`bhuman::bhuman_camera_2016_cfg`]).
    BHumanCamera2016,
    /// B-Human `jointCalibration.cfg` ([`bhuman_joint_cfg`]).
    BHumanJoints,
    /// HULKs per-head parameter JSON ([`hulks::head_json`]).
    HulksHead,
    /// HULKs per-body parameter JSON ([`hulks::body_json`]).
    HulksBody,
    /// NaoTH `CameraMatrixOffset.cfg` ([`naoth::camera_matrix_offset_cfg`]).
    NaothCamera,
    /// NomadZ `cameraCalibration.cfg` ([`nomadz::camera_calibration_cfg`]).
    NomadzCamera,
    /// NomadZ `jointCalibration.cfg` ([`nomadz::joint_calibration_cfg`]).
    NomadzJoints,
    /// rUNSWift `[kinematics]` camera entries ([`runswift::kinematics_cfg`]).
    RunswiftCamera,
}

/// What a robot's team file holds, as naocalib parameters in report units (deg): joint
/// offsets as α = −stored, camera corrections converted to naocalib's offsets.
pub type Imported = Vec<(Param, f64)>;

/// Reads a team file's values ([`Imported`]).
pub type ImportFn = fn(&str, &Path) -> Result<Imported, ExportError>;
/// A robot's file with what a calibration determined replaced, every other byte kept.
pub type UpdateFn = fn(&str, &Path, &Calibration) -> Result<String, ExportError>;

/// One format: everything the CLI, `--dir`, `import`, `--update` and docs/EXPORTS.md
/// know of it. Adding a team is one module and one row of [`REGISTRY`].
#[derive(Clone, Copy)]
pub struct FormatSpec {
    /// The format.
    pub format: ExportFormat,
    /// Its `--format` name.
    pub name: &'static str,
    /// The file name `--dir` gives it (relative to the directory).
    pub file: &'static str,
    /// One line: the team, the file and what it carries.
    pub description: &'static str,
    /// The calibration in this format, as a fresh file.
    pub render: fn(&Calibration) -> String,
    /// Reads a file of this format (`naocalib import`), when supported.
    pub read: Option<ImportFn>,
    /// Updates a robot's file of this format (`naocalib export --update`), when supported.
    pub update: Option<UpdateFn>,
    /// Whether a file is of this format, judged on its text without comments
    /// ([`source::code`]): for `naocalib import` without --format, and to refuse an
    /// `--update` of a file in another layout.
    pub recognise: fn(&str) -> bool,
    /// Whether the file carries joint offsets (which a calibration from angles already
    /// corrected by the robot's joint calibration can only write with `--update`).
    pub joints: bool,
}

fn json_text(cal: &Calibration) -> String {
    let mut s = serde_json::to_string_pretty(&cal.to_json()).expect("JSON of plain values");
    s.push('\n');
    s
}

fn is_naocalib(text: &str) -> bool {
    text.contains(crate::calibration::FORMAT)
}

/// Whether `code` (a text without comments) has an entry `key = …` (or `key=…`).
fn has_key(code: &str, key: &str) -> bool {
    code.match_indices(key).any(|(at, _)| {
        let before = code[..at].chars().next_back();
        let after = code[at + key.len()..].trim_start();
        !before.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_') && after.starts_with('=')
    })
}

/// Every format, one row each, in `--dir` order.
pub const REGISTRY: [FormatSpec; 11] = [
    FormatSpec {
        format: ExportFormat::Toml,
        name: "toml",
        file: "calibration.toml",
        description: "naocalib's calibration TOML: every parameter with sigma and unit",
        render: Calibration::to_toml,
        read: None,
        update: None,
        recognise: is_naocalib,
        joints: false,
    },
    FormatSpec {
        format: ExportFormat::Json,
        name: "json",
        file: "calibration.json",
        description: "naocalib's calibration JSON (same keys as the TOML)",
        render: json_text,
        read: None,
        update: None,
        recognise: is_naocalib,
        joints: false,
    },
    FormatSpec {
        format: ExportFormat::BHumanCamera,
        name: "bhuman-camera",
        file: "cameraCalibration.cfg",
        description: "B-Human (2019+), SPQR: cameraRotationCorrections.{lower,upper} {x; y; z} in deg",
        render: bhuman_camera_cfg,
        read: Some(bhuman::import_camera),
        update: Some(bhuman::update_camera),
        recognise: |c| has_key(c, "cameraRotationCorrections"),
        joints: false,
    },
    FormatSpec {
        format: ExportFormat::BHumanCamera2016,
        name: "bhuman-camera-2016",
        file: "bhuman2016/cameraCalibration.cfg",
        description: "B-Human up to 2018: lower/upperCameraRotationCorrection {x; y; z} in deg",
        render: bhuman::bhuman_camera_2016_cfg,
        read: Some(bhuman::import_camera),
        update: Some(bhuman::update_camera),
        recognise: |c| has_key(c, "lowerCameraRotationCorrection"),
        joints: false,
    },
    FormatSpec {
        format: ExportFormat::BHumanJoints,
        name: "bhuman-joints",
        file: "jointCalibration.cfg",
        description: "B-Human, SPQR: offsets {<joint> = -alpha deg; ...}",
        render: bhuman_joint_cfg,
        read: Some(bhuman::import_joints),
        update: Some(bhuman::update_joints),
        recognise: |c| {
            !c.trim_start().starts_with('{') && has_key(c, "offsets") && !c.contains("minAngle")
        },
        joints: true,
    },
    FormatSpec {
        format: ExportFormat::HulksHead,
        name: "hulks-head",
        file: "hulks/head.json",
        description: "HULKs head.<id>.json: correction_in_camera_bottom/_top [x, y, z] in rad",
        render: hulks::head_json,
        read: Some(hulks::import_head),
        update: Some(hulks::update_head),
        recognise: |c| {
            c.contains("\"correction_in_camera_bottom\"")
                || c.contains("\"correction_in_camera_top\"")
        },
        joints: false,
    },
    FormatSpec {
        format: ExportFormat::HulksBody,
        name: "hulks-body",
        file: "hulks/body.json",
        description: "HULKs body.<id>.json: joint_calibration_offsets = -alpha in rad",
        render: hulks::body_json,
        read: Some(hulks::import_body),
        update: Some(hulks::update_body),
        recognise: |c| c.contains("\"joint_calibration_offsets\""),
        joints: true,
    },
    FormatSpec {
        format: ExportFormat::NaothCamera,
        name: "naoth-camera",
        file: "naoth/CameraMatrixOffset.cfg",
        description: "NaoTH: [CameraMatrixOffset] cam_rot.bottom/top.x/y/z and head_rot.x/y/z in rad",
        render: naoth::camera_matrix_offset_cfg,
        read: Some(naoth::import),
        update: Some(naoth::update),
        recognise: |c| c.contains("[CameraMatrixOffset]"),
        joints: false,
    },
    FormatSpec {
        format: ExportFormat::NomadzCamera,
        name: "nomadz-camera",
        file: "nomadz/cameraCalibration.cfg",
        description: "NomadZ: camera/upperCamera Tilt/Roll/PanCorrection in rad",
        render: nomadz::camera_calibration_cfg,
        read: Some(nomadz::import_camera),
        update: Some(nomadz::update_camera),
        recognise: |c| has_key(c, "cameraTiltCorrection"),
        joints: false,
    },
    FormatSpec {
        format: ExportFormat::NomadzJoints,
        name: "nomadz-joints",
        file: "nomadz/jointCalibration.cfg",
        description: "NomadZ: <joint> = {offset = -alpha; minAngle; maxAngle; jointPlay} in deg",
        render: nomadz::joint_calibration_cfg,
        read: Some(nomadz::import_joints),
        update: Some(nomadz::update_joints),
        recognise: |c| has_key(c, "minAngle") && has_key(c, "jointPlay"),
        joints: true,
    },
    FormatSpec {
        format: ExportFormat::RunswiftCamera,
        name: "runswift-camera",
        file: "runswift/kinematics.cfg",
        description: "rUNSWift: [kinematics] camera{Yaw,Pitch,Roll}Bottom, …TopWhenLooking{Straight,Left,Right} in deg",
        render: runswift::kinematics_cfg,
        read: Some(runswift::import),
        update: Some(runswift::update),
        recognise: |c| c.contains("[kinematics]"),
        joints: false,
    },
];

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

impl ExportFormat {
    /// Every format, with its `--format` name and the file name [`export_all`] gives it
    /// (from [`REGISTRY`]).
    pub const ALL: [(ExportFormat, &'static str, &'static str); REGISTRY.len()] = {
        let mut out = [(ExportFormat::Toml, "", ""); REGISTRY.len()];
        let mut i = 0;
        while i < REGISTRY.len() {
            out[i] = (REGISTRY[i].format, REGISTRY[i].name, REGISTRY[i].file);
            i += 1;
        }
        out
    };

    /// The format's row of [`REGISTRY`].
    pub fn spec(self) -> &'static FormatSpec {
        REGISTRY
            .iter()
            .find(|s| s.format == self)
            .expect("every format has a registry row")
    }

    /// The `--format` names, comma-separated (for messages).
    pub fn names() -> String {
        Self::ALL.map(|(_, name, _)| name).join(", ")
    }

    /// One line per format, `name: description (file)` (for the CLI help).
    pub fn help() -> String {
        REGISTRY
            .iter()
            .map(|s| format!("{}: {} ({})", s.name, s.description, s.file))
            .collect::<Vec<_>>()
            .join("\n")
    }

    /// The format named `name` (`toml`, `json`, `bhuman-camera`, …; see [`Self::ALL`]).
    pub fn from_name(name: &str) -> Option<Self> {
        REGISTRY.iter().find(|s| s.name == name).map(|s| s.format)
    }

    /// The format's `--format` name.
    pub fn name(self) -> &'static str {
        self.spec().name
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

    /// The robot format a file's text is in ([`FormatSpec::recognise`] on the text without
    /// comments), if any.
    pub fn recognise(text: &str) -> Option<Self> {
        let code = source::code(text);
        REGISTRY
            .iter()
            .filter(|s| s.read.is_some())
            .find(|s| (s.recognise)(&code))
            .map(|s| s.format)
    }

    /// Whether `text` is in this format's layout ([`FormatSpec::recognise`] on the text
    /// without comments).
    pub fn matches(self, text: &str) -> bool {
        (self.spec().recognise)(&source::code(text))
    }

    /// The calibration rendered in this format (with the `NOT A CALIBRATION` marker when
    /// [`Calibration::problems`] finds any).
    pub fn render(self, cal: &Calibration) -> String {
        (self.spec().render)(cal)
    }
}

/// Refuses a fresh joint file (at `path`) for a calibration fitted to angles the robot's
/// joint calibration had already corrected: its offsets are changes to that calibration,
/// which only `--update` of the robot's file can compose (stored_new = stored_old − α).
pub fn check_fresh(
    cal: &Calibration,
    format: ExportFormat,
    path: &Path,
) -> Result<(), ExportError> {
    if format.spec().joints && cal.corrected_angles() {
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
    files: &[(ExportFormat, PathBuf)],
    options: &WriteOptions,
    allow_not_calibration: bool,
) -> Result<(), ExportError> {
    if !allow_not_calibration
        && let Some((_, path)) = files.iter().find(|(f, _)| f.is_robot_format())
    {
        check_usable(cal, || path.display().to_string())?;
    }
    for (format, path) in files {
        check_fresh(cal, *format, path)?;
        check_writable(path, options)?;
    }
    Ok(())
}

/// Writes `cal` as `files` (each a format and its path) after [`check_files`], atomically,
/// and returns the paths in the order given. The files inside `dir` are written all or
/// nothing: into a stage beside `dir`, published after the others.
pub fn write_files(
    cal: &Calibration,
    files: &[(ExportFormat, PathBuf)],
    dir: Option<&Path>,
    options: &WriteOptions,
    allow_not_calibration: bool,
) -> Result<Vec<PathBuf>, ExportError> {
    check_files(cal, files, options, allow_not_calibration)?;
    let stage = dir
        .map(|d| crate::output::Staged::new(d, options))
        .transpose()?;
    for (format, path) in files {
        let text = format.render(cal);
        match (&stage, dir.and_then(|d| path.strip_prefix(d).ok())) {
            (Some(stage), Some(rel)) => {
                write_atomic(&stage.dir().join(rel), text.as_bytes(), &stage.options())?
            }
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
    format: ExportFormat,
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
    /// had already corrected, so its offsets are changes to the robot's file ([`update()`]).
    JointFiles,
    /// Every robot file: the result is not a calibration (these reasons); only naocalib's
    /// own TOML and JSON, which say so.
    RobotFiles(Vec<String>),
}

/// The files a directory export of `cal` into `dir` writes under the outputs policy
/// (`naocalib solve --export`), with the file names of [`ExportFormat::ALL`], and what it
/// leaves out.
pub fn dir_files(cal: &Calibration, dir: &Path) -> (Vec<(ExportFormat, PathBuf)>, Withheld) {
    let problems = cal.problems();
    let withheld = if !problems.is_empty() {
        Withheld::RobotFiles(problems)
    } else if cal.corrected_angles() {
        Withheld::JointFiles
    } else {
        Withheld::Nothing
    };
    let files = ExportFormat::ALL
        .iter()
        .filter(|(format, _, _)| match withheld {
            Withheld::Nothing => true,
            Withheld::JointFiles => !format.spec().joints,
            Withheld::RobotFiles(_) => !format.is_robot_format(),
        })
        .map(|(format, _, name)| (*format, dir.join(name)))
        .collect();
    (files, withheld)
}

/// One file `naocalib import` read: its path, format name and how many values it held.
pub type FileRead = (PathBuf, &'static str, usize);

/// Reads a robot's team files into a [`Calibration`] (`naocalib import`): every value they
/// hold, as naocalib parameters held at it (`fixed`, the robot's current calibration);
/// every other parameter of the paper's set present but undetermined (never written into
/// a robot file). Returns it with `(file, format name, values read)` per file. The same
/// parameter in two files is an error.
pub fn import_calibration(
    files: &[PathBuf],
    format: Option<ExportFormat>,
) -> Result<(Calibration, Vec<FileRead>), ExportError> {
    let mut values: Vec<Option<(f64, usize)>> = vec![None; Param::ALL.len()];
    let mut read = Vec::new();
    for (k, file) in files.iter().enumerate() {
        let (format, imported) = import(file, format)?;
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
    format: Option<ExportFormat>,
) -> Result<(ExportFormat, Imported), ExportError> {
    let text = source::read(path)?.text;
    let format = match format {
        Some(f) => {
            if f.spec().read.is_some() && !f.matches(&text) {
                return Err(not_in_layout(path, f, &text));
            }
            f
        }
        None => ExportFormat::recognise(&text).ok_or_else(|| {
            parse_error(
                path,
                format!(
                    "not a team calibration file naocalib knows (give --format: {})",
                    ExportFormat::names()
                ),
            )
        })?,
    };
    let read = format.spec().read.ok_or_else(|| {
        parse_error(
            path,
            format!("import is not supported for --format {}", format.name()),
        )
    })?;
    let values = read(&text, path)?;
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
pub(crate) fn not_in_layout(path: &Path, format: ExportFormat, text: &str) -> ExportError {
    let looks = match ExportFormat::recognise(text) {
        Some(other) => format!("it looks like a {} file", other.name()),
        None => "its layout is none naocalib knows".to_string(),
    };
    parse_error(
        path,
        format!(
            "not a {} file ({}): {looks}; nothing written",
            format.name(),
            format.spec().description
        ),
    )
}

/// Writes `cal` into `dir` in every format (file names in [`ExportFormat::ALL`]) and
/// returns the paths written ([`write_files`]): every path is checked before any is
/// written, so that nothing is written when one is refused; a result that is not a
/// calibration is refused.
pub fn export_all(
    cal: &Calibration,
    dir: &Path,
    options: &WriteOptions,
) -> Result<Vec<PathBuf>, ExportError> {
    let files: Vec<(ExportFormat, PathBuf)> = ExportFormat::ALL
        .iter()
        .map(|(format, _, name)| (*format, dir.join(name)))
        .collect();
    write_files(cal, &files, Some(dir), options, false)
}

/// A number as team files carry it: the shortest text that reads back to the same `f64`
/// (so exports round-trip exactly), `-0` as `0`.
pub(crate) fn num(x: f64) -> String {
    if x == 0.0 { "0".into() } else { format!("{x}") }
}
