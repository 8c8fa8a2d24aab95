//! Exports of a calibration — the paper's compensation step: the joint offsets and camera
//! corrections in forms that people read and robots load.
//!
//! - [`Calibration`]: the estimated parameters with their one-sigma and unit, written as
//!   TOML ([`Calibration::to_toml`]) or JSON ([`Calibration::to_json`]) and read back by
//!   [`Calibration::from_toml`], [`Calibration::from_json`] or [`read_calibration`]. The
//!   JSON reader also accepts the result JSON of SPEC section 7 (`naocalib solve --json`),
//!   whose `parameters` object has the same form.
//! - [`bhuman_camera_cfg`]: a B-Human style `cameraCalibration.cfg` rotation-correction
//!   block for the lower camera.
//! - [`bhuman_joint_cfg`]: a B-Human style `jointCalibration.cfg` joint-offset list.
//!
//! Compensation (SPEC section 5, as in the paper): joint offsets are **added to requested
//! angles and subtracted from measured ones**; the camera offsets go into the camera
//! matrix. Every exported file says so in its header, with its units.
//!
//! Every file is written atomically ([`write_atomic`]: a temporary file in the same
//! directory, then a rename), never replaces an input file, and never replaces an existing
//! file unless asked to (`force`).
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

use std::fmt::Write as _;
use std::io::{self, Write as _};
use std::path::{Path, PathBuf};

use serde_json::{Map, Value, json};

use crate::model::{PAPER_PARAMETERS, Param};
use crate::solve::Solution;

/// The `format` key of the TOML and JSON calibration files.
pub const FORMAT: &str = "naocalib-calibration";
/// The `version` key of the TOML and JSON calibration files.
pub const VERSION: i64 = 1;

/// The compensation rule, as stated in every exported file.
pub const COMPENSATION: &str = "joint offsets are added to requested joint angles and \
     subtracted from measured joint angles; camera offsets are rotation corrections of the \
     lower camera in the camera matrix (SPEC section 5)";

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
        source: io::Error,
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
}

fn parse_error(path: &Path, message: impl Into<String>) -> ExportError {
    ExportError::Parse {
        path: path.to_path_buf(),
        message: message.into(),
    }
}

/// How exported files are written.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct WriteOptions {
    /// Replace an existing file (never an input file).
    pub force: bool,
    /// Files that must never be written to (the dataset's files, the file converted).
    pub inputs: Vec<PathBuf>,
}

impl WriteOptions {
    /// Options that protect the files of the dataset in `dir` (and any file in it that
    /// exists when asked: `dataset.toml`, `captures.csv`, `corners.csv`, `truth.toml`).
    pub fn protecting_dataset(dir: &Path, force: bool) -> Self {
        WriteOptions {
            force,
            inputs: dataset_files(dir),
        }
    }
}

/// The files of the dataset in `dir` that a writer must never replace.
pub fn dataset_files(dir: &Path) -> Vec<PathBuf> {
    use crate::dataset::{CAPTURES_CSV, CORNERS_CSV, DATASET_TOML, TRUTH_TOML};
    [DATASET_TOML, CAPTURES_CSV, CORNERS_CSV, TRUTH_TOML]
        .iter()
        .map(|f| dir.join(f))
        .collect()
}

/// Whether `a` and `b` name the same file (same canonical path; or the same path when
/// either does not exist).
fn same_file(a: &Path, b: &Path) -> bool {
    let canon = |p: &Path| -> Option<PathBuf> {
        if let Ok(c) = p.canonicalize() {
            return Some(c);
        }
        // Not existing: canonicalise the parent and keep the name.
        let parent = match p.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        Some(parent.canonicalize().ok()?.join(p.file_name()?))
    };
    match (canon(a), canon(b)) {
        (Some(x), Some(y)) => x == y,
        _ => a == b,
    }
}

/// Writes `contents` to `path` atomically (temporary file in the same directory, then a
/// rename; the directory is created if missing). Refuses a path that is one of
/// `options.inputs`, and an existing file unless `options.force`.
pub fn write_atomic(
    path: &Path,
    contents: &[u8],
    options: &WriteOptions,
) -> Result<(), ExportError> {
    write_atomic_with(path, options, |tmp| {
        let mut file = std::fs::OpenOptions::new().write(true).open(tmp)?;
        file.write_all(contents)?;
        file.sync_all()
    })
}

/// Like [`write_atomic`], but the content is produced by `fill`, which writes the
/// temporary file at the path it is given (a sibling of `path` with the same extension, so
/// that writers that look at the extension, such as image encoders, do the right thing).
pub fn write_atomic_with(
    path: &Path,
    options: &WriteOptions,
    fill: impl FnOnce(&Path) -> io::Result<()>,
) -> Result<(), ExportError> {
    if let Some(input) = options.inputs.iter().find(|i| same_file(i, path)) {
        return Err(ExportError::Input {
            path: input.clone(),
        });
    }
    if !options.force && path.symlink_metadata().is_ok() {
        return Err(ExportError::Exists {
            path: path.to_path_buf(),
        });
    }
    let dir = match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir,
        _ => Path::new("."),
    };
    let io_err = |action, source| ExportError::Io {
        path: path.to_path_buf(),
        action,
        source,
    };
    std::fs::create_dir_all(dir).map_err(|e| io_err("create the directory for", e))?;
    let suffix = path
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_else(|| ".tmp".into());
    let mut builder = tempfile::Builder::new();
    builder.prefix(".naocalib-").suffix(&suffix);
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    let tmp = builder
        .tempfile_in(dir)
        .map_err(|e| io_err("create a temporary file to write", e))?;
    fill(tmp.path()).map_err(|e| io_err("write", e))?;
    let persisted = if options.force {
        tmp.persist(path)
    } else {
        tmp.persist_noclobber(path)
    };
    persisted.map(|_| ()).map_err(|e| match e.error.kind() {
        io::ErrorKind::AlreadyExists if !options.force => ExportError::Exists {
            path: path.to_path_buf(),
        },
        _ => io_err("write", e.error),
    })
}

/// One calibrated parameter, in report units (deg / mm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Entry {
    /// The parameter.
    pub param: Param,
    /// Its estimate [deg or mm].
    pub value: f64,
    /// Its one-sigma uncertainty [deg or mm]; 0 when held fixed.
    pub std: f64,
    /// Whether it was held fixed (at `value`).
    pub fixed: bool,
}

/// A calibration as exported: every parameter with its one-sigma and unit.
#[derive(Debug, Clone, PartialEq)]
pub struct Calibration {
    /// The solver that produced it (`ceres`, …), when known.
    pub solver: Option<String>,
    /// The dataset it was calibrated from, when known.
    pub dataset: Option<String>,
    /// Every parameter, in the order of [`Param::ALL`].
    pub parameters: Vec<Entry>,
}

impl Calibration {
    /// The calibration of `solution` (from the dataset at `dataset`, if given).
    pub fn from_solution(solution: &Solution, dataset: Option<&Path>) -> Self {
        Calibration {
            solver: Some(solution.summary.solver.clone()),
            dataset: dataset.map(|d| d.display().to_string()),
            parameters: Param::ALL
                .iter()
                .map(|&p| {
                    let fixed = solution.fixed.is_fixed(p);
                    Entry {
                        param: p,
                        value: solution.report_value(p),
                        std: if fixed { 0.0 } else { solution.report_std(p) },
                        fixed,
                    }
                })
                .collect(),
        }
    }

    /// The entry of `param`, if present.
    pub fn get(&self, param: Param) -> Option<&Entry> {
        self.parameters.iter().find(|e| e.param == param)
    }

    /// The value of `param` in report units (deg / mm); 0 when absent.
    pub fn value(&self, param: Param) -> f64 {
        self.get(param).map_or(0.0, |e| e.value)
    }

    /// The calibration as TOML, with a header stating units and the compensation rule.
    pub fn to_toml(&self) -> String {
        let mut s = String::new();
        header(&mut s, "#", self);
        let _ = writeln!(s, "format = {}", toml_str(FORMAT));
        let _ = writeln!(s, "version = {VERSION}");
        if let Some(solver) = &self.solver {
            let _ = writeln!(s, "solver = {}", toml_str(solver));
        }
        if let Some(dataset) = &self.dataset {
            let _ = writeln!(s, "dataset = {}", toml_str(dataset));
        }
        let _ = writeln!(s, "compensation = {}", toml_str(COMPENSATION));
        for e in &self.parameters {
            let _ = writeln!(s, "\n[parameters.{}]", e.param.name());
            let _ = writeln!(s, "value = {}", toml_float(e.value));
            let _ = writeln!(s, "std = {}", toml_float(e.std));
            let _ = writeln!(s, "unit = {}", toml_str(e.param.unit().name()));
            if e.fixed {
                let _ = writeln!(s, "fixed = true");
            }
        }
        s
    }

    /// The calibration as JSON: the `parameters` object has the form of SPEC section 7.
    pub fn to_json(&self) -> Value {
        let mut params = Map::new();
        for e in &self.parameters {
            let mut entry = json!({"value": e.value, "std": e.std, "unit": e.param.unit().name()});
            if e.fixed {
                entry["fixed"] = Value::Bool(true);
            }
            params.insert(e.param.name().into(), entry);
        }
        let mut root = json!({
            "format": FORMAT,
            "version": VERSION,
            "units": {"angles": "deg", "lengths": "mm"},
            "compensation": COMPENSATION,
        });
        if let Some(solver) = &self.solver {
            root["solver"] = json!(solver);
        }
        if let Some(dataset) = &self.dataset {
            root["dataset"] = json!(dataset);
        }
        root["parameters"] = Value::Object(params);
        root
    }

    /// Reads a calibration TOML written by [`Calibration::to_toml`]; `path` names the
    /// source in errors.
    pub fn from_toml(text: &str, path: &Path) -> Result<Self, ExportError> {
        let value: toml::Table = text.parse().map_err(|e: toml::de::Error| {
            parse_error(path, format!("not valid TOML: {}", e.message()))
        })?;
        let json = serde_json::to_value(&value)
            .map_err(|e| parse_error(path, format!("cannot be read: {e}")))?;
        Self::from_value(&json, path)
    }

    /// Reads a calibration JSON written by [`Calibration::to_json`], or the result JSON of
    /// SPEC section 7 (`naocalib solve --json`, a run of `naocalib batch --out`).
    pub fn from_json(text: &str, path: &Path) -> Result<Self, ExportError> {
        let json: Value = serde_json::from_str(text)
            .map_err(|e| parse_error(path, format!("not valid JSON: {e}")))?;
        Self::from_value(&json, path)
    }

    fn from_value(root: &Value, path: &Path) -> Result<Self, ExportError> {
        let root = root
            .as_object()
            .ok_or_else(|| parse_error(path, "expected a table/object at the top"))?;
        if let Some(format) = root.get("format")
            && format.as_str() != Some(FORMAT)
        {
            return Err(parse_error(
                path,
                format!("format is {format}, expected \"{FORMAT}\""),
            ));
        }
        if let Some(version) = root.get("version")
            && version.as_i64() != Some(VERSION)
        {
            return Err(parse_error(
                path,
                format!("version {version} is not supported (expected {VERSION})"),
            ));
        }
        let text = |key: &str| -> Result<Option<String>, ExportError> {
            match root.get(key) {
                None => Ok(None),
                Some(Value::String(s)) => Ok(Some(s.clone())),
                Some(other) => Err(parse_error(
                    path,
                    format!("{key}: expected a string, got {other}"),
                )),
            }
        };
        let solver = text("solver")?;
        let dataset = text("dataset")?;
        let params = root
            .get("parameters")
            .and_then(Value::as_object)
            .ok_or_else(|| parse_error(path, "missing table 'parameters'"))?;
        for name in params.keys() {
            if Param::from_name(name).is_none() {
                return Err(parse_error(
                    path,
                    format!("parameters.{name}: unknown parameter"),
                ));
            }
        }
        let mut parameters = Vec::new();
        for p in Param::ALL {
            let Some(entry) = params.get(p.name()) else {
                if p.index() < PAPER_PARAMETERS {
                    return Err(parse_error(
                        path,
                        format!("parameters.{}: missing", p.name()),
                    ));
                }
                continue;
            };
            let at = |key: &str| format!("parameters.{}.{key}", p.name());
            let number = |key: &str, required: bool| -> Result<f64, ExportError> {
                match entry.get(key) {
                    None if !required => Ok(0.0),
                    None => Err(parse_error(path, format!("{}: missing", at(key)))),
                    Some(v) => v.as_f64().filter(|x| x.is_finite()).ok_or_else(|| {
                        parse_error(path, format!("{}: {v} is not a finite number", at(key)))
                    }),
                }
            };
            let value = number("value", true)?;
            let std = number("std", false)?;
            if std < 0.0 {
                return Err(parse_error(path, format!("{}: negative", at("std"))));
            }
            if let Some(unit) = entry.get("unit")
                && unit.as_str() != Some(p.unit().name())
            {
                return Err(parse_error(
                    path,
                    format!(
                        "{}: {unit}, but {} is in {}",
                        at("unit"),
                        p.name(),
                        p.unit().name()
                    ),
                ));
            }
            let fixed = match entry.get("fixed") {
                None => false,
                Some(Value::Bool(b)) => *b,
                Some(v) => {
                    return Err(parse_error(
                        path,
                        format!("{}: {v} is not true or false", at("fixed")),
                    ));
                }
            };
            parameters.push(Entry {
                param: p,
                value,
                std,
                fixed,
            });
        }
        Ok(Calibration {
            solver,
            dataset,
            parameters,
        })
    }
}

/// Reads a calibration file: TOML by the `.toml` extension, otherwise JSON (a calibration
/// JSON or a SPEC section 7 result JSON).
pub fn read_calibration(path: &Path) -> Result<Calibration, ExportError> {
    let text = std::fs::read_to_string(path).map_err(|source| ExportError::Io {
        path: path.to_path_buf(),
        action: "read",
        source,
    })?;
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("toml"))
    {
        Calibration::from_toml(&text, path)
    } else {
        Calibration::from_json(&text, path)
    }
}

fn toml_str(s: &str) -> String {
    toml::Value::String(s.to_string()).to_string()
}

/// A float as TOML that reads back to the same bits.
fn toml_float(x: f64) -> String {
    let s = format!("{x:?}");
    if s.contains(['.', 'e', 'E', 'n', 'i']) {
        s
    } else {
        format!("{s}.0")
    }
}

fn header(s: &mut String, comment: &str, cal: &Calibration) {
    let _ = writeln!(
        s,
        "{comment} NAO kinematic calibration written by naocalib {}",
        env!("CARGO_PKG_VERSION")
    );
    if let Some(d) = &cal.dataset {
        let _ = writeln!(s, "{comment} dataset: {d}");
    }
    if let Some(solver) = &cal.solver {
        let _ = writeln!(s, "{comment} solver: {solver}");
    }
    let _ = writeln!(
        s,
        "{comment} Units: angles in degrees (deg), board translations in millimetres (mm);"
    );
    let _ = writeln!(
        s,
        "{comment} std is the one-sigma uncertainty in the same unit."
    );
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
}

/// B-Human's name of each joint, in its `Joints` order (head, left arm, right arm, left
/// leg, right leg), with the naocalib parameter holding its offset, if any.
pub const BHUMAN_JOINTS: [(&str, Option<Param>); 26] = [
    ("headYaw", Some(Param::HeadYaw)),
    ("headPitch", Some(Param::HeadPitch)),
    ("lShoulderPitch", None),
    ("lShoulderRoll", None),
    ("lElbowYaw", None),
    ("lElbowRoll", None),
    ("lWristYaw", None),
    ("lHand", None),
    ("rShoulderPitch", None),
    ("rShoulderRoll", None),
    ("rElbowYaw", None),
    ("rElbowRoll", None),
    ("rWristYaw", None),
    ("rHand", None),
    ("lHipYawPitch", Some(Param::LHipYawPitch)),
    ("lHipRoll", Some(Param::LHipRoll)),
    ("lHipPitch", Some(Param::LHipPitch)),
    ("lKneePitch", Some(Param::LKneePitch)),
    ("lAnklePitch", Some(Param::LAnklePitch)),
    ("lAnkleRoll", Some(Param::LAnkleRoll)),
    ("rHipYawPitch", Some(Param::RHipYawPitch)),
    ("rHipRoll", Some(Param::RHipRoll)),
    ("rHipPitch", Some(Param::RHipPitch)),
    ("rKneePitch", Some(Param::RKneePitch)),
    ("rAnklePitch", Some(Param::RAnklePitch)),
    ("rAnkleRoll", Some(Param::RAnkleRoll)),
];

/// Degrees as B-Human writes angles: `-4.5627deg`.
fn deg(x: f64) -> String {
    // Four decimals as in the paper's tables; -0 printed as 0.
    let r = format!("{:.4}", x);
    if r.trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        "0deg".into()
    } else {
        format!("{r}deg")
    }
}

/// A B-Human style `cameraCalibration.cfg` block with the lower camera's rotation
/// correction, in degrees:
///
/// ```text
/// lowerCameraRotationCorrection = {x = <CamRoll>deg; y = <CamPitch>deg; z = <CamYaw>deg;};
/// ```
///
/// Mapping: B-Human's camera frame is SPEC's camera frame C (x along the optical axis,
/// y left, z up), and its camera matrix applies the corrections after the fixed tilt as
/// `rotateY(tilt + y) · rotateX(x) · rotateZ(z)` — SPEC eq. 3's
/// `Ry(tilt) · Ry(α_CamPitch) · Rx(α_CamRoll) · Rz(α_CamYaw)`. So `x = CamRoll`,
/// `y = CamPitch`, `z = CamYaw`, same signs. The upper camera and the body rotation are
/// not calibrated here and are written as zero.
pub fn bhuman_camera_cfg(cal: &Calibration) -> String {
    let mut s = String::new();
    header(&mut s, "//", cal);
    let _ = writeln!(
        s,
        "// Mapping: x = CamRoll, y = CamPitch, z = CamYaw (SPEC eq. 3: Ry(tilt)·Ry(CamPitch)·Rx(CamRoll)·Rz(CamYaw))."
    );
    let _ = writeln!(
        s,
        "// Only the lower camera is calibrated; the upper camera and body corrections are zero."
    );
    let _ = writeln!(
        s,
        "upperCameraRotationCorrection = {{x = 0deg; y = 0deg; z = 0deg;}};"
    );
    let _ = writeln!(
        s,
        "lowerCameraRotationCorrection = {{x = {}; y = {}; z = {};}};",
        deg(cal.value(Param::CamRoll)),
        deg(cal.value(Param::CamPitch)),
        deg(cal.value(Param::CamYaw))
    );
    let _ = writeln!(s, "bodyRotationCorrection = {{x = 0deg; y = 0deg;}};");
    s
}

/// A B-Human style `jointCalibration.cfg` joint-offset list in degrees, one entry per
/// joint in B-Human's joint order (`offsets = {headYaw = 0deg; …; rAnkleRoll = …deg;};`),
/// with the estimated leg offsets and zero for joints not calibrated (arms; the head unless
/// its offsets were estimated). Sign as in SPEC section 5: the value is added to requested
/// angles and subtracted from measured ones.
pub fn bhuman_joint_cfg(cal: &Calibration) -> String {
    let mut s = String::new();
    header(&mut s, "//", cal);
    let _ = writeln!(
        s,
        "// One offset per joint in B-Human's joint order; joints not calibrated are 0deg."
    );
    let _ = writeln!(s, "offsets = {{");
    for (name, param) in BHUMAN_JOINTS {
        let entry = param.and_then(|p| cal.get(p));
        let value = entry.map_or(0.0, |e| e.value);
        let note = match entry {
            Some(e) if !e.fixed => format!(" // {} ± {:.4} deg", e.param.name(), e.std),
            Some(e) => format!(" // {} held fixed", e.param.name()),
            None => " // not calibrated".to_string(),
        };
        let _ = writeln!(s, "  {name} = {};{note}", deg(value));
    }
    let _ = writeln!(s, "}};");
    s
}

/// Reads back the lower camera correction of a [`bhuman_camera_cfg`] file: `[x, y, z]`
/// in degrees (CamRoll, CamPitch, CamYaw).
pub fn read_bhuman_camera_cfg(text: &str, path: &Path) -> Result<[f64; 3], ExportError> {
    let line = text
        .lines()
        .find(|l| l.trim_start().starts_with("lowerCameraRotationCorrection"))
        .ok_or_else(|| parse_error(path, "no lowerCameraRotationCorrection"))?;
    let mut out = [f64::NAN; 3];
    for (k, key) in ["x", "y", "z"].iter().enumerate() {
        out[k] = cfg_value(line, key)
            .ok_or_else(|| parse_error(path, format!("lowerCameraRotationCorrection: no {key}")))?;
    }
    Ok(out)
}

/// Reads back the offsets of a [`bhuman_joint_cfg`] file: B-Human joint name → degrees.
pub fn read_bhuman_joint_cfg(text: &str, path: &Path) -> Result<Vec<(String, f64)>, ExportError> {
    let mut out = Vec::new();
    for line in text.lines() {
        let code = line.split("//").next().unwrap_or("").trim();
        let Some((name, rest)) = code.split_once('=') else {
            continue;
        };
        let name = name.trim();
        if name == "offsets" {
            continue;
        }
        let number = rest
            .trim()
            .trim_end_matches(';')
            .trim()
            .trim_end_matches("deg");
        let value: f64 = number.parse().map_err(|_| {
            parse_error(
                path,
                format!("{name}: '{}' is not an angle in deg", rest.trim()),
            )
        })?;
        out.push((name.to_string(), value));
    }
    Ok(out)
}

/// The number after `key = ` in a `{x = 1deg; y = …}` block.
fn cfg_value(line: &str, key: &str) -> Option<f64> {
    let inner = line.split_once('{')?.1;
    inner.split(';').find_map(|part| {
        let (k, v) = part.split_once('=')?;
        (k.trim() == key).then(|| v.trim().trim_end_matches("deg").parse().ok())?
    })
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
}

impl ExportFormat {
    /// Every format, with the file name [`export_all`] gives it.
    pub const ALL: [(ExportFormat, &'static str); 4] = [
        (ExportFormat::Toml, "calibration.toml"),
        (ExportFormat::Json, "calibration.json"),
        (ExportFormat::BHumanCamera, "cameraCalibration.cfg"),
        (ExportFormat::BHumanJoints, "jointCalibration.cfg"),
    ];

    /// The format named `name` (`toml`, `json`, `bhuman-camera`, `bhuman-joints`).
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "toml" => Some(ExportFormat::Toml),
            "json" => Some(ExportFormat::Json),
            "bhuman-camera" => Some(ExportFormat::BHumanCamera),
            "bhuman-joints" => Some(ExportFormat::BHumanJoints),
            _ => None,
        }
    }

    /// The format a file name implies: `*.toml`, `*.json`, `*camera*.cfg`, `*joint*.cfg`.
    pub fn from_path(path: &Path) -> Option<Self> {
        let name = path.file_name()?.to_string_lossy().to_lowercase();
        if name.ends_with(".toml") {
            Some(ExportFormat::Toml)
        } else if name.ends_with(".json") {
            Some(ExportFormat::Json)
        } else if name.ends_with(".cfg") && name.contains("camera") {
            Some(ExportFormat::BHumanCamera)
        } else if name.ends_with(".cfg") && name.contains("joint") {
            Some(ExportFormat::BHumanJoints)
        } else {
            None
        }
    }

    /// The calibration rendered in this format.
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
        }
    }
}

/// Writes `cal` to `path` in `format`, atomically (see [`write_atomic`]).
pub fn export(
    cal: &Calibration,
    format: ExportFormat,
    path: &Path,
    options: &WriteOptions,
) -> Result<(), ExportError> {
    write_atomic(path, format.render(cal).as_bytes(), options)
}

/// Writes `cal` into `dir` in every format (`calibration.toml`, `calibration.json`,
/// `cameraCalibration.cfg`, `jointCalibration.cfg`) and returns the paths written. Checks
/// all four paths before writing any, so that nothing is written when one is refused.
pub fn export_all(
    cal: &Calibration,
    dir: &Path,
    options: &WriteOptions,
) -> Result<Vec<PathBuf>, ExportError> {
    let paths: Vec<PathBuf> = ExportFormat::ALL
        .iter()
        .map(|(_, name)| dir.join(name))
        .collect();
    for path in &paths {
        if let Some(input) = options.inputs.iter().find(|i| same_file(i, path)) {
            return Err(ExportError::Input {
                path: input.clone(),
            });
        }
        if !options.force && path.symlink_metadata().is_ok() {
            return Err(ExportError::Exists { path: path.clone() });
        }
    }
    for ((format, _), path) in ExportFormat::ALL.iter().zip(&paths) {
        export(cal, *format, path, options)?;
    }
    Ok(paths)
}
