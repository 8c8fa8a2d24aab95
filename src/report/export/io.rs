//! Where exports may be written and how: the project's one atomic writer
//! ([`crate::output`]), with this module's error type.

use std::io;
use std::path::Path;

use super::ExportError;

pub use crate::output::{WriteOptions, dataset_files};

impl From<crate::output::WriteError> for ExportError {
    fn from(e: crate::output::WriteError) -> Self {
        use crate::output::WriteError as W;
        match e {
            W::Io {
                path,
                action,
                error,
            } => ExportError::Io {
                path,
                action,
                source: error,
            },
            W::Exists { path } => ExportError::Exists { path },
            W::Input { path } => ExportError::Input { path },
            W::NotAFile { path } => ExportError::Io {
                path,
                action: "write",
                source: io::Error::other("exists and is not a regular file"),
            },
            W::InTheWay { path, in_the_way } => ExportError::Io {
                path,
                action: "create its directory",
                source: io::Error::other(format!(
                    "a file is in the way: {} exists and is not a directory",
                    in_the_way.display()
                )),
            },
        }
    }
}

/// Whether `path` may be written under `options`: not one of `options.inputs`, and not
/// an existing file unless `options.force`.
pub fn check_writable(path: &Path, options: &WriteOptions) -> Result<(), ExportError> {
    Ok(crate::output::check_writable(path, options)?)
}

/// [`crate::output::write_atomic`], with this module's error type.
pub fn write_atomic(
    path: &Path,
    contents: &[u8],
    options: &WriteOptions,
) -> Result<(), ExportError> {
    Ok(crate::output::write_atomic(path, contents, options)?)
}

/// [`crate::output::write_atomic_with`], with this module's error type.
pub fn write_atomic_with(
    path: &Path,
    options: &WriteOptions,
    fill: impl FnOnce(&Path) -> io::Result<()>,
) -> Result<(), ExportError> {
    Ok(crate::output::write_atomic_with(path, options, fill)?)
}
