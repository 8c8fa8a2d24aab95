//! The configuration syntax of B-Human's framework and of those built on it (NomadZ, SPQR,
//! …): `key = value;` entries, `{ … }` maps, `[ … ]` lists, `//` and `/* */` comments,
//! read with the byte span and line of every value, so that an update replaces a value's
//! text and keeps every other byte of the file.
//!
//! Angles follow B-Human's `InText::readAngle` (`Src/Libs/Streaming/InStreams.cpp`): a
//! number with the suffix `deg` (degrees), `pi` (multiples of π), `rad` or none (radians).

use std::path::Path;

use super::{ExportError, parse_error};

/// A value of a config file, with where its text is.
pub type Value = super::tree::Node<Kind>;

/// The kinds of config values.
#[derive(Debug, Clone, PartialEq)]
pub enum Kind {
    /// A scalar's text (`-3.5deg`, `0`, `default`, `"text"`).
    Scalar(String),
    /// A `{ key = value; … }` map, in file order.
    Map(Vec<(String, Value)>),
    /// A `[ a, b, … ]` list.
    List(Vec<Value>),
}

impl super::tree::Members for Kind {
    fn members(&self) -> Option<&[(String, Value)]> {
        match self {
            Kind::Map(entries) => Some(entries),
            _ => None,
        }
    }
}

impl Value {
    /// The scalar's text, if a scalar.
    pub fn scalar(&self) -> Option<&str> {
        match &self.kind {
            Kind::Scalar(s) => Some(s),
            _ => None,
        }
    }
}

/// A parsed config file: its top-level map (spanning the whole text).
pub fn parse(text: &str, path: &Path) -> Result<Value, ExportError> {
    let mut p = Parser {
        text,
        bytes: text.as_bytes(),
        pos: 0,
        path,
        depth: 0,
    };
    let entries = p.entries(None)?;
    Ok(Value {
        kind: Kind::Map(entries),
        start: 0,
        end: text.len(),
        line: 1,
    })
}

/// Maps and lists nested deeper than this are refused (the teams' files nest three deep;
/// the parser recurses, so an unbounded depth would overflow the stack).
pub const MAX_DEPTH: usize = 64;

struct Parser<'a> {
    text: &'a str,
    bytes: &'a [u8],
    pos: usize,
    path: &'a Path,
    depth: usize,
}

impl Parser<'_> {
    fn line(&self, at: usize) -> usize {
        self.text[..at.min(self.text.len())].matches('\n').count() + 1
    }

    fn error(&self, at: usize, message: impl std::fmt::Display) -> ExportError {
        parse_error(self.path, format!("line {}: {message}", self.line(at)))
    }

    fn skip(&mut self) -> Result<(), ExportError> {
        loop {
            while self.pos < self.bytes.len() && self.bytes[self.pos].is_ascii_whitespace() {
                self.pos += 1;
            }
            if self.text[self.pos..].starts_with("//") || self.text[self.pos..].starts_with('#') {
                self.pos = self.text[self.pos..]
                    .find('\n')
                    .map_or(self.text.len(), |n| self.pos + n);
            } else if self.text[self.pos..].starts_with("/*") {
                let at = self.pos;
                self.pos = self.text[self.pos + 2..]
                    .find("*/")
                    .map(|n| self.pos + 2 + n + 2)
                    .ok_or_else(|| self.error(at, "unterminated /* comment"))?;
            } else {
                return Ok(());
            }
        }
    }

    fn peek(&self) -> Option<u8> {
        self.bytes.get(self.pos).copied()
    }

    /// `key = value;` entries up to `close` (or the end of the text when `None`).
    fn entries(&mut self, close: Option<u8>) -> Result<Vec<(String, Value)>, ExportError> {
        let mut out: Vec<(String, Value)> = Vec::new();
        loop {
            self.skip()?;
            match (self.peek(), close) {
                (None, None) => return Ok(out),
                (None, Some(c)) => {
                    return Err(self.error(self.pos, format!("missing '{}'", c as char)));
                }
                (Some(c), Some(close)) if c == close => {
                    self.pos += 1;
                    return Ok(out);
                }
                _ => {}
            }
            let at = self.pos;
            let key_len = self.text[at..]
                .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
                .unwrap_or(self.text.len() - at);
            if key_len == 0 {
                let shown: String = self.text[at..].chars().take(12).collect();
                return Err(self.error(at, format!("expected a key, found '{shown}'")));
            }
            let key = self.text[at..at + key_len].to_string();
            self.pos += key_len;
            self.skip()?;
            if self.peek() != Some(b'=') {
                return Err(self.error(self.pos, format!("{key}: expected '='")));
            }
            self.pos += 1;
            let value = self.value(&key)?;
            self.skip()?;
            if self.peek() == Some(b';') {
                self.pos += 1;
            } else if !(self.peek().is_some() && self.peek() == close) {
                return Err(self.error(self.pos, format!("{key}: expected ';'")));
            }
            if out.iter().any(|(k, _)| *k == key) {
                return Err(self.error(at, format!("{key}: given twice")));
            }
            out.push((key, value));
        }
    }

    fn value(&mut self, key: &str) -> Result<Value, ExportError> {
        self.skip()?;
        let start = self.pos;
        if matches!(self.peek(), Some(b'{' | b'[')) {
            self.depth += 1;
            if self.depth > MAX_DEPTH {
                return Err(self.error(
                    start,
                    format!("{key}: nested deeper than {MAX_DEPTH} levels"),
                ));
            }
        }
        let value = self.value_at(key, start);
        if matches!(self.bytes.get(start), Some(b'{' | b'[')) {
            self.depth -= 1;
        }
        value
    }

    fn value_at(&mut self, key: &str, start: usize) -> Result<Value, ExportError> {
        let line = self.line(start);
        let kind = match self.peek() {
            Some(b'{') => {
                self.pos += 1;
                Kind::Map(self.entries(Some(b'}'))?)
            }
            Some(b'[') => {
                self.pos += 1;
                let mut items = Vec::new();
                loop {
                    self.skip()?;
                    if self.peek() == Some(b']') {
                        self.pos += 1;
                        break;
                    }
                    items.push(self.value(key)?);
                    self.skip()?;
                    match self.peek() {
                        Some(b',') => self.pos += 1,
                        Some(b']') => {}
                        _ => {
                            return Err(self.error(self.pos, format!("{key}: expected ',' or ']'")));
                        }
                    }
                }
                Kind::List(items)
            }
            Some(b'"') => {
                let end = self.text[start + 1..]
                    .find('"')
                    .map(|n| start + 1 + n + 1)
                    .ok_or_else(|| self.error(start, format!("{key}: unterminated string")))?;
                self.pos = end;
                Kind::Scalar(self.text[start..end].to_string())
            }
            _ => {
                let len = self.text[start..]
                    .find([';', ',', '}', ']', '\n', '{', '['])
                    .unwrap_or(self.text.len() - start);
                let raw = &self.text[start..start + len];
                let trimmed = raw.trim_end();
                if trimmed.is_empty() {
                    return Err(self.error(start, format!("{key}: missing value")));
                }
                self.pos = start + trimmed.len();
                Kind::Scalar(trimmed.to_string())
            }
        };
        Ok(Value {
            kind,
            start,
            end: self.pos,
            line,
        })
    }
}

/// An angle as B-Human reads it (`-3deg`, `0.1`, `0.1rad`, `0.5pi`), in radians.
pub fn angle_rad(text: &str) -> Option<f64> {
    let t = text.trim();
    let (number, factor) = if let Some(n) = t.strip_suffix("deg") {
        (n, std::f64::consts::PI / 180.0)
    } else if let Some(n) = t.strip_suffix("pi") {
        (n, std::f64::consts::PI)
    } else if let Some(n) = t.strip_suffix("rad") {
        (n, 1.0)
    } else {
        (t, 1.0)
    };
    let x: f64 = number.trim().parse().ok()?;
    let x = x * factor;
    x.is_finite().then_some(x)
}

/// An angle as B-Human reads it, in degrees: exact for the `deg` suffix (so that files
/// written in degrees read back bit for bit).
pub fn angle_deg(text: &str) -> Option<f64> {
    let t = text.trim();
    match t.strip_suffix("deg") {
        Some(n) => n.trim().parse().ok().filter(|x: &f64| x.is_finite()),
        None => angle_rad(t).map(f64::to_degrees),
    }
}

/// A plain number (`-0.0874`), if the text is one.
pub fn number(text: &str) -> Option<f64> {
    let x: f64 = text.trim().parse().ok()?;
    x.is_finite().then_some(x)
}

/// The text with each `(start, end, replacement)` spliced in (spans must not overlap).
pub fn splice(text: &str, mut edits: Vec<(usize, usize, String)>) -> String {
    edits.sort_by_key(|e| std::cmp::Reverse(e.0));
    let mut out = text.to_string();
    for (start, end, new) in edits {
        out.replace_range(start..end, &new);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_nested_maps_lists_and_comments_with_spans() {
        let text = "// robot\na = {\n  b = {x = -3deg; y = 0.1;}; /* c */\n  l = [1, 2];\n};\nc = default;\n";
        let v = parse(text, Path::new("t.cfg")).unwrap();
        let x = v.get(&["a", "b", "x"]).unwrap();
        assert_eq!(&text[x.start..x.end], "-3deg");
        assert_eq!(x.line, 3);
        assert!((angle_rad(x.scalar().unwrap()).unwrap() + 3f64.to_radians()).abs() < 1e-15);
        assert_eq!(v.get(&["c"]).unwrap().scalar(), Some("default"));
        let bad = parse("a = {x = 1;\n", Path::new("t.cfg")).unwrap_err();
        assert!(bad.to_string().contains("missing '}'"), "{bad}");
        let bad = parse("a = 1;\nb 2;\n", Path::new("t.cfg")).unwrap_err();
        assert!(bad.to_string().contains("line 2"), "{bad}");
    }

    #[test]
    fn any_text_parses_or_is_refused_without_panic() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let alphabet: Vec<char> = "ab=;{}[],/*\"\n é0.5deg".chars().collect();
        for _ in 0..5000 {
            let len = rng.random_range(0..40);
            let text: String = (0..len)
                .map(|_| alphabet[rng.random_range(0..alphabet.len())])
                .collect();
            let _ = parse(&text, Path::new("t.cfg"));
        }
    }
}
