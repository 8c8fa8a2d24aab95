//! The plan as capture reads it, and the checks every row passes before anything is
//! written or moved: joint limits less a margin, HeadPitch's yaw-dependent range, one
//! HipYawPitch motor, no collision, a camera for every row, the arm joints within their
//! limits and one arm posture for the run; and the predicted time of running it (the
//! planner's timing model, [`route::step_times`]).

use std::path::Path;

use crate::body::{ARM_JOINTS, ArmPosture};
use crate::dataset::{self, DatasetError, Location};
use crate::model::head_pitch_limits;
use crate::model::{CameraId, Joint, JointAngles, Model, Side};
use crate::plan::collision::{self, BodyModel};
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
    /// The arm posture during the capture (the plan's `LShoulderPitch` … `RWristYaw`
    /// columns; [`ArmPosture::CAPTURE`] when the plan has none).
    pub arms: ArmPosture,
    /// The row's line in the plan file.
    pub line: u64,
}

/// Reads a plan (`capture,board,HeadYaw,…`, an optional `camera`, the optional arm
/// columns `LShoulderPitch` … `RWristYaw`; other columns ignored), keeping the ids. The arm
/// columns come all ten or none (none: [`ArmPosture::CAPTURE`] for every row); every arm
/// angle must be within its joint's limits ([`crate::body::posture::ARM_LIMITS`]) and every
/// row must hold the arms alike (capture keeps them in one posture for the whole run).
/// Errors name the file, the line and the field.
pub fn read_plan(path: &Path) -> Result<Vec<PlanRow>, CaptureError> {
    let captures = dataset::read_captures(path)?;
    let lines: Vec<u64> = captures.iter().map(|c| c.line).collect();
    let arms = read_arms(path, &lines)?;
    let rows: Vec<PlanRow> = captures
        .into_iter()
        .zip(arms)
        .map(|(c, arms)| PlanRow {
            id: c.id,
            side: c.side,
            camera: c.camera,
            joints: c.joints,
            arms: arms.unwrap_or(ArmPosture::CAPTURE),
            line: c.line,
        })
        .collect();
    check_arms(path, &rows)?;
    Ok(rows)
}

/// The arm columns of the plan at `path` (already read as a captures table whose rows are
/// on `lines`): each row's arm angles, `None` for every row when the header has no arm
/// column.
fn read_arms(path: &Path, lines: &[u64]) -> Result<Vec<Option<ArmPosture>>, CaptureError> {
    let count = lines.len();
    let bytes = std::fs::read(path).map_err(|e| DatasetError::io(path, "read", e))?;
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .trim(csv::Trim::All)
        .from_reader(&bytes[..]);
    // The records as the captures table has them: blank ones skipped, the first the header.
    let mut records = reader
        .records()
        .filter_map(Result::ok)
        .filter(|r| !r.iter().all(str::is_empty));
    let Some(header) = records.next() else {
        return Ok(vec![None; count]);
    };
    let columns = ARM_JOINTS.map(|name| header.iter().position(|h| h == name));
    if columns.iter().all(Option::is_none) {
        return Ok(vec![None; count]);
    }
    let header_line = header.position().map_or(1, |p| p.line());
    if let Some(k) = columns.iter().position(Option::is_none) {
        let have = ARM_JOINTS[columns.iter().position(Option::is_some).unwrap_or(0)];
        return Err(DatasetError::invalid(
            Location::line(path, header_line).field(ARM_JOINTS[k]),
            format!(
                "the header has the arm column '{have}' but no column '{}' (the arm \
                 columns come all ten or none)",
                ARM_JOINTS[k]
            ),
        )
        .into());
    }
    let columns = columns.map(|c| c.unwrap_or(0));
    let mut out = Vec::with_capacity(count);
    for (record, &line) in records.take(count).zip(lines) {
        let mut q = [0.0; 10];
        for (k, &col) in columns.iter().enumerate() {
            let text = record.get(col).unwrap_or("");
            q[k] = match text.parse::<f64>() {
                Ok(x) if x.is_finite() => x,
                _ => {
                    return Err(DatasetError::invalid(
                        Location::line(path, line).field(ARM_JOINTS[k]),
                        if text.is_empty() {
                            "missing value, expected a number".to_string()
                        } else {
                            format!("'{text}' is not a finite number")
                        },
                    )
                    .into());
                }
            };
        }
        out.push(Some(ArmPosture(q)));
    }
    out.resize(count, None);
    Ok(out)
}

/// Refuses a row whose arm angle is outside its joint's limits, naming the file, the line
/// and the joint; and a plan whose rows hold the arms differently (capture holds them in
/// one posture for the whole run), naming the first row that differs from the first.
pub fn check_arms(path: &Path, rows: &[PlanRow]) -> Result<(), CaptureError> {
    for row in rows {
        if let Some((k, message)) = crate::robot::arms::outside_limits(&row.arms) {
            return Err(CaptureError::Unsafe {
                at: Location::line(path, row.line).field(ARM_JOINTS[k]),
                message,
            });
        }
    }
    let Some(first) = rows.first() else {
        return Ok(());
    };
    if let Some(row) = rows.iter().find(|r| r.arms != first.arms) {
        let k = (0..10)
            .find(|&k| row.arms.0[k] != first.arms.0[k])
            .unwrap_or(0);
        return Err(CaptureError::Unsafe {
            at: Location::line(path, row.line).field(ARM_JOINTS[k]),
            message: format!(
                "{} rad differs from line {}'s {} rad: capture holds the arms in one \
                 posture for the whole run",
                row.arms.0[k], first.line, first.arms.0[k]
            ),
        });
    }
    Ok(())
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plan::{PlannedCapture, render_csv};

    /// A plan of three captures as the planner writes it, arm columns and all.
    fn planned() -> String {
        let captures: Vec<PlannedCapture> = (0..3)
            .map(|k| PlannedCapture {
                camera: CameraId::Lower,
                side: if k % 2 == 0 { Side::Left } else { Side::Right },
                joints: crate::plan::route::rest_posture(),
            })
            .collect();
        String::from_utf8(render_csv(&captures)).unwrap()
    }

    fn read(text: &str) -> Result<Vec<PlanRow>, String> {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("plan.csv");
        std::fs::write(&path, text).unwrap();
        read_plan(&path).map_err(|e| {
            e.to_string()
                .replace(&dir.path().display().to_string(), "DIR")
        })
    }

    /// `text` with field `field` of line `line` (1-based) set to `value`.
    fn with(text: &str, line: usize, field: &str, value: &str) -> String {
        let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
        let col = header.iter().position(|h| *h == field).unwrap();
        let lines: Vec<String> = text
            .lines()
            .enumerate()
            .map(|(k, l)| {
                if k + 1 != line {
                    return l.to_string();
                }
                let mut f: Vec<&str> = l.split(',').collect();
                f[col] = value;
                f.join(",")
            })
            .collect();
        lines.join("\n") + "\n"
    }

    #[test]
    fn the_plans_arm_columns_are_read_and_a_plan_without_them_gets_captures_posture() {
        let rows = read(&planned()).unwrap();
        assert_eq!(rows.len(), 3);
        assert!(rows.iter().all(|r| r.arms == ArmPosture::CAPTURE));
        // Every arm column a name the captures table ignores (no near miss of its own).
        let moved = planned()
            .replace("-1.5707963267948966,0.45", "-1.5,0.45")
            .replace("-1.5707963267948966,-0.45", "-1.5,-0.45");
        let rows = read(&moved).unwrap();
        assert_eq!(rows[2].arms.0[0], -1.5);
        assert_eq!(rows[2].arms.0[5], -1.5);
        // Without the arm columns: capture's posture.
        let text = planned();
        let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
        let keep: Vec<usize> = (0..header.len())
            .filter(|&k| !ARM_JOINTS.contains(&header[k]))
            .collect();
        let without: String = planned()
            .lines()
            .map(|l| {
                let f: Vec<&str> = l.split(',').collect();
                keep.iter().map(|&k| f[k]).collect::<Vec<_>>().join(",") + "\n"
            })
            .collect();
        assert!(!without.contains("Shoulder"));
        let rows = read(&without).unwrap();
        assert!(rows.iter().all(|r| r.arms == ArmPosture::CAPTURE));
    }

    #[test]
    fn an_arm_angle_outside_its_limits_or_a_second_arm_posture_is_refused_with_file_line_and_field()
    {
        let e = read(&with(&planned(), 3, "RElbowRoll", "1.7")).unwrap_err();
        assert!(
            e.starts_with(
                "DIR/plan.csv line 3, field RElbowRoll: 97.40° is outside the joint's limits \
                 2.00° … 88.50°; nothing was moved"
            ),
            "{e}"
        );
        let e = read(&with(&planned(), 4, "LWristYaw", "0.3")).unwrap_err();
        assert!(
            e.starts_with("DIR/plan.csv line 4, field LWristYaw: 0.3 rad differs from line 2's 0 rad: capture holds the arms in one posture"),
            "{e}"
        );
        let e = read(&with(&planned(), 2, "LElbowYaw", "x")).unwrap_err();
        assert!(
            e.contains("plan.csv line 2, field LElbowYaw: 'x' is not a finite number"),
            "{e}"
        );
        let partial = planned().replacen("RWristYaw", "Note", 1);
        let e = read(&partial).unwrap_err();
        assert!(
            e.contains("line 1, field RWristYaw: the header has the arm column 'LShoulderPitch' but no column 'RWristYaw'"),
            "{e}"
        );
    }
}
