//! What `naocalib batch` makes of its flags and prints: the drift options checked, what
//! goes to standard output (the table, or the JSON with the failures told apart) and the
//! exit code.

use super::{Batch, DriftMode, DriftOptions, Grouping};

/// The drift options: runs compared by `mode`, within the robots of `grouping`, a change
/// flagged beyond |z| = `threshold` (a positive number).
pub fn drift_options(
    mode: DriftMode,
    threshold: f64,
    grouping: Grouping,
) -> Result<DriftOptions, String> {
    if !(threshold.is_finite() && threshold > 0.0) {
        return Err(format!(
            "--drift-threshold must be a positive number, got {threshold}"
        ));
    }
    Ok(DriftOptions {
        mode,
        threshold,
        grouping,
    })
}

/// What a batch prints: the table, or with `json` every run and the summary as JSON and,
/// apart (for standard error), a line per failure.
pub fn printed(
    batch: &Batch,
    drift: &DriftOptions,
    json: bool,
) -> Result<(String, Vec<String>), serde_json::Error> {
    if !json {
        return Ok((batch.table(drift), Vec::new()));
    }
    let text = format!("{}\n", serde_json::to_string_pretty(&batch.json(drift))?);
    let failures = batch
        .failures
        .iter()
        .map(|f| format!("naocalib: {}: {}", f.dataset.display(), f.error))
        .collect();
    Ok((text, failures))
}

/// The exit code of a batch: 0 when every dataset was solved and converged, 2 when some
/// dataset failed, 3 when all were solved but some did not converge.
pub fn exit_code(batch: &Batch) -> u8 {
    if !batch.all_solved() {
        2
    } else if !batch.all_converged() {
        3
    } else {
        0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::batch::{BatchError, Failure};

    #[test]
    fn the_threshold_must_be_positive() {
        let ok = drift_options(DriftMode::First, 2.5, Grouping::All).unwrap();
        assert_eq!(ok.threshold, 2.5);
        assert_eq!(ok.mode, DriftMode::First);
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            let e = drift_options(DriftMode::First, bad, Grouping::All).unwrap_err();
            assert!(
                e.starts_with("--drift-threshold must be a positive number"),
                "{e}"
            );
        }
    }

    #[test]
    fn failures_set_the_exit_code_and_are_told_apart_in_json() {
        let empty = Batch::default();
        assert_eq!(exit_code(&empty), 0);
        let failed = Batch {
            runs: Vec::new(),
            failures: vec![Failure {
                dataset: "ds".into(),
                error: BatchError::Panic("boom".into()),
            }],
        };
        assert_eq!(exit_code(&failed), 2);
        let drift = DriftOptions::default();
        let (text, notes) = printed(&failed, &drift, true).unwrap();
        assert!(text.starts_with('{') && text.ends_with("}\n"), "{text}");
        assert_eq!(notes, ["naocalib: ds: internal error (panic): boom"]);
        let (_, none) = printed(&failed, &drift, false).unwrap();
        assert!(none.is_empty());
    }
}
