//! What `naocalib sandal` is asked for: the sandals of a dataset's board (or the paper's)
//! written into a directory, the notes on them and the list of what was written.

use std::path::PathBuf;

use crate::model::Board;
use crate::output::WriteOptions;

use super::{PlateParams, SandalError, SandalFile, files, notes, write};

/// The sandals to make, as `naocalib sandal` is asked for them.
#[derive(Debug, Clone, PartialEq)]
pub struct SandalRequest {
    /// The directory to write the files into.
    pub out_dir: PathBuf,
    /// The dataset.toml whose board the sandals carry (the paper's board without it).
    pub config: Option<PathBuf>,
    /// Replace the files of an earlier run.
    pub force: bool,
}

/// The sandals made and written.
#[derive(Debug, Clone)]
pub struct Made {
    /// The board they carry.
    pub board: Board,
    /// The files written.
    pub files: Vec<SandalFile>,
    /// What to know about them (a sole reaching onto the squares, …).
    pub notes: Vec<String>,
}

/// Makes the sandals of `request` and writes them (all or none; never over the
/// `config` input); a board that cannot be a sandal is placed on its key's line of the
/// file.
pub fn run(request: &SandalRequest) -> Result<Made, SandalError> {
    let board = crate::dataset::read_model_or_unconfigured(request.config.as_deref())?.board;
    let plate = PlateParams::default();
    let in_file = |e: SandalError| match &request.config {
        Some(config) => e.in_file(config),
        None => e,
    };
    let made = files(&board, plate).map_err(in_file)?;
    let options = WriteOptions::new(request.force).protecting(request.config.iter().cloned());
    write(&request.out_dir, &made, &options)?;
    Ok(Made {
        notes: notes(&board, plate).map_err(in_file)?,
        board,
        files: made,
    })
}

/// What `naocalib sandal` prints: the board, every file with what it is, and how to
/// print them.
pub fn summary(request: &SandalRequest, made: &Made) -> String {
    let board = &made.board;
    let mut text = format!(
        "Wrote the sandals for a board of {} × {} squares of {} mm into {}:\n",
        board.squares_x,
        board.squares_y,
        board.square,
        request.out_dir.display()
    );
    let width = made.files.iter().map(|f| f.name.len()).max().unwrap_or(0);
    for f in &made.files {
        text.push_str(&format!("  {:<width$}  {}\n", f.name, f.what));
    }
    text.push_str(
        "Print at 100 % (actual size) and check both 100 mm bars before gluing; \
         docs/SANDALS.md says how to make, mount and check them.\n",
    );
    if request.config.is_none() {
        text.push_str(&board_table(board));
    }
    text
}

/// What to put into the robot's `dataset.toml` for sandals made without `--config`
/// (naocalib's: a `dataset.toml` without `[board]` means the paper's board): their
/// `[board]` table, as `dataset.toml` is written.
fn board_table(board: &Board) -> String {
    let table = crate::dataset::render_board(board)
        .expect("a board's table is plain numbers and serialises");
    format!(
        "These are naocalib's sandals: put their [board] into the robot's dataset.toml (one \
         without [board] means the paper's board):\n{table}"
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_files_are_written_listed_and_never_replaced_without_force() {
        let dir = tempfile::tempdir().unwrap();
        let request = SandalRequest {
            out_dir: dir.path().join("sandals"),
            config: None,
            force: false,
        };
        let made = run(&request).unwrap();
        let text = summary(&request, &made);
        let lines: Vec<&str> = text.lines().collect();
        assert!(lines[0].starts_with("Wrote the sandals for a board of 7 × 5 squares of 25 mm"));
        // The files, the printing advice, and naocalib's [board] to put into dataset.toml.
        assert_eq!(made.board, Board::turned());
        let table = &text[text.find("[board]\n").expect("[board]")..];
        assert_eq!(lines.len(), made.files.len() + 3 + table.lines().count());
        let config = dir.path().join("dataset.toml");
        let camera =
            "[camera]\nwidth = 640\nheight = 480\nfx = 562.5\nfy = 562.5\ncx = 320.0\ncy = 240.0\n";
        std::fs::write(&config, format!("{camera}{table}")).unwrap();
        assert_eq!(
            crate::dataset::read_model(&config).unwrap().board,
            made.board
        );
        for f in &made.files {
            assert!(request.out_dir.join(&f.name).is_file(), "{}", f.name);
            assert!(text.contains(&format!("  {}", f.name)));
        }
        assert!(matches!(run(&request), Err(SandalError::Write(_))));
        let forced = SandalRequest {
            force: true,
            ..request
        };
        assert!(run(&forced).is_ok());
    }
}
