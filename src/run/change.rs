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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibration::{Entry, Origin, Posture};

    /// A calibration of `values` (every other parameter absent), carrying `cameras`.
    fn calibration(values: &[(Param, f64, bool)], cameras: &[(CameraId, Prior)]) -> Calibration {
        Calibration {
            origin: Origin::Solved,
            solver: None,
            dataset: None,
            converged: Some(true),
            rms_px: None,
            parameters: values
                .iter()
                .map(|&(param, value, fixed)| Entry {
                    param,
                    value,
                    std: Some(if fixed { 0.0 } else { 0.1 }),
                    fixed,
                })
                .collect(),
            angles: None,
            posture: Posture::Lying,
            standing: Default::default(),
            cameras: cameras.iter().copied().collect(),
        }
    }

    #[test]
    fn the_previous_intrinsics_are_the_robots_camera_at_the_calibrations_size() {
        let model = Model::default();
        let prior = Prior::of(&model.camera);
        let params = intrinsics::params(CameraId::Lower);
        let now = calibration(
            &params.map(|p| (p, 3.0, false)),
            &[(CameraId::Lower, prior)],
        );
        // The robot's file: another camera at twice the resolution, held at it.
        let robot = Prior {
            width: 1280,
            height: 960,
            fx: 1237.4,
            fy: 1234.4,
            cx: 640.0,
            cy: 480.0,
        };
        let previous = calibration(&params.map(|p| (p, 0.0, true)), &[(CameraId::Lower, robot)]);
        let cameras = intrinsics_of(&now, Some(&previous), &model);
        assert_eq!(cameras.len(), 1);
        let c = &cameras[0];
        assert_eq!(c.now.value, prior.values().map(|v| v + 3.0));
        assert_eq!(c.previous, Some([618.7, 617.2, 320.0, 240.0]));
        // Without a previous calibration, or one without the intrinsics, none.
        assert_eq!(intrinsics_of(&now, None, &model)[0].previous, None);
        let none = calibration(&[], &[]);
        assert_eq!(intrinsics_of(&now, Some(&none), &model)[0].previous, None);
        // A calibration with the intrinsics held carries no camera: nothing to show.
        let held = calibration(&params.map(|p| (p, 0.0, true)), &[]);
        assert!(intrinsics_of(&held, Some(&previous), &model).is_empty());
    }
}
