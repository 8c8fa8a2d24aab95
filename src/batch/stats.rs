//! Statistics across runs: per parameter the mean and the sample standard deviation of the
//! estimates (the paper's Table 2, column Ø) and the mean one-sigma the runs reported, so
//! that the scatter the runs show can be compared with the uncertainty they claim.

use crate::model::Param;
use crate::solve::Solution;

/// Statistics of one parameter over the runs, in report units (deg / mm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParamStats {
    /// The parameter.
    pub param: Param,
    /// Runs that determined it ([`determined`]).
    pub n: usize,
    /// Mean of the estimates (NaN when `n` is 0).
    pub mean: f64,
    /// Sample standard deviation of the estimates (`n − 1` in the denominator, as in the
    /// paper's Table 2); NaN when `n < 2`.
    pub std: f64,
    /// Mean of the reported one-sigma (NaN when `n` is 0).
    pub mean_sigma: f64,
    /// Smallest estimate.
    pub min: f64,
    /// Largest estimate.
    pub max: f64,
}

/// Statistics of a batch.
#[derive(Debug, Clone, PartialEq)]
pub struct Summary {
    /// Runs summarised.
    pub runs: usize,
    /// Runs whose solver reported convergence.
    pub converged: usize,
    /// Per parameter: the paper's 21 and every further one estimated in some run.
    pub parameters: Vec<ParamStats>,
    /// Mean iterations.
    pub iterations: f64,
    /// Mean RMS in u and v at the solutions (px).
    pub rms_px: [f64; 2],
    /// Mean wall time of a solve (s).
    pub seconds: f64,
}

impl Summary {
    /// The statistics of `param`, if it is shown.
    pub fn get(&self, param: Param) -> Option<&ParamStats> {
        self.parameters.iter().find(|s| s.param == param)
    }
}

/// Mean and sample standard deviation (`n − 1`); the std is NaN below two values.
pub fn mean_std(values: &[f64]) -> (f64, f64) {
    let n = values.len();
    if n == 0 {
        return (f64::NAN, f64::NAN);
    }
    let mean = values.iter().sum::<f64>() / n as f64;
    if n < 2 {
        return (mean, f64::NAN);
    }
    let var = values.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
    (mean, var.sqrt())
}

/// Whether the run `s` determined `p`: free in it and determined by its data
/// ([`Solution::is_determined`]). A parameter held on purpose, held because its data leave
/// it undetermined, or never observed (the lower camera of an upper-camera-only run) sits
/// at its start value: it takes no part in statistics or drift.
pub fn determined(s: &Solution, p: Param) -> bool {
    !s.fixed.is_fixed(p) && s.is_determined(p)
}

/// Summarises `solutions`: for every parameter estimated in at least one run (and always
/// the paper's 21) the statistics over the runs that determined it ([`determined`]).
pub fn summarize(solutions: &[&Solution]) -> Summary {
    let mut parameters = Vec::new();
    for p in Param::ALL {
        let free: Vec<&&Solution> = solutions.iter().filter(|s| determined(s, p)).collect();
        if free.is_empty() && !solutions.iter().any(|s| s.fixed.is_shown(p)) {
            continue;
        }
        let values: Vec<f64> = free.iter().map(|s| s.report_value(p)).collect();
        let sigmas: Vec<f64> = free.iter().map(|s| s.report_std(p)).collect();
        let (mean, std) = mean_std(&values);
        parameters.push(ParamStats {
            param: p,
            n: values.len(),
            mean,
            std,
            mean_sigma: mean_std(&sigmas).0,
            min: values.iter().copied().fold(f64::NAN, f64::min),
            max: values.iter().copied().fold(f64::NAN, f64::max),
        });
    }
    let mean_of = |f: &dyn Fn(&Solution) -> f64| {
        mean_std(&solutions.iter().map(|s| f(s)).collect::<Vec<_>>()).0
    };
    Summary {
        runs: solutions.len(),
        converged: solutions.iter().filter(|s| s.summary.converged).count(),
        parameters,
        iterations: mean_of(&|s| s.summary.iterations as f64),
        rms_px: [mean_of(&|s| s.rms_px[0]), mean_of(&|s| s.rms_px[1])],
        seconds: mean_of(&|s| s.seconds),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_table_2_column_mean() {
        // CamYaw and LHipPitch of the paper's three runs and its Ø column.
        let (m, s) = mean_std(&[0.4764, 0.4751, 0.4466]);
        assert!(
            (m - 0.4660).abs() < 5e-5 && (s - 0.0168).abs() < 5e-5,
            "{m} {s}"
        );
        let (m, s) = mean_std(&[0.2299, 1.3066, 0.8783]);
        assert!(
            (m - 0.8049).abs() < 5e-5 && (s - 0.5421).abs() < 5e-5,
            "{m} {s}"
        );
    }

    #[test]
    fn degenerate_counts() {
        assert!(mean_std(&[]).0.is_nan());
        let (m, s) = mean_std(&[2.0]);
        assert_eq!(m, 2.0);
        assert!(s.is_nan());
    }
}
