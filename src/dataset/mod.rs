//! Datasets on disk (docs/MODEL.md §7): `dataset.toml`, `captures.csv`, `corners.csv`,
//! `truth.toml`, and an optional `images/` folder.
//!
//! [`Dataset::load`] reads and validates a dataset directory; every error is a
//! [`DatasetError`] naming the file, the line and the field, e.g.
//! `data/x/captures.csv line 7, field LKneePitch: 'abc' is not a number`.
//! [`Dataset::write`] and [`write_corners`] write files atomically and never replace an
//! existing file unless asked to (`force`).

mod captures;
mod config;
mod corners;
mod csv_table;
mod error;
pub mod settings;
mod text;
mod toml_doc;
mod truth;
mod units;
mod write;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

pub use config::{camera_table, render_board};
pub use error::{DatasetError, Location};

use crate::model::{CameraId, JointAngles, Model, PARAMETER_COUNT, Param, Side, Vertex};
use crate::output::{WriteOptions, write_atomic};

/// File name of the camera, board and robot description (required).
pub const DATASET_TOML: &str = "dataset.toml";
/// File name of the captures table (required).
pub const CAPTURES_CSV: &str = "captures.csv";
/// File name of the corners table (optional when reading).
pub const CORNERS_CSV: &str = "corners.csv";
/// File name of the true parameters of a simulated dataset (optional).
pub const TRUTH_TOML: &str = "truth.toml";

/// The files of the dataset in `dir` that a writer must never replace: `dataset.toml`,
/// `captures.csv`, `corners.csv` and `truth.toml`.
pub fn dataset_files(dir: &Path) -> Vec<PathBuf> {
    [DATASET_TOML, CAPTURES_CSV, CORNERS_CSV, TRUTH_TOML]
        .iter()
        .map(|f| dir.join(f))
        .collect()
}

impl WriteOptions {
    /// Options that protect the files of the dataset in `dir` (see [`dataset_files`]).
    pub fn protecting_dataset(dir: &Path, force: bool) -> Self {
        WriteOptions::new(force).protecting(dataset_files(dir))
    }
}

/// One captured image: which camera took it, which board is in view and the logged joint
/// angles.
#[derive(Debug, Clone, PartialEq)]
pub struct Capture {
    /// Unique capture id.
    pub id: u64,
    /// The foot whose board is in view.
    pub side: Side,
    /// The camera that took it (`camera` column; lower when absent or empty).
    pub camera: CameraId,
    /// Image path relative to the dataset directory, if any.
    pub image: Option<PathBuf>,
    /// Logged joint angles, in radians.
    pub joints: JointAngles,
    /// Line in `captures.csv` (1-based, header is line 1); 0 when not read from a file.
    pub line: u64,
}

/// One detected (or logged) vertex.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Corner {
    /// The capture it belongs to.
    pub capture: u64,
    /// Which vertex of the board.
    pub vertex: Vertex,
    /// Its position in the image, in pixels (u, v).
    pub pixel: [f64; 2],
    /// Line in `corners.csv` (1-based, header is line 1); 0 when not read from a file.
    pub line: u64,
}

/// The true parameters of a simulated dataset (`truth.toml`).
#[derive(Debug, Clone, PartialEq)]
pub struct Truth {
    /// True values of every parameter, internal units (rad / mm); parameters not named in
    /// the file are zero.
    pub values: [f64; PARAMETER_COUNT],
    /// Free-form `[simulation]` keys (noise levels, seed, …).
    pub simulation: toml::Table,
}

/// What the joint angles in `captures.csv` are (`[joints] angles` in `dataset.toml`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum AngleKind {
    /// Raw encoder readings, as LoLA reports them: nothing has corrected them.
    #[default]
    Raw,
    /// Angles a team framework logged after correcting them with the robot's joint
    /// calibration (true = sensor − stored offset), e.g. B-Human's `JointAngles`.
    Corrected,
}

/// Where a dataset's joint angles come from: raw or corrected, and by which calibration.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct AngleSource {
    /// Raw or corrected.
    pub kind: AngleKind,
    /// The joint calibration that corrected them (a file name or a note), when corrected.
    pub corrected_by: Option<String>,
}

/// A whole dataset, in memory.
#[derive(Debug, Clone, PartialEq)]
pub struct Dataset {
    /// The directory it was read from (or will be written to).
    pub dir: PathBuf,
    /// Camera intrinsics, board and robot geometry from `dataset.toml`.
    pub model: Model,
    /// Rows of `captures.csv`, in file order.
    pub captures: Vec<Capture>,
    /// Rows of `corners.csv`, in file order (empty when there is no such file).
    pub corners: Vec<Corner>,
    /// `truth.toml`, when present.
    pub truth: Option<Truth>,
    /// What the logged joint angles are (`[joints]` in `dataset.toml`; raw by default).
    pub angles: AngleSource,
}

impl Truth {
    /// The true value of `param`, internal units (rad / mm).
    pub fn value(&self, param: Param) -> f64 {
        self.values[param.index()]
    }

    /// The true value of `param`, report units (deg / mm).
    pub fn report_value(&self, param: Param) -> f64 {
        param.unit().to_report(self.value(param))
    }
}

impl Dataset {
    /// An empty dataset (no captures, corners or truth) for `model`, to live in `dir`.
    pub fn new(dir: impl Into<PathBuf>, model: Model) -> Self {
        Dataset {
            dir: dir.into(),
            model,
            captures: Vec::new(),
            corners: Vec::new(),
            truth: None,
            angles: AngleSource::default(),
        }
    }

    /// Reads and validates the dataset in `dir`.
    ///
    /// `dataset.toml` and `captures.csv` are required; a missing `corners.csv` gives no
    /// corners, a missing `truth.toml` no truth. Rows keep their line numbers. Every
    /// problem is an error naming the file, the line and the field; nothing panics.
    pub fn load(dir: &Path) -> Result<Dataset, DatasetError> {
        Self::load_parts(dir, true)
    }

    /// Reads and validates the dataset in `dir` as [`Dataset::load`] does, but without
    /// `corners.csv`, which is neither required nor read (the corners are left empty): for
    /// detecting the vertices in the images instead.
    pub fn load_without_corners(dir: &Path) -> Result<Dataset, DatasetError> {
        Self::load_parts(dir, false)
    }

    fn load_parts(dir: &Path, with_corners: bool) -> Result<Dataset, DatasetError> {
        if dir.metadata().is_ok_and(|m| !m.is_dir()) {
            return Err(DatasetError::invalid(
                Location::file(dir),
                "is not a directory; a dataset is a directory holding dataset.toml and \
                 captures.csv",
            ));
        }
        let path = dir.join(DATASET_TOML);
        let bytes = text::read_file(&path, true, " (it needs at least a [camera] table)")?;
        let (model, angles) = config::parse_with_angles(&path, &bytes.unwrap_or_default())?;

        let path = dir.join(CAPTURES_CSV);
        let bytes = text::read_file(&path, true, " (it needs at least its header line)")?;
        let captures = captures::parse(&path, &bytes.unwrap_or_default())?;
        let ids = captures::validate(&path, &captures, |_, c| c.line)?;
        captures::check_cameras(&path, &captures, &model, |_, c| c.line)?;

        let path = dir.join(CORNERS_CSV);
        let bytes = if with_corners {
            text::read_file(&path, false, " (it needs at least its header line)")?
        } else {
            None
        };
        let corners = match bytes {
            Some(bytes) => corners::parse(&path, &bytes)?,
            None => Vec::new(),
        };
        corners::validate(&path, &corners, Some(&ids), Some(&model), |_, c| c.line)?;

        let path = dir.join(TRUTH_TOML);
        let truth = match text::read_file(&path, false, " (it needs a [parameters] table)")? {
            Some(bytes) => Some(truth::parse(&path, &bytes)?),
            None => None,
        };
        Ok(Dataset {
            dir: dir.to_path_buf(),
            model,
            captures,
            corners,
            truth,
            angles,
        })
    }

    /// Checks the dataset in memory against the rules [`Dataset::load`] applies (valid
    /// camera and board, unique capture ids, finite numbers, relative image paths, corners
    /// of known captures on the board, no vertex twice). Errors name the files in
    /// [`Dataset::dir`] and the rows' `line` (or, for rows not read from a file, the line
    /// they would be written to).
    pub fn validate(&self) -> Result<(), DatasetError> {
        self.check(&self.dir, false)
    }

    fn check(&self, dir: &Path, written: bool) -> Result<(), DatasetError> {
        let line = |index: usize, recorded: u64| {
            if written || recorded == 0 {
                index as u64 + 2
            } else {
                recorded
            }
        };
        config::validate(&dir.join(DATASET_TOML), &self.model)?;
        let ids = captures::validate(&dir.join(CAPTURES_CSV), &self.captures, |i, c| {
            line(i, c.line)
        })?;
        captures::check_cameras(
            &dir.join(CAPTURES_CSV),
            &self.captures,
            &self.model,
            |i, c| line(i, c.line),
        )?;
        corners::validate(
            &dir.join(CORNERS_CSV),
            &self.corners,
            Some(&ids),
            Some(&self.model),
            |i, c| line(i, c.line),
        )?;
        if let Some(truth) = &self.truth {
            truth::validate(&dir.join(TRUTH_TOML), truth)?;
        }
        Ok(())
    }

    /// Writes the dataset into `dir` (created if missing): `dataset.toml` with every
    /// camera, board and robot value, `captures.csv`, `corners.csv` (a header only when
    /// there are no corners) and, when there is a truth, `truth.toml`.
    ///
    /// The dataset is validated first, so what is written can be read back: [`Dataset::load`]
    /// of the directory gives this dataset again, with the rows' `line` fields set to their
    /// lines and `dir` set to `dir`, every number bit for bit. One exception: angles stored
    /// in degrees (truth parameters, mount angles, camera tilt) are written as the degrees
    /// that read back to the very same radians, which exist for every angle that is the
    /// conversion of some float of degrees; any other angle reads back within an ulp or two.
    ///
    /// Each file is written atomically. Unless `force`, nothing is written when any of the
    /// files already exists, or when a `truth.toml` exists and this dataset has no truth;
    /// with `force`, such a stale `truth.toml` is removed. `images/` is not touched.
    pub fn write(&self, dir: &Path, force: bool) -> Result<(), DatasetError> {
        self.check(dir, true)?;
        let toml_path = dir.join(DATASET_TOML);
        let captures_path = dir.join(CAPTURES_CSV);
        let corners_path = dir.join(CORNERS_CSV);
        let truth_path = dir.join(TRUTH_TOML);
        let dataset_toml = config::render(&self.model, &self.angles).map_err(|e| {
            DatasetError::invalid(
                Location::file(&toml_path),
                format!("cannot be written as TOML: {e}"),
            )
        })?;
        let captures_csv = captures::render(&self.captures)
            .map_err(|e| DatasetError::io(&captures_path, "write", e.into()))?;
        let corners_csv = corners::render(&self.corners)
            .map_err(|e| DatasetError::io(&corners_path, "write", e.into()))?;
        let truth_toml = match &self.truth {
            Some(t) => Some(truth::render(t, self.has_upper_captures()).map_err(|e| {
                DatasetError::invalid(
                    Location::file(&truth_path).field("simulation"),
                    format!("cannot be written as TOML: {e}"),
                )
            })?),
            None => None,
        };

        write::create_dir(dir)?;
        check_writable(dir, truth_toml.is_some(), force)?;
        let stale_truth = truth_path.symlink_metadata().is_ok();

        let options = WriteOptions::new(force);
        write_atomic(&toml_path, dataset_toml.as_bytes(), &options)?;
        write_atomic(&captures_path, &captures_csv, &options)?;
        write_atomic(&corners_path, &corners_csv, &options)?;
        match truth_toml {
            Some(text) => write_atomic(&truth_path, text.as_bytes(), &options)?,
            None if stale_truth => std::fs::remove_file(&truth_path)
                .map_err(|e| DatasetError::io(&truth_path, "remove", e))?,
            None => {}
        }
        Ok(())
    }

    /// Whether any capture was taken with the upper camera.
    pub fn has_upper_captures(&self) -> bool {
        self.captures.iter().any(|c| c.camera == CameraId::Upper)
    }

    /// The capture with id `id`.
    pub fn capture(&self, id: u64) -> Option<&Capture> {
        self.captures.iter().find(|c| c.id == id)
    }

    /// The corners of every capture, by capture id, each list in file order. Every capture
    /// has an entry, an empty one when none of its vertices was found.
    pub fn corners_by_capture(&self) -> BTreeMap<u64, Vec<Corner>> {
        let mut map: BTreeMap<u64, Vec<Corner>> =
            self.captures.iter().map(|c| (c.id, Vec::new())).collect();
        for corner in &self.corners {
            map.entry(corner.capture).or_default().push(*corner);
        }
        map
    }

    /// The corners of capture `id`, in file order.
    pub fn corners_of(&self, id: u64) -> impl Iterator<Item = &Corner> + '_ {
        self.corners.iter().filter(move |c| c.capture == id)
    }

    /// The full path of a capture's image, if it has one.
    pub fn image_path(&self, capture: &Capture) -> Option<PathBuf> {
        capture.image.as_ref().map(|image| self.dir.join(image))
    }
}

/// Checks that [`Dataset::write`] into `dir` of a dataset with or without a truth would not
/// be refused for an existing file: with `force` always, else only when none of
/// `dataset.toml`, `captures.csv`, `corners.csv` and `truth.toml` exists. For writers that
/// put other files (images) into `dir` first and must not leave them behind a refusal.
pub fn check_writable(dir: &Path, with_truth: bool, force: bool) -> Result<(), DatasetError> {
    for name in [DATASET_TOML, CAPTURES_CSV, CORNERS_CSV] {
        write::check_absent(&dir.join(name), force)?;
    }
    let truth_path = dir.join(TRUTH_TOML);
    if with_truth {
        write::check_absent(&truth_path, force)?;
    } else if !force && truth_path.symlink_metadata().is_ok() {
        return Err(DatasetError::Exists {
            path: truth_path,
            reason: "exists, but the dataset being written has no truth",
        });
    }
    Ok(())
}

/// Reads a `truth.toml` file on its own (e.g. the true parameters to simulate with): the
/// same format and checks as a dataset's `truth.toml`, but the file must exist.
pub fn read_truth(path: &Path) -> Result<Truth, DatasetError> {
    let bytes = text::read_file(path, true, " (it needs a [parameters] table)")?;
    truth::parse(path, &bytes.unwrap_or_default())
}

/// Reads a captures table on its own (such as the stance schedule `naocalib plan` writes):
/// the format and checks of `captures.csv`, its `image` column optional.
pub fn read_captures(path: &Path) -> Result<Vec<Capture>, DatasetError> {
    let bytes = text::read_file(path, true, " (it needs at least its header line)")?;
    let captures = captures::parse(path, &bytes.unwrap_or_default())?;
    captures::validate(path, &captures, |_, c| c.line)?;
    Ok(captures)
}

/// Where the key path `field` (`board.mount_rpy_deg[0]`) is in the TOML file `path`: its
/// line when the file has the key, else just the file and the field (for the errors of a
/// later check of what the file holds).
pub fn locate(path: &Path, field: &str) -> Location {
    let bytes = std::fs::read(path).unwrap_or_default();
    match toml_doc::TomlDoc::new(path, &bytes) {
        Ok(doc) => doc.at(field),
        Err(_) => Location::file(path).field(field),
    }
}

/// Reads a `dataset.toml` on its own: the camera, board and robot it describes.
pub fn read_model(path: &Path) -> Result<Model, DatasetError> {
    let bytes = text::read_file(path, true, " (it needs at least a [camera] table)")?;
    config::parse(path, &bytes.unwrap_or_default())
}

/// The model of `path` when given, else [`Model::unconfigured`] (naocalib's sandal).
pub fn read_model_or_unconfigured(path: Option<&Path>) -> Result<Model, DatasetError> {
    path.map_or_else(|| Ok(Model::unconfigured()), read_model)
}

/// `dataset.toml` as `naocalib capture` writes it: `model` (validated; raw joint angles)
/// with the capture settings each camera was driven with in its table (`settings`, the
/// keys of [`crate::dataset::settings::SETTING_KEYS`]) and `notes` as comment lines
/// under the header. `path` names the file in errors.
pub fn render_captured(
    path: &Path,
    model: &Model,
    settings: &[(
        crate::model::CameraId,
        crate::dataset::settings::SettingsChanges,
    )],
    notes: &[String],
) -> Result<String, DatasetError> {
    config::validate(path, model)?;
    config::render_with_settings(model, &AngleSource::default(), settings, notes).map_err(|e| {
        DatasetError::invalid(
            Location::file(path),
            format!("cannot be written as TOML: {e}"),
        )
    })
}

/// Reads the capture settings of a `dataset.toml` (`[camera]` and `[upper_camera]`'s
/// `flip`, `exposure`, `gain`, `white_balance_k`, `fps`): per camera with a table, what it
/// changes of the team defaults capture starts from.
pub fn read_camera_settings(
    path: &Path,
) -> Result<
    Vec<(
        crate::model::CameraId,
        crate::dataset::settings::SettingsChanges,
    )>,
    DatasetError,
> {
    let bytes = text::read_file(path, true, " (it needs at least a [camera] table)")?;
    config::parse_settings(path, &bytes.unwrap_or_default())
}

/// Writes `contents` to the file `path` atomically (its directory must exist); refuses to
/// replace an existing file unless `force`.
pub fn write_file(path: &Path, contents: &[u8], force: bool) -> Result<(), DatasetError> {
    Ok(write_atomic(path, contents, &WriteOptions::new(force))?)
}

/// Writes `corners.csv` into `dir` (created if missing), atomically; refuses to replace an
/// existing file unless `force`. For detection, which adds corners to an existing dataset.
///
/// Checks what can be checked without the rest of the dataset (finite pixels, no vertex
/// twice in a capture); [`Dataset::load`] checks the corners against the captures and the
/// board.
pub fn write_corners(dir: &Path, corners: &[Corner], force: bool) -> Result<(), DatasetError> {
    let path = dir.join(CORNERS_CSV);
    corners::validate(&path, corners, None, None, |i, _| i as u64 + 2)?;
    let csv = corners::render(corners).map_err(|e| DatasetError::io(&path, "write", e.into()))?;
    write::create_dir(dir)?;
    Ok(write_atomic(&path, &csv, &WriteOptions::new(force))?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Joint;

    fn capture(id: u64, side: Side) -> Capture {
        let mut joints = JointAngles::default();
        joints.set(Joint::HeadYaw, id as f64 / 10.0);
        Capture {
            id,
            side,
            camera: CameraId::Lower,
            image: None,
            joints,
            line: 0,
        }
    }

    fn corner(capture: u64, row: u32, col: u32) -> Corner {
        Corner {
            capture,
            vertex: Vertex { row, col },
            pixel: [row as f64, col as f64],
            line: 0,
        }
    }

    fn sample(dir: &Path) -> Dataset {
        let mut ds = Dataset::new(dir, Model::default());
        ds.captures = vec![
            capture(5, Side::Left),
            capture(2, Side::Right),
            capture(9, Side::Left),
        ];
        ds.corners = vec![corner(2, 0, 0), corner(5, 1, 1), corner(2, 3, 5)];
        ds
    }

    #[test]
    fn lookups() {
        let ds = sample(Path::new("d"));
        assert_eq!(ds.capture(2).unwrap().side, Side::Right);
        assert!(ds.capture(3).is_none());
        let by = ds.corners_by_capture();
        assert_eq!(by.keys().copied().collect::<Vec<_>>(), [2, 5, 9]);
        assert_eq!(by[&2].len(), 2);
        assert!(by[&9].is_empty());
        assert_eq!(ds.corners_of(2).count(), 2);
        let mut c = capture(1, Side::Left);
        assert_eq!(ds.image_path(&c), None);
        c.image = Some("images/1.png".into());
        assert_eq!(ds.image_path(&c), Some(PathBuf::from("d/images/1.png")));
    }

    #[test]
    fn validate_uses_recorded_or_written_lines() {
        let mut ds = sample(Path::new("d"));
        assert!(ds.validate().is_ok());
        ds.corners.push(corner(7, 0, 0));
        let e = ds.validate().unwrap_err();
        assert_eq!(
            e.to_string(),
            "d/corners.csv line 5, field capture: capture 7 is not in captures.csv"
        );
        ds.corners[3].line = 12;
        let e = ds.validate().unwrap_err();
        assert_eq!(e.line(), Some(12));
        let e = ds
            .write(Path::new("/nonexistent/never"), false)
            .unwrap_err();
        assert_eq!(
            e.to_string(),
            "/nonexistent/never/corners.csv line 5, field capture: capture 7 is not in captures.csv"
        );
    }

    #[test]
    fn write_then_load() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("new/sub");
        let ds = sample(&dir);
        ds.write(&dir, false).unwrap();
        let back = Dataset::load(&dir).unwrap();
        assert_eq!(
            back.captures.iter().map(|c| c.line).collect::<Vec<_>>(),
            [2, 3, 4]
        );
        assert_eq!(
            back.corners.iter().map(|c| c.line).collect::<Vec<_>>(),
            [2, 3, 4]
        );
        assert_eq!(back.captures[1].id, 2);
        assert_eq!(back.truth, None);
        let e = ds.write(&dir, false).unwrap_err();
        assert!(matches!(e, DatasetError::Exists { .. }), "{e}");
        ds.write(&dir, true).unwrap();
    }

    #[test]
    fn stale_truth_is_refused_then_removed() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path();
        std::fs::write(dir.join(TRUTH_TOML), "[parameters]\n").unwrap();
        let ds = sample(dir);
        let e = ds.write(dir, false).unwrap_err();
        assert!(
            e.to_string().contains(
                "truth.toml: exists, but the dataset being written has no truth; use --force"
            ),
            "{e}"
        );
        assert!(!dir.join(DATASET_TOML).exists(), "nothing written");
        ds.write(dir, true).unwrap();
        assert!(!dir.join(TRUTH_TOML).exists());
        assert_eq!(Dataset::load(dir).unwrap().truth, None);
    }

    #[test]
    fn write_corners_alone() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("d");
        write_corners(&dir, &[corner(1, 0, 0), corner(1, 0, 1)], false).unwrap();
        let text = std::fs::read_to_string(dir.join(CORNERS_CSV)).unwrap();
        assert_eq!(text, "capture,row,col,u,v\n1,0,0,0,0\n1,0,1,0,1\n");
        let e = write_corners(&dir, &[], false).unwrap_err();
        assert!(matches!(
            e,
            DatasetError::Write(crate::output::WriteError::Exists { .. })
        ));
        write_corners(&dir, &[], true).unwrap();
        let e = write_corners(&dir, &[corner(1, 0, 0), corner(1, 0, 0)], true).unwrap_err();
        assert_eq!(e.line(), Some(3));
        let mut bad = corner(1, 0, 0);
        bad.pixel[1] = f64::NAN;
        let e = write_corners(&dir, &[bad], true).unwrap_err();
        assert_eq!(e.field(), Some("v"));
    }
}
