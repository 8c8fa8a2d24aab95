//! A CSV file with a header, read whole, with true line numbers and columns found by name.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use super::error::{DatasetError, Location};
use super::text::{line_at, parse_f64, parse_uint};

/// A parsed CSV file: its header and its non-blank records, each with its line. The
/// records' trimmed fields are kept in one string (a dataset's `corners.csv` has thousands
/// of short records, and a record each cost an allocation).
#[derive(Debug)]
pub(crate) struct CsvTable {
    path: PathBuf,
    header_line: u64,
    /// Column name → every index it appears at.
    columns: HashMap<String, Vec<usize>>,
    /// Fields per record (the header's).
    width: usize,
    /// Every record's trimmed fields, one after the other.
    text: String,
    /// Where each field ends in `text` (`width` per record; a field starts where the one
    /// before it ends).
    ends: Vec<usize>,
    /// The line each record starts on.
    lines: Vec<u64>,
}

impl CsvTable {
    /// Parses `bytes` (the content of `path`). Fields are trimmed, blank lines skipped, and
    /// every record must have as many fields as the header.
    pub fn parse(path: &Path, bytes: &[u8]) -> Result<CsvTable, DatasetError> {
        let mut reader = csv::ReaderBuilder::new()
            .has_headers(false)
            .flexible(true)
            .from_reader(bytes);
        let mut lines = LineCounter::new(bytes);
        let mut header: Option<(u64, csv::StringRecord)> = None;
        let mut text = String::with_capacity(bytes.len());
        let mut ends = Vec::new();
        let mut lines_of_rows = Vec::new();
        let mut record = csv::StringRecord::new();
        loop {
            match reader.read_record(&mut record) {
                Ok(false) => break,
                Ok(true) => {}
                Err(e) => return Err(csv_error(path, &mut lines, e)),
            }
            let line = lines.line_of_record(record.position().map_or(0, |p| p.byte()));
            // Fields are trimmed where they are read (cheaper than csv's own trimming).
            if record.iter().all(|f| f.trim().is_empty()) {
                continue; // a line of blanks
            }
            match &header {
                None => header = Some((line, std::mem::take(&mut record))),
                Some((_, h)) if record.len() != h.len() => {
                    return Err(DatasetError::invalid(
                        Location::line(path, line),
                        format!(
                            "has {} fields but the header has {} columns",
                            record.len(),
                            h.len()
                        ),
                    ));
                }
                Some(_) => {
                    for field in record.iter() {
                        text.push_str(field.trim());
                        ends.push(text.len());
                    }
                    lines_of_rows.push(line);
                }
            }
        }
        let Some((header_line, header)) = header else {
            return Err(DatasetError::Empty {
                path: path.to_path_buf(),
                hint: String::new(),
            });
        };
        let mut columns: HashMap<String, Vec<usize>> = HashMap::new();
        for (i, name) in header.iter().map(str::trim).enumerate() {
            columns.entry(name.to_string()).or_default().push(i);
        }
        Ok(CsvTable {
            path: path.to_path_buf(),
            header_line,
            columns,
            width: header.len(),
            text,
            ends,
            lines: lines_of_rows,
        })
    }

    /// The index of column `name`, if the header has it; an error if it has it twice.
    pub fn column(&self, name: &str) -> Result<Option<usize>, DatasetError> {
        match self.columns.get(name).map(Vec::as_slice) {
            None | Some([]) => Ok(None),
            Some([i]) => Ok(Some(*i)),
            Some([a, b, ..]) => Err(DatasetError::invalid(
                Location::line(&self.path, self.header_line).field(name),
                format!(
                    "the header has column '{name}' twice (columns {} and {})",
                    a + 1,
                    b + 1
                ),
            )),
        }
    }

    /// The index of column `name`, which the header must have.
    pub fn require(&self, name: &str) -> Result<usize, DatasetError> {
        self.column(name)?.ok_or_else(|| {
            DatasetError::invalid(
                Location::line(&self.path, self.header_line).field(name),
                format!("the header has no column '{name}'"),
            )
        })
    }

    /// Refuses a column that is none of `known` but resembles one of them (see
    /// [`near_miss`]): a header `Camera` or `camra` would otherwise be ignored as an extra
    /// column and every row read as if it had none. Columns that resemble none stay
    /// ignored (arm joints, timestamps). The error names the header line, the column and
    /// the known one it resembles.
    pub fn refuse_near_misses(&self, known: &[&str]) -> Result<(), DatasetError> {
        let mut unknown: Vec<(usize, &str)> = self
            .columns
            .iter()
            .filter(|(name, _)| !known.contains(&name.as_str()))
            .flat_map(|(name, at)| at.iter().map(move |&i| (i, name.as_str())))
            .collect();
        unknown.sort_unstable();
        for (i, name) in unknown {
            if let Some(like) = known.iter().find(|k| near_miss(name, k)) {
                return Err(DatasetError::invalid(
                    Location::line(&self.path, self.header_line).field(name),
                    format!(
                        "column {} '{name}' is not a known column; did you mean '{like}'? \
                         (column names are case-sensitive; a column resembling a known one \
                         is refused rather than ignored)",
                        i + 1
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The records, in file order.
    pub fn rows(&self) -> impl Iterator<Item = Row<'_>> {
        self.lines.iter().enumerate().map(|(k, line)| {
            let first = k * self.width;
            Row {
                path: &self.path,
                line: *line,
                text: &self.text,
                start: if first == 0 { 0 } else { self.ends[first - 1] },
                ends: &self.ends[first..first + self.width],
            }
        })
    }
}

/// Whether the column name `name` is a near miss of the known column `known`: the same
/// once case, `_`, `-` and blanks are set aside, or within a Damerau–Levenshtein distance
/// of 1 (known names of 4 to 6 letters) or 2 (longer ones) of it.
pub(crate) fn near_miss(name: &str, known: &str) -> bool {
    let plain = |s: &str| -> String {
        s.chars()
            .filter(|c| !matches!(c, '_' | '-') && !c.is_whitespace())
            .flat_map(char::to_lowercase)
            .collect()
    };
    let (a, b) = (plain(name), plain(known));
    if a.is_empty() {
        return false;
    }
    let limit = match b.chars().count() {
        0..=3 => 0,
        4..=6 => 1,
        _ => 2,
    };
    strsim::damerau_levenshtein(&a, &b) <= limit
}

/// One record of a [`CsvTable`].
pub(crate) struct Row<'a> {
    path: &'a Path,
    /// The line the record starts on.
    pub line: u64,
    text: &'a str,
    /// Where the record's first field starts in `text`.
    start: usize,
    /// Where each of its fields ends.
    ends: &'a [usize],
}

impl Row<'_> {
    /// The location of field `name` of this row.
    pub fn at(&self, name: &str) -> Location {
        Location::line(self.path, self.line).field(name)
    }

    /// The (trimmed) text of column `col`.
    pub fn str(&self, col: usize) -> &str {
        let Some(&end) = self.ends.get(col) else {
            return "";
        };
        let start = if col == 0 {
            self.start
        } else {
            self.ends[col - 1]
        };
        &self.text[start..end]
    }

    /// Column `col`, named `name`, as a finite number.
    pub fn f64(&self, col: usize, name: &str) -> Result<f64, DatasetError> {
        parse_f64(self.str(col)).map_err(|m| DatasetError::invalid(self.at(name), m))
    }

    /// Column `col`, named `name`, as a non-negative integer.
    pub fn uint<T: TryFrom<u64>>(&self, col: usize, name: &str) -> Result<T, DatasetError> {
        parse_uint(self.str(col)).map_err(|m| DatasetError::invalid(self.at(name), m))
    }
}

/// Turns a byte offset reported by the csv crate into a line number. The crate reports the
/// offset just after the previous record, so blank lines (and the `\n` of a `\r\n`) before
/// a record are skipped here. Offsets only grow, so counting is incremental.
struct LineCounter<'a> {
    text: &'a [u8],
    offset: usize,
    line: u64,
}

impl<'a> LineCounter<'a> {
    fn new(text: &'a [u8]) -> Self {
        LineCounter {
            text,
            offset: 0,
            line: 1,
        }
    }

    fn line_of_record(&mut self, byte: u64) -> u64 {
        let mut start = (byte as usize).min(self.text.len());
        while start < self.text.len() && matches!(self.text[start], b'\r' | b'\n') {
            start += 1;
        }
        if start < self.offset {
            return line_at(self.text, start);
        }
        self.line += self.text[self.offset..start]
            .iter()
            .filter(|&&b| b == b'\n')
            .count() as u64;
        self.offset = start;
        self.line
    }
}

fn csv_error(path: &Path, lines: &mut LineCounter<'_>, e: csv::Error) -> DatasetError {
    let line = e.position().map(|p| lines.line_of_record(p.byte()));
    let message = match e.kind() {
        csv::ErrorKind::Utf8 { err, .. } => {
            format!("field {} is not valid UTF-8", err.field() + 1)
        }
        _ => e.to_string(),
    };
    let at = Location {
        path: path.to_path_buf(),
        line,
        field: None,
    };
    match e.into_kind() {
        csv::ErrorKind::Io(source) => DatasetError::io(path, "read", source),
        _ => DatasetError::invalid(at, message),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table(text: &str) -> CsvTable {
        CsvTable::parse(Path::new("t.csv"), text.as_bytes()).unwrap()
    }

    #[test]
    fn lines_count_blank_lines_and_crlf() {
        let t = table("a,b\n\n1,2\n  ,  \n3,4\n");
        let lines: Vec<_> = t.rows().map(|r| r.line).collect();
        assert_eq!(lines, [3, 5]);
        let t = table("\r\n a , b \r\n\r\n1,2\r\n\r\n\r\n3,4");
        assert_eq!(t.rows().map(|r| r.line).collect::<Vec<_>>(), [4, 7]);
        assert_eq!(t.require("a").unwrap(), 0);
        assert_eq!(t.rows().nth(1).unwrap().str(1), "4");
    }

    #[test]
    fn quoted_fields_spanning_lines() {
        let t = table("a,b\n\"x\ny\",1\n2,3\n");
        let rows: Vec<_> = t.rows().map(|r| (r.line, r.str(0).to_string())).collect();
        assert_eq!(rows, [(2, "x\ny".to_string()), (4, "2".to_string())]);
    }

    #[test]
    fn ragged_rows_and_columns() {
        let e = CsvTable::parse(Path::new("t.csv"), b"a,b\n1,2\n1,2,3\n").unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.csv line 3: has 3 fields but the header has 2 columns"
        );
        let t = table("a,b,a\n1,2,3\n");
        let e = t.column("a").unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.csv line 1, field a: the header has column 'a' twice (columns 1 and 3)"
        );
        assert_eq!(t.column("c").unwrap(), None);
        let e = t.require("c").unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.csv line 1, field c: the header has no column 'c'"
        );
    }

    #[test]
    fn typed_fields() {
        let t = table("n,x\n-1,abc\n");
        let row = t.rows().next().unwrap();
        assert_eq!(
            row.uint::<u64>(0, "n").unwrap_err().to_string(),
            "t.csv line 2, field n: must not be negative, got -1"
        );
        assert_eq!(
            row.f64(1, "x").unwrap_err().to_string(),
            "t.csv line 2, field x: 'abc' is not a number"
        );
    }

    #[test]
    fn invalid_utf8() {
        let e = CsvTable::parse(Path::new("t.csv"), b"a,b\n1,2\n3,\xff\n").unwrap_err();
        assert_eq!(e.to_string(), "t.csv line 3: field 2 is not valid UTF-8");
    }
}
