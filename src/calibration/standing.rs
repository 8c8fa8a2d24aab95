//! The standing leg offsets: the offsets robot files carry for a robot in the standard
//! stand, `α + κ·τ_stand + ½π·sgn τ_stand` with the compliance `κ` and play `π` a
//! calibration estimated, with their one-sigma and the lying torques they rest on.

use super::{Calibration, StandingFile};
use crate::model::Param;
use crate::solve::Solution;

/// What a standing leg offset ([`Calibration::standing_offset`]) rests on.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Standing {
    /// Its one-sigma (deg): `√(gᵀ C g)` with `g = (1, τ_stand, ½·sgn τ_stand)` and `C` the
    /// covariance of `α`, `κ` and `π` of the joint, correlations included; `None` when
    /// not known.
    pub std: Option<f64>,
    /// The largest |gravity torque| (N·m) about the joint in the lying captures its
    /// compliance was estimated from; `None` when not known.
    pub lying_torque: Option<f64>,
}

/// The accuracy a standing leg offset should reach (deg, one sigma): beyond it the report
/// and `export` name the joint and the reason.
pub const STANDING_TARGET_DEG: f64 = 0.05;

/// A compliance applied at more than this many times the largest torque it was estimated
/// from is an extrapolation the report names.
pub const EXTRAPOLATION_LIMIT: f64 = 3.0;

/// The standing gravity torque (N·m) about the leg joint whose offset is `param`, in the
/// standard stand with the default geometry; `None` for other parameters.
pub fn stand_torque(param: Param) -> Option<f64> {
    use crate::model::{RobotGeometry, Side, gravity};
    let side = match param.group() {
        crate::model::ParamGroup::LeftLeg => Side::Left,
        crate::model::ParamGroup::RightLeg => Side::Right,
        _ => return None,
    };
    let k = side.leg_joints().iter().position(|j| j.offset() == param)?;
    let torques =
        gravity::standing_leg_torques(&RobotGeometry::default(), side, &gravity::stand_joints());
    Some(torques[k])
}

/// The one-sigma (deg) of the standing offset of `param` in `cal` from the covariance of
/// `solution`: `√(gᵀ C g)` over the offset, and the compliance and play `cal` estimated
/// (held or undetermined ones enter with zero weight, as in the offset itself).
pub(super) fn standing_std_of(solution: &Solution, cal: &Calibration, param: Param) -> Option<f64> {
    cal.standing_offset(param)?;
    let tau = stand_torque(param)?;
    let estimated = |suffix: &str| {
        Param::from_name(&format!("{}{suffix}", param.name()))
            .filter(|p| cal.get(*p).is_some_and(|e| !e.fixed && e.std.is_some()))
    };
    let mut g = vec![(param, 1.0)];
    g.extend(estimated("Compliance").map(|p| (p, tau)));
    let sign = if tau == 0.0 { 0.0 } else { tau.signum() };
    g.extend(estimated("Play").map(|p| (p, 0.5 * sign)));
    let c = &solution.covariance;
    let variance: f64 = g
        .iter()
        .flat_map(|&(a, ga)| {
            g.iter()
                .map(move |&(b, gb)| ga * gb * c[(a.index(), b.index())])
        })
        .sum();
    Some(param.unit().to_report(variance.max(0.0).sqrt()))
}

impl Calibration {
    /// captures of `dataset` (lying, the board of that leg in view): how far the standing
    /// torque extrapolates the compliance estimated from them.
    pub fn with_lying_torques(mut self, dataset: &crate::dataset::Dataset) -> Self {
        use crate::model::{Side, gravity};
        for side in [Side::Left, Side::Right] {
            let mut largest = [0.0f64; 6];
            for c in dataset.captures.iter().filter(|c| c.side == side) {
                let tau = gravity::leg_torques(
                    &dataset.model.robot,
                    &dataset.model.board,
                    side,
                    &c.joints,
                );
                for (m, t) in largest.iter_mut().zip(tau) {
                    *m = m.max(t.abs());
                }
            }
            for (joint, m) in side.leg_joints().into_iter().zip(largest) {
                if self.standing_offset(joint.offset()).is_some() {
                    self.standing
                        .entry(joint.offset())
                        .or_default()
                        .lying_torque = Some(m);
                }
            }
        }
        self
    }

    /// The one-sigma (deg) of [`Calibration::standing_offset`] of `param`, when known.
    pub fn standing_std(&self, param: Param) -> Option<f64> {
        self.standing_offset(param)?;
        self.standing.get(&param)?.std
    }

    /// Why the standing offset of `param` is less certain than [`STANDING_TARGET_DEG`], or
    /// rests on a compliance extrapolated beyond [`EXTRAPOLATION_LIMIT`] times its lying
    /// torques (`None` when neither): the joint, the reason and its one-sigma.
    pub fn standing_caveat(&self, param: Param) -> Option<String> {
        self.standing_offset(param)?;
        let tau = stand_torque(param)?;
        let info = self.standing.get(&param).copied().unwrap_or_default();
        let compliance = Param::from_name(&format!("{}Compliance", param.name()))
            .and_then(|p| self.get(p))
            .is_some_and(|e| !e.fixed && e.std.is_some());
        // σ falls as 1/√captures: how many times the captures would reach the target.
        let sigma = match info.std {
            None => "σ unknown".to_string(),
            Some(s) if s > STANDING_TARGET_DEG => format!(
                "±{s:.3}° (about {:.1}× the captures would reach ±{STANDING_TARGET_DEG}°)",
                (s / STANDING_TARGET_DEG).powi(2)
            ),
            Some(s) => format!("±{s:.3}°"),
        };
        let extrapolated = info
            .lying_torque
            .filter(|&m| compliance && tau.abs() > EXTRAPOLATION_LIMIT * m);
        if let Some(m) = extrapolated {
            let factor = if m > 0.0 {
                format!("×{:.0}", tau.abs() / m)
            } else {
                "from no torque at all".to_string()
            };
            return Some(format!(
                "{param}: compliance determined only up to {m:.3} N·m lying, extrapolated \
                 {factor} to the stand's {:.2} N·m: standing offset {sigma}",
                tau.abs()
            ));
        }
        match info.std {
            Some(s) if s > STANDING_TARGET_DEG => Some(format!(
                "{param}: standing offset {sigma}, beyond the {STANDING_TARGET_DEG}° target"
            )),
            _ => None,
        }
    }

    /// Every standing leg offset with what it rests on, in registry order: what the
    /// calibration file's `[standing]` table and the result JSON's `standing` carry.
    pub fn standing_files(&self) -> Vec<(Param, StandingFile)> {
        self.parameters
            .iter()
            .filter_map(|e| {
                let value = self.standing_offset(e.param)?;
                let info = self.standing.get(&e.param).copied().unwrap_or_default();
                Some((
                    e.param,
                    StandingFile {
                        value,
                        std: info.std,
                        tau_stand: stand_torque(e.param),
                        tau_lying_max: info.lying_torque,
                    },
                ))
            })
            .collect()
    }

    /// [`Calibration::standing_caveat`] of every leg offset that has one.
    pub fn standing_caveats(&self) -> Vec<String> {
        self.parameters
            .iter()
            .filter_map(|e| self.standing_caveat(e.param))
            .collect()
    }

    /// The effective offset (deg) of the leg joint whose offset is `param` for a robot in
    /// the standard stand: `α + κ·τ_stand + ½π·sgn τ_stand` with the compliance `κ` and
    /// play `π` this calibration estimated (zero when held or not determined) — `None` when
    /// `param` is no leg offset, or when neither compliance nor play was estimated (the
    /// standing offset is then `α` itself).
    pub fn standing_offset(&self, param: Param) -> Option<f64> {
        let tau = stand_torque(param)?;
        let alpha = self.get(param)?.value;
        // Only compliance and play this calibration estimated: held values (a robot's
        // imported jointPlay, say) are already in the offsets its file holds.
        let other = |suffix: &str| {
            Param::from_name(&format!("{}{suffix}", param.name()))
                .and_then(|p| self.get(p))
                .filter(|e| !e.fixed && e.std.is_some())
                .map_or(0.0, |e| e.value)
        };
        let (kappa, play) = (other("Compliance"), other("Play"));
        if kappa == 0.0 && play == 0.0 {
            return None;
        }
        let sign = if tau > 0.0 {
            1.0
        } else if tau < 0.0 {
            -1.0
        } else {
            0.0
        };
        Some(alpha + kappa * tau + 0.5 * play * sign)
    }

    /// The leg offsets for a robot in the standard stand beside the lying ones (when
    /// compliance or play have values; empty otherwise): `(offset, lying α, standing α +
    /// κ·τ_stand + ½π·sgn τ_stand, its one-sigma)` ([`Calibration::standing_offset`],
    /// [`Calibration::standing_std`]).
    pub fn standing_rows(&self) -> Vec<(Param, f64, f64, Option<f64>)> {
        self.parameters
            .iter()
            .filter_map(|e| {
                let s = self.standing_offset(e.param)?;
                Some((e.param, e.value, s, self.standing_std(e.param)))
            })
            .collect()
    }

    /// [`Calibration::standing_rows`] in one line, `LHipPitch 0.1234 ± 0.0100°, …` (`None`
    /// when there are none): what `export` and `solve --export` log for the team files.
    pub fn standing_summary(&self) -> Option<String> {
        let rows = self.standing_rows();
        (!rows.is_empty()).then(|| {
            rows.iter()
                .map(|(p, _, v, s)| match s {
                    Some(s) => format!("{p} {v:.4} ± {s:.4}°"),
                    None => format!("{p} {v:.4}°"),
                })
                .collect::<Vec<_>>()
                .join(", ")
        })
    }

    /// What `export` and `solve --export` say of the standing leg offsets before writing
    /// team files: the [`Calibration::standing_summary`] and a warning for every
    /// [`Calibration::standing_caveats`], one line each.
    pub fn standing_notes(&self) -> Vec<String> {
        let mut notes: Vec<String> = self
            .standing_summary()
            .map(|summary| {
                format!(
                    "standing leg offsets for the team files (α + κ·τ_stand + ½π·sgn τ_stand): {summary}"
                )
            })
            .into_iter()
            .collect();
        notes.extend(
            self.standing_caveats()
                .into_iter()
                .map(|caveat| format!("warning: standing leg offset {caveat}")),
        );
        notes
    }
}
