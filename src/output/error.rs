//! Why a file was not written.

use std::io;
use std::path::{Path, PathBuf};

/// Why a file was not written. The message names the file; the operating system's error
/// is part of the message (and deliberately not also a `source`, so that a printed error
/// chain does not repeat it).
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    /// Creating the directory, the temporary file, writing or renaming failed.
    #[error("{}: cannot {action}: {error}", path.display())]
    Io {
        /// The file being written.
        path: PathBuf,
        /// What was attempted.
        action: &'static str,
        /// The operating system's error.
        error: io::Error,
    },
    /// The file exists and `force` was not given.
    #[error("{}: already exists; use --force to overwrite", path.display())]
    Exists {
        /// The existing file.
        path: PathBuf,
    },
    /// The path is one of the inputs.
    #[error("{}: is an input file; refusing to overwrite it", path.display())]
    Input {
        /// The input file.
        path: PathBuf,
    },
    /// Something other than a regular file or a symbolic link is in the way.
    #[error("{}: exists and is not a regular file; refusing to replace it", path.display())]
    NotAFile {
        /// The path.
        path: PathBuf,
    },
    /// The file to change is read-only.
    #[error("{}: is read-only; refusing to change it (make it writable first)", path.display())]
    ReadOnly {
        /// The file.
        path: PathBuf,
    },
    /// A directory on the way to the file cannot be made: a file is in the way.
    #[error("{}", in_the_way_message(path, in_the_way))]
    InTheWay {
        /// The file being written.
        path: PathBuf,
        /// The existing non-directory where a directory is needed.
        in_the_way: PathBuf,
    },
    /// The directory to write into, or one on the way to it, is a symbolic link to
    /// nothing: no directory is made through it.
    #[error("{}", dangling_message(path, link, target))]
    DanglingLink {
        /// The file (or directory) being written.
        path: PathBuf,
        /// The symbolic link.
        link: PathBuf,
        /// Where it points.
        target: PathBuf,
    },
}

impl WriteError {
    /// The file the error is about.
    pub fn path(&self) -> &Path {
        match self {
            WriteError::Io { path, .. }
            | WriteError::Exists { path }
            | WriteError::Input { path }
            | WriteError::NotAFile { path }
            | WriteError::ReadOnly { path }
            | WriteError::InTheWay { path, .. }
            | WriteError::DanglingLink { path, .. } => path,
        }
    }
}

impl WriteError {
    /// The error with every path it names passed through `f` (a staged file named where
    /// it is published).
    pub fn map_paths(self, f: impl Fn(&Path) -> PathBuf) -> WriteError {
        match self {
            WriteError::Io {
                path,
                action,
                error,
            } => WriteError::Io {
                path: f(&path),
                action,
                error,
            },
            WriteError::Exists { path } => WriteError::Exists { path: f(&path) },
            WriteError::Input { path } => WriteError::Input { path: f(&path) },
            WriteError::NotAFile { path } => WriteError::NotAFile { path: f(&path) },
            WriteError::ReadOnly { path } => WriteError::ReadOnly { path: f(&path) },
            WriteError::InTheWay { path, in_the_way } => WriteError::InTheWay {
                path: f(&path),
                in_the_way: f(&in_the_way),
            },
            WriteError::DanglingLink { path, link, target } => WriteError::DanglingLink {
                path: f(&path),
                link: f(&link),
                target,
            },
        }
    }
}

/// The message of [`WriteError::InTheWay`].
fn in_the_way_message(path: &Path, in_the_way: &Path) -> String {
    if path == in_the_way {
        format!(
            "{}: exists and is not a directory: a file is in the way of the directory to \
             write into",
            path.display()
        )
    } else {
        format!(
            "{}: exists and is not a directory: a file is in the way of the directory for {}",
            in_the_way.display(),
            path.display()
        )
    }
}

/// The message of [`WriteError::DanglingLink`].
fn dangling_message(path: &Path, link: &Path, target: &Path) -> String {
    let what = if path == link {
        format!(
            "{}: is a symbolic link to {}",
            path.display(),
            target.display()
        )
    } else {
        format!(
            "{}: cannot be written: {} on its way is a symbolic link to {}",
            path.display(),
            link.display(),
            target.display()
        )
    };
    format!(
        "{what}, which does not exist: nothing is written through it (make that directory, \
         or name another)"
    )
}
