//! The measurement phase: drive the stances of a plan over LoLA, wait for each to settle,
//! take the picture, log the mean of the readings around it, and write every capture
//! atomically as soon as it is taken (docs/CAPTURE.md).

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;

use crate::dataset::{self, Dataset, DatasetError, Location};
use crate::model::{CameraId, Joint, JointAngles, Model, Side};
use crate::output::{WriteError, WriteOptions, write_atomic};
use crate::plan::collision::{self, BodyModel};
use crate::plan::feasible::head_pitch_limits;
use crate::plan::route;

use super::camera::{Camera, CameraError, Picture, check_picture};
use super::lola::{self, ActuatorMessage, JOINTS, Link, LolaError, SensorMessage};
use super::motion::{MotionOptions, Readings, Settle, SettleState};
use super::plausible::{Believed, ReadingFault};
use super::safety::{SafetyLimits, Verdict, Watch};

/// How a capture run behaves.
#[derive(Debug, Clone, PartialEq)]
pub struct CaptureOptions {
    /// Motion, settling and measurement.
    pub motion: MotionOptions,
    /// Temperature, current and silence limits.
    pub safety: SafetyLimits,
    /// Planned angles must stay this far inside the joints' mechanical limits (rad).
    pub joint_margin: f64,
    /// The posture the robot returns to: lying on its back, legs straight and spread by
    /// 0.15 rad of HipRoll (as the plan's resting leg, so that the sandals do not touch).
    pub rest: JointAngles,
    /// How many times a stance is tried again after the motors had to cool.
    pub hot_retries: u32,
}

impl Default for CaptureOptions {
    /// The defaults of [`MotionOptions`] and [`SafetyLimits`], a margin of 2° from the
    /// limits, [`rest_posture`], two retries after cooling.
    fn default() -> Self {
        CaptureOptions {
            motion: MotionOptions::default(),
            safety: SafetyLimits::default(),
            joint_margin: 2f64.to_radians(),
            rest: rest_posture(),
            hot_retries: 2,
        }
    }
}

pub use crate::plan::route::rest_posture;

/// One row of the plan: what to capture.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlanRow {
    /// The capture id (the plan's `capture` column).
    pub id: u64,
    /// The leg whose board is in view.
    pub side: Side,
    /// The camera that takes the picture (the plan's `camera` column; lower when absent).
    pub camera: CameraId,
    /// The joint angles to command (rad).
    pub joints: JointAngles,
    /// The row's line in the plan file.
    pub line: u64,
}

/// Why a run could not start or had to stop.
#[derive(Debug, thiserror::Error)]
pub enum CaptureError {
    /// The plan could not be read.
    #[error(transparent)]
    Dataset(#[from] DatasetError),
    /// A plan row is unsafe to execute; nothing moved.
    #[error("{at}: {message}; nothing was moved")]
    Unsafe {
        /// File, line and field.
        at: Location,
        /// What is wrong.
        message: String,
    },
    /// An option is out of range.
    #[error("{0}")]
    Options(String),
    /// The output could not be written.
    #[error(transparent)]
    Write(#[from] WriteError),
    /// LoLA failed.
    #[error(transparent)]
    Lola(#[from] LolaError),
    /// The camera failed.
    #[error(transparent)]
    Camera(#[from] CameraError),
    /// A motor went beyond a safety limit.
    #[error("{0}")]
    Safety(String),
    /// The output directory already holds a dataset's file.
    #[error(
        "{}: exists; to go on with the dataset there use --resume, else choose another \
         output directory", .0.display()
    )]
    Exists(PathBuf),
    /// A joint reading is implausible (not finite, out of range, or a jump) and repeats.
    #[error(transparent)]
    Reading(ReadingFault),
    /// LoLA's first message is implausible: nothing was commanded.
    #[error("{0} in LoLA's first message; nothing was commanded")]
    FirstReading(ReadingFault),
}

/// Reads a plan (`capture,board,HeadYaw,…`, an optional `camera`; other columns ignored),
/// keeping the ids.
pub fn read_plan(path: &Path) -> Result<Vec<PlanRow>, CaptureError> {
    Ok(dataset::read_captures(path)?
        .into_iter()
        .map(|c| PlanRow {
            id: c.id,
            side: c.side,
            camera: c.camera,
            joints: c.joints,
            line: c.line,
        })
        .collect())
}

/// Why the posture `joints` may not be commanded: a joint outside its limits less
/// `margin`, HeadPitch outside its yaw-dependent range, the HipYawPitch angles differing
/// (one motor), or two parts colliding (the plan's own checks, `plan::feasible::check`
/// without the view). The message names the joint.
pub fn unsafe_posture(
    model: &Model,
    joints: &JointAngles,
    margin: f64,
) -> Option<(&'static str, String)> {
    for j in Joint::ALL {
        let (lo, hi) = j.limits();
        let q = joints.get(j);
        if !(lo + margin..=hi - margin).contains(&q) {
            return Some((
                j.name(),
                format!(
                    "{:.2}° is outside the joint's limits {:.2}° … {:.2}° less {:.1}°",
                    q.to_degrees(),
                    lo.to_degrees(),
                    hi.to_degrees(),
                    margin.to_degrees()
                ),
            ));
        }
    }
    let (lo, hi) = head_pitch_limits(joints.get(Joint::HeadYaw));
    let pitch = joints.get(Joint::HeadPitch);
    if !(lo + margin..=hi - margin).contains(&pitch) {
        return Some((
            "HeadPitch",
            format!(
                "{:.2}° is outside {:.2}° … {:.2}° at this HeadYaw (less {:.1}°)",
                pitch.to_degrees(),
                lo.to_degrees(),
                hi.to_degrees(),
                margin.to_degrees()
            ),
        ));
    }
    if (joints.get(Joint::LHipYawPitch) - joints.get(Joint::RHipYawPitch)).abs() > 1e-9 {
        return Some((
            "RHipYawPitch",
            "differs from LHipYawPitch; they are one motor".into(),
        ));
    }
    collision::collision(&model.robot, &BodyModel::default(), joints)
        .map(|what| ("", format!("collision: {what}")))
}

/// Refuses a plan with a row that is not safe to execute (see [`unsafe_posture`]), naming
/// the file, the line and the joint; also an empty plan, and an upper-camera row when
/// `model` has no upper camera (`[upper_camera]` of `dataset.toml`).
pub fn check_plan(
    path: &Path,
    model: &Model,
    rows: &[PlanRow],
    margin: f64,
) -> Result<(), CaptureError> {
    if rows.is_empty() {
        return Err(CaptureError::Unsafe {
            at: Location::file(path),
            message: "the plan has no captures".into(),
        });
    }
    for row in rows {
        if row.camera == CameraId::Upper && model.upper_camera.is_none() {
            return Err(CaptureError::Unsafe {
                at: Location::line(path, row.line).field("camera"),
                message: format!(
                    "capture {} is for the upper camera, but the robot's dataset.toml has no \
                     [upper_camera] table (its intrinsics)",
                    row.id
                ),
            });
        }
        if let Some((field, message)) = unsafe_posture(model, &row.joints, margin) {
            let mut at = Location::line(path, row.line);
            if !field.is_empty() {
                at = at.field(field);
            }
            return Err(CaptureError::Unsafe { at, message });
        }
    }
    Ok(())
}

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
    for j in Joint::ALL {
        out.push(',');
        out.push_str(j.name());
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
    /// copy of the plan (`plan`, the file's bytes); refuses a directory that already holds
    /// dataset files.
    pub fn create(dir: &Path, model: &Model, plan: &[u8]) -> Result<DatasetOut, CaptureError> {
        DatasetOut::check_new(dir)?;
        // dataset.toml as Dataset::write renders it (every value, `[joints] angles = "raw"`).
        let scratch = tempfile::tempdir().map_err(|e| DatasetError::io(dir, "write", e))?;
        let mut ds = Dataset::new(scratch.path(), *model);
        ds.angles = dataset::AngleSource::default();
        ds.write(scratch.path(), false)?;
        let toml = std::fs::read(scratch.path().join(dataset::DATASET_TOML))
            .map_err(|e| DatasetError::io(scratch.path(), "read", e))?;
        std::fs::create_dir_all(dir).map_err(|e| DatasetError::io(dir, "create", e))?;
        write_atomic(
            &dir.join(dataset::DATASET_TOML),
            &toml,
            &WriteOptions::new(false),
        )?;
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

    /// Writes capture `id` (of the board on `side`, by `camera`): its image, then
    /// `captures.csv` with its row added.
    #[allow(clippy::too_many_arguments)] // one row of captures.csv
    pub fn add(
        &mut self,
        id: u64,
        side: Side,
        camera: CameraId,
        picture: &Picture,
        joints: &JointAngles,
        spread: f64,
        frames: u32,
    ) -> Result<(), CaptureError> {
        let image = format!("images/{id:04}.{}", picture.extension);
        // An image without its row is what an interrupted write leaves: replace it.
        write_atomic(
            &self.dir.join(&image),
            &picture.bytes,
            &WriteOptions::new(true),
        )?;
        let mut row = format!("{id},{},{image},{}", side.name(), camera.name());
        for j in Joint::ALL {
            row.push_str(&format!(",{}", joints.get(j)));
        }
        row.push_str(&format!(",{:.5},{frames}", spread.to_degrees()));
        self.rows.push(row);
        self.done.insert(id);
        self.write_captures(true)?;
        Ok(())
    }
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
                && Joint::ALL
                    .iter()
                    .all(|&j| (a.joints.get(j) - b.joints.get(j)).abs() <= 1e-9)
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
        if let Some(j) = Joint::ALL
            .into_iter()
            .find(|&j| (row.joints.get(j) - c.joints.get(j)).abs() > RESUME_TOLERANCE)
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

/// What happened during a run, as it happens.
#[derive(Debug, Clone, PartialEq)]
pub enum Event {
    /// The robot is stiff and about to move.
    Started,
    /// A capture was written (its id; captures written so far, the plan's total).
    Taken {
        /// Capture id.
        id: u64,
        /// Captures in the dataset now.
        done: usize,
    },
    /// A stance was skipped (its id, why).
    Skipped {
        /// Capture id.
        id: u64,
        /// Why.
        reason: String,
    },
    /// The legs rest until the motors cool (the joint, °C).
    Cooling {
        /// The hottest joint.
        joint: Joint,
        /// Its temperature.
        temperature: f64,
    },
}

/// How a run ended.
#[derive(Debug)]
pub enum End {
    /// Every stance of the plan was visited.
    Completed,
    /// Ctrl-C or SIGTERM: the robot went to rest and its stiffness was ramped down.
    Interrupted,
    /// A fault stopped the run (after rest and ramp-down when the robot still answered).
    Stopped(CaptureError),
}

/// The account of a run.
#[derive(Debug)]
pub struct Report {
    /// Captures taken in this run.
    pub taken: Vec<u64>,
    /// Stances skipped, with the reason.
    pub skipped: Vec<(u64, String)>,
    /// Captures already in the dataset before the run (`--resume`).
    pub already: usize,
    /// LoLA cycles the run lasted.
    pub cycles: u64,
    /// How it ended.
    pub end: End,
}

/// Why a stance or the run halts.
#[derive(Debug)]
enum Halt {
    Link(LolaError),
    Fault(CaptureError),
    Interrupted,
}

impl From<LolaError> for Halt {
    fn from(e: LolaError) -> Self {
        Halt::Link(e)
    }
}

/// How one stance ended.
enum Stance {
    Taken,
    /// Skipped before anything moved.
    Unreachable(String),
    Skipped(String),
    Hot(Joint, f64),
}

/// Jobs of the worker thread that owns the camera and the dataset.
enum Job {
    Take(u64, CameraId),
    Store {
        id: u64,
        side: Side,
        camera: CameraId,
        picture: Picture,
        joints: JointAngles,
        spread: f64,
        frames: u32,
    },
}

enum Done {
    Taken(Result<Picture, CameraError>),
    Stored(u64, Result<usize, CaptureError>),
}

/// A camera with the size (width, height) its pictures must have.
type SizedCamera = (CameraId, Box<dyn Camera>, (u32, u32));

/// The worker: takes pictures and writes captures while the main loop keeps answering
/// LoLA every cycle.
struct Worker {
    jobs: Option<mpsc::Sender<Job>>,
    done: mpsc::Receiver<Done>,
    handle: Option<std::thread::JoinHandle<DatasetOut>>,
    pending: usize,
    cancel: Vec<std::sync::Arc<AtomicBool>>,
}

impl Worker {
    /// The worker of `cameras`, each with the size (width, height) its pictures must have.
    fn spawn(mut cameras: Vec<SizedCamera>, mut out: DatasetOut, scratch: PathBuf) -> Worker {
        let (jobs, rx) = mpsc::channel::<Job>();
        let (tx, done) = mpsc::channel::<Done>();
        let cancel = cameras
            .iter()
            .filter_map(|(_, camera, _)| camera.cancel_flag())
            .collect();
        let handle = std::thread::spawn(move || {
            for job in rx {
                let result = match job {
                    Job::Take(id, which) => {
                        Done::Taken(match cameras.iter_mut().find(|(c, _, _)| *c == which) {
                            None => Err(CameraError::Missing(which)),
                            Some((_, camera, (w, h))) => {
                                camera.take(&scratch).and_then(|picture| {
                                    check_picture(&picture.bytes, *w, *h)
                                        .map(|_| picture)
                                        .map_err(|message| CameraError::Unreadable { id, message })
                                })
                            }
                        })
                    }
                    Job::Store {
                        id,
                        side,
                        camera,
                        picture,
                        joints,
                        spread,
                        frames,
                    } => Done::Stored(
                        id,
                        out.add(id, side, camera, &picture, &joints, spread, frames)
                            .map(|()| out.len()),
                    ),
                };
                if tx.send(result).is_err() {
                    break;
                }
            }
            out
        });
        Worker {
            jobs: Some(jobs),
            done,
            handle: Some(handle),
            pending: 0,
            cancel,
        }
    }

    fn send(&mut self, job: Job) {
        if let Some(jobs) = &self.jobs
            && jobs.send(job).is_ok()
        {
            self.pending += 1;
        }
    }

    fn poll(&mut self) -> Option<Done> {
        let done = self.done.try_recv().ok()?;
        self.pending -= 1;
        Some(done)
    }

    /// Stops a picture under way, waits for the other jobs sent and stops the thread.
    fn finish(&mut self) -> Vec<Done> {
        for flag in &self.cancel {
            flag.store(true, Ordering::Relaxed);
        }
        self.jobs = None;
        let mut out = Vec::new();
        while self.pending > 0 {
            match self.done.recv() {
                Ok(d) => {
                    self.pending -= 1;
                    out.push(d);
                }
                Err(_) => break,
            }
        }
        if let Some(h) = self.handle.take() {
            let _ = h.join();
        }
        out
    }
}

/// The run loop: one actuator message per sensor message.
struct Runner<'a> {
    link: &'a mut dyn Link,
    options: &'a CaptureOptions,
    stop: &'a AtomicBool,
    watch: Watch,
    last: SensorMessage,
    /// The readings believed ([`Believed`]).
    believed: Believed,
    /// Positions of the joints naocalib does not move (arms, hands), as first read.
    base: [f32; JOINTS],
    /// The commanded posture.
    command: JointAngles,
    /// The commanded stiffness of each motor (LoLA's order).
    stiffness: [f64; JOINTS],
    cycles: u64,
    hot: Option<(Joint, f64)>,
    /// On the way out: only a broken link stops the rest and ramp-down.
    finishing: bool,
    /// Whether the ramp-up ended and the robot was moved.
    moved: bool,
}

impl Runner<'_> {
    fn message(&self) -> ActuatorMessage {
        let mut position = self.base;
        for j in Joint::ALL {
            position[lola::index(j)] = self.command.get(j) as f32;
        }
        ActuatorMessage {
            position,
            stiffness: self.stiffness.map(|s| s as f32),
        }
    }

    /// Answers the last message with the command and reads the next one.
    fn cycle(&mut self) -> Result<(), Halt> {
        self.link.send(&self.message())?;
        self.last = self.link.receive()?;
        self.cycles += 1;
        let fault = self.believed.check(&self.last);
        if self.finishing {
            return Ok(());
        }
        if let Some(fault) = fault {
            return Err(Halt::Fault(CaptureError::Reading(fault)));
        }
        match self.watch.check(&self.options.safety, &self.last) {
            Verdict::Fine => self.hot = None,
            Verdict::Hot(j, t) => self.hot = Some((j, t)),
            Verdict::Overheated(j, t) => {
                return Err(Halt::Fault(CaptureError::Safety(format!(
                    "{} reached {t:.1} °C (limit {:.0} °C)",
                    j.name(),
                    self.options.safety.stop_temperature
                ))));
            }
            Verdict::Overcurrent(j, a) => {
                return Err(Halt::Fault(CaptureError::Safety(format!(
                    "{} drew {a:.2} A for {} cycles (limit {:.2} A)",
                    j.name(),
                    self.options.safety.current_cycles,
                    self.options.safety.max_current
                ))));
            }
            Verdict::Unreadable(j, what, value) => {
                return Err(Halt::Fault(CaptureError::Safety(format!(
                    "{} reports a {what} of {value}: its limits cannot be watched",
                    j.name()
                ))));
            }
        }
        if self.stop.load(Ordering::Relaxed) {
            return Err(Halt::Interrupted);
        }
        Ok(())
    }

    /// The believed readings; a joint no longer believed reads as commanded (so that
    /// nothing follows it on the way out).
    fn reading(&self) -> JointAngles {
        let mut out = self.believed.readings();
        for j in Joint::ALL {
            if self.believed.lost(j) {
                out.set(j, self.command.get(j));
            }
        }
        out
    }

    /// Ramps each motor's stiffness from what the robot reported at the start to the
    /// measuring stiffness (head and legs) or 0 (arms, hands), holding the posture measured
    /// at the start: a leg that sags meanwhile does not drag the command along.
    fn ramp_up(&mut self) -> Result<(), Halt> {
        let m = self.options.motion;
        let from = self.stiffness;
        let mut to = [0.0; JOINTS];
        for j in Joint::ALL {
            to[lola::index(j)] = m.stiffness;
        }
        for k in 0..=m.ramp_cycles {
            self.stiffness = std::array::from_fn(|i| m.ramp(from[i], to[i], k));
            self.cycle()?;
        }
        Ok(())
    }

    /// Ramps the stiffness down to 0, holding the command.
    fn ramp_down(&mut self) -> Result<(), Halt> {
        let m = self.options.motion;
        let from = self.stiffness;
        for k in 0..m.ramp_cycles {
            self.stiffness = from.map(|s| m.ramp_down(s, k));
            self.cycle()?;
        }
        Ok(())
    }

    /// Moves to `target` at bounded speed, then waits for the readings to settle.
    /// `Ok(None)` when settled; `Ok(Some(reason))` when obstructed or not settling, after
    /// which the command holds the joints where they are.
    fn move_to(&mut self, target: &JointAngles, watch_hot: bool) -> Result<Option<Stance>, Halt> {
        let m = self.options.motion;
        let mut settle = Settle::new();
        let path = m.path(&self.command, target);
        let timeout = m.settle_timeout_cycles as usize;
        for k in 0..path.len() + timeout {
            self.command = *path.get(k).unwrap_or(target);
            self.cycle()?;
            if watch_hot && let Some((j, t)) = self.hot {
                return Ok(Some(Stance::Hot(j, t)));
            }
            let reading = self.reading();
            match settle.push(&m, &self.command, &reading) {
                SettleState::Settled if k + 1 >= path.len() => return Ok(None),
                SettleState::Obstructed(j, gap) => {
                    // Stop pushing against what is in the way: the command comes back to
                    // where the joints are, at bounded speed.
                    for p in m.path(&self.command, &reading) {
                        self.command = p;
                        self.cycle()?;
                    }
                    return Ok(Some(Stance::Skipped(format!(
                        "{} stayed {:.1}° from its command for {} cycles (obstructed?)",
                        j.name(),
                        gap.to_degrees(),
                        m.obstruction_cycles
                    ))));
                }
                _ => {}
            }
        }
        Ok(Some(Stance::Skipped(format!(
            "the joints did not settle within {} cycles",
            timeout
        ))))
    }

    /// One stance: move, settle, picture, readings.
    fn stance(
        &mut self,
        model: &Model,
        row: &PlanRow,
        worker: &mut Worker,
        taken: &mut dyn FnMut(Done) -> Result<(), Halt>,
    ) -> Result<Stance, Halt> {
        let m = self.options.motion;
        let rest = self.options.rest;
        let way = match route::route(
            model,
            &BodyModel::default(),
            &self.command,
            &row.joints,
            &rest,
        ) {
            Ok(way) => way,
            Err(reason) => return Ok(Stance::Unreachable(reason.to_string())),
        };
        for target in &way {
            if let Some(outcome) = self.move_to(target, true)? {
                return Ok(outcome);
            }
        }
        worker.send(Job::Take(row.id, row.camera));
        let mut readings = Readings::default();
        let mut picture = None;
        let mut after = 0u32;
        let mut k = 0u32;
        loop {
            self.cycle()?;
            k += 1;
            // A cycle with a glitch is left out of the capture's readings.
            if k > m.sensor_lag_cycles && self.believed.all_believed() {
                readings.push(&self.reading());
            }
            if picture.is_none() {
                while let Some(done) = worker.poll() {
                    match done {
                        Done::Taken(result) => {
                            picture = Some(result.map_err(|e| Halt::Fault(e.into()))?)
                        }
                        stored => taken(stored)?,
                    }
                }
            } else {
                after += 1;
                if after >= m.sensor_lag_cycles && readings.count() >= m.window_cycles {
                    break;
                }
            }
        }
        worker.send(Job::Store {
            id: row.id,
            side: row.side,
            camera: row.camera,
            picture: picture.expect("taken"),
            joints: readings.mean(),
            spread: readings.spread(),
            frames: readings.count(),
        });
        Ok(Stance::Taken)
    }

    /// Rests until the head and leg motors are at or below the resume temperature.
    fn cool(&mut self) -> Result<(), Halt> {
        let limits = self.options.safety;
        let rest = self.options.rest;
        self.move_to(&rest, false)?;
        for _ in 0..limits.max_pause_cycles {
            self.cycle()?;
            if SafetyLimits::hottest(&self.last).1 <= limits.resume_temperature {
                return Ok(());
            }
        }
        let (j, t) = SafetyLimits::hottest(&self.last);
        Err(Halt::Fault(CaptureError::Safety(format!(
            "{} still at {t:.1} °C after {} cycles at rest",
            j.name(),
            limits.max_pause_cycles
        ))))
    }
}

/// Sends a stiffness ramp-down without reading (after a message that did not parse, the
/// stream cannot be trusted): one message per 12 ms.
fn blind_ramp_down(link: &mut dyn Link, last: ActuatorMessage, options: &MotionOptions) {
    let mut message = last;
    let from = message.stiffness;
    for k in 0..options.ramp_cycles {
        let f = options.ramp_down(1.0, k) as f32;
        for (s, s0) in message.stiffness.iter_mut().zip(from) {
            *s = s0 * f;
        }
        link.drain();
        if link.send(&message).is_err() {
            return;
        }
        std::thread::sleep(lola::CYCLE);
    }
    std::thread::sleep(lola::CYCLE);
    link.drain();
}

/// Runs the plan `rows` on the robot behind `link`, taking each row's picture with its
/// camera of `cameras` (each row's camera must be there), writing into `out`: ramps the
/// stiffness up from what the robot reports, holding the posture it first reports, visits every row not yet in `out` (skipping
/// obstructed stances, resting while motors are hot), and at the end, on `stop` and on any
/// fault it can still command, returns to rest and ramps the stiffness down.
/// `events` hears of each capture written and each stance skipped.
#[allow(clippy::too_many_arguments)] // the robot, the plan, the output and the run's settings
pub fn run(
    model: &Model,
    rows: &[PlanRow],
    out: DatasetOut,
    cameras: Vec<(CameraId, Box<dyn Camera>)>,
    link: &mut dyn Link,
    options: &CaptureOptions,
    stop: &AtomicBool,
    events: &mut dyn FnMut(Event),
) -> Result<Report, CaptureError> {
    options.motion.validate().map_err(CaptureError::Options)?;
    options.safety.validate().map_err(CaptureError::Options)?;
    if let Some((field, message)) = unsafe_posture(model, &options.rest, 0.0) {
        return Err(CaptureError::Options(format!(
            "the rest posture is unsafe: {}",
            [field, message.as_str()].join(" ").trim()
        )));
    }
    let already = out.len();
    let todo: Vec<PlanRow> = rows.iter().filter(|r| !out.has(r.id)).copied().collect();
    if let Some(row) = todo
        .iter()
        .find(|r| !cameras.iter().any(|(c, _)| *c == r.camera))
    {
        return Err(CaptureError::Options(format!(
            "capture {} (plan line {}) is for the {} camera, and no {} camera is given \
             (--camera {}=SPEC); nothing was moved",
            row.id,
            row.line,
            row.camera.name(),
            row.camera.name(),
            row.camera.name()
        )));
    }
    let scratch = tempfile::tempdir()
        .map_err(|e| CaptureError::Dataset(DatasetError::io(Path::new("/tmp"), "create", e)))?;
    let cameras = cameras
        .into_iter()
        .map(|(id, camera)| {
            let size = model.intrinsics(id);
            (id, camera, (size.width, size.height))
        })
        .collect();
    let mut worker = Worker::spawn(cameras, out, scratch.path().to_path_buf());
    let mut report = Report {
        taken: Vec::new(),
        skipped: Vec::new(),
        already,
        cycles: 0,
        end: End::Completed,
    };
    let first = match link.receive() {
        Ok(m) => m,
        Err(e) => {
            worker.finish();
            return Err(e.into());
        }
    };
    let believed = match Believed::start(options.safety.readings, &first) {
        Ok(b) => b,
        Err(e) => {
            worker.finish();
            return Err(CaptureError::FirstReading(e));
        }
    };
    let mut runner = Runner {
        link,
        options,
        stop,
        watch: Watch::default(),
        base: first.position,
        command: believed.readings(),
        believed,
        stiffness: first.stiffness.map(f64::from),
        last: first,
        cycles: 0,
        hot: None,
        finishing: false,
        moved: false,
    };
    let mut taken_ids: Vec<u64> = Vec::new();
    let mut on_done = |done: Done, events: &mut dyn FnMut(Event)| -> Result<(), Halt> {
        match done {
            Done::Stored(id, Ok(n)) => {
                taken_ids.push(id);
                events(Event::Taken { id, done: n });
                Ok(())
            }
            Done::Stored(_, Err(e)) => Err(Halt::Fault(e)),
            Done::Taken(_) => Ok(()),
        }
    };
    let result: Result<(), Halt> = (|| {
        runner.ramp_up()?;
        runner.moved = true;
        events(Event::Started);
        for row in &todo {
            let mut tries = 0;
            loop {
                let outcome =
                    runner.stance(model, row, &mut worker, &mut |d| on_done(d, events))?;
                match outcome {
                    Stance::Taken => break,
                    Stance::Unreachable(reason) => {
                        events(Event::Skipped {
                            id: row.id,
                            reason: reason.clone(),
                        });
                        report.skipped.push((row.id, reason));
                        break;
                    }
                    Stance::Skipped(reason) => {
                        events(Event::Skipped {
                            id: row.id,
                            reason: reason.clone(),
                        });
                        report.skipped.push((row.id, reason));
                        // The leg returns to rest.
                        let rest = runner.options.rest;
                        runner.move_to(&rest, false)?;
                        break;
                    }
                    Stance::Hot(joint, temperature) => {
                        events(Event::Cooling { joint, temperature });
                        tries += 1;
                        if tries > options.hot_retries {
                            return Err(Halt::Fault(CaptureError::Safety(format!(
                                "{} overheats again and again ({temperature:.1} °C)",
                                joint.name()
                            ))));
                        }
                        runner.cool()?;
                    }
                }
            }
            while let Some(done) = worker.poll() {
                on_done(done, events)?;
            }
        }
        Ok(())
    })();
    // The way out: rest, then the stiffness ramp-down, unless the link is gone.
    runner.finishing = true;
    let end = match result {
        Ok(()) => End::Completed,
        Err(Halt::Interrupted) => End::Interrupted,
        Err(Halt::Fault(e)) => End::Stopped(e),
        Err(Halt::Link(e)) => End::Stopped(e.into()),
    };
    let link_ok = !matches!(end, End::Stopped(CaptureError::Lola(_)));
    if link_ok {
        // A robot stopped during the ramp-up has not moved: it ramps down where it lies.
        let rest = options.rest;
        let back = if runner.moved {
            runner.move_to(&rest, false).map(|_| ())
        } else {
            Ok(())
        }
        .and_then(|()| runner.ramp_down());
        if let Err(Halt::Link(LolaError::Parse(_))) = back {
            let last = runner.message();
            blind_ramp_down(runner.link, last, &options.motion);
        }
    } else if let End::Stopped(CaptureError::Lola(LolaError::Parse(_))) = end {
        let last = runner.message();
        blind_ramp_down(runner.link, last, &options.motion);
    }
    report.cycles = runner.cycles;
    let mut end = end;
    for done in worker.finish() {
        if let Err(Halt::Fault(e)) = on_done(done, events)
            && matches!(end, End::Completed)
        {
            end = End::Stopped(e);
        }
    }
    report.taken = taken_ids;
    report.end = end;
    Ok(report)
}

/// The predicted time (s) of each move of running `rows` from the rest posture with the
/// plan's timing model at `options`' speeds: the way to each row with its picture (0 for a
/// row without a collision-free way), and last the return to rest
/// ([`route::step_times`]).
pub fn predicted_steps(model: &Model, rows: &[PlanRow], options: &CaptureOptions) -> Vec<f64> {
    let timing = route::Timing {
        leg_speed: options.motion.leg_speed,
        head_speed: options.motion.head_speed,
        ..Default::default()
    };
    let postures: Vec<JointAngles> = rows.iter().map(|r| r.joints).collect();
    route::step_times(
        model,
        &BodyModel::default(),
        &timing,
        &options.rest,
        &postures,
    )
}

/// The signals that would end the process: SIGHUP (the terminal or the ssh session to the
/// robot is lost), SIGINT (Ctrl-C), SIGQUIT (`Ctrl-\`) and SIGTERM.
pub const STOP_SIGNALS: [i32; 4] = [
    signal_hook::consts::SIGHUP,
    signal_hook::consts::SIGINT,
    signal_hook::consts::SIGQUIT,
    signal_hook::consts::SIGTERM,
];

/// The stop flag, set by any of [`STOP_SIGNALS`], as often as they come: the run then
/// returns to rest and ramps the stiffness down before the process ends. (A lost terminal
/// also makes every later message fail; messages are written without panicking.)
pub fn stop_on_signals() -> std::io::Result<std::sync::Arc<AtomicBool>> {
    let flag = std::sync::Arc::new(AtomicBool::new(false));
    for signal in STOP_SIGNALS {
        signal_hook::flag::register(signal, flag.clone())?;
    }
    Ok(flag)
}

/// Turns `Duration` of cycles into wall time at LoLA's rate (for messages).
pub fn cycles_to_seconds(cycles: u64) -> f64 {
    cycles as f64 * lola::CYCLE_S
}
