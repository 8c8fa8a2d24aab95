//! The files `naocalib solve` writes beside its printout, and the policy they follow: every
//! one checked against the run's inputs before the solve ([`RunFiles::check`]), none ever
//! written over an input, each set all or nothing; a result that is not a calibration gets
//! only naocalib's own calibration TOML/JSON (which say so) and no robot files.

use std::path::{Path, PathBuf};

use super::html::ReportError;
use super::plot::{self, PlotError};
use crate::dataset::Dataset;
use crate::export::{self, ExportError, Withheld};
use crate::output::{Staged, WriteError, WriteOptions};
use crate::run::Run;

/// Why a run's files could not be written (each names its flag).
#[derive(Debug, thiserror::Error)]
pub enum FilesError {
    /// An output would replace an input or an existing file, or has a file in its way.
    #[error(transparent)]
    Check(#[from] WriteError),
    /// The plots.
    #[error("--plots")]
    Plots(#[source] PlotError),
    /// The calibration files.
    #[error("--export")]
    Export(#[source] ExportError),
    /// The HTML report.
    #[error("--report")]
    Report(#[source] ReportError),
}

/// Which files a run is written to, each optional.
#[derive(Debug, Clone, Default)]
pub struct RunFiles {
    /// Plots (PNG and SVG) into this directory: residuals before and after, per capture,
    /// and the misfit pictures.
    pub plots: Option<PathBuf>,
    /// The calibration files into this directory, one per export format.
    pub export: Option<PathBuf>,
    /// The self-contained HTML report into this file.
    pub report: Option<PathBuf>,
    /// Replace existing files (never an input).
    pub force: bool,
    /// Inputs besides the dataset's files that no output may replace (the calibration
    /// the run starts from).
    pub inputs: Vec<PathBuf>,
}

impl RunFiles {
    /// The write options for a run of the dataset in `dataset`: its files and
    /// [`RunFiles::inputs`] protected.
    fn options(&self, dataset: &Path) -> WriteOptions {
        WriteOptions::protecting_dataset(dataset, self.force).protecting(self.inputs.clone())
    }

    /// Checks every output against the inputs of a run of the dataset in `dataset` (and
    /// against existing files unless [`RunFiles::force`]): before the solve, so that a
    /// mistake does not wait for it.
    pub fn check(&self, dataset: &Path) -> Result<(), WriteError> {
        crate::output::check_outputs(
            &self.report.as_deref().into_iter().collect::<Vec<_>>(),
            &self
                .plots
                .iter()
                .chain(&self.export)
                .map(PathBuf::as_path)
                .collect::<Vec<_>>(),
            &self.options(dataset),
        )
    }

    /// Writes the files of `run`, fitted to `dataset`; `note` is told, one line each, what
    /// was written and what was withheld and why.
    pub fn write(
        &self,
        run: &Run,
        dataset: &Dataset,
        note: &mut dyn FnMut(&str),
    ) -> Result<(), FilesError> {
        let options = self.options(&dataset.dir);
        if let Some(dir) = &self.plots {
            let files = plots(run, dataset, dir, &options).map_err(FilesError::Plots)?;
            note(&format!(
                "wrote {} plot files into {}",
                files.len(),
                dir.display()
            ));
        }
        if let Some(dir) = &self.export {
            let calibration = &run.calibration;
            for line in calibration.standing_notes() {
                note(&line);
            }
            let (files, withheld) = export::dir_files(calibration, dir);
            match withheld {
                Withheld::Nothing => {}
                Withheld::JointFiles => note(
                    "warning: the dataset's joint angles were already corrected by the robot's \
                     joint calibration: --export writes no joint files (their offsets are changes \
                     to the robot's file: use `naocalib export --update FILE`)",
                ),
                Withheld::RobotFiles(problems) => note(&format!(
                    "warning: not a calibration ({}); --export writes only calibration.toml and \
                     calibration.json, marked so, and no robot files",
                    problems.join("; ")
                )),
            }
            let files = export::write_files(calibration, &files, Some(dir), &options, false)
                .map_err(FilesError::Export)?;
            for f in files {
                note(&format!("wrote {}", f.display()));
            }
        }
        if let Some(path) = &self.report {
            super::html::write_report(run, dataset, path, &options).map_err(FilesError::Report)?;
            note(&format!("wrote {}", path.display()));
        }
        Ok(())
    }
}

/// `e`, an error of drawing a plot into `stage`, naming the file where it would be
/// published (never the stage).
pub(crate) fn staged_plot_error(e: PlotError, stage: &Staged) -> PlotError {
    match e {
        PlotError::Draw { path, message } => PlotError::Draw {
            path: stage.published(&path),
            message,
        },
        PlotError::Write(e) => PlotError::Write(stage.named(e)),
        e => e,
    }
}

/// The plots of `run` into `dir`, all or nothing: staged beside it, published when every
/// plot is drawn.
fn plots(
    run: &Run,
    dataset: &Dataset,
    dir: &Path,
    options: &WriteOptions,
) -> Result<Vec<PathBuf>, PlotError> {
    let stage = Staged::new(dir, options)?;
    let staged = stage.options();
    plot::solution_plots(
        &run.solution,
        Some(&run.sides),
        stage.dir(),
        "solve",
        &staged,
    )
    .map_err(|e| staged_plot_error(e, &stage))?;
    super::misfit_plot::misfit_plots(&run.solution, dataset, stage.dir(), "misfit", &staged)
        .map_err(|e| staged_plot_error(e, &stage))?;
    Ok(stage.publish()?)
}
