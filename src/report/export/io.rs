//! Where exports may be written and how: never over an input, never over an existing file
//! unless asked, always atomically (a temporary file in the same directory, then a rename).

use std::io::{self, Write as _};
use std::path::{Path, PathBuf};

use super::ExportError;

/// How exported files are written.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct WriteOptions {
    /// Replace an existing file (never an input file).
    pub force: bool,
    /// Files that must never be written to (the dataset's files, the file converted).
    pub inputs: Vec<PathBuf>,
}

impl WriteOptions {
    /// Options that protect the files of the dataset in `dir` (and any file in it that
    /// exists when asked: `dataset.toml`, `captures.csv`, `corners.csv`, `truth.toml`).
    pub fn protecting_dataset(dir: &Path, force: bool) -> Self {
        WriteOptions {
            force,
            inputs: dataset_files(dir),
        }
    }
}

/// The files of the dataset in `dir` that a writer must never replace.
pub fn dataset_files(dir: &Path) -> Vec<PathBuf> {
    use crate::dataset::{CAPTURES_CSV, CORNERS_CSV, DATASET_TOML, TRUTH_TOML};
    [DATASET_TOML, CAPTURES_CSV, CORNERS_CSV, TRUTH_TOML]
        .iter()
        .map(|f| dir.join(f))
        .collect()
}

/// Whether `a` and `b` name the same file (same canonical path; or the same path when
/// either does not exist).
fn same_file(a: &Path, b: &Path) -> bool {
    let canon = |p: &Path| -> Option<PathBuf> {
        if let Ok(c) = p.canonicalize() {
            return Some(c);
        }
        // Not existing: canonicalise the parent and keep the name.
        let parent = match p.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        Some(parent.canonicalize().ok()?.join(p.file_name()?))
    };
    match (canon(a), canon(b)) {
        (Some(x), Some(y)) => x == y,
        _ => a == b,
    }
}

/// Whether `path` may be written under `options`: not one of `options.inputs`, and not
/// an existing file unless `options.force`.
pub fn check_writable(path: &Path, options: &WriteOptions) -> Result<(), ExportError> {
    if let Some(input) = options.inputs.iter().find(|i| same_file(i, path)) {
        return Err(ExportError::Input {
            path: input.clone(),
        });
    }
    if !options.force && path.symlink_metadata().is_ok() {
        return Err(ExportError::Exists {
            path: path.to_path_buf(),
        });
    }
    Ok(())
}

/// Writes `contents` to `path` atomically (temporary file in the same directory, then a
/// rename; the directory is created if missing). Refuses a path that is one of
/// `options.inputs`, and an existing file unless `options.force`.
pub fn write_atomic(
    path: &Path,
    contents: &[u8],
    options: &WriteOptions,
) -> Result<(), ExportError> {
    write_atomic_with(path, options, |tmp| {
        let mut file = std::fs::OpenOptions::new().write(true).open(tmp)?;
        file.write_all(contents)?;
        file.sync_all()
    })
}

/// Like [`write_atomic`], but the content is produced by `fill`, which writes the
/// temporary file at the path it is given (a sibling of `path` with the same extension, so
/// that writers that look at the extension, such as image encoders, do the right thing).
pub fn write_atomic_with(
    path: &Path,
    options: &WriteOptions,
    fill: impl FnOnce(&Path) -> io::Result<()>,
) -> Result<(), ExportError> {
    check_writable(path, options)?;
    let dir = match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir,
        _ => Path::new("."),
    };
    let io_err = |action, source| ExportError::Io {
        path: path.to_path_buf(),
        action,
        source,
    };
    std::fs::create_dir_all(dir).map_err(|e| io_err("create the directory for", e))?;
    let suffix = path
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_else(|| ".tmp".into());
    let mut builder = tempfile::Builder::new();
    builder.prefix(".naocalib-").suffix(&suffix);
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    let tmp = builder
        .tempfile_in(dir)
        .map_err(|e| io_err("create a temporary file to write", e))?;
    fill(tmp.path()).map_err(|e| io_err("write", e))?;
    let persisted = if options.force {
        tmp.persist(path)
    } else {
        tmp.persist_noclobber(path)
    };
    persisted.map(|_| ()).map_err(|e| match e.error.kind() {
        io::ErrorKind::AlreadyExists if !options.force => ExportError::Exists {
            path: path.to_path_buf(),
        },
        _ => io_err("write", e.error),
    })
}
