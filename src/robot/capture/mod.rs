//! The measurement phase: drive the stances of a plan over LoLA, wait for each to settle,
//! take the picture, log the mean of the readings around it, and write every capture
//! atomically as soon as it is taken (docs/CAPTURE.md).
//!
//! In the order a run uses them:
//! - [`plan`]: the plan's rows and the checks every row passes before anything moves;
//! - [`start`]: a new dataset or the one a run left (`--resume`), checked against the plan
//!   and the robot before anything is written or moved;
//! - [`writer`]: the dataset, written capture by capture;
//! - `worker`: the thread that takes the pictures and writes the captures;
//! - `drive`: the robot cycle by cycle — ramps, bounded-speed moves, settling, cooling,
//!   the way out;
//! - [`session`]: the loop over the plan, its observers and stop flag;
//! - [`signals`]: the signals that set the stop flag;
//! - [`guard`]: the process that takes the robot to rest when capture dies in a way it
//!   cannot handle itself (SIGKILL, an abort, the out-of-memory kill).
//!
//! The ways between stances are the planner's ([`crate::plan::route`]), so that a plan runs
//! as it was planned.

use std::path::PathBuf;

use crate::dataset::{DatasetError, Location};
use crate::model::{CameraId, JointAngles};
use crate::output::WriteError;

use super::body::BodyStop;
use super::camera::CameraError;
use super::lola::{self, LolaError};
use super::motion::MotionOptions;
use super::plausible::ReadingFault;
use super::safety::SafetyLimits;

mod drive;
pub mod guard;
pub mod plan;
pub mod request;
pub mod session;
pub mod signals;
pub mod start;
mod worker;
pub mod writer;

pub use crate::plan::route::rest_posture;
pub use plan::{
    PlanRow, check_cameras, check_plan, missing_camera, predicted_steps, read_plan, unsafe_posture,
};
pub use session::{End, Event, Forecast, Report, Session};
pub use signals::{STOP_SIGNALS, stop_on_signals};
pub use start::Start;
pub use writer::{DatasetOut, PLAN_CSV, RESUME_TOLERANCE, Taken, captures_header};

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
    /// A plan row is for a camera that was not given; nothing moved.
    #[error(
        "{at}: capture {id} is for the {camera} camera; give it with --camera {camera}=SPEC \
         (nothing was moved)"
    )]
    NoCamera {
        /// The plan's file and the row's line.
        at: Location,
        /// The capture id.
        id: u64,
        /// The camera the row needs.
        camera: CameraId,
    },
    /// A new dataset needs the robot's `dataset.toml`.
    #[error("--config DATASET.toml is needed (the robot's camera intrinsics and sandals)")]
    NoConfig,
    /// The robot's `dataset.toml` given differs from the one of the dataset resumed.
    #[error(
        "{}: its camera, sandals or geometry differ from {}'s dataset.toml; resume with the \
         same robot configuration", config.display(), dir.display()
    )]
    OtherRobot {
        /// The `dataset.toml` given.
        config: PathBuf,
        /// The dataset's directory.
        dir: PathBuf,
    },
    /// `--resume` with a camera driven otherwise than the dataset's pictures were taken.
    #[error(transparent)]
    OtherSettings(Box<SettingsMismatch>),
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
    /// The checks before the first move do not hold (what does not): nothing was moved.
    #[error("{0}; nothing was moved")]
    NotReady(String),
    /// The robot as a whole stopped the run: it rolled over, the chest button, a motor's
    /// status, the battery.
    #[error(transparent)]
    Body(#[from] BodyStop),
    /// naocalib itself failed (a panic, a thread that ended): a bug.
    #[error("naocalib failed inside: {0} (a bug; please report it)")]
    Internal(String),
}

/// A camera that `--resume` would drive otherwise than the dataset's pictures were taken;
/// nothing was moved.
#[derive(Debug, thiserror::Error)]
#[error(
    "{at}: the dataset's {camera} camera pictures were taken with {control} {then}, this run \
     would take them with {now}; resume with the same settings (the dataset's own \
     dataset.toml, without --config or --camera-setting), or start a new dataset (nothing \
     was moved)"
)]
pub struct SettingsMismatch {
    /// The setting in the dataset's `dataset.toml`.
    pub at: Location,
    /// The camera.
    pub camera: CameraId,
    /// The control (its key in `dataset.toml`).
    pub control: String,
    /// The value the dataset records.
    pub then: String,
    /// The value of this run.
    pub now: String,
}

/// Turns a number of LoLA cycles into wall time (s) at LoLA's rate (for messages).
pub fn cycles_to_seconds(cycles: u64) -> f64 {
    cycles as f64 * lola::CYCLE_S
}
