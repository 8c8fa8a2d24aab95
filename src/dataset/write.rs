//! Checks before writing dataset files (which go through the one writer,
//! [`crate::output::write_atomic`]).

use std::path::Path;

use super::error::DatasetError;

/// Creates `dir` (and its parents) if it does not exist.
pub(crate) fn create_dir(dir: &Path) -> Result<(), DatasetError> {
    if dir.metadata().is_ok_and(|m| !m.is_dir()) {
        return Err(DatasetError::Refused {
            path: dir.to_path_buf(),
            reason: "exists and is not a directory; a dataset is written into a directory".into(),
        });
    }
    if let Some(file) = crate::output::file_in_the_way(dir) {
        return Err(DatasetError::Refused {
            path: file,
            reason: format!(
                "exists and is not a directory: a file is in the way of {}",
                dir.display()
            ),
        });
    }
    std::fs::create_dir_all(dir).map_err(|e| DatasetError::io(dir, "create the directory", e))
}

/// Fails if `path` exists and `force` is not set.
pub(crate) fn check_absent(path: &Path, force: bool) -> Result<(), DatasetError> {
    if !force && path.symlink_metadata().is_ok() {
        return Err(DatasetError::Exists {
            path: path.to_path_buf(),
            reason: "already exists",
        });
    }
    Ok(())
}
