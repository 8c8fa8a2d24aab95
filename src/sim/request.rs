//! What `naocalib simulate` is asked for, in the user's units: its checks, the model and
//! [`SimOptions`] made of it, and the run that writes the simulated dataset.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use crate::dataset::{Dataset, DatasetError};
use crate::model::{CameraId, Family, Model, PARAMETER_COUNT};
use crate::output::{Staged, WriteError, WriteOptions};

use super::camera::CameraPreset;
use super::render::{ImageOutput, RenderOptions};
use super::{SimError, SimOptions, Stance, simulate};

/// The most captures a simulated dataset may have.
pub const MAX_CAPTURES: usize = 100_000;

/// A dataset to simulate and write, as `naocalib simulate` is asked for it.
#[derive(Debug, Clone, PartialEq)]
pub struct SimRequest {
    /// The dataset directory to write.
    pub out: PathBuf,
    /// Replace the files of an existing dataset in `out`.
    pub force: bool,
    /// Seed of the random generator.
    pub seed: u64,
    /// Stances per leg (lower camera).
    pub stances: usize,
    /// Head postures per stance.
    pub heads: usize,
    /// Stances per leg photographed with the upper camera.
    pub upper_stances: usize,
    /// Draw the true offsets as the teams' robot files show them.
    pub team_offsets: bool,
    /// Pixel noise σ per coordinate (px).
    pub px_noise: f64,
    /// Joint-angle noise σ per joint and capture (deg).
    pub joint_noise_deg: f64,
    /// A truth.toml whose parameters are the true ones (drawn without it).
    pub truth: Option<PathBuf>,
    /// Families beyond the paper's whose effects the drawn robot has.
    pub effects: Vec<Family>,
    /// Render one image per capture (corners.csv is then left empty).
    pub images: bool,
    /// Image blur σ (px).
    pub blur: f64,
    /// Image grey-level noise σ.
    pub grey_noise: f64,
    /// Image vignetting.
    pub vignetting: f64,
    /// The robot's own body in front of the boards: the vertices it hides give no corner,
    /// and images draw it.
    pub body: bool,
    /// The simulated lower camera (and the upper one, the same model).
    pub camera: CameraPreset,
    /// A plan whose stances are photographed instead of random ones.
    pub stance_file: Option<PathBuf>,
    /// Let boards come near and across the image border.
    pub near_border: bool,
    /// Lens distortion k1, k2, p1, p2, k3 of the simulated cameras.
    pub distortion: Option<Vec<f64>>,
    /// A dataset.toml whose `[board]` the sandals are (without it naocalib's,
    /// [`crate::model::Board::turned`]; the paper's when the file has no `[board]`).
    pub board: Option<PathBuf>,
}

/// Why a dataset could not be simulated or written.
#[derive(Debug, thiserror::Error)]
pub enum SimRequestError {
    /// A count, noise level or coefficient is out of range.
    #[error("{0}")]
    Bounds(String),
    /// The truth.toml given is the one the dataset would write.
    #[error(
        "--truth {} is the truth.toml this would write; copy it out of {} first",
        .truth.display(),
        .out.display()
    )]
    TruthIsOutput {
        /// The truth.toml given.
        truth: PathBuf,
        /// The dataset directory.
        out: PathBuf,
    },
    /// The plan has no captures.
    #[error("{}: the plan has no captures", .0.display())]
    EmptyPlan(PathBuf),
    /// An input could not be read, or the dataset not written.
    #[error(transparent)]
    Dataset(#[from] DatasetError),
    /// An output would replace an input, or exists.
    #[error(transparent)]
    Output(#[from] WriteError),
    /// The simulation failed.
    #[error(transparent)]
    Sim(#[from] SimError),
}

/// A dataset simulated and written.
#[derive(Debug, Clone)]
pub struct Simulated {
    /// The dataset (its directory the one written).
    pub dataset: Dataset,
    /// Vertices of planned stances left out because the true offsets put them outside the
    /// image.
    pub outside: usize,
}

impl SimRequest {
    /// Checks the counts and noise levels before anything is simulated or written.
    pub fn check_bounds(&self) -> Result<(), SimRequestError> {
        let bail = |m: String| Err(SimRequestError::Bounds(m));
        if self.stances == 0 || self.heads == 0 {
            return bail(format!(
                "--stances and --heads must be at least 1 (got {} and {})",
                self.stances, self.heads
            ));
        }
        let captures = self
            .stances
            .checked_add(self.upper_stances)
            .and_then(|n| n.checked_mul(self.heads))
            .and_then(|n| n.checked_mul(2));
        if captures.is_none_or(|n| n > MAX_CAPTURES) {
            let count = captures.map_or("more than 2⁶⁴".to_string(), |n| n.to_string());
            return bail(format!(
                "--stances {} --upper-stances {} --heads {} would make 2 × ({} + {}) × {} = \
                 {count} captures; at most {MAX_CAPTURES} are allowed",
                self.stances,
                self.upper_stances,
                self.heads,
                self.stances,
                self.upper_stances,
                self.heads
            ));
        }
        let within = |flag: &str, x: f64, hi: f64, unit: &str| {
            if x.is_finite() && (0.0..=hi).contains(&x) {
                Ok(())
            } else {
                bail(format!("{flag} must be 0 … {hi} {unit}, got {x}"))
            }
        };
        within("--px-noise", self.px_noise, 100.0, "px")?;
        within("--joint-noise-deg", self.joint_noise_deg, 10.0, "°")?;
        if let Some(d) = &self.distortion
            && let Some(k) = d.iter().find(|k| !(k.is_finite() && k.abs() <= 100.0))
        {
            return bail(format!(
                "--distortion coefficients must be finite and within ±100, got {k}"
            ));
        }
        Ok(())
    }

    /// The true parameters of `truth`, refused when it is the truth.toml this would write
    /// (with `force` it would be replaced: never an input).
    pub fn read_truth(&self) -> Result<Option<[f64; PARAMETER_COUNT]>, SimRequestError> {
        let Some(path) = &self.truth else {
            return Ok(None);
        };
        let written = self.out.join(crate::dataset::TRUTH_TOML);
        if let (Ok(a), Ok(b)) = (path.canonicalize(), written.canonicalize())
            && a == b
        {
            return Err(SimRequestError::TruthIsOutput {
                truth: path.clone(),
                out: self.out.clone(),
            });
        }
        Ok(Some(crate::dataset::read_truth(path)?.values))
    }

    /// The stances of `stance_file` and the camera of each (its `camera` column; lower
    /// when absent), if given.
    pub fn read_schedule(&self) -> Result<(Option<Vec<Stance>>, Vec<CameraId>), SimRequestError> {
        let Some(path) = &self.stance_file else {
            return Ok((None, Vec::new()));
        };
        // A plan has the columns of captures.csv without `image` (`plan::render_csv`).
        let plan = crate::dataset::read_captures(path)?;
        if plan.is_empty() {
            return Err(SimRequestError::EmptyPlan(path.clone()));
        }
        let (stances, cameras) =
            super::schedule(plan.into_iter().map(|c| (c.camera, c.side, c.joints)));
        Ok((Some(stances), cameras))
    }

    /// The simulated robot's model: the camera preset with the distortion, and the same
    /// camera as the upper one when `upper` (the V6's two cameras are the same model).
    pub fn model(&self, upper: bool) -> Result<Model, SimRequestError> {
        let mut model = Model {
            camera: self.camera.camera(),
            ..Model::unconfigured()
        };
        if let Some(path) = &self.board {
            model.board = crate::dataset::read_model(path)?.board;
        }
        if let Some(d) = &self.distortion {
            if d.len() != 5 {
                return Err(SimRequestError::Bounds(
                    "--distortion takes five numbers: k1,k2,p1,p2,k3".into(),
                ));
            }
            model.camera.distortion = std::array::from_fn(|i| d[i]);
        }
        if upper {
            model.upper_camera = Some(model.camera);
        }
        Ok(model)
    }

    /// The simulator's options, the images (if any) rendered into `dir`.
    pub fn options(
        &self,
        truth: Option<[f64; PARAMETER_COUNT]>,
        schedule: (Option<Vec<Stance>>, Vec<CameraId>),
        dir: &Path,
    ) -> SimOptions {
        let (schedule, schedule_cameras) = schedule;
        SimOptions {
            seed: self.seed,
            stances: self.stances,
            heads: self.heads,
            px_noise: self.px_noise,
            joint_noise: self.joint_noise_deg.to_radians(),
            truth,
            effects: self.effects.clone(),
            noise_seed: None,
            near_border: self.near_border,
            images: self.images.then(|| ImageOutput {
                dir: dir.to_path_buf(),
                options: RenderOptions {
                    blur: self.blur,
                    noise: self.grey_noise,
                    vignetting: self.vignetting,
                    seed: self.seed,
                    body: self.body.then(crate::body::BodyModel::default),
                    ..Default::default()
                },
                force: true,
            }),
            upper_stances: self.upper_stances,
            team_offsets: self.team_offsets,
            body: self.body.then(crate::body::BodyModel::default),
            schedule_cameras,
            schedule,
        }
    }
}

/// Simulates the dataset of `request` and writes it: every check of the inputs and
/// outputs first, the dataset staged beside `out` and published at the end (a failure or
/// a kill part-way leaves `out` as it was).
pub fn run(request: &SimRequest) -> Result<Simulated, SimRequestError> {
    request.check_bounds()?;
    let truth = request.read_truth()?;
    let schedule = request.read_schedule()?;
    // Every output against every input, and the dataset files against `force`, before
    // anything is simulated or written.
    let inputs: Vec<PathBuf> = request
        .truth
        .iter()
        .chain(&request.stance_file)
        .chain(&request.board)
        .cloned()
        .collect();
    let write_options = WriteOptions::new(request.force).protecting(inputs);
    let dataset_files = crate::dataset::dataset_files(&request.out);
    let files: Vec<&Path> = dataset_files.iter().map(PathBuf::as_path).collect();
    crate::output::check_outputs(&files, &[&request.out], &write_options)?;
    crate::dataset::check_writable(&request.out, true, request.force)?;
    let stage = Staged::new(&request.out, &write_options)?;
    let options = request.options(truth, schedule, stage.dir());
    let upper = request.upper_stances > 0 || options.schedule_cameras.contains(&CameraId::Upper);
    let model = request.model(upper)?;
    let mut dataset = simulate(&model, &options)?;
    if request.images {
        dataset.corners.clear();
    }
    let mut outside = 0;
    if let Some(path) = &request.stance_file {
        // A planned stance may show part of the board outside the image for offsets beyond
        // the plan's bounds: those vertices are not seen.
        let camera_of: HashMap<u64, CameraId> =
            dataset.captures.iter().map(|c| (c.id, c.camera)).collect();
        let before = dataset.corners.len();
        dataset.corners.retain(|c| {
            let camera = camera_of.get(&c.capture).copied().unwrap_or_default();
            model.intrinsics(camera).contains(c.pixel, 0.0)
        });
        outside = before - dataset.corners.len();
        if let Some(truth) = &mut dataset.truth {
            for key in ["stances_per_leg", "head_postures"] {
                truth.simulation.remove(key);
            }
            truth.simulation.insert(
                "stance_file".into(),
                toml::Value::String(path.display().to_string()),
            );
        }
    }
    dataset.dir = request.out.clone();
    dataset.write(stage.dir(), true)?;
    stage.publish()?;
    Ok(Simulated { dataset, outside })
}

/// What `naocalib simulate` prints about the dataset written.
pub fn summary(request: &SimRequest, simulated: &Simulated) -> String {
    let dataset = &simulated.dataset;
    let upper = dataset
        .captures
        .iter()
        .filter(|c| c.camera == CameraId::Upper)
        .count();
    let upper = if upper == 0 {
        String::new()
    } else {
        format!(" ({upper} with the upper camera)")
    };
    if request.images {
        return format!(
            "wrote {}: {} captures{upper} with images in {} (seed {}, blur {} px, grey noise {}, \
             vignetting {}, {}° joint noise); corners.csv is empty: run `naocalib detect`\n",
            request.out.display(),
            dataset.captures.len(),
            request.out.join("images").display(),
            request.seed,
            request.blur,
            request.grey_noise,
            request.vignetting,
            request.joint_noise_deg
        );
    }
    let mut text = format!(
        "wrote {}: {} captures{upper}, {} vertices (seed {}, {} px, {}° joint noise)\n",
        request.out.display(),
        dataset.captures.len(),
        dataset.corners.len(),
        request.seed,
        request.px_noise,
        request.joint_noise_deg
    );
    if simulated.outside > 0 {
        text.push_str(&format!(
            "{} vertices fell outside the image at the true offsets and were left out\n",
            simulated.outside
        ));
    }
    text
}

/// The families whose effects a simulated robot may have: every one beyond the paper's
/// but the upper camera's (drawn with the paper's whenever there are upper-camera
/// captures), comma-separated.
pub fn effect_families() -> String {
    Family::names(
        Family::ALL
            .into_iter()
            .filter(|f| !matches!(f, Family::Paper | Family::UpperCamera)),
    )
}

/// Parses a comma-separated list of effect families, or `realistic` for
/// [`Family::realistic`] (each family once).
pub fn parse_effects(text: &str) -> Result<Vec<Family>, String> {
    let mut out = Vec::new();
    for name in text.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let named: Vec<Family> = match (name, Family::from_name(name)) {
            ("realistic", _) => Family::realistic(),
            (_, Some(Family::Paper | Family::UpperCamera)) | (_, None) => {
                return Err(format!(
                    "unknown effect '{name}' ({}, realistic = {})",
                    effect_families(),
                    Family::names(Family::realistic())
                ));
            }
            (_, Some(f)) => vec![f],
        };
        for f in named {
            if !out.contains(&f) {
                out.push(f);
            }
        }
    }
    Ok(out)
}

/// Parses a camera preset's name.
pub fn parse_camera(text: &str) -> Result<CameraPreset, String> {
    CameraPreset::from_name(text).ok_or_else(|| {
        let names: Vec<&str> = CameraPreset::ALL.iter().map(|(_, n)| *n).collect();
        format!("unknown camera '{text}' ({})", names.join(", "))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn request(out: &Path) -> SimRequest {
        SimRequest {
            out: out.to_path_buf(),
            force: false,
            seed: 3,
            stances: 2,
            heads: 2,
            upper_stances: 0,
            team_offsets: false,
            px_noise: 0.1,
            joint_noise_deg: 0.0,
            truth: None,
            effects: Vec::new(),
            images: false,
            blur: 0.8,
            grey_noise: 2.0,
            vignetting: 0.3,
            body: false,
            camera: CameraPreset::V4,
            stance_file: None,
            near_border: false,
            distortion: None,
            board: None,
        }
    }

    fn bounds_error(r: SimRequest) -> String {
        r.check_bounds().unwrap_err().to_string()
    }

    #[test]
    fn counts_and_noise_levels_are_checked() {
        let r = || request(Path::new("d"));
        assert!(r().check_bounds().is_ok());
        let none = SimRequest { heads: 0, ..r() };
        assert_eq!(
            bounds_error(none),
            "--stances and --heads must be at least 1 (got 2 and 0)"
        );
        let many = SimRequest {
            stances: 30_000,
            upper_stances: 1,
            heads: 2,
            ..r()
        };
        assert!(bounds_error(many).contains("= 120004 captures; at most 100000"));
        let overflow = SimRequest {
            stances: usize::MAX,
            upper_stances: 1,
            ..r()
        };
        assert!(bounds_error(overflow).contains("more than 2⁶⁴ captures"));
        let px = SimRequest {
            px_noise: f64::NAN,
            ..r()
        };
        assert_eq!(bounds_error(px), "--px-noise must be 0 … 100 px, got NaN");
        let joint = SimRequest {
            joint_noise_deg: 11.0,
            ..r()
        };
        assert_eq!(
            bounds_error(joint),
            "--joint-noise-deg must be 0 … 10 °, got 11"
        );
        let distortion = SimRequest {
            distortion: Some(vec![0.0, 101.0]),
            ..r()
        };
        assert!(bounds_error(distortion).contains("within ±100, got 101"));
    }

    #[test]
    fn the_model_takes_the_preset_the_distortion_and_the_upper_camera() {
        let r = SimRequest {
            distortion: Some(vec![0.01, -0.02, 0.0, 0.0, 0.003]),
            camera: CameraPreset::V6,
            ..request(Path::new("d"))
        };
        let model = r.model(true).unwrap();
        assert_eq!(model.camera.distortion, [0.01, -0.02, 0.0, 0.0, 0.003]);
        assert_eq!(model.upper_camera, Some(model.camera));
        assert!(r.model(false).unwrap().upper_camera.is_none());
        let short = SimRequest {
            distortion: Some(vec![0.01]),
            ..r
        };
        assert!(matches!(
            short.model(false),
            Err(SimRequestError::Bounds(_))
        ));
    }

    /// `--board` takes the sandals of a dataset.toml's `[board]`, writes them into the
    /// simulated dataset, and is never replaced by it.
    #[test]
    fn the_board_is_the_one_of_the_dataset_toml_given() {
        let dir = tempfile::tempdir().unwrap();
        let config = dir.path().join("dataset.toml");
        let turned = "[camera]\nwidth = 640\nheight = 480\nfx = 562.5\nfy = 562.5\n\
                      cx = 320.0\ncy = 240.0\n[board]\nsquares_x = 7\nsquares_y = 5\nsquare_mm = 25.0\n\
                      mount_origin_mm = [210.0, 0.0, 0.0]\nmount_rpy_deg = [0.0, 0.0, -90.0]\n";
        std::fs::write(&config, turned).unwrap();
        let out = dir.path().join("ds");
        let r = SimRequest {
            board: Some(config.clone()),
            ..request(&out)
        };
        let board = r.model(false).unwrap().board;
        assert_eq!(board.mount_origin, [210.0, 0.0, 0.0]);
        assert!((board.mount_rpy[2] + 90f64.to_radians()).abs() < 1e-12);
        // Without --board: naocalib's sandal.
        assert_eq!(
            request(&out).model(false).unwrap().board,
            crate::model::Board::turned()
        );
        run(&r).unwrap();
        let written = crate::dataset::read_model(&out.join("dataset.toml")).unwrap();
        assert_eq!(written.board, board);
        assert_eq!(std::fs::read_to_string(&config).unwrap(), turned);
        // The dataset.toml given is an input: never the one written.
        let over = SimRequest {
            out: dir.path().to_path_buf(),
            force: true,
            board: Some(config.clone()),
            ..request(&out)
        };
        assert!(run(&over).is_err());
        assert_eq!(std::fs::read_to_string(&config).unwrap(), turned);
        let missing = SimRequest {
            board: Some(dir.path().join("none.toml")),
            ..request(&out)
        };
        assert!(
            missing
                .model(false)
                .unwrap_err()
                .to_string()
                .contains("none.toml")
        );
    }

    #[test]
    fn a_dataset_is_written_and_told_and_its_truth_never_replaced() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("ds");
        let r = request(&out);
        let simulated = run(&r).unwrap();
        assert_eq!(simulated.dataset.captures.len(), 8);
        assert!(out.join(crate::dataset::TRUTH_TOML).is_file());
        let text = summary(&r, &simulated);
        assert!(
            text.starts_with(&format!("wrote {}: 8 captures, ", out.display())),
            "{text}"
        );
        assert!(
            text.ends_with("(seed 3, 0.1 px, 0° joint noise)\n"),
            "{text}"
        );
        let again = run(&r).unwrap_err().to_string();
        assert!(
            again.ends_with("already exists; use --force to overwrite"),
            "{again}"
        );
        let own_truth = SimRequest {
            truth: Some(out.join(crate::dataset::TRUTH_TOML)),
            force: true,
            ..r
        };
        assert!(matches!(
            run(&own_truth),
            Err(SimRequestError::TruthIsOutput { .. })
        ));
    }

    #[test]
    fn effects_are_families_or_realistic() {
        assert_eq!(
            parse_effects("play, compliance,play").unwrap(),
            vec![Family::Play, Family::Compliance]
        );
        assert_eq!(parse_effects("realistic").unwrap(), Family::realistic());
        let paper = parse_effects("paper").unwrap_err();
        assert!(
            paper.starts_with("unknown effect 'paper' (head, "),
            "{paper}"
        );
        assert!(!effect_families().contains("upper_camera"));
        assert_eq!(parse_camera("v6-640x480"), Ok(CameraPreset::V6));
        assert_eq!(
            parse_camera("v5").unwrap_err(),
            "unknown camera 'v5' (v4, v6, v6-1280x960)"
        );
    }
}
