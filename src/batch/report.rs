//! The reports of a batch: the text table (the paper's Table 2), the JSON, and the files of
//! `--out`.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use serde_json::{Map, Value, json};

use super::drift::{DriftMode, DriftOptions, DriftPair, Grouping};
use super::{Batch, Run};
use crate::dataset::dataset_files;
use crate::export::ExportError;
use crate::output::{WriteOptions, write_atomic};
use crate::report::ResultJson;

/// Most runs shown as columns of the text table; with more, only the summary columns are
/// shown (every run is in the JSON).
pub const MAX_RUN_COLUMNS: usize = 8;

/// The files [`Batch::write`] wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct OutputFiles {
    /// One result JSON per run, in the order of [`Batch::runs`].
    pub runs: Vec<PathBuf>,
    /// The summary JSON (runs, failures, statistics, drift).
    pub summary: PathBuf,
}

/// File names for the runs' result JSON: the dataset directory's name plus `.json`, made
/// unique with the parent directory's name and then a number.
pub fn run_file_names(runs: &[Run]) -> Vec<String> {
    let base = |p: &Path, with_parent: bool| {
        let name = p
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| "run".into());
        let parent = p
            .parent()
            .and_then(Path::file_name)
            .map(|n| n.to_string_lossy().into_owned());
        match parent {
            Some(parent) if with_parent => format!("{parent}_{name}"),
            _ => name,
        }
    };
    let simple: Vec<String> = runs.iter().map(|r| base(r.dataset(), false)).collect();
    let mut names: Vec<String> = Vec::new();
    for (i, run) in runs.iter().enumerate() {
        let clash = simple.iter().filter(|s| **s == simple[i]).count() > 1;
        let mut name = if clash {
            base(run.dataset(), true)
        } else {
            simple[i].clone()
        };
        if name == "summary" {
            name = "run_summary".into();
        }
        let mut candidate = name.clone();
        let mut k = 2;
        while names.contains(&candidate) {
            candidate = format!("{name}-{k}");
            k += 1;
        }
        names.push(candidate);
    }
    names.into_iter().map(|n| format!("{n}.json")).collect()
}

/// The JSON of a batch (`naocalib batch --json`): every run's result JSON, the type
/// `naocalib solve --json` prints, and the summary ([`Batch::summary_json`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BatchJson {
    /// Every solved run, in input order.
    pub runs: Vec<ResultJson>,
    /// Counts, per-parameter statistics, failures and drift.
    pub summary: Value,
}

fn fmt_or_dash(x: f64, decimals: usize) -> String {
    if x.is_finite() {
        format!("{x:.decimals$}")
    } else {
        "-".into()
    }
}

impl Batch {
    /// The human-readable report: the runs, one column each (up to
    /// `MAX_RUN_COLUMNS`), then mean ± std across runs and the mean reported one-sigma
    /// per parameter, iterations, RMS and time; then the failures and the drift.
    pub fn table(&self, drift: &DriftOptions) -> String {
        let mut out = String::new();
        let summary = self.summary();
        let runs = &self.runs;
        let columns = runs.len() <= MAX_RUN_COLUMNS;
        if !runs.is_empty() {
            let _ = writeln!(out, "runs:");
            for (i, run) in runs.iter().enumerate() {
                let s = &run.solution.summary;
                let _ = writeln!(
                    out,
                    "  {:>3}  {}{}",
                    i + 1,
                    run.dataset().display(),
                    if s.converged { "" } else { "  (NOT converged)" }
                );
            }
            let _ = write!(out, "\n{:<14} {:<4}", "parameter", "unit");
            if columns {
                for i in 0..runs.len() {
                    let _ = write!(out, " {:>10}", i + 1);
                }
            }
            let _ = writeln!(out, " {:>21} {:>9}", "mean ± std", "mean σ");
            for st in &summary.parameters {
                let p = st.param;
                let _ = write!(out, "{:<14} {:<4}", p.name(), p.unit().name());
                if columns {
                    for run in runs {
                        let cell = if !run.solution.fixed.in_model(p) {
                            // A run without upper-camera captures has no upper camera.
                            "–".to_string()
                        } else if run.solution.fixed.is_fixed(p) {
                            "fixed".to_string()
                        } else if !super::stats::determined(&run.solution, p) {
                            // Free, but not determined by this run's data: its start value.
                            "undet.".to_string()
                        } else {
                            format!("{:.4}", run.solution.report_value(p))
                        };
                        let _ = write!(out, " {cell:>10}");
                    }
                }
                let ms = if st.n == 0 && runs.iter().any(|r| !r.solution.fixed.is_fixed(p)) {
                    "undet.".to_string()
                } else if st.n == 0 {
                    "fixed".to_string()
                } else {
                    format!("{:.4} ± {}", st.mean, fmt_or_dash(st.std, 4))
                };
                let _ = writeln!(out, " {ms:>21} {:>9}", fmt_or_dash(st.mean_sigma, 4));
            }
            let row = |out: &mut String,
                       name: &str,
                       unit: &str,
                       f: &dyn Fn(&Run) -> String,
                       mean: String| {
                let _ = write!(out, "{name:<14} {unit:<4}");
                if columns {
                    for run in runs {
                        let _ = write!(out, " {:>10}", f(run));
                    }
                }
                let _ = writeln!(out, " {mean:>21}");
            };
            row(
                &mut out,
                "iterations",
                "",
                &|r| r.solution.summary.iterations.to_string(),
                format!("{:.1}", summary.iterations),
            );
            row(
                &mut out,
                "rms x",
                "px",
                &|r| format!("{:.5}", r.solution.rms_px[0]),
                format!("{:.5}", summary.rms_px[0]),
            );
            row(
                &mut out,
                "rms y",
                "px",
                &|r| format!("{:.5}", r.solution.rms_px[1]),
                format!("{:.5}", summary.rms_px[1]),
            );
            row(
                &mut out,
                "time",
                "ms",
                &|r| format!("{:.1}", r.solution.seconds * 1e3),
                format!("{:.1}", summary.seconds * 1e3),
            );
            if !columns {
                let _ = writeln!(
                    out,
                    "({} runs: per-run values are in --json and --out)",
                    runs.len()
                );
            }
        }
        let _ = writeln!(
            out,
            "\n{} solved ({} converged), {} failed",
            runs.len(),
            summary.converged,
            self.failures.len()
        );
        for f in &self.failures {
            let _ = writeln!(out, "FAILED {}: {}", f.dataset.display(), f.error);
        }
        let pairs = self.drift(drift);
        if !pairs.is_empty() {
            let _ = writeln!(
                out,
                "\ndrift ({}, flagged when |z| > {}; z = Δ / √(σ₁² + σ₂²)):",
                match drift.mode {
                    DriftMode::Consecutive => "each run vs the one before",
                    DriftMode::First => "each run vs the first",
                },
                drift.threshold
            );
            for pair in &pairs {
                let flagged: Vec<_> = pair.flagged().collect();
                let _ = writeln!(
                    out,
                    "  run {} → run {}{}: {}",
                    pair.from + 1,
                    pair.to + 1,
                    if drift.grouping == Grouping::Parent {
                        format!(" ({})", pair.robot)
                    } else {
                        String::new()
                    },
                    if flagged.is_empty() {
                        "no parameter changed beyond its uncertainty".to_string()
                    } else {
                        format!("{} changed", flagged.len())
                    }
                );
                for d in flagged {
                    let _ = writeln!(
                        out,
                        "      {:<14} Δ {:>+9.4} {:<3} (σ {:.4}, z {:+.1})",
                        d.param.name(),
                        d.delta,
                        d.param.unit().name(),
                        d.sigma,
                        d.z.unwrap_or(f64::NAN)
                    );
                }
            }
        }
        out
    }

    /// One run's result JSON: docs/MODEL.md §8, as `naocalib solve --json` prints it
    /// ([`ResultJson::from_run`]), keys in alphabetical order.
    pub fn run_json(run: &Run) -> Value {
        ResultJson::from_run(run).to_value()
    }

    /// The summary as JSON: counts, per-parameter statistics, failures and drift (no
    /// per-run results; see [`Batch::json`]).
    pub fn summary_json(&self, drift: &DriftOptions) -> Value {
        let summary = self.summary();
        let mut params = Map::new();
        for st in &summary.parameters {
            let num = |x: f64| if x.is_finite() { json!(x) } else { Value::Null };
            params.insert(
                st.param.name().into(),
                json!({
                    "n": st.n,
                    "mean": num(st.mean),
                    "std": num(st.std),
                    "mean_sigma": num(st.mean_sigma),
                    "min": num(st.min),
                    "max": num(st.max),
                    "unit": st.param.unit().name(),
                }),
            );
        }
        let failures: Vec<Value> = self
            .failures
            .iter()
            .map(|f| json!({"dataset": f.dataset.display().to_string(), "error": f.error.to_string()}))
            .collect();
        let pairs: Vec<Value> = self
            .drift(drift)
            .iter()
            .map(|pair| drift_json(self, pair))
            .collect();
        json!({
            "runs": summary.runs,
            "converged": summary.converged,
            "failed": self.failures.len(),
            "datasets": self.runs.iter().map(|r| r.dataset().display().to_string()).collect::<Vec<_>>(),
            "iterations_mean": summary.iterations,
            "rms_px_mean": summary.rms_px,
            "seconds_mean": summary.seconds,
            "parameters": Value::Object(params),
            "failures": failures,
            "drift": {
                "mode": match drift.mode { DriftMode::Consecutive => "consecutive", DriftMode::First => "first" },
                "threshold": drift.threshold,
                "grouping": match drift.grouping { Grouping::Parent => "parent", Grouping::All => "all", Grouping::None => "none" },
                "pairs": pairs,
            },
        })
    }

    /// The whole batch as JSON ([`BatchJson`]), keys in alphabetical order at every level.
    pub fn json(&self, drift: &DriftOptions) -> Value {
        let batch = BatchJson {
            runs: self.runs.iter().map(ResultJson::from_run).collect(),
            summary: self.summary_json(drift),
        };
        serde_json::to_value(batch).expect("JSON of plain values")
    }

    /// Writes every run's result JSON (names from [`run_file_names`]) and `summary.json`
    /// into `dir`, each atomically. Never writes over a file of any dataset of the batch;
    /// refuses existing files unless `options.force`, checking all before writing any.
    pub fn write(
        &self,
        dir: &Path,
        drift: &DriftOptions,
        options: &WriteOptions,
    ) -> Result<OutputFiles, ExportError> {
        let options = options.clone().protecting(self.input_files());
        let names = run_file_names(&self.runs);
        let runs: Vec<PathBuf> = names.iter().map(|n| dir.join(n)).collect();
        let summary = dir.join("summary.json");
        // Check everything first, so that a refusal leaves nothing half-written.
        for path in runs.iter().chain([&summary]) {
            crate::output::check_writable(path, &options)?;
        }
        // All or nothing: written into a stage beside `dir` and published at the end, so
        // that a kill or a full disk part-way leaves `dir` as it was.
        let stage = crate::output::Staged::new(dir, &options)?;
        let staged = stage.options();
        for (run, name) in self.runs.iter().zip(&names) {
            let text = pretty(&Batch::run_json(run));
            write_atomic(&stage.dir().join(name), text.as_bytes(), &staged)?;
        }
        write_atomic(
            &stage.dir().join("summary.json"),
            pretty(&self.summary_json(drift)).as_bytes(),
            &staged,
        )?;
        stage.publish()?;
        Ok(OutputFiles { runs, summary })
    }

    /// The files of every dataset of the batch (solved or failed), which no output may
    /// replace.
    pub fn input_files(&self) -> Vec<PathBuf> {
        self.runs
            .iter()
            .map(|r| r.dataset())
            .chain(self.failures.iter().map(|f| f.dataset.as_path()))
            .flat_map(dataset_files)
            .collect()
    }
}

fn pretty(value: &Value) -> String {
    let mut s = serde_json::to_string_pretty(value).expect("JSON of plain values");
    s.push('\n');
    s
}

fn drift_json(batch: &Batch, pair: &DriftPair) -> Value {
    let mut params = Map::new();
    for d in &pair.params {
        params.insert(
            d.param.name().into(),
            json!({
                "delta": d.delta,
                "sigma": d.sigma,
                "z": d.z,
                "flagged": d.flagged,
                "unit": d.param.unit().name(),
            }),
        );
    }
    json!({
        "robot": pair.robot,
        "from": batch.runs[pair.from].dataset().display().to_string(),
        "to": batch.runs[pair.to].dataset().display().to_string(),
        "flagged": pair.flagged().map(|d| d.param.name()).collect::<Vec<_>>(),
        "parameters": Value::Object(params),
    })
}

impl Batch {
    /// Writes the batch's plots into `dir`: `parameters` (estimates with error bars across
    /// the runs) and for every run `<name>_residuals` and `<name>_captures` (names as in
    /// [`run_file_names`]), PNG and SVG each. Returns the files written.
    pub fn plots(
        &self,
        dir: &Path,
        options: &WriteOptions,
    ) -> Result<Vec<PathBuf>, crate::report::plot::PlotError> {
        use crate::report::plot;
        let options = options.clone().protecting(self.input_files());
        // All or nothing: drawn into a stage beside `dir`, published at the end.
        let stage = crate::output::Staged::new(dir, &options)?;
        let staged = stage.options();
        let solutions: Vec<_> = self.runs.iter().map(|r| &r.solution).collect();
        let named = |e| crate::report::files::staged_plot_error(e, &stage);
        if !solutions.is_empty() {
            plot::parameter_estimates(&solutions, &stage.dir().join("parameters"), &staged)
                .map_err(named)?;
        }
        for (run, name) in self.runs.iter().zip(run_file_names(&self.runs)) {
            let prefix = name.trim_end_matches(".json");
            plot::solution_plots(
                &run.solution,
                Some(&run.sides),
                stage.dir(),
                prefix,
                &staged,
            )
            .map_err(named)?;
        }
        Ok(stage.publish()?)
    }
}
