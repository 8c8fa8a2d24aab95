//! The one error type of dataset reading, validation and writing.

use std::fmt;
use std::io;
use std::path::{Path, PathBuf};

/// Where in a dataset something is wrong: a file, and when known the line in it (1-based,
/// the CSV header is line 1) and the field (a CSV column name, or a TOML key path such as
/// `camera.fx` or `camera.distortion[2]`).
///
/// Displays as `data/x/captures.csv line 7, field LKneePitch`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Location {
    /// The file.
    pub path: PathBuf,
    /// The line in the file, 1-based, when known.
    pub line: Option<u64>,
    /// The CSV column or TOML key path, when the problem is in one field.
    pub field: Option<String>,
}

impl Location {
    /// A whole file.
    pub fn file(path: impl Into<PathBuf>) -> Self {
        Location {
            path: path.into(),
            line: None,
            field: None,
        }
    }

    /// A line of a file.
    pub fn line(path: impl Into<PathBuf>, line: u64) -> Self {
        Location {
            path: path.into(),
            line: Some(line),
            field: None,
        }
    }

    /// The same location, narrowed to a field.
    pub fn field(mut self, field: impl Into<String>) -> Self {
        self.field = Some(field.into());
        self
    }
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.path.display())?;
        if let Some(line) = self.line {
            write!(f, " line {line}")?;
        }
        if let Some(field) = &self.field {
            write!(f, ", field {field}")?;
        }
        Ok(())
    }
}

/// Everything that can go wrong reading, validating or writing a dataset. The message
/// always names the file, and where it can, the line and the field.
#[derive(Debug, thiserror::Error)]
pub enum DatasetError {
    /// A file the dataset needs does not exist.
    #[error("{}: no such file{hint}", path.display())]
    NotFound {
        /// The missing file.
        path: PathBuf,
        /// What the file is for, or where to look (starts with a separator, may be empty).
        hint: String,
    },
    /// A file exists but holds nothing.
    #[error("{}: the file is empty{hint}", path.display())]
    Empty {
        /// The empty file.
        path: PathBuf,
        /// What the file must at least contain (starts with a separator, may be empty).
        hint: String,
    },
    /// Reading, writing or creating a file or directory failed. The operating system's
    /// error is part of the message, and deliberately not also the error's `source`, so
    /// that a printed error chain does not repeat it.
    #[error("{}: cannot {action}: {error}", path.display())]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// What was attempted (`read`, `write`, `create the directory`, …).
        action: &'static str,
        /// The operating system's error.
        error: io::Error,
    },
    /// Writing would replace (or leave behind) an existing file, and `force` was not given.
    #[error("{}: {reason}; use --force to overwrite", path.display())]
    Exists {
        /// The existing file.
        path: PathBuf,
        /// Why it is in the way.
        reason: &'static str,
    },
    /// The dataset's directory cannot be made: it, or a file on the way to it, is not a
    /// directory.
    #[error("{}: {reason}", path.display())]
    Refused {
        /// The file not written.
        path: PathBuf,
        /// Why.
        reason: String,
    },
    /// Writing a file failed or was refused ([`crate::output`], the one writer): it exists
    /// and `force` was not given, it is an input, something is in the way.
    #[error(transparent)]
    Write(#[from] crate::output::WriteError),
    /// The content of a file (or of a dataset about to be written) is wrong.
    #[error("{at}: {message}")]
    Invalid {
        /// File, line and field.
        at: Location,
        /// What is wrong, and what was expected.
        message: String,
    },
}

impl DatasetError {
    /// An [`DatasetError::Invalid`] at `at`.
    pub fn invalid(at: Location, message: impl Into<String>) -> Self {
        DatasetError::Invalid {
            at,
            message: message.into(),
        }
    }

    /// The file the error is about.
    pub fn path(&self) -> &Path {
        match self {
            DatasetError::NotFound { path, .. }
            | DatasetError::Empty { path, .. }
            | DatasetError::Io { path, .. }
            | DatasetError::Exists { path, .. }
            | DatasetError::Refused { path, .. } => path,
            DatasetError::Write(e) => e.path(),
            DatasetError::Invalid { at, .. } => &at.path,
        }
    }

    /// The line the error is about, when known.
    pub fn line(&self) -> Option<u64> {
        match self {
            DatasetError::Invalid { at, .. } => at.line,
            _ => None,
        }
    }

    /// The field (CSV column or TOML key path) the error is about, when known.
    pub fn field(&self) -> Option<&str> {
        match self {
            DatasetError::Invalid { at, .. } => at.field.as_deref(),
            _ => None,
        }
    }

    pub(crate) fn io(path: &Path, action: &'static str, error: io::Error) -> Self {
        DatasetError::Io {
            path: path.to_path_buf(),
            action,
            error,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn location_display() {
        let at = Location::line("data/x/captures.csv", 7).field("LKneePitch");
        assert_eq!(
            at.to_string(),
            "data/x/captures.csv line 7, field LKneePitch"
        );
        let at = Location::file("d/dataset.toml").field("camera");
        assert_eq!(at.to_string(), "d/dataset.toml, field camera");
        assert_eq!(Location::line("c.csv", 3).to_string(), "c.csv line 3");
    }

    #[test]
    fn error_display_and_accessors() {
        let e = DatasetError::invalid(
            Location::line("d/captures.csv", 7).field("LKneePitch"),
            "'abc' is not a number",
        );
        assert_eq!(
            e.to_string(),
            "d/captures.csv line 7, field LKneePitch: 'abc' is not a number"
        );
        assert_eq!(e.line(), Some(7));
        assert_eq!(e.field(), Some("LKneePitch"));
        assert_eq!(e.path(), Path::new("d/captures.csv"));
        let e = DatasetError::Exists {
            path: "d/corners.csv".into(),
            reason: "already exists",
        };
        assert_eq!(
            e.to_string(),
            "d/corners.csv: already exists; use --force to overwrite"
        );
    }
}
