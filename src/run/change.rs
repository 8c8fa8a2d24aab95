//! The change since the robot's previous calibration (`solve --start-from`).

use crate::calibration::Calibration;
use crate::model::Param;
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
/// `corrected_angles` the joint offsets estimated are changes to the previous ones.
pub fn changes(solution: &Solution, previous: &Calibration, corrected_angles: bool) -> Vec<Change> {
    Param::ALL
        .iter()
        .filter(|&&p| !solution.fixed.is_fixed(p) && solution.is_determined(p))
        .filter_map(|&p| {
            let before = previous.get(p).filter(|e| e.is_determined())?;
            let estimate = solution.report_value(p);
            let (value, change) = if corrected_angles && crate::solve::problem::is_joint_offset(p) {
                (before.value + estimate, estimate)
            } else {
                (estimate, estimate - before.value)
            };
            let sigma = solution.report_std(p).hypot(before.std.unwrap_or(0.0));
            Some(Change {
                param: p,
                previous: before.value,
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
