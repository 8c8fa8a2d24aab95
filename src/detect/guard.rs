//! The guard of `solve --detect`: captures whose residuals after the fit are many times the
//! others' (a board numbered wrongly turns good images into wrong data that the fit
//! averages in) are named, so the run can be marked.

use std::collections::BTreeMap;

use crate::solve::Solution;

/// A capture's residual RMS beyond this many times the median capture's marks it.
pub const SUSPECT_RATIO: f64 = 5.0;
/// Below this RMS (px) no capture is marked, whatever the ratio.
pub const SUSPECT_FLOOR_PX: f64 = 1.0;

/// A capture whose residuals stand out.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Suspect {
    /// The capture id.
    pub capture: u64,
    /// Its RMS residual after the fit (px, per coordinate).
    pub rms_px: f64,
    /// The median of all captures' RMS (px).
    pub median_px: f64,
}

impl std::fmt::Display for Suspect {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "capture {}: residual RMS {:.2} px after the fit, {:.0}× the median capture's {:.3} px \
             (a board numbered wrongly, or a bad image?)",
            self.capture,
            self.rms_px,
            self.rms_px / self.median_px.max(1e-12),
            self.median_px
        )
    }
}

/// The RMS residual (px, per coordinate) of every capture after the fit, by capture id.
pub fn capture_rms(solution: &Solution) -> BTreeMap<u64, f64> {
    let mut sums: BTreeMap<u64, (f64, usize)> = BTreeMap::new();
    for r in &solution.residuals {
        let e = sums.entry(r.capture).or_default();
        e.0 += r.solved[0].powi(2) + r.solved[1].powi(2);
        e.1 += 2;
    }
    sums.into_iter()
        .map(|(c, (s, n))| (c, (s / n as f64).sqrt()))
        .collect()
}

/// The captures whose RMS residual after the fit is more than [`SUSPECT_RATIO`] times the
/// median capture's and more than [`SUSPECT_FLOOR_PX`], worst first.
pub fn suspects(solution: &Solution) -> Vec<Suspect> {
    let rms = capture_rms(solution);
    let mut values: Vec<f64> = rms.values().copied().collect();
    if values.len() < 3 {
        return Vec::new();
    }
    values.sort_by(f64::total_cmp);
    let median_px = values[values.len() / 2];
    let mut out: Vec<Suspect> = rms
        .into_iter()
        .filter(|(_, r)| *r > SUSPECT_RATIO * median_px && *r > SUSPECT_FLOOR_PX)
        .map(|(capture, rms_px)| Suspect {
            capture,
            rms_px,
            median_px,
        })
        .collect();
    out.sort_by(|a, b| b.rms_px.total_cmp(&a.rms_px));
    out
}
