//! The change since the robot's previous calibration (`solve --start-from`).

use crate::calibration::{Calibration, Intrinsics, Prior, intrinsics};
use crate::model::{CameraId, Model, Param};
use crate::solve::Solution;

/// One parameter's change since the robot's previous calibration (report units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Change {
    /// The parameter.
    pub param: Param,
    /// Its value in the previous calibration.
    pub previous: f64,
    /// Its value now (for offsets estimated on already-corrected angles: previous + the
    /// estimated change).
    pub value: f64,
    /// `value − previous`.
    pub change: f64,
    /// `change / σ`, σ combining this calibration's and the previous one's one-sigma.
    pub z: f64,
}

/// What changed since the robot's previous calibration: every parameter estimated now
/// (free and determined) that the previous calibration holds with a known value. With
/// `corrected_angles` the joint offsets estimated are changes to the previous ones. The
/// previous intrinsics corrections are taken relative to `model`'s a-priori cameras
/// ([`Calibration::intrinsics_relative_to`]), as the solve started from them: a robot's
/// intrinsics read from its team file are corrections of this dataset's cameras.
pub fn changes(
    solution: &Solution,
    previous: &Calibration,
    corrected_angles: bool,
    model: &Model,
) -> Vec<Change> {
    let (relative, _) = previous.intrinsics_relative_to(model);
    Param::ALL
        .iter()
        .filter(|&&p| !solution.fixed.is_fixed(p) && solution.is_determined(p))
        .filter_map(|&p| {
            let before = previous.get(p).filter(|e| e.is_determined())?;
            let before_value = relative
                .iter()
                .find(|(q, _)| *q == p)
                .map_or(before.value, |(_, v)| *v);
            let estimate = solution.report_value(p);
            let (value, change) = if corrected_angles && crate::solve::problem::is_joint_offset(p) {
                (before_value + estimate, estimate)
            } else {
                (estimate, estimate - before_value)
            };
            let sigma = solution.report_std(p).hypot(before.std.unwrap_or(0.0));
            Some(Change {
                param: p,
                previous: before_value,
                value,
                change,
                z: if sigma > 0.0 {
                    change / sigma
                } else {
                    f64::NAN
                },
            })
        })
        .collect()
}

/// One calibrated camera's intrinsics and the robot's previous ones (`--start-from`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraIntrinsics {
    /// The calibrated intrinsics, with their one-sigma.
    pub now: Intrinsics,
    /// The previous calibration's `[fx, fy, cx, cy]` (px) at the image size of `now`, when
    /// it holds all four.
    pub previous: Option<[f64; 4]>,
}

/// The intrinsics of every camera `calibration` carries a prior for (those it estimated),
/// each with the previous calibration's at the same image size: its start values for a
/// problem of `model` ([`Calibration::start_values`]) on `model`'s a-priori camera.
pub fn intrinsics_of(
    calibration: &Calibration,
    previous: Option<&Calibration>,
    model: &Model,
) -> Vec<CameraIntrinsics> {
    let start = previous.map(|p| p.start_values(model));
    CameraId::ALL
        .into_iter()
        .filter_map(|camera| {
            let now = calibration.intrinsics(camera)?;
            let previous = start.as_ref().and_then(|start| {
                let corrections = intrinsics::params(camera)
                    .map(|p| start.iter().find(|(q, _)| *q == p).map(|(_, v)| *v));
                let base = Prior::of(model.intrinsics(camera));
                let [fx, fy, cx, cy] = base.values();
                Some(
                    Prior {
                        fx: fx + corrections[0]?,
                        fy: fy + corrections[1]?,
                        cx: cx + corrections[2]?,
                        cy: cy + corrections[3]?,
                        ..base
                    }
                    .scaled_to(now.prior.width, now.prior.height),
                )
            });
            Some(CameraIntrinsics { now, previous })
        })
        .collect()
}
