//! Changing an existing file: its content replaced through its links, keeping its mode,
//! owner and hard links; and a new file (a backup) made like another.

use std::io::{self, Write as _};
use std::path::{Path, PathBuf};

use super::{WriteError, WriteOptions, same_file, write_atomic_with};

/// Replaces the content of the existing regular file `path` with `contents` and returns
/// the file written: symbolic links are followed (the file they point to is replaced, the
/// links stay), and the file keeps its mode, owner and group. A file with one link is
/// replaced atomically (a temporary file with the same mode and owner, renamed over it); a
/// file with several hard links, or one whose owner this process cannot give a new file,
/// is rewritten in place (every link sees the new content; a crash part-way can leave it
/// partly written, so callers keep a backup first). Refuses an input, something that is
/// not a regular file, and a read-only file.
pub fn rewrite(
    path: &Path,
    contents: &[u8],
    options: &WriteOptions,
) -> Result<PathBuf, WriteError> {
    let io_err = |path: &Path, action, error| WriteError::Io {
        path: path.to_path_buf(),
        action,
        error,
    };
    let (real, meta) = check_rewritable(path, options)?;
    let in_place = |real: &Path| -> Result<(), WriteError> {
        let mut file = std::fs::OpenOptions::new()
            .write(true)
            .open(real)
            .map_err(|e| io_err(real, "open", e))?;
        file.write_all(contents)
            .and_then(|_| file.set_len(contents.len() as u64))
            .and_then(|_| file.sync_all())
            .map_err(|e| io_err(real, "write", e))
    };
    if links(&meta) > 1 {
        in_place(&real)?;
        return Ok(real);
    }
    let owner_kept = std::cell::Cell::new(true);
    let options = WriteOptions {
        force: true,
        inputs: options.inputs.clone(),
    };
    let written = write_atomic_with(&real, &options, |tmp| {
        let mut file = std::fs::OpenOptions::new().write(true).open(tmp)?;
        file.write_all(contents)?;
        file.sync_all()?;
        if !like(tmp, &meta) {
            owner_kept.set(false);
            return Err(io::Error::other("cannot give the file its owner"));
        }
        Ok(())
    });
    match written {
        Err(_) if !owner_kept.get() => in_place(&real)?,
        other => other?,
    }
    Ok(real)
}

/// Checks, without writing, that [`rewrite`] would not refuse `path`; returns the file it
/// would write (symbolic links resolved) and its metadata.
pub fn check_rewritable(
    path: &Path,
    options: &WriteOptions,
) -> Result<(PathBuf, std::fs::Metadata), WriteError> {
    let io_err = |path: &Path, action, error| WriteError::Io {
        path: path.to_path_buf(),
        action,
        error,
    };
    let real = path
        .canonicalize()
        .map_err(|e| io_err(path, "resolve", e))?;
    if let Some(input) = options.inputs.iter().find(|i| same_file(i, &real)) {
        return Err(WriteError::Input {
            path: input.clone(),
        });
    }
    let meta = std::fs::metadata(&real).map_err(|e| io_err(&real, "read", e))?;
    if !meta.is_file() {
        return Err(WriteError::NotAFile { path: real });
    }
    if is_read_only(&real, &meta) {
        return Err(WriteError::ReadOnly {
            path: path.to_path_buf(),
        });
    }
    Ok((real, meta))
}

/// Writes the new file `path` (never over an existing one) with the mode, owner and group
/// of the file whose metadata is `model` (the owner as far as this process may give it).
pub fn write_new_like(
    path: &Path,
    contents: &[u8],
    model: &std::fs::Metadata,
    options: &WriteOptions,
) -> Result<(), WriteError> {
    let options = WriteOptions {
        force: false,
        inputs: options.inputs.clone(),
    };
    write_atomic_with(path, &options, |tmp| {
        let mut file = std::fs::OpenOptions::new().write(true).open(tmp)?;
        file.write_all(contents)?;
        file.sync_all()?;
        like(tmp, model);
        Ok(())
    })
}

/// Gives `path` the mode of `model`, and its owner and group; `false` when the owner or
/// group could not be given (the mode is set either way).
fn like(path: &Path, model: &std::fs::Metadata) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::{MetadataExt, PermissionsExt};
        let _ =
            std::fs::set_permissions(path, std::fs::Permissions::from_mode(model.mode() & 0o7777));
        let mine = std::fs::metadata(path)
            .map(|m| (m.uid(), m.gid()))
            .unwrap_or((u32::MAX, u32::MAX));
        if mine == (model.uid(), model.gid()) {
            return true;
        }
        let owned = std::os::unix::fs::chown(path, Some(model.uid()), Some(model.gid())).is_ok();
        // chown clears set-id bits: set the mode again.
        let _ =
            std::fs::set_permissions(path, std::fs::Permissions::from_mode(model.mode() & 0o7777));
        owned
    }
    #[cfg(not(unix))]
    {
        let _ = std::fs::set_permissions(path, model.permissions());
        true
    }
}

/// The number of hard links of a file.
fn links(meta: &std::fs::Metadata) -> u64 {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        meta.nlink()
    }
    #[cfg(not(unix))]
    {
        let _ = meta;
        1
    }
}

/// Whether the file at `path` is read-only: no write permission for anyone, or (Unix) none
/// for this process.
fn is_read_only(path: &Path, meta: &std::fs::Metadata) -> bool {
    if meta.permissions().readonly() {
        return true;
    }
    #[cfg(unix)]
    {
        use std::os::unix::ffi::OsStrExt;
        let Ok(c) = std::ffi::CString::new(path.as_os_str().as_bytes()) else {
            return false;
        };
        // SAFETY: `c` is a valid NUL-terminated path; access only reads it.
        unsafe { libc::access(c.as_ptr(), libc::W_OK) != 0 }
    }
    #[cfg(not(unix))]
    {
        false
    }
}
