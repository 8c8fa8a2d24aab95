//! JSON read with the byte span of every value, so that an update of a robot's parameter
//! file replaces (or inserts) a value and keeps every other byte.

use std::path::Path;

use super::{ExportError, parse_error};

/// A JSON value with where its text is.
pub type Value = super::tree::Node<Kind>;

/// The kinds of JSON values.
#[derive(Debug, Clone, PartialEq)]
pub enum Kind {
    /// A number (its value, when finite).
    Number(f64),
    /// A string, `true`, `false` or `null` (their text).
    Other,
    /// An object, in file order.
    Object(Vec<(String, Value)>),
    /// An array.
    Array(Vec<Value>),
}

impl super::tree::Members for Kind {
    fn members(&self) -> Option<&[(String, Value)]> {
        match self {
            Kind::Object(members) => Some(members),
            _ => None,
        }
    }
}

/// Objects and arrays nested deeper than this are refused (the teams' files nest four
/// deep; the parser recurses, so an unbounded depth would overflow the stack).
pub const MAX_DEPTH: usize = 64;

/// The line where `text`'s objects and arrays first nest deeper than [`MAX_DEPTH`], if
/// anywhere (strings skipped).
fn too_deep(text: &str) -> Option<usize> {
    let (mut depth, mut line, mut in_string, mut escaped) = (0usize, 1, false, false);
    for b in text.bytes() {
        match b {
            b'\n' => line += 1,
            _ if in_string => {}
            b'[' | b'{' => {
                depth += 1;
                if depth > MAX_DEPTH {
                    return Some(line);
                }
            }
            b']' | b'}' => depth = depth.saturating_sub(1),
            _ => {}
        }
        if in_string {
            match (escaped, b) {
                (true, _) => escaped = false,
                (false, b'\\') => escaped = true,
                (false, b'"') => in_string = false,
                _ => {}
            }
        } else if b == b'"' {
            in_string = true;
        }
    }
    None
}

/// Parses `text` (checked with serde_json first, whose error names the line; nesting
/// deeper than [`MAX_DEPTH`] refused).
pub fn parse(text: &str, path: &Path) -> Result<Value, ExportError> {
    if let Some(line) = too_deep(text) {
        return Err(parse_error(
            path,
            format!("line {line}: nested deeper than {MAX_DEPTH} levels"),
        ));
    }
    serde_json::from_str::<serde::de::IgnoredAny>(text)
        .map_err(|e| parse_error(path, format!("line {}: {e}", e.line())))?;
    let mut p = Parser {
        text,
        b: text.as_bytes(),
        pos: 0,
        twice: None,
    };
    let root = p.value();
    match p.twice {
        // serde keeps the last of a repeated key, a team's framework may keep the first:
        // which one the robot runs with is unknown.
        Some((line, key)) => Err(parse_error(
            path,
            format!("line {line}: \"{key}\" is given twice in the same object"),
        )),
        None => Ok(root),
    }
}

struct Parser<'a> {
    text: &'a str,
    b: &'a [u8],
    pos: usize,
    /// The first key given twice in one object, with its line.
    twice: Option<(usize, String)>,
}

impl Parser<'_> {
    fn ws(&mut self) {
        while self.pos < self.b.len() && self.b[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
    }

    fn string(&mut self) -> String {
        // At the opening quote; the text is valid JSON.
        let start = self.pos;
        self.pos += 1;
        while self.b[self.pos] != b'"' {
            if self.b[self.pos] == b'\\' {
                self.pos += 1;
            }
            self.pos += 1;
        }
        self.pos += 1;
        serde_json::from_str(&self.text[start..self.pos]).unwrap_or_default()
    }

    fn value(&mut self) -> Value {
        self.ws();
        let start = self.pos;
        let line = self.text[..start].matches('\n').count() + 1;
        let kind = match self.b[self.pos] {
            b'{' => {
                self.pos += 1;
                let mut members = Vec::new();
                let mut seen = std::collections::HashSet::new();
                loop {
                    self.ws();
                    if self.b[self.pos] == b'}' {
                        self.pos += 1;
                        break;
                    }
                    if self.b[self.pos] == b',' {
                        self.pos += 1;
                        continue;
                    }
                    let key_at = self.pos;
                    let key = self.string();
                    if !seen.insert(key.clone()) && self.twice.is_none() {
                        let line = self.text[..key_at].matches('\n').count() + 1;
                        self.twice = Some((line, key.clone()));
                    }
                    self.ws();
                    self.pos += 1; // ':'
                    let v = self.value();
                    members.push((key, v));
                }
                Kind::Object(members)
            }
            b'[' => {
                self.pos += 1;
                let mut items = Vec::new();
                loop {
                    self.ws();
                    if self.b[self.pos] == b']' {
                        self.pos += 1;
                        break;
                    }
                    if self.b[self.pos] == b',' {
                        self.pos += 1;
                        continue;
                    }
                    items.push(self.value());
                }
                Kind::Array(items)
            }
            b'"' => {
                self.string();
                Kind::Other
            }
            _ => {
                let len = self.text[start..]
                    .find(|c: char| !(c.is_ascii_alphanumeric() || matches!(c, '-' | '+' | '.')))
                    .unwrap_or(self.text.len() - start);
                self.pos = start + len;
                match self.text[start..self.pos].parse::<f64>() {
                    Ok(x) => Kind::Number(x),
                    Err(_) => Kind::Other,
                }
            }
        };
        Value {
            kind,
            start,
            end: self.pos,
            line,
        }
    }
}

/// The whitespace that starts the line holding byte `at`.
fn indent_at(text: &str, at: usize) -> &str {
    let line_start = text[..at].rfind('\n').map_or(0, |n| n + 1);
    let rest = &text[line_start..];
    &rest[..rest.len() - rest.trim_start().len()]
}

/// `text` with the number at `path` set to `new` (its text): replaced where it exists,
/// otherwise inserted into the deepest existing object on the path, creating the missing
/// objects. Fails when something on the path is not an object.
pub fn set(text: &str, path: &[&str], new: &str, file: &Path) -> Result<String, ExportError> {
    let root = parse(text, file)?;
    let mut node = &root;
    for (depth, key) in path.iter().enumerate() {
        let Kind::Object(members) = &node.kind else {
            return Err(parse_error(
                file,
                format!(
                    "line {}: {}: expected an object",
                    node.line,
                    path[..depth].join(".")
                ),
            ));
        };
        match members.iter().find(|(k, _)| k == key) {
            Some((_, v)) => node = v,
            None => {
                // Insert `key: {rest…: new}` into this object.
                let mut value = new.to_string();
                for k in path[depth + 1..].iter().rev() {
                    value = format!("{{\"{k}\": {value}}}");
                }
                let member = format!("\"{key}\": {value}");
                let (at, insert) = match members.last() {
                    Some((_, last)) => {
                        // The last member's key starts its line (pretty-printed files).
                        let indent = indent_at(text, last.start);
                        (last.end, format!(",\n{indent}{member}"))
                    }
                    None => {
                        let indent = indent_at(text, node.start);
                        (node.start + 1, format!("\n{indent}  {member}\n{indent}"))
                    }
                };
                let mut out = text.to_string();
                out.insert_str(at, &insert);
                return Ok(out);
            }
        }
    }
    match node.kind {
        Kind::Number(_) => {
            let mut out = text.to_string();
            out.replace_range(node.start..node.end, new);
            Ok(out)
        }
        _ => Err(parse_error(
            file,
            format!("line {}: {}: expected a number", node.line, path.join(".")),
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sets_existing_and_inserts_missing_keeping_other_bytes() {
        let text = "{\n  \"a\": {\n    \"x\": 1.5\n  },\n  \"b\": [1, 2]\n}\n";
        let f = Path::new("t.json");
        let out = set(text, &["a", "x"], "-2", f).unwrap();
        assert_eq!(out, text.replace("1.5", "-2"));
        let out = set(text, &["a", "y"], "3", f).unwrap();
        assert_eq!(
            out,
            "{\n  \"a\": {\n    \"x\": 1.5,\n    \"y\": 3\n  },\n  \"b\": [1, 2]\n}\n"
        );
        let out = set(text, &["c", "d"], "4", f).unwrap();
        let v: serde_json::Value = serde_json::from_str(&out).unwrap();
        assert_eq!(v["c"]["d"], 4);
        assert_eq!(v["b"][1], 2);
        assert!(set(text, &["b", "x"], "1", f).is_err());
        assert!(
            parse("{\n\"a\": 1,\n}", f)
                .unwrap_err()
                .to_string()
                .contains("line 3")
        );
    }
}
