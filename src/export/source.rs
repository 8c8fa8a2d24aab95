//! A robot's file as naocalib reads it: a regular file of a plausible size, UTF-8, with an
//! optional byte-order mark (kept on update); and its text without comments, by which its
//! layout is recognised.

use std::io::Read as _;
use std::path::Path;

use super::{ExportError, parse_error};

/// A calibration file larger than this (bytes) is no calibration file: the teams' are a
/// few kilobytes.
pub const MAX_FILE_BYTES: u64 = 4 << 20;

/// The UTF-8 byte-order mark some editors put at the start of a file.
pub const BOM: char = '\u{feff}';

/// A file's text, with whether it started with a byte-order mark (not part of `text`).
#[derive(Debug, Clone, PartialEq)]
pub struct Source {
    /// The text after the byte-order mark.
    pub text: String,
    /// Whether the file started with [`BOM`].
    pub bom: bool,
}

impl Source {
    /// The file's bytes for `text` in place of its text (the byte-order mark kept).
    pub fn with_text(&self, text: &str) -> String {
        if self.bom {
            format!("{BOM}{text}")
        } else {
            text.to_string()
        }
    }
}

/// Reads `path` (symbolic links followed): refuses what is not a regular file (a FIFO, a
/// device, a directory) before opening it, so that nothing blocks; a file beyond
/// [`MAX_FILE_BYTES`]; text that is not UTF-8 (naming the line). A leading byte-order
/// mark is accepted and set apart.
pub fn read(path: &Path) -> Result<Source, ExportError> {
    let io = |action, source| ExportError::Io {
        path: path.to_path_buf(),
        action,
        source,
    };
    let meta = std::fs::metadata(path).map_err(|e| io("read", e))?;
    if !meta.is_file() {
        let kind = if meta.is_dir() {
            "a directory"
        } else {
            "not a regular file (a FIFO, socket or device)"
        };
        return Err(parse_error(path, format!("is {kind}: refusing to read it")));
    }
    if meta.len() > MAX_FILE_BYTES {
        return Err(too_large(path, meta.len()));
    }
    let mut bytes = Vec::new();
    std::fs::File::open(path)
        .and_then(|f| f.take(MAX_FILE_BYTES + 1).read_to_end(&mut bytes))
        .map_err(|e| io("read", e))?;
    if bytes.len() as u64 > MAX_FILE_BYTES {
        return Err(too_large(path, bytes.len() as u64));
    }
    let text = String::from_utf8(bytes).map_err(|e| {
        let good = &e.as_bytes()[..e.utf8_error().valid_up_to()];
        let line = good.iter().filter(|&&b| b == b'\n').count() + 1;
        parse_error(path, format!("line {line}: not UTF-8 text"))
    })?;
    Ok(match text.strip_prefix(BOM) {
        Some(rest) => Source {
            text: rest.to_string(),
            bom: true,
        },
        None => Source { text, bom: false },
    })
}

fn too_large(path: &Path, len: u64) -> ExportError {
    parse_error(
        path,
        format!(
            "{len} bytes is no calibration file (at most {MAX_FILE_BYTES} bytes): refusing to \
             read it"
        ),
    )
}

/// `text` without its comments (`//` and `/* */` as in B-Human's configs, whole lines
/// starting with `#` or `;` as in INI files), for recognising a layout by its keys rather
/// than by words in a header. Strings are not special: a key's name in a string value
/// still counts.
pub fn code(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    let mut in_block = false;
    while !rest.is_empty() {
        if in_block {
            match rest.find("*/") {
                Some(n) => {
                    rest = &rest[n + 2..];
                    in_block = false;
                }
                None => break,
            }
            continue;
        }
        let (line, next) = match rest.find('\n') {
            Some(n) => (&rest[..n], &rest[n + 1..]),
            None => (rest, ""),
        };
        let trimmed = line.trim_start();
        if trimmed.starts_with('#') || trimmed.starts_with(';') {
            out.push('\n');
            rest = next;
            continue;
        }
        let cut = [line.find("//"), line.find("/*")]
            .into_iter()
            .flatten()
            .min();
        match cut {
            Some(n) if line[n..].starts_with("/*") => {
                out.push_str(&line[..n]);
                // The block comment may close on this line or a later one.
                let after = &rest[n + 2..];
                in_block = true;
                rest = after;
            }
            Some(n) => {
                out.push_str(&line[..n]);
                out.push('\n');
                rest = next;
            }
            None => {
                out.push_str(line);
                out.push('\n');
                rest = next;
            }
        }
    }
    out
}

/// Whether `code` (a text without comments, [`code`]) has an entry `key = …` (or `key=…`),
/// `key` not the end of a longer name.
pub fn has_key(code: &str, key: &str) -> bool {
    code.match_indices(key).any(|(at, _)| {
        let before = code[..at].chars().next_back();
        let after = code[at + key.len()..].trim_start();
        !before.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_') && after.starts_with('=')
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn code_drops_comments_of_every_syntax() {
        let text = "// offsets\n# cameraPitchBottom\n; [CameraMatrixOffset]\na = 1; // offsets\n\
                    b /* minAngle */ = 2;\n/* x\n offsets */ c = 3;\n";
        let c = code(text);
        assert!(!c.contains("offsets") && !c.contains("minAngle"), "{c}");
        assert!(!c.contains("cameraPitchBottom") && !c.contains("CameraMatrixOffset"));
        assert!(
            c.contains("a = 1;") && c.contains("= 2;") && c.contains("c = 3;"),
            "{c}"
        );
    }
}
