//! `naocalib batch --report FILE.html`: one self-contained page of a batch, made of the
//! parts of `solve --report` (`crate::report::html`): the summary table, the estimates
//! across runs, and each run's section.

use std::fmt::Write as _;
use std::path::Path;

use super::Batch;
use super::drift::DriftOptions;
use crate::output::{WriteOptions, write_atomic};
use crate::report::html::{self, ReportError};
use crate::report::plot;
use crate::solve::Solution;

/// The report of a batch: the summary table, the estimates across runs, and each run's
/// section (without overlays, which would need every dataset's images).
pub fn batch_page(batch: &Batch, drift: &DriftOptions) -> Result<String, ReportError> {
    let mut out = String::new();
    html::page_start(
        &mut out,
        &format!(
            "naocalib batch of {} datasets",
            batch.runs.len() + batch.failures.len()
        ),
    );
    out.push_str("<h2>Summary</h2>\n<div class=\"diag\">");
    out.push_str(&html::escape(&batch.table(drift)));
    out.push_str("</div>\n");
    if !batch.runs.is_empty() {
        let runs: Vec<&Solution> = batch.runs.iter().map(|r| &r.solution).collect();
        let svg = plot::parameter_estimates_svg(&runs)?;
        let _ = writeln!(
            out,
            "<figure id=\"estimates\">{}<figcaption>Estimates of every run with ±1σ.\
             </figcaption></figure>",
            html::inline_svg(&svg)
        );
    }
    for (k, run) in batch.runs.iter().enumerate() {
        html::run_section(&mut out, run, format!("-{}", k + 1))?;
    }
    html::page_end(&mut out);
    Ok(out)
}

/// Writes [`batch_page`] to `path` (atomically; never over an input).
pub fn write_batch_report(
    batch: &Batch,
    drift: &DriftOptions,
    path: &Path,
    options: &WriteOptions,
) -> Result<(), ReportError> {
    let page = batch_page(batch, drift)?;
    Ok(write_atomic(path, page.as_bytes(), options)?)
}
