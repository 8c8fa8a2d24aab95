//! Reading a TOML file into a `#[derive(Deserialize)]` struct with errors that name the
//! file, the line and the key path (`camera.fx`, `camera.distortion[2]`).
//!
//! serde does the typed reading; this module adds what serde's errors lack: the key path of
//! the error's position (from the document's spans), wording in the dataset's terms
//! ("expected a number, found a string"), a check that no float anywhere is NaN or infinite,
//! and [`TomlDoc::at`] to place the errors of a later `validate()` on their line.

use std::ops::Range;
use std::path::{Path, PathBuf};

use serde::de::DeserializeOwned;
use toml::de::{DeTable, DeValue};

use super::error::{DatasetError, Location};
use super::text::line_at;

/// A TOML document that parsed: its path and text, and every key path with its spans.
pub(crate) struct TomlDoc<'t> {
    path: PathBuf,
    text: &'t str,
    /// Every key path of the document (tables, keys, array items), with the span of its
    /// key (none for array items) and of its value, in file order.
    keys: Vec<(String, Option<Range<usize>>, Range<usize>)>,
}

impl<'t> TomlDoc<'t> {
    /// Parses `bytes`, the content of `path`: UTF-8, TOML syntax, and finite floats
    /// everywhere (`nan` and `inf` are valid TOML but never a valid dataset value).
    pub fn new(path: &Path, bytes: &'t [u8]) -> Result<Self, DatasetError> {
        let text = std::str::from_utf8(bytes).map_err(|e| {
            DatasetError::invalid(
                Location::line(path, line_at(bytes, e.valid_up_to())),
                "the file is not valid UTF-8",
            )
        })?;
        let parsed = DeTable::parse(text).map_err(|e| {
            let line = e.span().map(|s| line_at(bytes, s.start));
            let at = Location {
                path: path.to_path_buf(),
                line,
                field: None,
            };
            DatasetError::invalid(at, format!("invalid TOML: {}", e.message()))
        })?;
        let mut doc = TomlDoc {
            path: path.to_path_buf(),
            text,
            keys: Vec::new(),
        };
        doc.index_table("", parsed.get_ref())?;
        doc.keys.sort_by_key(|(_, key, value)| {
            key.as_ref()
                .map_or(value.start, |k| k.start.min(value.start))
        });
        Ok(doc)
    }

    fn index_table(&mut self, prefix: &str, table: &DeTable<'t>) -> Result<(), DatasetError> {
        for (key, value) in table {
            let path = join(prefix, key.get_ref());
            self.keys
                .push((path.clone(), Some(key.span()), value.span()));
            self.index_value(&path, value.get_ref(), value.span())?;
        }
        Ok(())
    }

    fn index_value(
        &mut self,
        path: &str,
        value: &DeValue<'t>,
        span: Range<usize>,
    ) -> Result<(), DatasetError> {
        match value {
            DeValue::Float(f) => match f.as_str().parse::<f64>() {
                Ok(x) if x.is_finite() => Ok(()),
                _ => Err(DatasetError::invalid(
                    self.location(path, Some(span.start)),
                    format!("{} is not a finite number", f.as_str()),
                )),
            },
            DeValue::Array(items) => {
                for (i, item) in items.iter().enumerate() {
                    let item_path = format!("{path}[{i}]");
                    self.keys.push((item_path.clone(), None, item.span()));
                    self.index_value(&item_path, item.get_ref(), item.span())?;
                }
                Ok(())
            }
            DeValue::Table(table) => self.index_table(path, table),
            _ => Ok(()),
        }
    }

    fn location(&self, field: &str, offset: Option<usize>) -> Location {
        Location {
            path: self.path.clone(),
            line: offset.map(|o| line_at(self.text.as_bytes(), o)),
            field: (!field.is_empty()).then(|| field.to_string()),
        }
    }

    /// The location of key path `field`: the line its key (or array item) is on, when the
    /// document has it; just the file and the field when not.
    pub fn at(&self, field: &str) -> Location {
        let offset = self
            .keys
            .iter()
            .find(|(path, ..)| path == field)
            .map(|(_, key, value)| key.as_ref().unwrap_or(value).start);
        self.location(field, offset)
    }

    /// An [`DatasetError::Invalid`] at key path `field` (see [`TomlDoc::at`]).
    pub fn error(&self, field: &str, message: impl Into<String>) -> DatasetError {
        DatasetError::invalid(self.at(field), message)
    }

    /// The key paths of the document, in file order (array items included).
    #[cfg(test)]
    pub fn key_paths(&self) -> impl Iterator<Item = &str> {
        self.keys.iter().map(|(path, ..)| path.as_str())
    }

    /// The key path at byte `offset`: the innermost key or value whose span holds it.
    fn path_at(&self, offset: usize) -> String {
        self.keys
            .iter()
            .filter_map(|(path, key, value)| {
                let hit = |r: &Range<usize>| r.start <= offset && offset < r.end.max(r.start + 1);
                [key.as_ref(), Some(value)]
                    .into_iter()
                    .flatten()
                    .filter(|r| hit(r))
                    .map(|r| (r.len(), path))
                    .min()
            })
            .min()
            .map(|(_, path)| path.clone())
            .unwrap_or_default()
    }

    /// Deserializes the whole document into `T`; serde's errors become errors naming the
    /// line and the key path, worded in this crate's terms.
    pub fn deserialize<T: DeserializeOwned>(&self) -> Result<T, DatasetError> {
        toml::from_str(self.text).map_err(|e| {
            // An empty span is the document itself (a key missing at the top level).
            let offset = e.span().filter(|s| !s.is_empty()).map(|s| s.start);
            let path = offset.map(|o| self.path_at(o)).unwrap_or_default();
            let (field, message) = reword(&path, e.message());
            DatasetError::invalid(self.location(&field, offset), message)
        })
    }
}

fn join(prefix: &str, key: &str) -> String {
    if prefix.is_empty() {
        key.to_string()
    } else {
        format!("{prefix}.{key}")
    }
}

/// The names quoted in backticks in a serde message, in order.
fn quoted(message: &str) -> Vec<&str> {
    message.split('`').skip(1).step_by(2).collect()
}

/// serde's name of a value's type → ours.
fn kind(serde: &str) -> String {
    let serde = serde.trim();
    let word = serde.split([' ', '`', '"']).next().unwrap_or(serde);
    match word {
        "string" | "char" => "a string".into(),
        "integer" | "u8" | "u16" | "u32" | "u64" | "i8" | "i16" | "i32" | "i64" => {
            "an integer".into()
        }
        "floating" => "a float".into(),
        "f64" | "f32" => "a number".into(),
        "boolean" | "bool" => "a boolean".into(),
        "sequence" => "an array".into(),
        "map" | "struct" => "a table".into(),
        "a" if serde.starts_with("a sequence") => "an array".into(),
        "a" if serde.starts_with("a map") => "a table".into(),
        _ => serde.to_string(),
    }
}

/// The key path and the message for serde's error `message` at key path `path`.
fn reword(path: &str, message: &str) -> (String, String) {
    let table = if path.is_empty() {
        "the file".to_string()
    } else {
        format!("[{path}]")
    };
    if let Some(rest) = message.strip_prefix("missing field ") {
        let name = quoted(rest).first().copied().unwrap_or(rest).to_string();
        return (join(path, &name), format!("{table} has no key '{name}'"));
    }
    if let Some(rest) = message.strip_prefix("unknown field ") {
        // The error is at the unknown key itself: `path` ends with its name.
        let names = quoted(rest);
        let name = names.first().copied().unwrap_or(rest);
        let place = match path.rsplit_once('.') {
            Some((parent, _)) => format!("in [{parent}]"),
            None => "at the top level".to_string(),
        };
        let known = names.get(1..).unwrap_or_default().join(", ");
        return (
            path.to_string(),
            format!("unknown key '{name}' {place} (known keys: {known})"),
        );
    }
    if let Some(rest) = message.strip_prefix("invalid type: ")
        && let Some((found, expected)) = rest.split_once(", expected ")
    {
        if found.ends_with(" as i128") {
            // An integer too large for any integer type.
            let value = quoted(found).first().copied().unwrap_or(found).to_string();
            return (path.to_string(), format!("integer {value} is out of range"));
        }
        return (
            path.to_string(),
            format!("expected {}, found {}", kind(expected), kind(found)),
        );
    }
    if let Some(rest) = message.strip_prefix("invalid length ")
        && let Some((found, expected)) = rest.split_once(", expected an array of ")
    {
        return (
            path.to_string(),
            format!("expected exactly {expected}, found {found}"),
        );
    }
    if let Some(rest) = message.strip_prefix("invalid value: ")
        && let Some((found, expected)) = rest.split_once(", expected ")
    {
        let value = quoted(found).first().copied().unwrap_or(found).to_string();
        let range = match expected {
            "u32" => " (a whole number from 0 to 4294967295)",
            "u64" => " (a whole number from 0 to 18446744073709551615)",
            _ => "",
        };
        return (path.to_string(), format!("{value} is out of range{range}"));
    }
    (path.to_string(), message.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::Deserialize;

    #[derive(Debug, Deserialize)]
    #[serde(deny_unknown_fields)]
    #[allow(dead_code)]
    struct Doc {
        cam: Cam,
        #[serde(default)]
        other: Option<Other>,
    }

    #[derive(Debug, Deserialize)]
    #[serde(deny_unknown_fields)]
    #[allow(dead_code)]
    struct Cam {
        w: u32,
        f: f64,
        #[serde(default)]
        d: Vec<f64>,
    }

    #[derive(Debug, Deserialize)]
    #[serde(deny_unknown_fields)]
    #[allow(dead_code)]
    struct Other {
        q: u32,
    }

    fn read(text: &str) -> String {
        let doc = match TomlDoc::new(Path::new("d.toml"), text.as_bytes()) {
            Ok(doc) => doc,
            Err(e) => return e.to_string(),
        };
        match doc.deserialize::<Doc>() {
            Ok(d) => format!("ok {d:?}"),
            Err(e) => e.to_string(),
        }
    }

    #[test]
    fn syntax_errors_have_lines() {
        let e = read("[a]\nx = 1\nx = 2\n");
        assert_eq!(e, "d.toml line 3: invalid TOML: duplicate key");
        let e = read("[a]\nx = [1,\n");
        assert!(e.starts_with("d.toml line 2: invalid TOML: "), "{e}");
        let e = TomlDoc::new(Path::new("d.toml"), b"a = 1\n\xff = 2\n")
            .err()
            .unwrap();
        assert_eq!(e.to_string(), "d.toml line 2: the file is not valid UTF-8");
    }

    #[test]
    fn typed_errors_name_line_and_key() {
        let cases = [
            ("# c\n[cam]\nw = 640\nf = 1_000.5\n", "ok Doc"),
            (
                "[cam]\nw = 640\nf = 1\nd = [1, 2.0,\n  'x']\n",
                "d.toml line 5, field cam.d[2]: expected a number, found a string",
            ),
            (
                "[cam]\nw = 640.0\nf = 1\n",
                "d.toml line 2, field cam.w: expected an integer, found a float",
            ),
            (
                "[cam]\nw = -3\nf = 1\n",
                "d.toml line 2, field cam.w: -3 is out of range (a whole number from 0 to",
            ),
            (
                "[cam]\nw = 3\nf = 's'\n",
                "d.toml line 3, field cam.f: expected a number, found a string",
            ),
            (
                "[cam]\nw = 3\n",
                "d.toml line 1, field cam.f: [cam] has no key 'f'",
            ),
            (
                "x = 1\n",
                "d.toml line 1, field x: unknown key 'x' at the top level",
            ),
            (
                "[cam]\nw = 3\nf = 1\nzoom = 2\n",
                "d.toml line 4, field cam.zoom: unknown key 'zoom' in [cam] (known keys: w, f, d)",
            ),
            (
                "[cam]\nw = 3\nf = 99999999999999999999\n",
                "d.toml line 3, field cam.f: integer 99999999999999999999 is out of range",
            ),
            (
                "cam = 3\n",
                "d.toml line 1, field cam: expected a table, found an integer",
            ),
            (
                "[cam]\nw = 3\nf = 1\nd = 2\n",
                "d.toml line 4, field cam.d: expected an array, found an integer",
            ),
            (
                "[cam]\nw = 3\nf = 1\n[other]\nq = 1\ny = 2\n",
                "d.toml line 6, field other.y: unknown key 'y' in [other] (known keys: q)",
            ),
            (
                "[cam]\nw = 3\nf = 1\nd = { c = [1.0, nan] }\n",
                "d.toml line 4, field cam.d.c[1]: nan is not a finite number",
            ),
            (
                "[cam]\nw = 3\nf = -inf\n",
                "d.toml line 3, field cam.f: -inf is not a finite number",
            ),
            ("", "d.toml, field cam: the file has no key 'cam'"),
        ];
        for (text, expected) in cases {
            let e = read(text);
            assert!(
                e.starts_with(expected),
                "{text:?}: {e:?} should start with {expected:?}"
            );
        }
    }

    #[test]
    fn locates_keys_for_later_checks() {
        let text = "[cam]\nw = 3\nf = 1\nd = [1,\n 2]\n";
        let doc = TomlDoc::new(Path::new("d.toml"), text.as_bytes()).unwrap();
        assert_eq!(doc.at("cam.f").to_string(), "d.toml line 3, field cam.f");
        assert_eq!(
            doc.at("cam.d[1]").to_string(),
            "d.toml line 5, field cam.d[1]"
        );
        assert_eq!(doc.at("cam").to_string(), "d.toml line 1, field cam");
        assert_eq!(doc.at("cam.x").to_string(), "d.toml, field cam.x");
        let paths: Vec<_> = doc.key_paths().collect();
        assert_eq!(
            paths,
            ["cam", "cam.w", "cam.f", "cam.d", "cam.d[0]", "cam.d[1]"]
        );
    }
}
