//! Writing files atomically: a temporary file in the same directory, then a rename.

use std::io::{self, Write as _};
use std::path::Path;

use super::error::DatasetError;

/// Creates `dir` (and its parents) if it does not exist.
pub(crate) fn create_dir(dir: &Path) -> Result<(), DatasetError> {
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

/// Writes `contents` to `path` atomically: readers see the old file or the new one, never
/// a part. Refuses to replace an existing file unless `force`. The directory must exist.
pub(crate) fn write_atomic(path: &Path, contents: &[u8], force: bool) -> Result<(), DatasetError> {
    check_absent(path, force)?;
    let dir = match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir,
        _ => Path::new("."),
    };
    let mut builder = tempfile::Builder::new();
    builder.prefix(".naocalib-").suffix(".tmp");
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        // Like any new file: read-write for everyone the umask allows (tempfile's default
        // is owner-only).
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    let mut tmp = builder
        .tempfile_in(dir)
        .map_err(|e| DatasetError::io(path, "create a temporary file to write", e))?;
    tmp.write_all(contents)
        .and_then(|()| tmp.as_file().sync_all())
        .map_err(|e| DatasetError::io(path, "write", e))?;
    let persisted = if force {
        tmp.persist(path)
    } else {
        tmp.persist_noclobber(path)
    };
    persisted.map(|_| ()).map_err(|e| match e.error.kind() {
        io::ErrorKind::AlreadyExists if !force => DatasetError::Exists {
            path: path.to_path_buf(),
            reason: "already exists",
        },
        _ => DatasetError::io(path, "write", e.error),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_refuses_and_forces() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.csv");
        write_atomic(&path, b"one", false).unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"one");
        let e = write_atomic(&path, b"two", false).unwrap_err();
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
        let names: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, ["a.csv"], "no temporary file left behind");
    }

    #[cfg(unix)]
    #[test]
    fn written_files_get_the_usual_permissions() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.csv");
        write_atomic(&path, b"x", false).unwrap();
        let plain = dir.path().join("b.csv");
        std::fs::write(&plain, b"x").unwrap();
        let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode();
        assert_eq!(
            mode(&path),
            mode(&plain),
            "same as a file made by std::fs::write"
        );
    }

    #[test]
    fn missing_directory_is_an_io_error() {
        let dir = tempfile::tempdir().unwrap();
        let e = write_atomic(&dir.path().join("no/a.csv"), b"x", false).unwrap_err();
        assert!(matches!(e, DatasetError::Io { .. }), "{e}");
    }
}
