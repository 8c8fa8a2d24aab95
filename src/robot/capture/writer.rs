//! The dataset writer: `dataset.toml` and a copy of the plan once, then each capture's
//! picture and the whole `captures.csv` rewritten atomically after every capture, so that
//! the directory is a valid dataset at every moment; and the dataset a run left, opened
//! again to go on with the same plan (`--resume`).

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use crate::dataset::{self, Dataset, DatasetError, Location};
use crate::model::{CameraId, Joint, JointAngles, Model, Side};
use crate::output::{WriteError, WriteOptions, write_atomic};
use crate::robot::camera::settings::UsedSettings;
use crate::robot::camera::{Picture, check_picture};

use super::CaptureError;
use super::plan::{PlanRow, read_plan};

/// The dataset being written: `dataset.toml` and the plan (`plan.csv`, what `--resume`
/// checks against) once, then each capture's image and the whole `captures.csv` rewritten
/// atomically after every capture.
#[derive(Debug)]
pub struct DatasetOut {
    dir: PathBuf,
    rows: Vec<String>,
    done: BTreeSet<u64>,
    retake: Vec<(u64, String)>,
}

/// The copy of the plan a run keeps in its output directory.
pub const PLAN_CSV: &str = "plan.csv";

/// How far (rad) a capture's logged angles may be from its plan row for `--resume` to
/// accept the plan when the output keeps no copy of it: the readings of a settled stance lie
/// within a degree of the command (sag under the load, encoder steps); another plan's rows
/// differ by far more.
pub const RESUME_TOLERANCE: f64 = 0.035;

/// The header of the `captures.csv` that capture writes: the dataset's columns (with
/// `camera`), then the quality columns `spread_deg` (largest standard deviation of a joint's
/// readings around the picture) and `frames` (readings averaged).
pub fn captures_header() -> String {
    captures_header_with(true)
}

/// [`captures_header`], with the `camera` column or (as capture wrote lower-camera datasets
/// before it had one) without.
fn captures_header_with(camera: bool) -> String {
    let mut out = String::from("capture,board,image");
    if camera {
        out.push_str(",camera");
    }
    for name in Joint::ALL.map(Joint::name) {
        out.push(',');
        out.push_str(name);
    }
    out.push_str(",spread_deg,frames");
    out
}

impl DatasetOut {
    /// Refuses an output directory that holds a dataset's file (or a plan's copy).
    pub fn check_new(dir: &Path) -> Result<(), CaptureError> {
        for name in [
            dataset::DATASET_TOML,
            dataset::CAPTURES_CSV,
            dataset::CORNERS_CSV,
            dataset::TRUTH_TOML,
            PLAN_CSV,
        ] {
            let path = dir.join(name);
            if path.symlink_metadata().is_ok() {
                return Err(CaptureError::Exists(path));
            }
        }
        dataset::check_writable(dir, false, false)?;
        Ok(())
    }

    /// Starts a new dataset in `dir` for `model` (joint angles raw LoLA readings) with a
    /// copy of the plan (`plan`, the file's bytes) and, in `dataset.toml`, the settings
    /// each camera was driven with (`used`: its table's `flip`, `exposure`, … and a comment
    /// saying how they were applied); refuses a directory that already holds dataset
    /// files.
    pub fn create(
        dir: &Path,
        model: &Model,
        plan: &[u8],
        used: &[UsedSettings],
    ) -> Result<DatasetOut, CaptureError> {
        DatasetOut::check_new(dir)?;
        let path = dir.join(dataset::DATASET_TOML);
        let settings: Vec<_> = used.iter().map(|u| (u.camera, u.values)).collect();
        let notes: Vec<String> = used.iter().map(UsedSettings::note).collect();
        let toml = dataset::render_captured(&path, model, &settings, &notes)?;
        std::fs::create_dir_all(dir).map_err(|e| DatasetError::io(dir, "create", e))?;
        write_atomic(&path, toml.as_bytes(), &WriteOptions::new(false))?;
        write_atomic(&dir.join(PLAN_CSV), plan, &WriteOptions::new(false))?;
        let out = DatasetOut {
            dir: dir.to_path_buf(),
            rows: Vec::new(),
            done: BTreeSet::new(),
            retake: Vec::new(),
        };
        out.write_captures(false)?;
        Ok(out)
    }

    /// Opens the dataset a run left in `dir` to go on with the plan `rows` (read from
    /// `plan`); returns it with its model. Refuses a dataset that capture did not write
    /// (another `captures.csv` header) and one that another plan began: its `plan.csv`
    /// differs from `rows`, or (without a `plan.csv`) a capture is not a row of `rows`, is
    /// of the other board, or lies farther than [`RESUME_TOLERANCE`] from its row. A
    /// capture whose picture is missing, does not decode or does not have the camera's size
    /// is dropped, to be taken again ([`DatasetOut::retake`]).
    pub fn resume(
        dir: &Path,
        plan: &Path,
        rows: &[PlanRow],
    ) -> Result<(DatasetOut, Model), CaptureError> {
        let ds = Dataset::load_without_corners(dir)?;
        let path = dir.join(dataset::CAPTURES_CSV);
        let text =
            std::fs::read_to_string(&path).map_err(|e| DatasetError::io(&path, "read", e))?;
        let mut lines = text.lines();
        let header = lines.next().map(str::trim);
        let with_camera = header == Some(captures_header().as_str());
        if !with_camera && header != Some(captures_header_with(false).as_str()) {
            return Err(CaptureError::Dataset(DatasetError::invalid(
                Location::line(&path, 1),
                "is not a captures.csv that naocalib capture wrote (its header differs); \
                 --resume goes on only with a run of capture",
            )));
        }
        check_same_plan(dir, &ds, plan, rows)?;
        // The captures whose pictures are fine; the others are taken again.
        let mut retake = Vec::new();
        let mut done = BTreeSet::new();
        for c in &ds.captures {
            let problem = match ds.image_path(c) {
                None => Some("its row names no picture".to_string()),
                Some(image) => match std::fs::read(&image) {
                    Err(e) => Some(format!("{}: {e}", image.display())),
                    Ok(bytes) => {
                        let size = ds.model.intrinsics(c.camera);
                        check_picture(&bytes, size.width, size.height)
                            .err()
                            .map(|m| format!("{} {m}", image.display()))
                    }
                },
            };
            match problem {
                Some(p) => retake.push((c.id, p)),
                None => {
                    done.insert(c.id);
                }
            }
        }
        let kept: Vec<String> = lines
            .filter(|l| !l.trim().is_empty())
            .filter(|l| {
                l.split(',')
                    .next()
                    .and_then(|id| id.trim().parse::<u64>().ok())
                    .is_some_and(|id| done.contains(&id))
            })
            .map(|l| {
                if with_camera {
                    l.to_string()
                } else {
                    // A row of a dataset without the column: capture,board,image,…
                    let mut fields: Vec<&str> = l.split(',').collect();
                    fields.insert(3.min(fields.len()), CameraId::Lower.name());
                    fields.join(",")
                }
            })
            .collect();
        let out = DatasetOut {
            dir: dir.to_path_buf(),
            rows: kept,
            done,
            retake,
        };
        if !out.retake.is_empty() || !with_camera {
            out.write_captures(true)?;
        }
        Ok((out, ds.model))
    }

    /// The captures of the dataset resumed that are taken again, with the reason (their
    /// picture is missing or unreadable).
    pub fn retake(&self) -> &[(u64, String)] {
        &self.retake
    }

    /// Whether capture `id` was taken.
    pub fn has(&self, id: u64) -> bool {
        self.done.contains(&id)
    }

    /// The rows of `rows` not yet taken, in order.
    pub fn todo(&self, rows: &[PlanRow]) -> Vec<PlanRow> {
        rows.iter().filter(|r| !self.has(r.id)).copied().collect()
    }

    /// The ids of the captures taken.
    pub fn ids(&self) -> impl Iterator<Item = u64> + '_ {
        self.done.iter().copied()
    }

    /// Captures taken.
    pub fn len(&self) -> usize {
        self.done.len()
    }

    /// Whether no capture was taken.
    pub fn is_empty(&self) -> bool {
        self.done.is_empty()
    }

    fn write_captures(&self, force: bool) -> Result<(), WriteError> {
        let mut text = captures_header();
        text.push('\n');
        for row in &self.rows {
            text.push_str(row);
            text.push('\n');
        }
        write_atomic(
            &self.dir.join(dataset::CAPTURES_CSV),
            text.as_bytes(),
            &WriteOptions::new(force),
        )
    }

    /// Writes capture `taken`: its picture, then `captures.csv` with its row added.
    pub fn add(&mut self, taken: &Taken, picture: &Picture) -> Result<(), CaptureError> {
        let Taken {
            id,
            side,
            camera,
            joints,
            spread,
            frames,
        } = taken;
        let image = format!("images/{id:04}.{}", picture.extension);
        // An image without its row is what an interrupted write leaves: replace it.
        write_atomic(
            &self.dir.join(&image),
            &picture.bytes,
            &WriteOptions::new(true),
        )?;
        let mut row = format!("{id},{},{image},{}", side.name(), camera.name());
        for (_, q) in joints.iter() {
            row.push_str(&format!(",{q}"));
        }
        row.push_str(&format!(",{:.5},{frames}", spread.to_degrees()));
        self.rows.push(row);
        self.done.insert(*id);
        self.write_captures(true)?;
        Ok(())
    }
}

/// What a capture logs besides its picture: one row of the `captures.csv` that capture
/// writes ([`captures_header`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Taken {
    /// The capture id (the plan's).
    pub id: u64,
    /// The leg whose board is in view.
    pub side: Side,
    /// The camera that took the picture.
    pub camera: CameraId,
    /// The mean of the readings around the picture (rad).
    pub joints: JointAngles,
    /// The largest standard deviation of a joint's readings (rad).
    pub spread: f64,
    /// Readings averaged.
    pub frames: u32,
}

/// Refuses to resume the dataset `ds` in `dir` with another plan than the one it began
/// with (see [`DatasetOut::resume`]).
fn check_same_plan(
    dir: &Path,
    ds: &Dataset,
    plan: &Path,
    rows: &[PlanRow],
) -> Result<(), CaptureError> {
    let kept = dir.join(PLAN_CSV);
    let differs = |message: String| {
        CaptureError::Dataset(DatasetError::invalid(
            Location::file(plan),
            format!("{message}; --resume needs the plan the run began with"),
        ))
    };
    if kept.symlink_metadata().is_ok() {
        let before = read_plan(&kept)?;
        let same_row = |a: &PlanRow, b: &PlanRow| {
            a.id == b.id
                && a.side == b.side
                && a.camera == b.camera
                && (a.joints - b.joints).iter().all(|(_, d)| d.abs() <= 1e-9)
        };
        if before.len() != rows.len() {
            return Err(differs(format!(
                "has {} rows, the plan {} began with {}",
                rows.len(),
                dir.display(),
                before.len()
            )));
        }
        if let Some((a, b)) = before.iter().zip(rows).find(|(a, b)| !same_row(a, b)) {
            return Err(differs(format!(
                "line {} (capture {}) differs from {} line {} (capture {})",
                b.line,
                b.id,
                kept.display(),
                a.line,
                a.id
            )));
        }
        return Ok(());
    }
    for c in &ds.captures {
        let Some(row) = rows.iter().find(|r| r.id == c.id) else {
            return Err(differs(format!(
                "has no capture {} (in {})",
                c.id,
                dir.display()
            )));
        };
        if row.side != c.side || row.camera != c.camera {
            return Err(differs(format!(
                "line {}: capture {} is of the {} board by the {} camera, in {} of the {} \
                 by the {}",
                row.line,
                c.id,
                row.side.name(),
                row.camera.name(),
                dir.display(),
                c.side.name(),
                c.camera.name()
            )));
        }
        if let Some((j, _)) = (row.joints - c.joints)
            .iter()
            .find(|(_, d)| d.abs() > RESUME_TOLERANCE)
        {
            return Err(differs(format!(
                "line {}: capture {}'s {} is {:.2}°, in {} {:.2}°",
                row.line,
                c.id,
                j.name(),
                row.joints.get(j).to_degrees(),
                dir.display(),
                c.joints.get(j).to_degrees()
            )));
        }
    }
    Ok(())
}
