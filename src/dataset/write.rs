//! Writing dataset files, through the one atomic writer ([`crate::output`]).

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

/// Writes `contents` to `path` with [`crate::output::write_atomic`]: atomically, refusing
/// to replace an existing file unless `force`. The directory must exist.
pub(crate) fn write_atomic(path: &Path, contents: &[u8], force: bool) -> Result<(), DatasetError> {
    Ok(crate::output::write_atomic(
        path,
        contents,
        &crate::output::WriteOptions::new(force),
    )?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refusal_is_a_dataset_error() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.csv");
        write_atomic(&path, b"one", false).unwrap();
        let e = write_atomic(&path, b"two", false).unwrap_err();
        assert!(matches!(e, DatasetError::Exists { .. }), "{e}");
        assert_eq!(
            e.to_string(),
            format!(
                "{}: already exists; use --force to overwrite",
                path.display()
            )
        );
        assert_eq!(std::fs::read(&path).unwrap(), b"one");
        write_atomic(&path, b"two", true).unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"two");
    }
}
