//! The checkerboard sandals a team makes (docs/SANDALS.md): for each foot the pattern to
//! print at 1:1 (SVG, and PDF on each paper size), a drilling and cutting template and a
//! parametric OpenSCAD plate — all drawn from the model's [`Board`], so the printed
//! pattern has the vertex numbering, orientation and offsets the solver assumes.
//!
//! Data flows one way: [`Board`] → [`Sandal`] (geometry in the sole frame) → the drawing
//! (`drawing.rs`, page millimetres) → SVG / PDF; the template and the OpenSCAD source
//! read the [`Sandal`] directly. [`files`] makes every file, [`write()`] writes them
//! together through [`crate::output`].

pub mod drawing;
pub mod geometry;
pub mod pdf;
pub mod request;
mod scad;
mod svg;
mod template;

use std::path::{Path, PathBuf};

use crate::model::{Board, Side};
use crate::output::{Staged, WriteError, WriteOptions};
pub use drawing::{Drawing, Role, SCALE_BAR_MM};
pub use geometry::{
    BORDER_SQUARES, LEFT_FSR, LEFT_SOLE, Pin, PlateParams, Sandal, Slot, fsr_positions,
};
pub use pdf::{PAPERS, Paper};

/// Why no sandal was made.
#[derive(Debug, thiserror::Error)]
pub enum SandalError {
    /// The board cannot be made as a sandal.
    #[error("field {field}: {message}")]
    Board {
        /// The `dataset.toml` key (`board.mount_rpy_deg[0]`).
        field: String,
        /// What is wrong.
        message: String,
    },
    /// The board of a file cannot be made as a sandal: the error names the file, the
    /// line and the key ([`SandalError::in_file`]).
    #[error(transparent)]
    Config(#[from] crate::dataset::DatasetError),
    /// Writing failed (nothing is written then).
    #[error(transparent)]
    Write(#[from] WriteError),
}

impl SandalError {
    /// This error, for a board read from the `dataset.toml` at `config`: a board that
    /// cannot be a sandal is placed on the file's line of its key.
    pub fn in_file(self, config: &Path) -> SandalError {
        match self {
            SandalError::Board { field, message } => {
                SandalError::Config(crate::dataset::DatasetError::invalid(
                    crate::dataset::locate(config, &field),
                    message,
                ))
            }
            e => e,
        }
    }
}

/// One file to write.
#[derive(Debug, Clone, PartialEq)]
pub struct SandalFile {
    /// File name: the foot and, for a PDF, the paper size (`sandal-left-a4.pdf`).
    pub name: String,
    /// What it is, for people.
    pub what: String,
    /// The content.
    pub bytes: Vec<u8>,
}

/// Every file for both feet, left first: the pattern as SVG and as PDF on each of
/// [`PAPERS`], the template (`.txt`) and the OpenSCAD source (`.scad`).
pub fn files(board: &Board, plate: PlateParams) -> Result<Vec<SandalFile>, SandalError> {
    let mut out = Vec::new();
    for side in Side::BOTH {
        let sandal = Sandal::new(board, side, plate)?;
        let name = side.name();
        let title = format!("naocalib sandal · {} foot", name.to_uppercase());
        let drawing = Drawing::of(&sandal);
        out.push(SandalFile {
            name: format!("sandal-{name}.svg"),
            what: format!(
                "the {name} pattern at 1:1 with plate, pins and sole ({} × {} mm)",
                drawing::num(drawing.size[0].round()),
                drawing::num(drawing.size[1].round())
            ),
            bytes: svg::svg(&drawing, &title).into_bytes(),
        });
        for paper in &PAPERS {
            let (bytes, sheets) = pdf::pdf(&drawing, paper, &title);
            let layout = if sheets == 1 {
                "one page".to_string()
            } else {
                format!("{sheets} sheets to join (the drawing exceeds one page)")
            };
            out.push(SandalFile {
                name: format!("sandal-{name}-{}.pdf", paper.name),
                what: format!("the same to print on {}, {layout}", paper.label),
                bytes,
            });
        }
        out.push(SandalFile {
            name: format!("sandal-{name}-template.txt"),
            what: "drilling and cutting dimensions (mm from the ankle's projection)".into(),
            bytes: template::template(&sandal).into_bytes(),
        });
        out.push(SandalFile {
            name: format!("sandal-{name}.scad"),
            what: "parametric OpenSCAD plate with its pins".into(),
            bytes: scad::scad(&sandal).into_bytes(),
        });
    }
    Ok(out)
}

/// What a maker should know about `board` on both feet ([`Sandal::notes`]).
pub fn notes(board: &Board, plate: PlateParams) -> Result<Vec<String>, SandalError> {
    let mut out = Vec::new();
    for side in Side::BOTH {
        out.extend(Sandal::new(board, side, plate)?.notes());
    }
    Ok(out)
}

/// Writes `files` into the directory `dir` together: all of them or none (a staging
/// directory published at the end, [`Staged`]); returns their paths.
pub fn write(
    dir: &Path,
    files: &[SandalFile],
    options: &WriteOptions,
) -> Result<Vec<PathBuf>, SandalError> {
    let staged = Staged::new(dir, options)?;
    for file in files {
        staged.write(Path::new(&file.name), &file.bytes)?;
    }
    Ok(staged.publish()?)
}
