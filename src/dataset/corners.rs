//! `corners.csv`: one row per detected vertex (docs/MODEL.md §7).

use std::collections::HashMap;
use std::path::Path;

use crate::model::{Model, Vertex};

use super::Corner;
use super::csv_table::CsvTable;
use super::error::{DatasetError, Location};
use super::units::csv_float;

/// The columns of `corners.csv`, in the order they are written.
pub(crate) const HEADER: [&str; 5] = ["capture", "row", "col", "u", "v"];

/// Reads the corners from the content of `corners.csv` at `path`.
pub(crate) fn parse(path: &Path, bytes: &[u8]) -> Result<Vec<Corner>, DatasetError> {
    let table = CsvTable::parse(path, bytes)?;
    table.refuse_near_misses(&HEADER)?;
    let [capture, row_col, col_col, u, v] = HEADER.map(|name| table.require(name));
    let (capture, row_col, col_col, u, v) = (capture?, row_col?, col_col?, u?, v?);
    table
        .rows()
        .map(|row| {
            Ok(Corner {
                capture: row.uint(capture, "capture")?,
                vertex: Vertex {
                    row: row.uint(row_col, "row")?,
                    col: row.uint(col_col, "col")?,
                },
                pixel: [row.f64(u, "u")?, row.f64(v, "v")?],
                line: row.line,
            })
        })
        .collect()
}

/// How far outside the image a vertex may lie, as a fraction of the image size: detections
/// are inside it, and a prediction-based or hand-made table a little outside at most.
pub(crate) const PIXEL_BAND: f64 = 1.0;

/// Checks corners in memory: finite pixels and no vertex twice in one capture; with
/// `captures` (id → line in `captures.csv`), that every capture is known, and with `model`,
/// that every vertex is on its board and every pixel within the image ± [`PIXEL_BAND`] (the
/// larger image of a dataset with two cameras).
/// `line` gives the line of each corner (by index).
pub(crate) fn validate(
    path: &Path,
    corners: &[Corner],
    captures: Option<&HashMap<u64, u64>>,
    model: Option<&Model>,
    line: impl Fn(usize, &Corner) -> u64,
) -> Result<(), DatasetError> {
    let mut seen: HashMap<(u64, Vertex), u64> = HashMap::with_capacity(corners.len());
    for (i, corner) in corners.iter().enumerate() {
        let here = line(i, corner);
        let at = |field: &str| Location::line(path, here).field(field);
        if let Some(captures) = captures
            && !captures.contains_key(&corner.capture)
        {
            return Err(DatasetError::invalid(
                at("capture"),
                format!("capture {} is not in captures.csv", corner.capture),
            ));
        }
        if let Some(Model { board, .. }) = model {
            let Vertex { row, col } = corner.vertex;
            if row >= board.rows() {
                return Err(DatasetError::invalid(
                    at("row"),
                    format!(
                        "row {row} is outside the board: a board of {} × {} squares has vertex \
                         rows 0 to {}",
                        board.squares_x,
                        board.squares_y,
                        board.rows().saturating_sub(1)
                    ),
                ));
            }
            if col >= board.cols() {
                return Err(DatasetError::invalid(
                    at("col"),
                    format!(
                        "col {col} is outside the board: a board of {} × {} squares has vertex \
                         columns 0 to {}",
                        board.squares_x,
                        board.squares_y,
                        board.cols().saturating_sub(1)
                    ),
                ));
            }
        }
        // The larger camera's image where the dataset has two cameras.
        let largest = |size: fn(&crate::model::Camera) -> u32| {
            model.map(|m| {
                m.upper_camera
                    .as_ref()
                    .map_or(size(&m.camera), |u| size(u).max(size(&m.camera)))
            })
        };
        for (field, x, size) in [
            ("u", corner.pixel[0], largest(|c| c.width)),
            ("v", corner.pixel[1], largest(|c| c.height)),
        ] {
            if !x.is_finite() {
                return Err(DatasetError::invalid(
                    at(field),
                    format!("{x} is not a finite number"),
                ));
            }
            if let Some(size) = size {
                let size = f64::from(size);
                let (lo, hi) = (-PIXEL_BAND * size, (1.0 + PIXEL_BAND) * size);
                if x < lo || x > hi {
                    return Err(DatasetError::invalid(
                        at(field),
                        format!(
                            "{x} px is outside {lo} … {hi} px (the {size} px of the camera in \
                             dataset.toml, ± 100 %)"
                        ),
                    ));
                }
            }
        }
        if let Some(first) = seen.insert((corner.capture, corner.vertex), here) {
            return Err(DatasetError::invalid(
                at("capture"),
                format!(
                    "capture {}, row {}, col {} is given twice: on line {first} and on line \
                     {here}",
                    corner.capture, corner.vertex.row, corner.vertex.col
                ),
            ));
        }
    }
    Ok(())
}

/// `corners.csv` for `corners` (already validated).
pub(crate) fn render(corners: &[Corner]) -> Result<Vec<u8>, csv::Error> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(HEADER)?;
    for c in corners {
        w.write_record([
            c.capture.to_string(),
            c.vertex.row.to_string(),
            c.vertex.col.to_string(),
            csv_float(c.pixel[0]),
            csv_float(c.pixel[1]),
        ])?;
    }
    w.into_inner().map_err(|e| e.into_error().into())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse_str(text: &str) -> Result<Vec<Corner>, String> {
        parse(Path::new("d/corners.csv"), text.as_bytes()).map_err(|e| e.to_string())
    }

    fn check(text: &str) -> Result<(), String> {
        let corners = parse_str(text)?;
        let captures = HashMap::from([(0, 2), (1, 3)]);
        validate(
            Path::new("d/corners.csv"),
            &corners,
            Some(&captures),
            Some(&Model::default()),
            |_, c| c.line,
        )
        .map_err(|e| e.to_string())
    }

    #[test]
    fn reads_rows_any_column_order() {
        let c =
            parse_str("v,u,extra,col,row,capture\n2.5,1.25,x,5,3,1\n\n-0,1e3,y,0,0,0\n").unwrap();
        assert_eq!(c.len(), 2);
        assert_eq!(
            c[0],
            Corner {
                capture: 1,
                vertex: Vertex { row: 3, col: 5 },
                pixel: [1.25, 2.5],
                line: 2
            }
        );
        assert_eq!(c[1].line, 4);
        assert_eq!(c[1].pixel[0], 1000.0);
        assert!(c[1].pixel[1].is_sign_negative());
        assert!(check("capture,row,col,u,v\n0,3,5,1,1\n1,0,0,2,2\n").is_ok());
    }

    #[test]
    fn errors() {
        let h = "capture,row,col,u,v\n";
        let cases = [
            (
                "capture,row,u,v\n0,0,1,1\n",
                "d/corners.csv line 1, field col: the header has no column 'col'",
            ),
            (
                "0,0,0,1,1\n",
                "d/corners.csv line 1, field capture: the header has no column 'capture'",
            ),
            (
                "capture,row,col,u,v\n0,0,0,1,abc\n",
                "d/corners.csv line 2, field v: 'abc' is not a number",
            ),
            (
                "capture,row,col,u,v\n0,0,0,inf,1\n",
                "d/corners.csv line 2, field u: 'inf' is not a finite number",
            ),
            (
                "capture,row,col,u,v\n0,-1,0,1,1\n",
                "d/corners.csv line 2, field row: must not be negative, got -1",
            ),
            (
                "capture,row,col,u,v\n0,0,0,1,1\n7,0,0,1,1\n",
                "d/corners.csv line 3, field capture: capture 7 is not in captures.csv",
            ),
            (
                "capture,row,col,u,v\n0,4,0,1,1\n",
                "d/corners.csv line 2, field row: row 4 is outside the board: a board of 7 × 5 squares has vertex rows 0 to 3",
            ),
            (
                "capture,row,col,u,v\n0,0,6,1,1\n",
                "d/corners.csv line 2, field col: col 6 is outside the board: a board of 7 × 5 squares has vertex columns 0 to 5",
            ),
            (
                "capture,row,col,u,v\n0,1,2,1,1\n1,1,2,1,1\n\n0,1,2,3,3\n",
                "d/corners.csv line 5, field capture: capture 0, row 1, col 2 is given twice: on line 2 and on line 5",
            ),
        ];
        for (text, expected) in cases {
            assert_eq!(check(text).unwrap_err(), expected);
        }
        assert!(check(h).is_ok());
    }
}
