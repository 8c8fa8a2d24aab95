//! The plan as capture reads it, and the checks every row passes before anything is
//! written or moved: joint limits less a margin, HeadPitch's yaw-dependent range, one
//! HipYawPitch motor, no collision, a camera for every row; and the predicted time of
//! running it (the planner's timing model, [`route::step_times`]).

use std::path::Path;

use crate::body::{self as collision, BodyModel};
use crate::dataset::{self, Location};
use crate::model::{CameraId, Joint, JointAngles, Model, Side};
use crate::plan::feasible::head_pitch_limits;
use crate::plan::route;

use super::{CaptureError, CaptureOptions};

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
    let outside = joints.iter().find(|&(j, q)| {
        let (lo, hi) = j.limits();
        !(lo + margin..=hi - margin).contains(&q)
    });
    if let Some((j, q)) = outside {
        let (lo, hi) = j.limits();
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
    collision::collision(&model.robot, &model.board, &BodyModel::default(), joints)
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

/// The first row of `rows` whose camera is not among `cameras`.
pub fn missing_camera<'r>(rows: &'r [PlanRow], cameras: &[CameraId]) -> Option<&'r PlanRow> {
    rows.iter().find(|r| !cameras.contains(&r.camera))
}

/// Refuses the plan at `path` when a row's camera is not among `cameras` (the ones given),
/// naming the line, the capture and the camera.
pub fn check_cameras(
    path: &Path,
    rows: &[PlanRow],
    cameras: &[CameraId],
) -> Result<(), CaptureError> {
    match missing_camera(rows, cameras) {
        None => Ok(()),
        Some(row) => Err(CaptureError::NoCamera {
            at: Location::line(path, row.line),
            id: row.id,
            camera: row.camera,
        }),
    }
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
