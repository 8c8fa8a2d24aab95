//! Where a run starts: the plan read and checked against the robot, the robot's model (its
//! `dataset.toml`, or the one of the dataset a run left, with `--resume`) and the dataset
//! to write — all before anything is written or moved.

use std::path::{Path, PathBuf};

use crate::dataset::{self, DatasetError};
use crate::model::{CameraId, Model};
use crate::robot::camera::settings::{UsedSettings, table_name};

use super::plan::{PlanRow, check_cameras, check_plan, read_plan};
use super::writer::DatasetOut;
use super::{CaptureError, SettingsMismatch};

/// A run ready to start: the plan, the robot, and the dataset it goes into.
#[derive(Debug)]
pub struct Start {
    /// The plan's rows, in order.
    pub rows: Vec<PlanRow>,
    /// The robot: the `dataset.toml` given, or the resumed dataset's.
    pub model: Model,
    /// The dataset's directory.
    dir: PathBuf,
    /// The plan file's bytes (its copy in a new dataset).
    plan: Vec<u8>,
    /// The dataset resumed; `None` for a new one, created by [`Start::open`].
    resumed: Option<DatasetOut>,
}

impl Start {
    /// Reads the plan at `plan` and checks it before anything is written or moved. With
    /// `resume`, the dataset a run left in `dir` goes on ([`DatasetOut::resume`]: the same
    /// plan; `config`, if given, must describe the same robot); without, `config` (the
    /// robot's `dataset.toml`) is needed and `dir` must hold no dataset. Every row must be
    /// safe ([`check_plan`] with `margin`) and its camera among `cameras`.
    pub fn new(
        plan: &Path,
        dir: &Path,
        config: Option<&Path>,
        resume: bool,
        cameras: &[CameraId],
        margin: f64,
    ) -> Result<Start, CaptureError> {
        let rows = read_plan(plan)?;
        let config_model = config.map(dataset::read_model).transpose()?;
        let (resumed, model) = if resume {
            let (out, model) = DatasetOut::resume(dir, plan, &rows)?;
            if let Some(config) = config
                && config_model.is_some_and(|m| m != model)
            {
                return Err(CaptureError::OtherRobot {
                    config: config.to_path_buf(),
                    dir: dir.to_path_buf(),
                });
            }
            (Some(out), model)
        } else {
            let model = config_model.ok_or(CaptureError::NoConfig)?;
            DatasetOut::check_new(dir)?;
            (None, model)
        };
        check_plan(plan, &model, &rows, margin)?;
        let bytes = std::fs::read(plan).map_err(|e| DatasetError::io(plan, "read", e))?;
        check_cameras(plan, &rows, cameras)?;
        Ok(Start {
            rows,
            model,
            dir: dir.to_path_buf(),
            plan: bytes,
            resumed,
        })
    }

    /// The captures of the dataset resumed that are taken again, with the reason (their
    /// picture is missing or unreadable); none for a new dataset.
    pub fn retake(&self) -> &[(u64, String)] {
        self.resumed.as_ref().map_or(&[], DatasetOut::retake)
    }

    /// Checks, with `--resume`, that each camera is driven with the settings the dataset
    /// records for it (`used`, [`UsedSettings::check_same`]): the pictures of one dataset
    /// are taken alike. Nothing to check for a new dataset.
    pub fn check_settings(&self, used: &[UsedSettings]) -> Result<(), CaptureError> {
        if self.resumed.is_none() {
            return Ok(());
        }
        let path = self.dir.join(dataset::DATASET_TOML);
        let recorded = dataset::read_camera_settings(&path)?;
        for u in used {
            let Some((_, then)) = recorded.iter().find(|(c, _)| *c == u.camera) else {
                continue;
            };
            if let Err((control, then, now)) = u.check_same(then) {
                return Err(CaptureError::OtherSettings(Box::new(SettingsMismatch {
                    at: dataset::locate(&path, &format!("{}.{control}", table_name(u.camera))),
                    camera: u.camera,
                    control,
                    then,
                    now,
                })));
            }
        }
        Ok(())
    }

    /// The dataset to write: the one resumed, or a new one created now (`dataset.toml`
    /// with the settings each camera is driven with, `used`; the plan's copy; an empty
    /// `captures.csv`).
    pub fn open(&mut self, used: &[UsedSettings]) -> Result<DatasetOut, CaptureError> {
        match self.resumed.take() {
            Some(out) => Ok(out),
            None => DatasetOut::create(&self.dir, &self.model, &self.plan, used),
        }
    }
}
