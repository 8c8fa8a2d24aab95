//! What `naocalib solve` prints on standard output, and its exit code.

use crate::run::Run;

use super::{ResultJson, run_text};

/// The line that ends the text of a run whose captures `solve --detect`'s guard marked.
pub const MARKED: &str =
    "MARKED: captures with residuals many times the others' (see the warnings above)\n";

/// What `solve` prints of `run`: its JSON (docs/MODEL.md §8) with `json`, else its text,
/// ending in [`MARKED`] when the run is `marked`.
pub fn solve_output(run: &Run, json: bool, marked: bool) -> Result<String, serde_json::Error> {
    Ok(if json {
        let value = ResultJson::from_run(run).to_value();
        format!("{}\n", serde_json::to_string_pretty(&value)?)
    } else if marked {
        format!("{}{MARKED}", run_text(run))
    } else {
        run_text(run)
    })
}

/// The exit code of `solve`: 0 for a calibration, 3 for a result that is not one (not
/// converged, non-finite, implausible residuals) or a `marked` run.
pub fn solve_exit_code(run: &Run, marked: bool) -> u8 {
    if run.solution.is_calibration() && !marked {
        0
    } else {
        3
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dataset::Dataset;
    use crate::run::{RunOptions, calibrate};
    use std::path::Path;

    #[test]
    fn a_marked_run_says_so_and_exits_3() {
        let dataset = Dataset::load(Path::new("data/sample")).unwrap();
        let run = calibrate(&dataset, &RunOptions::default()).unwrap();
        assert_eq!(solve_exit_code(&run, false), 0);
        assert_eq!(solve_exit_code(&run, true), 3);
        let text = solve_output(&run, false, false).unwrap();
        assert_eq!(text, run_text(&run));
        let marked = solve_output(&run, false, true).unwrap();
        assert_eq!(marked, format!("{text}{MARKED}"));
        let json = solve_output(&run, true, true).unwrap();
        assert!(
            json.starts_with("{\n") && !json.contains("MARKED"),
            "{json}"
        );
    }
}
