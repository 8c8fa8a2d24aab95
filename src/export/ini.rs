//! INI files (NaoTH's GLib key files, rUNSWift's configs) read with the span of every
//! value, so that an update replaces a value's text and keeps every other byte.

use std::path::Path;

use super::{ExportError, parse_error};

/// One `key=value` entry of a section.
#[derive(Debug, Clone, PartialEq)]
pub struct Entry {
    /// The key (trimmed).
    pub key: String,
    /// The value's text (trimmed).
    pub value: String,
    /// Byte span of the value's text.
    pub start: usize,
    /// Byte offset after the value's text.
    pub end: usize,
    /// Its line (1-based).
    pub line: usize,
}

/// The entries of `section`, and the byte offset after its last line (where a new entry
/// goes); `None` when the file has no such section. Comments `#` and `;`.
pub fn section(
    text: &str,
    section: &str,
    path: &Path,
) -> Result<Option<(Vec<Entry>, usize)>, ExportError> {
    let mut inside = false;
    let mut found = None::<(Vec<Entry>, usize)>;
    let mut offset = 0;
    for (n, raw) in text.split_inclusive('\n').enumerate() {
        let line_start = offset;
        offset += raw.len();
        let line = raw.trim();
        if line.is_empty() || line.starts_with('#') || line.starts_with(';') {
            continue;
        }
        if let Some(name) = line.strip_prefix('[').and_then(|l| l.strip_suffix(']')) {
            inside = name.trim() == section;
            if inside && found.is_some() {
                return Err(parse_error(
                    path,
                    format!("line {}: [{section}] given twice", n + 1),
                ));
            }
            if inside {
                found = Some((Vec::new(), offset));
            }
            continue;
        }
        if !inside {
            continue;
        }
        let (key, value) = raw
            .split_once('=')
            .ok_or_else(|| parse_error(path, format!("line {}: expected key=value", n + 1)))?;
        let value_start = line_start + key.len() + 1;
        let lead = value.len() - value.trim_start().len();
        let trimmed = value.trim();
        let (entries, end) = found.as_mut().expect("inside a section");
        entries.push(Entry {
            key: key.trim().to_string(),
            value: trimmed.to_string(),
            start: value_start + lead,
            end: value_start + lead + trimmed.len(),
            line: n + 1,
        });
        *end = offset;
    }
    Ok(found)
}

/// The number of `key` in `entries`, with its entry; an error names the line.
pub fn number<'a>(
    entries: &'a [Entry],
    key: &str,
    path: &Path,
) -> Result<Option<(f64, &'a Entry)>, ExportError> {
    let Some(e) = entries.iter().find(|e| e.key == key) else {
        return Ok(None);
    };
    let x: f64 = e
        .value
        .parse()
        .ok()
        .filter(|x: &f64| x.is_finite())
        .ok_or_else(|| {
            parse_error(
                path,
                format!("line {}: {key}: '{}' is not a number", e.line, e.value),
            )
        })?;
    Ok(Some((x, e)))
}

/// `text` with each `(key, value)` of `section` set: replaced where the key exists,
/// otherwise added after the section's last entry (or a new section at the end).
pub fn set(
    text: &str,
    section_name: &str,
    values: &[(&str, String)],
    path: &Path,
) -> Result<String, ExportError> {
    let Some((entries, end)) = section(text, section_name, path)? else {
        let mut out = text.to_string();
        if !out.is_empty() && !out.ends_with('\n') {
            out.push('\n');
        }
        out.push_str(&format!("[{section_name}]\n"));
        for (k, v) in values {
            out.push_str(&format!("{k}={v}\n"));
        }
        return Ok(out);
    };
    let mut edits = Vec::new();
    let mut added = String::new();
    for (k, v) in values {
        match entries.iter().find(|e| e.key == *k) {
            Some(e) => edits.push((e.start, e.end, v.clone())),
            None => added.push_str(&format!("{k}={v}\n")),
        }
    }
    if !added.is_empty() {
        let prefix = if end > 0 && !text[..end].ends_with('\n') {
            "\n"
        } else {
            ""
        };
        edits.push((end, end, format!("{prefix}{added}")));
    }
    Ok(super::cfg::splice(text, edits))
}
