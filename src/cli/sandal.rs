//! `naocalib sandal`: write the files to make the checkerboard sandals.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use clap::Args;

use naocalib::model::Board;
use naocalib::output::WriteOptions;
use naocalib::sandal::{self, PlateParams};

use super::print_out;

#[derive(Debug, Args)]
pub struct SandalArgs {
    /// Directory to write the files into (created if missing).
    out_dir: PathBuf,
    /// The dataset.toml whose [board] describes the sandals (default: the paper's board,
    /// 7 × 5 squares of 25 mm centred 170 mm ahead of the ankle).
    #[arg(long, value_name = "DATASET_TOML")]
    config: Option<PathBuf>,
    /// Replace the files of an earlier run in OUT_DIR.
    #[arg(long)]
    force: bool,
}

/// Runs `naocalib sandal`.
pub fn run(args: &SandalArgs) -> Result<ExitCode> {
    let board = match &args.config {
        Some(path) => naocalib::dataset::read_model(path)?.board,
        None => Board::default(),
    };
    let plate = PlateParams::default();
    let in_file = |e: sandal::SandalError| match &args.config {
        Some(config) => e.in_file(config),
        None => e,
    };
    let files = sandal::files(&board, plate).map_err(in_file)?;
    let options = WriteOptions::new(args.force).protecting(args.config.iter().cloned());
    sandal::write(&args.out_dir, &files, &options)?;
    for n in sandal::notes(&board, plate).map_err(in_file)? {
        note!("naocalib sandal: note: {n}");
    }
    let mut text = format!(
        "Wrote the sandals for a board of {} × {} squares of {} mm into {}:\n",
        board.squares_x,
        board.squares_y,
        board.square,
        args.out_dir.display()
    );
    let width = files.iter().map(|f| f.name.len()).max().unwrap_or(0);
    for f in &files {
        text.push_str(&format!("  {:<width$}  {}\n", f.name, f.what));
    }
    text.push_str(
        "Print at 100 % (actual size) and check both 100 mm bars before gluing; \
         docs/SANDALS.md says how to make, mount and check them.\n",
    );
    print_out(text)?;
    Ok(ExitCode::SUCCESS)
}
