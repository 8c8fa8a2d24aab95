//! Reading TOML files key by key with toml's spans, so that every error names the line and
//! the key path (`camera.fx`, `camera.distortion[2]`).

use std::ops::Range;
use std::path::{Path, PathBuf};

use toml::Spanned;
use toml::de::{DeTable, DeValue};

use super::error::{DatasetError, Location};
use super::text::line_at;

/// A TOML document being read: its path and text, for locations.
pub(crate) struct TomlDoc<'t> {
    path: PathBuf,
    text: &'t str,
}

/// One table of the document, with the key path leading to it (empty for the root).
pub(crate) struct Table<'a, 't> {
    doc: &'a TomlDoc<'t>,
    prefix: String,
    span: Option<Range<usize>>,
    table: &'a DeTable<'t>,
}

/// One value of the document, with its key path and span.
pub(crate) struct Value<'a, 't> {
    doc: &'a TomlDoc<'t>,
    /// The key path, e.g. `camera.fx`.
    pub key: String,
    value: &'a Spanned<DeValue<'t>>,
}

impl<'t> TomlDoc<'t> {
    /// A document: `bytes` is the content of `path`.
    pub fn new(path: &Path, bytes: &'t [u8]) -> Result<Self, DatasetError> {
        let text = std::str::from_utf8(bytes).map_err(|e| {
            DatasetError::invalid(
                Location::line(path, line_at(bytes, e.valid_up_to())),
                "the file is not valid UTF-8",
            )
        })?;
        Ok(TomlDoc {
            path: path.to_path_buf(),
            text,
        })
    }

    /// Parses the document.
    pub fn parse(&self) -> Result<Spanned<DeTable<'t>>, DatasetError> {
        DeTable::parse(self.text).map_err(|e| {
            let line = e.span().map(|s| line_at(self.text.as_bytes(), s.start));
            let at = Location {
                path: self.path.clone(),
                line,
                field: None,
            };
            DatasetError::invalid(at, format!("invalid TOML: {}", e.message()))
        })
    }

    /// The root table of a parsed document.
    pub fn root<'a>(&'a self, parsed: &'a Spanned<DeTable<'t>>) -> Table<'a, 't> {
        Table {
            doc: self,
            prefix: String::new(),
            span: None,
            table: parsed.get_ref(),
        }
    }

    /// The location of `span`, field `key`.
    pub fn at(&self, span: Option<Range<usize>>, key: &str) -> Location {
        Location {
            path: self.path.clone(),
            line: span.map(|s| line_at(self.text.as_bytes(), s.start)),
            field: (!key.is_empty()).then(|| key.to_string()),
        }
    }

    /// The whole text (to hand to `toml::from_str` for free-form tables).
    pub fn text(&self) -> &'t str {
        self.text
    }
}

fn join(prefix: &str, key: &str) -> String {
    if prefix.is_empty() {
        key.to_string()
    } else {
        format!("{prefix}.{key}")
    }
}

fn describe(value: &DeValue<'_>) -> &'static str {
    match value {
        DeValue::String(_) => "a string",
        DeValue::Integer(_) => "an integer",
        DeValue::Float(_) => "a float",
        DeValue::Boolean(_) => "a boolean",
        DeValue::Datetime(_) => "a date-time",
        DeValue::Array(_) => "an array",
        DeValue::Table(_) => "a table",
    }
}

impl<'a, 't> Table<'a, 't> {
    /// The entries, in the order they appear in the file.
    pub fn entries(&self) -> Vec<Value<'a, 't>> {
        let mut entries: Vec<_> = self.table.iter().collect();
        entries.sort_by_key(|(k, _)| k.span().start);
        entries
            .into_iter()
            .map(|(k, v)| Value {
                doc: self.doc,
                key: join(&self.prefix, k.get_ref()),
                value: v,
            })
            .collect()
    }

    /// Fails on the first key (in file order) that is not in `known`.
    pub fn deny_unknown(&self, known: &[&str]) -> Result<(), DatasetError> {
        let mut keys: Vec<_> = self.table.keys().collect();
        keys.sort_by_key(|k| k.span().start);
        match keys
            .into_iter()
            .find(|k| !known.contains(&k.get_ref().as_ref()))
        {
            None => Ok(()),
            Some(k) => {
                let what = if self.prefix.is_empty() {
                    "at the top level".to_string()
                } else {
                    format!("in [{}]", self.prefix)
                };
                Err(DatasetError::invalid(
                    self.doc
                        .at(Some(k.span()), &join(&self.prefix, k.get_ref())),
                    format!(
                        "unknown key '{}' {what} (known keys: {})",
                        k.get_ref(),
                        known.join(", ")
                    ),
                ))
            }
        }
    }

    /// The value of `key`, if present.
    pub fn get(&self, key: &str) -> Option<Value<'a, 't>> {
        self.table
            .iter()
            .find(|(k, _)| k.get_ref() == key)
            .map(|(_, v)| Value {
                doc: self.doc,
                key: join(&self.prefix, key),
                value: v,
            })
    }

    /// The value of `key`, which must be present.
    pub fn require(&self, key: &str) -> Result<Value<'a, 't>, DatasetError> {
        self.get(key).ok_or_else(|| {
            let table = if self.prefix.is_empty() {
                "the file".to_string()
            } else {
                format!("[{}]", self.prefix)
            };
            DatasetError::invalid(
                self.doc.at(self.span.clone(), &join(&self.prefix, key)),
                format!("{table} has no key '{key}'"),
            )
        })
    }

    /// The sub-table `key`, if present (an error if `key` is not a table).
    pub fn table(&self, key: &str) -> Result<Option<Table<'a, 't>>, DatasetError> {
        self.get(key).map(|v| v.table()).transpose()
    }
}

impl<'a, 't> Value<'a, 't> {
    /// The location of this value.
    pub fn at(&self) -> Location {
        self.doc.at(Some(self.value.span()), &self.key)
    }

    fn invalid(&self, message: impl Into<String>) -> DatasetError {
        DatasetError::invalid(self.at(), message)
    }

    fn expected(&self, what: &str) -> DatasetError {
        self.invalid(format!(
            "expected {what}, found {}",
            describe(self.value.get_ref())
        ))
    }

    /// The value as a table.
    pub fn table(&self) -> Result<Table<'a, 't>, DatasetError> {
        match self.value.get_ref() {
            DeValue::Table(table) => Ok(Table {
                doc: self.doc,
                prefix: self.key.clone(),
                span: Some(self.value.span()),
                table,
            }),
            _ => Err(self.expected("a table")),
        }
    }

    /// The value as a finite number (a TOML float or integer).
    pub fn f64(&self) -> Result<f64, DatasetError> {
        match self.value.get_ref() {
            DeValue::Float(f) => match f.as_str().parse::<f64>() {
                Ok(x) if x.is_finite() => Ok(x),
                Ok(_) => Err(self.invalid(format!("{} is not a finite number", f.as_str()))),
                Err(_) => Err(self.invalid(format!("'{}' is not a number", f.as_str()))),
            },
            DeValue::Integer(_) => Ok(self.i64()? as f64),
            _ => Err(self.expected("a number")),
        }
    }

    /// The value as an integer.
    pub fn i64(&self) -> Result<i64, DatasetError> {
        match self.value.get_ref() {
            DeValue::Integer(i) => i64::from_str_radix(i.as_str(), i.radix())
                .map_err(|_| self.invalid(format!("integer {i} is out of range"))),
            _ => Err(self.expected("an integer")),
        }
    }

    /// The value as an integer of at least `min` that fits a `u32`.
    pub fn u32_at_least(&self, min: u32) -> Result<u32, DatasetError> {
        let n = self.i64()?;
        if n < i64::from(min) {
            return Err(self.invalid(format!("must be at least {min}, got {n}")));
        }
        u32::try_from(n).map_err(|_| self.invalid(format!("{n} is too large")))
    }

    /// The value as a number greater than zero.
    pub fn positive(&self) -> Result<f64, DatasetError> {
        let x = self.f64()?;
        if x > 0.0 {
            Ok(x)
        } else {
            Err(self.invalid(format!("must be greater than 0, got {x}")))
        }
    }

    /// The value as an array of exactly `N` finite numbers.
    pub fn f64_array<const N: usize>(&self) -> Result<[f64; N], DatasetError> {
        let DeValue::Array(items) = self.value.get_ref() else {
            return Err(self.expected(&format!("an array of {N} numbers")));
        };
        if items.len() != N {
            return Err(self.invalid(format!(
                "expected exactly {N} numbers, found {}",
                items.len()
            )));
        }
        let mut out = [0.0; N];
        for (i, (slot, item)) in out.iter_mut().zip(items.iter()).enumerate() {
            let value = Value {
                doc: self.doc,
                key: format!("{}[{i}]", self.key),
                value: item,
            };
            *slot = value.f64()?;
        }
        Ok(out)
    }

    /// Fails if any float in this value (recursively) is NaN or infinite.
    pub fn deny_non_finite(&self) -> Result<(), DatasetError> {
        match self.value.get_ref() {
            DeValue::Float(_) => self.f64().map(|_| ()),
            DeValue::Array(items) => items.iter().enumerate().try_for_each(|(i, item)| {
                Value {
                    doc: self.doc,
                    key: format!("{}[{i}]", self.key),
                    value: item,
                }
                .deny_non_finite()
            }),
            DeValue::Table(_) => self
                .table()?
                .entries()
                .iter()
                .try_for_each(Value::deny_non_finite),
            _ => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn with_doc(text: &str, f: impl FnOnce(Table<'_, '_>) -> Result<(), DatasetError>) -> String {
        let doc = TomlDoc::new(Path::new("d.toml"), text.as_bytes()).unwrap();
        match doc.parse() {
            Err(e) => e.to_string(),
            Ok(parsed) => match f(doc.root(&parsed)) {
                Ok(()) => "ok".into(),
                Err(e) => e.to_string(),
            },
        }
    }

    #[test]
    fn syntax_errors_have_lines() {
        let e = with_doc("[a]\nx = 1\nx = 2\n", |_| Ok(()));
        assert_eq!(e, "d.toml line 3: invalid TOML: duplicate key");
        let e = with_doc("[a]\nx = [1,\n", |_| Ok(()));
        assert!(e.starts_with("d.toml line 2: invalid TOML: "), "{e}");
    }

    #[test]
    fn values() {
        let text = "# c\n[cam]\nw = 640\nf = 1_000.5\nn = -nan\ni = +inf\nd = [1, 2.0,\n  'x']\n\
                    s = 'str'\nneg = -3\nbig = 99999999999999999999\n";
        let check = |key: &str, f: &dyn Fn(&Value<'_, '_>) -> Result<String, DatasetError>| {
            with_doc(text, |root| {
                let cam = root.table("cam")?.unwrap();
                let s = f(&cam.require(key)?)?;
                Err(DatasetError::invalid(Location::file("ok"), s))
            })
        };
        assert_eq!(
            check("w", &|v| v.u32_at_least(1).map(|n| n.to_string())),
            "ok: 640"
        );
        assert_eq!(check("w", &|v| v.f64().map(|n| n.to_string())), "ok: 640");
        assert_eq!(
            check("f", &|v| v.f64().map(|n| n.to_string())),
            "ok: 1000.5"
        );
        assert_eq!(
            check("f", &|v| v.i64().map(|n| n.to_string())),
            "d.toml line 4, field cam.f: expected an integer, found a float"
        );
        assert_eq!(
            check("n", &|v| v.f64().map(|n| n.to_string())),
            "d.toml line 5, field cam.n: -nan is not a finite number"
        );
        assert_eq!(
            check("i", &|v| v.positive().map(|n| n.to_string())),
            "d.toml line 6, field cam.i: +inf is not a finite number"
        );
        assert_eq!(
            check("d", &|v| v.f64_array::<3>().map(|a| format!("{a:?}"))),
            "d.toml line 8, field cam.d[2]: expected a number, found a string"
        );
        assert_eq!(
            check("d", &|v| v.f64_array::<5>().map(|a| format!("{a:?}"))),
            "d.toml line 7, field cam.d: expected exactly 5 numbers, found 3"
        );
        assert_eq!(
            check("neg", &|v| v.u32_at_least(1).map(|n| n.to_string())),
            "d.toml line 10, field cam.neg: must be at least 1, got -3"
        );
        assert_eq!(
            check("neg", &|v| v.positive().map(|n| n.to_string())),
            "d.toml line 10, field cam.neg: must be greater than 0, got -3"
        );
        assert_eq!(
            check("big", &|v| v.f64().map(|n| n.to_string())),
            "d.toml line 11, field cam.big: integer 99999999999999999999 is out of range"
        );
        assert_eq!(
            check("nope", &|v| v.f64().map(|n| n.to_string())),
            "d.toml line 2, field cam.nope: [cam] has no key 'nope'"
        );
        assert_eq!(
            check("s", &|v| v.f64().map(|n| n.to_string())),
            "d.toml line 9, field cam.s: expected a number, found a string"
        );
    }

    #[test]
    fn unknown_keys_in_file_order() {
        let e = with_doc("z = 1\n[b]\ny = 2\nx = 3\n", |root| {
            root.deny_unknown(&["z", "b"])?;
            root.table("b")?.unwrap().deny_unknown(&["q"])
        });
        assert_eq!(
            e,
            "d.toml line 3, field b.y: unknown key 'y' in [b] (known keys: q)"
        );
        let e = with_doc("z = 1\n[b]\n", |root| root.deny_unknown(&["b"]));
        assert_eq!(
            e,
            "d.toml line 1, field z: unknown key 'z' at the top level (known keys: b)"
        );
    }

    #[test]
    fn non_finite_anywhere() {
        let e = with_doc("[s]\na = 1\nb = { c = [1.0, nan] }\n", |root| {
            root.get("s").unwrap().deny_non_finite()
        });
        assert_eq!(
            e,
            "d.toml line 3, field s.b.c[1]: nan is not a finite number"
        );
    }
}
