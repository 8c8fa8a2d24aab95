//! The files `naocalib batch` writes beside its printout: every run's result JSON and the
//! summary (`--out`), plots and the HTML report; each checked against every dataset's files
//! before anything is solved ([`BatchFiles::check`]), never written over an input.

use std::path::{Path, PathBuf};

use super::{Batch, DriftOptions};
use crate::export::ExportError;
use crate::output::{WriteError, WriteOptions};
use crate::report::html::ReportError;
use crate::report::plot::PlotError;

/// Why a batch's files could not be written (each names its flag).
#[derive(Debug, thiserror::Error)]
pub enum BatchFilesError {
    /// An output would replace an input or an existing file, or has a file in its way.
    #[error(transparent)]
    Check(#[from] WriteError),
    /// The run results and summary.
    #[error("--out")]
    Out(#[source] ExportError),
    /// The plots.
    #[error("--plots")]
    Plots(#[source] PlotError),
    /// The HTML report.
    #[error("--report")]
    Report(#[source] ReportError),
}

/// Which files a batch is written to, each optional.
#[derive(Debug, Clone, Default)]
pub struct BatchFiles {
    /// Every run's result JSON and `summary.json` into this directory ([`Batch::write`]).
    pub out: Option<PathBuf>,
    /// Plots into this directory ([`Batch::plots`]).
    pub plots: Option<PathBuf>,
    /// The HTML report of every run into this file.
    pub report: Option<PathBuf>,
    /// Replace existing files (never a dataset's).
    pub force: bool,
}

impl BatchFiles {
    /// Checks every output against the files of the datasets in `datasets` (and against
    /// existing files unless [`BatchFiles::force`]), before anything is solved.
    pub fn check(&self, datasets: &[PathBuf]) -> Result<(), WriteError> {
        crate::output::check_outputs(
            &self.report.as_deref().into_iter().collect::<Vec<_>>(),
            &self
                .out
                .iter()
                .chain(&self.plots)
                .map(PathBuf::as_path)
                .collect::<Vec<_>>(),
            &self.options(datasets.iter().map(PathBuf::as_path)),
        )
    }

    /// The write options protecting the files of `datasets`.
    fn options<'a>(&self, datasets: impl Iterator<Item = &'a Path>) -> WriteOptions {
        WriteOptions::new(self.force).protecting(
            datasets
                .flat_map(crate::dataset::dataset_files)
                .collect::<Vec<_>>(),
        )
    }

    /// Writes the files of `batch` (drift as `drift` says); `note` is told, one line each,
    /// what was written.
    pub fn write(
        &self,
        batch: &Batch,
        drift: &DriftOptions,
        note: &mut dyn FnMut(&str),
    ) -> Result<(), BatchFilesError> {
        let options = WriteOptions::new(self.force).protecting(batch.input_files());
        if let Some(dir) = &self.out {
            let files = batch
                .write(dir, drift, &options)
                .map_err(BatchFilesError::Out)?;
            note(&format!(
                "wrote {} run results and {}",
                files.runs.len(),
                files.summary.display()
            ));
        }
        if let Some(dir) = &self.plots {
            let files = batch.plots(dir, &options).map_err(BatchFilesError::Plots)?;
            note(&format!(
                "wrote {} plot files into {}",
                files.len(),
                dir.display()
            ));
        }
        if let Some(path) = &self.report {
            super::html::write_batch_report(batch, drift, path, &options)
                .map_err(BatchFilesError::Report)?;
            note(&format!("wrote {}", path.display()));
        }
        Ok(())
    }
}
