//! Batch solving: many datasets in parallel, summary statistics across runs (the paper's
//! Table 2), and drift between runs of the same robot.
//!
//! - [`find_datasets`] turns arguments into dataset directories: a directory holding
//!   `captures.csv` or `dataset.toml` is a dataset, any other directory stands for its
//!   immediate subdirectories that are datasets.
//! - [`solve_dirs`] (from disk) and [`solve_datasets`] (in memory) solve every dataset on
//!   all cores into its [`Run`], each exactly as `naocalib solve` does
//!   ([`crate::run::calibrate`] with [`BatchOptions::run`]); a broken dataset becomes a
//!   [`Failure`] with its reason and never stops the batch.
//! - [`Batch::summary`] gives mean ± std across runs and the mean reported one-sigma
//!   ([`stats`]); [`Batch::drift`] the z-scores of the changes between runs ([`mod@drift`]).
//! - [`Batch::table`] and [`Batch::json`] are the reports (every run's JSON is its
//!   [`crate::report::ResultJson`], as `solve --json` prints it); [`Batch::write`] writes
//!   every run's result JSON and the summary into a directory, atomically; [`BatchFiles`] is
//!   the policy of `naocalib batch`'s files.
//!
//! ```
//! use naocalib::batch::{BatchOptions, solve_datasets};
//! use naocalib::model::Model;
//! use naocalib::sim::{SimOptions, simulate};
//!
//! let datasets: Vec<_> = (1..=2)
//!     .map(|seed| {
//!         let options = SimOptions { seed, stances: 4, heads: 2, ..SimOptions::default() };
//!         let mut d = simulate(&Model::default(), &options).unwrap();
//!         d.dir = format!("nao/run{seed}").into();
//!         d
//!     })
//!     .collect();
//! let mut options = BatchOptions::default();
//! options.run.solver = "lm".into();
//! let batch = solve_datasets(&datasets, &options, &|_| {});
//! assert_eq!(batch.runs.len(), 2);
//! assert!(batch.failures.is_empty());
//! let summary = batch.summary();
//! println!("{}", batch.table(&options.drift));
//! # let _ = summary;
//! ```

pub mod drift;
mod files;
mod html;
mod report;
pub mod request;
pub mod stats;

use std::panic::AssertUnwindSafe;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

use crate::dataset::{CAPTURES_CSV, DATASET_TOML, Dataset, DatasetError};
pub use crate::run::Run;
use crate::run::{RunError, RunOptions};
use crate::solve::{Solution, UncertaintyOptions};

pub use drift::{DriftMode, DriftOptions, DriftPair, Grouping, ParamDrift, drift};
pub use files::{BatchFiles, BatchFilesError};
pub use stats::{ParamStats, Summary, summarize};

/// What a batch solves with.
#[derive(Debug, Clone, Default)]
pub struct BatchOptions {
    /// How every dataset is solved: what `naocalib solve` takes from the same flags.
    pub run: RunOptions,
    /// Worker threads; 0 for one per core.
    pub threads: usize,
    /// Drift options for the reports.
    pub drift: DriftOptions,
}

impl BatchOptions {
    /// These options, solving each dataset with `uncertainty` (as `naocalib solve` does
    /// with the corresponding options).
    pub fn with_uncertainty(mut self, uncertainty: UncertaintyOptions) -> Self {
        self.run.uncertainty = uncertainty;
        self
    }
}

/// Why one dataset of a batch has no result.
#[derive(Debug, thiserror::Error)]
pub enum BatchError {
    /// The path is not a dataset, nor a directory holding datasets.
    #[error("{reason}")]
    NotADataset {
        /// The path given.
        path: PathBuf,
        /// Why not.
        reason: String,
    },
    /// The dataset could not be read.
    #[error(transparent)]
    Dataset(#[from] DatasetError),
    /// The dataset could not be solved.
    #[error(transparent)]
    Run(#[from] RunError),
    /// The solve panicked (a bug); the batch goes on.
    #[error("internal error (panic): {0}")]
    Panic(String),
}

/// One dataset that could not be solved.
#[derive(Debug)]
pub struct Failure {
    /// The dataset directory (or the argument that held none).
    pub dataset: PathBuf,
    /// Why.
    pub error: BatchError,
}

/// The outcome of a batch: the solved runs and the failures, each in input order.
#[derive(Debug, Default)]
pub struct Batch {
    /// Solved datasets, in the order they were given (or found).
    pub runs: Vec<Run>,
    /// Datasets (or arguments) without a result, with the reason.
    pub failures: Vec<Failure>,
}

/// How far a batch has got, for a progress display.
#[derive(Debug, Clone, Copy)]
pub struct Progress<'a> {
    /// Datasets finished (solved or failed).
    pub done: usize,
    /// Datasets in the batch.
    pub total: usize,
    /// The dataset just finished.
    pub dataset: &'a Path,
    /// Whether it was solved.
    pub ok: bool,
}

/// Whether `dir` is a dataset directory (holds `captures.csv` or `dataset.toml`).
pub fn is_dataset(dir: &Path) -> bool {
    dir.join(CAPTURES_CSV).is_file() || dir.join(DATASET_TOML).is_file()
}

/// The dataset directories named by `paths`: a dataset directory stands for itself, any
/// other directory for its immediate subdirectories that are datasets (sorted by name).
/// Paths that are neither (missing, a file, a directory without datasets) are returned as
/// failures. A dataset named twice is solved once.
pub fn find_datasets(paths: &[PathBuf]) -> (Vec<PathBuf>, Vec<Failure>) {
    let mut found: Vec<PathBuf> = Vec::new();
    let mut failures = Vec::new();
    // A directory that exists is the same as one found before exactly when it has its
    // device and inode: looked up at once, not compared with every one found.
    let mut seen = std::collections::HashSet::new();
    let mut add = |p: PathBuf, found: &mut Vec<PathBuf>| {
        let fresh = match crate::output::identity(&p) {
            Some(id) => seen.insert(id),
            None => !found.iter().any(|f| crate::output::same_file(f, &p)),
        };
        if fresh {
            found.push(p);
        }
    };
    for path in paths {
        let fail = |reason: String| Failure {
            dataset: path.clone(),
            error: BatchError::NotADataset {
                path: path.clone(),
                reason,
            },
        };
        if !path.is_dir() {
            failures.push(fail(if path.exists() {
                "not a directory".into()
            } else {
                "no such directory".into()
            }));
            continue;
        }
        if is_dataset(path) {
            add(path.clone(), &mut found);
            continue;
        }
        let entries = match std::fs::read_dir(path) {
            Ok(entries) => entries,
            Err(e) => {
                failures.push(fail(format!("cannot list the directory: {e}")));
                continue;
            }
        };
        let mut subdirs: Vec<PathBuf> = entries
            .filter_map(Result::ok)
            .map(|e| e.path())
            .filter(|p| p.is_dir() && is_dataset(p))
            .collect();
        subdirs.sort();
        if subdirs.is_empty() {
            failures.push(fail(format!(
                "not a dataset ({CAPTURES_CSV} and {DATASET_TOML} missing), and no \
                 subdirectory is one"
            )));
        }
        for d in subdirs {
            add(d, &mut found);
        }
    }
    (found, failures)
}

/// Solves the datasets in the directories `dirs` on all cores (see
/// [`crate::run::calibrate`]); `progress` is called after each one. Results are in the
/// order of `dirs`.
pub fn solve_dirs(
    dirs: &[PathBuf],
    options: &BatchOptions,
    progress: &(dyn Fn(Progress<'_>) + Sync),
) -> Batch {
    let results = par_map(dirs, options.threads, progress, |dir: &PathBuf| {
        let dataset = Dataset::load(dir)?;
        Ok(crate::run::calibrate(&dataset, &options.run)?)
    });
    collect(dirs.iter().cloned(), results)
}

/// Solves datasets already in memory on all cores (see [`crate::run::calibrate`]); each run
/// is named by its dataset's [`Dataset::dir`].
pub fn solve_datasets(
    datasets: &[Dataset],
    options: &BatchOptions,
    progress: &(dyn Fn(Progress<'_>) + Sync),
) -> Batch {
    let results = par_map(datasets, options.threads, progress, |dataset: &Dataset| {
        Ok(crate::run::calibrate(dataset, &options.run)?)
    });
    collect(datasets.iter().map(|d| d.dir.clone()), results)
}

/// [`find_datasets`] then [`solve_dirs`]: the whole `naocalib batch` as a library call.
/// Arguments that hold no dataset come first among the failures.
pub fn run(
    paths: &[PathBuf],
    options: &BatchOptions,
    progress: &(dyn Fn(Progress<'_>) + Sync),
) -> Batch {
    let (dirs, mut failures) = find_datasets(paths);
    let mut batch = solve_dirs(&dirs, options, progress);
    failures.append(&mut batch.failures);
    batch.failures = failures;
    batch
}

fn collect(names: impl Iterator<Item = PathBuf>, results: Vec<Result<Run, BatchError>>) -> Batch {
    let mut batch = Batch::default();
    for (dataset, result) in names.zip(results) {
        match result {
            Ok(run) => batch.runs.push(run),
            Err(error) => batch.failures.push(Failure { dataset, error }),
        }
    }
    batch
}

/// A name for items in progress reports.
trait Named {
    fn name(&self) -> &Path;
}

impl Named for PathBuf {
    fn name(&self) -> &Path {
        self
    }
}

impl Named for Dataset {
    fn name(&self) -> &Path {
        &self.dir
    }
}

/// Maps `f` over `items` on `threads` worker threads (0: one per core), taking the next
/// item from a shared counter, so that slow and fast datasets balance out. A panic in `f`
/// becomes a [`BatchError::Panic`] for that item.
fn par_map<T: Named + Sync, R: Send>(
    items: &[T],
    threads: usize,
    progress: &(dyn Fn(Progress<'_>) + Sync),
    f: impl Fn(&T) -> Result<R, BatchError> + Sync,
) -> Vec<Result<R, BatchError>> {
    let threads = if threads == 0 {
        std::thread::available_parallelism().map_or(1, |n| n.get())
    } else {
        threads
    }
    .min(items.len())
    .max(1);
    let next = AtomicUsize::new(0);
    let done = AtomicUsize::new(0);
    let slots: Mutex<Vec<Option<Result<R, BatchError>>>> =
        Mutex::new((0..items.len()).map(|_| None).collect());
    let work = || {
        loop {
            let i = next.fetch_add(1, Ordering::Relaxed);
            let Some(item) = items.get(i) else { break };
            let result = std::panic::catch_unwind(AssertUnwindSafe(|| f(item)))
                .unwrap_or_else(|panic| Err(BatchError::Panic(panic_message(&*panic))));
            let ok = result.is_ok();
            slots.lock().unwrap_or_else(|e| e.into_inner())[i] = Some(result);
            let finished = done.fetch_add(1, Ordering::Relaxed) + 1;
            progress(Progress {
                done: finished,
                total: items.len(),
                dataset: item.name(),
                ok,
            });
        }
    };
    if threads == 1 {
        work();
    } else {
        std::thread::scope(|s| {
            for _ in 0..threads {
                s.spawn(work);
            }
        });
    }
    slots
        .into_inner()
        .unwrap_or_else(|e| e.into_inner())
        .into_iter()
        .map(|slot| slot.unwrap_or_else(|| Err(BatchError::Panic("no result".into()))))
        .collect()
}

fn panic_message(panic: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = panic.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = panic.downcast_ref::<String>() {
        s.clone()
    } else {
        "unknown panic".into()
    }
}

impl Batch {
    /// Whether every dataset was solved.
    pub fn all_solved(&self) -> bool {
        self.failures.is_empty()
    }

    /// Whether every solved run converged.
    pub fn all_converged(&self) -> bool {
        self.runs.iter().all(|r| r.solution.summary.converged)
    }

    /// Mean ± std across the runs and the mean reported one-sigma (see [`summarize`]).
    pub fn summary(&self) -> Summary {
        let solutions: Vec<&Solution> = self.runs.iter().map(|r| &r.solution).collect();
        summarize(&solutions)
    }

    /// The drift between runs of the same robot (see [`drift::batch_drift`]).
    pub fn drift(&self, options: &DriftOptions) -> Vec<DriftPair> {
        drift::batch_drift(&self.runs, options)
    }
}

pub use report::{BatchJson, OutputFiles, run_file_names};

#[cfg(test)]
mod tests {
    use super::*;

    /// A dataset named twice — as itself, through its parent, through a symbolic link and
    /// with `..` in its path — is found once; two datasets stay two.
    #[test]
    fn a_dataset_named_twice_is_found_once() {
        let root = tempfile::tempdir().unwrap();
        let runs = root.path().join("runs");
        for name in ["a", "b"] {
            std::fs::create_dir_all(runs.join(name)).unwrap();
            std::fs::write(runs.join(name).join(CAPTURES_CSV), "").unwrap();
        }
        let link = root.path().join("link");
        #[cfg(unix)]
        std::os::unix::fs::symlink(runs.join("a"), &link).unwrap();
        let mut named = vec![
            runs.join("a"),
            runs.clone(),
            runs.join("b").join("..").join("a"),
        ];
        if cfg!(unix) {
            named.push(link);
        }
        let (found, failures) = find_datasets(&named);
        assert!(failures.is_empty(), "{failures:?}");
        assert_eq!(found, vec![runs.join("a"), runs.join("b")]);
    }
}
