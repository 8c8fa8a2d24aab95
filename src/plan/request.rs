//! What `naocalib plan` is asked for, in the user's units: the options of [`plan`] made
//! of it (the cameras, the free parameters, the box of offsets around the robot's
//! calibration), the checks of the schedule file, and the run that writes it.

use std::path::PathBuf;
use std::time::Instant;

use crate::calibration::Calibration;
use crate::dataset::DatasetError;
use crate::export::ExportError;
use crate::model::{CameraId, Family, FixedSet, Model, Param};
use crate::output::{WriteError, WriteOptions};
use crate::solve::noise::NoiseLevels;

use super::{Plan, PlanError, PlanOptions, plan};

/// A stance schedule to design and write, as `naocalib plan` is asked for it.
#[derive(Debug, Clone, PartialEq)]
pub struct PlanRequest {
    /// The schedule (CSV) to write.
    pub out: PathBuf,
    /// Replace an existing `out`.
    pub force: bool,
    /// Number of captures, both legs together (144 when not given; with `budget_s`, as
    /// many as fit, at most this).
    pub captures: Option<usize>,
    /// The robot time the measurement phase may take (s): as many captures as fit.
    pub budget_s: Option<f64>,
    /// The families the calibration will free.
    pub families: Vec<Family>,
    /// Pixel noise σ the prediction assumes (px).
    pub px_noise: f64,
    /// Joint-angle noise σ per joint and capture the prediction assumes (deg).
    pub joint_noise_deg: f64,
    /// Seed of the random candidate pool.
    pub seed: u64,
    /// The robot's dataset.toml (the default model without it).
    pub camera: Option<PathBuf>,
    /// The box of offsets the board must stay in view for (deg, and mm for the sandals).
    pub offset_deg: f64,
    /// The cameras to plan for; those the model has when not given.
    pub cameras: Option<Vec<CameraId>>,
    /// The box of offsets for upper-camera captures (deg, and mm); not given:
    /// [`UPPER_OFFSET_DEG`], narrowed as far as [`NARROWEST_UPPER_OFFSET_DEG`] when no
    /// upper-camera capture of a leg stays in view over it.
    pub upper_offset_deg: Option<f64>,
    /// The σ aimed at for the upper camera's offsets, relative to the 15 angle offsets'.
    pub upper_sigma_ratio: f64,
    /// Leg stances drawn into each camera's pool per leg.
    pub pool: usize,
    /// The robot's current calibration, the centre of the box of offsets.
    pub around: Option<PathBuf>,
    /// Plan past the robot's own body ([`crate::plan::Feasibility::sight`]).
    pub sight: bool,
}

/// Why a plan could not be made or written.
#[derive(Debug, thiserror::Error)]
pub enum PlanRequestError {
    /// The schedule to write names a directory.
    #[error("{} is a directory; name the CSV file to write", .0.display())]
    OutIsDirectory(PathBuf),
    /// The schedule exists and `force` is not given.
    #[error("{} exists (use --force to replace it)", .0.display())]
    OutExists(PathBuf),
    /// The directory of the schedule does not exist.
    #[error("the directory {} does not exist", .0.display())]
    NoDirectory(PathBuf),
    /// The upper camera is asked for, but the model has no intrinsics for it.
    #[error(
        "--cameras names the upper camera, but {model} has no [upper_camera] table (its \
         intrinsics)"
    )]
    NoUpperCamera {
        /// The model's file, or "the default model".
        model: String,
    },
    /// The `around` calibration could not be read.
    #[error("--around {}", .path.display())]
    Around {
        /// The calibration file.
        path: PathBuf,
        /// Why.
        #[source]
        source: ExportError,
    },
    /// The schedule could not be written.
    #[error("writing the plan {}", .path.display())]
    Write {
        /// The schedule.
        path: PathBuf,
        /// Why.
        #[source]
        source: WriteError,
    },
    /// An output would replace an input, or exists.
    #[error(transparent)]
    Output(#[from] WriteError),
    /// The robot's dataset.toml could not be read.
    #[error(transparent)]
    Dataset(#[from] DatasetError),
    /// No plan could be made.
    #[error(transparent)]
    Plan(#[from] PlanError),
}

impl PlanRequest {
    /// How the schedule is written: never over the `camera` input, over an existing file
    /// only with `force`; refused here, before any planning, when it cannot be.
    pub fn check_out(&self) -> Result<WriteOptions, PlanRequestError> {
        if self.out.is_dir() {
            return Err(PlanRequestError::OutIsDirectory(self.out.clone()));
        }
        if !self.force && self.out.symlink_metadata().is_ok() {
            return Err(PlanRequestError::OutExists(self.out.clone()));
        }
        let options = WriteOptions::new(self.force).protecting(self.camera.clone());
        crate::output::check_outputs(&[&self.out], &[], &options)?;
        Ok(options)
    }

    /// The robot's model: `camera`'s, or [`Model::unconfigured`] (naocalib's sandal).
    pub fn model(&self) -> Result<Model, PlanRequestError> {
        Ok(crate::dataset::read_model_or_unconfigured(
            self.camera.as_deref(),
        )?)
    }

    /// The cameras to plan for: those asked for, else both when `model` has an upper
    /// camera, else the lower; an upper camera the model lacks is refused.
    pub fn cameras(&self, model: &Model) -> Result<Vec<CameraId>, PlanRequestError> {
        let cameras = match &self.cameras {
            Some(c) => c.clone(),
            None if model.upper_camera.is_some() => vec![CameraId::Lower, CameraId::Upper],
            None => vec![CameraId::Lower],
        };
        if cameras.contains(&CameraId::Upper) && model.upper_camera.is_none() {
            return Err(PlanRequestError::NoUpperCamera {
                model: self
                    .camera
                    .as_ref()
                    .map_or("the default model".to_string(), |p| p.display().to_string()),
            });
        }
        Ok(cameras)
    }

    /// The parameters held: all but those of `families`, and of the upper camera when it
    /// is planned for.
    pub fn fixed(&self, upper: bool) -> FixedSet {
        let mut fixed = FixedSet::with(&Param::ALL);
        let upper = upper.then_some(Family::UpperCamera);
        for family in self.families.iter().copied().chain(upper) {
            for p in family.params() {
                fixed.set(p, false);
            }
        }
        fixed
    }

    /// The options of [`plan`] for `model`, with the box of offsets centred on `around`
    /// (the robot's current calibration) when given.
    pub fn options(
        &self,
        model: &Model,
        around: Option<&Calibration>,
    ) -> Result<PlanOptions, PlanRequestError> {
        let cameras = self.cameras(model)?;
        let mut options = PlanOptions {
            captures: self.captures.unwrap_or(PlanOptions::default().captures),
            fixed: self.fixed(cameras.contains(&CameraId::Upper)),
            levels: NoiseLevels {
                px: self.px_noise,
                joint: self.joint_noise_deg.to_radians(),
            },
            seed: self.seed,
            cameras,
            pool_stances: self.pool,
            upper_pool_stances: self.pool,
            upper_sigma_ratio: self.upper_sigma_ratio,
            ..PlanOptions::default()
        };
        options.feasibility.offset_angle = self.offset_deg.to_radians();
        options.feasibility.offset_length = self.offset_deg;
        options.feasibility.upper_offset = self
            .upper_offset_deg
            .unwrap_or(UPPER_OFFSET_DEG)
            .to_radians();
        options.feasibility.sight = self.sight.then(crate::body::BodyModel::default);
        if let Some(current) = around {
            for (p, value) in current.start_values(model) {
                options.feasibility.centre[p.index()] = p.unit().from_report(value);
            }
        }
        Ok(options)
    }

    /// The `around` calibration, if given.
    pub fn read_around(&self) -> Result<Option<Calibration>, PlanRequestError> {
        self.around
            .as_ref()
            .map(|path| {
                crate::export::read_start_from(path).map_err(|source| PlanRequestError::Around {
                    path: path.clone(),
                    source,
                })
            })
            .transpose()
    }
}

/// The upper camera's box of offsets when none is asked for (deg): lying on its back the
/// NAO sees a sandal through its upper camera only from 220–390 mm, where the board spans
/// most of the image; the robot's imported calibration knows its offsets far better.
pub const UPPER_OFFSET_DEG: f64 = 0.5;

/// How far the box of [`UPPER_OFFSET_DEG`] is halved when no upper-camera capture of a leg
/// stays in view over it (a robot whose upper camera looks past a sandal at the edge of
/// SPQR's per-robot files, pitch −10.2°): capture and detection check every picture again.
pub const NARROWEST_UPPER_OFFSET_DEG: f64 = 0.125;

/// `make(options)`, and when it finds no upper-camera capture of a leg that stays in view
/// for every offset in the upper camera's box of offsets (`box_deg`, as `options` have it),
/// `make` again with the box halved, down to [`NARROWEST_UPPER_OFFSET_DEG`]: what was
/// made, the options it was made with and the box it was narrowed to (deg; `None` when not
/// narrowed).
pub fn narrowing_the_upper_box<T>(
    mut options: PlanOptions,
    box_deg: f64,
    make: impl Fn(&PlanOptions) -> Result<T, PlanError>,
) -> Result<(T, PlanOptions, Option<f64>), PlanError> {
    let mut narrowed: Option<f64> = None;
    loop {
        match make(&options) {
            Err(PlanError::Pool {
                camera: "upper", ..
            }) if narrowed.unwrap_or(f64::INFINITY) > NARROWEST_UPPER_OFFSET_DEG => {
                let half = narrowed.unwrap_or(box_deg) * 0.5;
                options.feasibility.upper_offset = half.to_radians();
                narrowed = Some(half);
            }
            made => return made.map(|made| (made, options, narrowed)),
        }
    }
}

/// A plan made and written.
#[derive(Debug, Clone)]
pub struct Planned {
    /// The plan.
    pub plan: Plan,
    /// The options it was made with.
    pub options: PlanOptions,
    /// The planning's wall time (s).
    pub seconds: f64,
    /// The upper camera's box of offsets when it was narrowed from [`UPPER_OFFSET_DEG`]
    /// (deg): none of a leg's captures stayed in view over the wider ones.
    pub narrowed: Option<f64>,
}

/// Designs the schedule of `request` and writes it: every check of the output and the
/// inputs first, then the plan, then the file.
pub fn run(request: &PlanRequest) -> Result<Planned, PlanRequestError> {
    let write_options = request.check_out()?;
    let model = request.model()?;
    // The cameras checked before the calibration is read.
    request.cameras(&model)?;
    let around = request.read_around()?;
    let options = request.options(&model, around.as_ref())?;
    let start = Instant::now();
    let make = |options: &PlanOptions| match request.budget_s {
        Some(budget) => super::plan_within(&model, options, budget, request.captures),
        None => plan(&model, options),
    };
    let (plan, options, narrowed) = if request.upper_offset_deg.is_none() {
        narrowing_the_upper_box(options, UPPER_OFFSET_DEG, make)?
    } else {
        (make(&options)?, options, None)
    };
    let seconds = start.elapsed().as_secs_f64();
    if let Some(dir) = request.out.parent().filter(|d| !d.as_os_str().is_empty())
        && !dir.is_dir()
    {
        return Err(PlanRequestError::NoDirectory(dir.to_path_buf()));
    }
    crate::output::write_atomic(
        &request.out,
        &super::render_csv(&plan.captures),
        &write_options,
    )
    .map_err(|source| PlanRequestError::Write {
        path: request.out.clone(),
        source,
    })?;
    Ok(Planned {
        plan,
        options,
        seconds,
        narrowed,
    })
}

/// Parses a comma-separated list of families (each once, at least one).
pub fn parse_families(text: &str) -> Result<Vec<Family>, String> {
    let mut out = Vec::new();
    for name in text.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let family = Family::from_name(name).ok_or_else(|| {
            format!(
                "unknown family '{name}' (families: {})",
                Family::names(Family::ALL)
            )
        })?;
        if !out.contains(&family) {
            out.push(family);
        }
    }
    if out.is_empty() {
        return Err("name at least one family".into());
    }
    Ok(out)
}

/// Parses a comma-separated list of cameras, `lower` and `upper` (each once, at least
/// one).
pub fn parse_cameras(text: &str) -> Result<Vec<CameraId>, String> {
    let mut out = Vec::new();
    for name in text.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let camera = CameraId::from_name(name)
            .ok_or_else(|| format!("unknown camera '{name}' (cameras: lower, upper)"))?;
        if !out.contains(&camera) {
            out.push(camera);
        }
    }
    if out.is_empty() {
        return Err("name at least one camera".into());
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn request() -> PlanRequest {
        PlanRequest {
            out: PathBuf::from("plan.csv"),
            force: false,
            captures: Some(24),
            budget_s: None,
            families: vec![Family::Paper],
            px_noise: 0.2,
            joint_noise_deg: 0.5,
            seed: 7,
            camera: None,
            offset_deg: 2.0,
            cameras: None,
            upper_offset_deg: None,
            upper_sigma_ratio: 0.9,
            pool: 40,
            around: None,
            sight: false,
        }
    }

    #[test]
    fn the_cameras_default_to_those_of_the_model() {
        let mut model = Model::default();
        assert_eq!(request().cameras(&model).unwrap(), vec![CameraId::Lower]);
        model.upper_camera = Some(model.camera);
        assert_eq!(
            request().cameras(&model).unwrap(),
            vec![CameraId::Lower, CameraId::Upper]
        );
        let lower = PlanRequest {
            cameras: Some(vec![CameraId::Lower]),
            ..request()
        };
        assert_eq!(lower.cameras(&model).unwrap(), vec![CameraId::Lower]);
    }

    #[test]
    fn an_upper_camera_the_model_lacks_is_refused() {
        let upper = PlanRequest {
            cameras: Some(vec![CameraId::Upper]),
            ..request()
        };
        let e = upper.cameras(&Model::default()).unwrap_err();
        assert_eq!(
            e.to_string(),
            "--cameras names the upper camera, but the default model has no [upper_camera] \
             table (its intrinsics)"
        );
    }

    #[test]
    fn the_families_and_the_planned_upper_camera_are_freed() {
        let paper = request().fixed(false);
        assert!(!paper.is_fixed(Param::CamPitch));
        assert!(paper.is_fixed(Param::HeadYaw));
        assert!(paper.is_fixed(Param::UpperCamPitch));
        assert!(!request().fixed(true).is_fixed(Param::UpperCamPitch));
        let head = PlanRequest {
            families: vec![Family::Paper, Family::Head],
            ..request()
        };
        assert!(!head.fixed(false).is_fixed(Param::HeadYaw));
    }

    #[test]
    fn the_options_are_in_internal_units() {
        let options = request().options(&Model::default(), None).unwrap();
        assert_eq!(options.captures, 24);
        assert_eq!(options.seed, 7);
        assert_eq!(options.levels.px, 0.2);
        assert_eq!(options.levels.joint, 0.5f64.to_radians());
        assert_eq!(options.feasibility.offset_angle, 2.0f64.to_radians());
        assert_eq!(options.feasibility.offset_length, 2.0);
        assert_eq!(options.feasibility.upper_offset, 0.5f64.to_radians());
        assert_eq!((options.pool_stances, options.upper_pool_stances), (40, 40));
        assert!(options.feasibility.centre.iter().all(|c| *c == 0.0));
    }

    #[test]
    fn the_schedule_is_not_written_over_a_directory_or_an_existing_file() {
        let dir = tempfile::tempdir().unwrap();
        let at_dir = PlanRequest {
            out: dir.path().to_path_buf(),
            ..request()
        };
        assert!(matches!(
            at_dir.check_out(),
            Err(PlanRequestError::OutIsDirectory(_))
        ));
        let file = dir.path().join("plan.csv");
        std::fs::write(&file, "kept").unwrap();
        let existing = PlanRequest {
            out: file.clone(),
            ..request()
        };
        assert!(matches!(
            existing.check_out(),
            Err(PlanRequestError::OutExists(_))
        ));
        let forced = PlanRequest {
            force: true,
            ..existing
        };
        assert!(forced.check_out().unwrap().force);
        let over_input = PlanRequest {
            camera: Some(file.clone()),
            ..forced
        };
        assert!(matches!(
            over_input.check_out(),
            Err(PlanRequestError::Output(_))
        ));
    }

    #[test]
    fn lists_are_parsed_each_name_once() {
        assert_eq!(
            parse_families("paper, head,paper").unwrap(),
            vec![Family::Paper, Family::Head]
        );
        assert!(
            parse_families("nope")
                .unwrap_err()
                .contains("unknown family 'nope'")
        );
        assert_eq!(
            parse_families(" , ").unwrap_err(),
            "name at least one family"
        );
        assert_eq!(
            parse_cameras("upper,lower,upper").unwrap(),
            vec![CameraId::Upper, CameraId::Lower]
        );
        assert_eq!(
            parse_cameras("middle").unwrap_err(),
            "unknown camera 'middle' (cameras: lower, upper)"
        );
        assert_eq!(parse_cameras("").unwrap_err(), "name at least one camera");
    }
}
