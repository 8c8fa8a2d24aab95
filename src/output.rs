//! The one way naocalib writes a file: [`write_atomic`].
//!
//! Every output — dataset files, corners, exports, plots, batch results, rendered images,
//! overlays — goes through it, so every output is
//!
//! - **atomic**: written to a temporary file in the same directory, synced, then renamed
//!   over the target; readers see the old file or the new one, never a part, and a failed
//!   write leaves what was there untouched (the temporary file is removed);
//! - **no-clobber**: an existing path is refused unless [`WriteOptions::force`];
//! - **input-safe**: a path that is one of [`WriteOptions::inputs`] is refused even with
//!   `force`, compared after resolving symbolic links and `..` (and, on Unix, by device
//!   and inode, so a hard link to an input is refused too);
//! - **the same file when changed**: [`rewrite`] replaces an existing file's content
//!   through its symbolic links, keeping its mode, owner and hard links, and refuses a
//!   read-only one; [`write_new_like`] writes a new file (a backup) with another's mode
//!   and owner;
//! - **clean after a kill**: temporary files and staging directories are named
//!   `.naocalib-<pid>-…`; the next write into the same directory removes those whose
//!   process is gone ([`sweep_stale`]).
//!
//! A set of files that belongs together (`solve --plots`, `--export`, `batch --out`, a
//! simulated dataset) is written through a [`Staged`] directory beside its target and
//! published at the end, so that a refusal, an error or a kill part-way leaves the
//! previous state. [`check_outputs`] checks every output of a command against every input
//! before anything is written.

use std::io::{self, Write as _};
use std::path::{Path, PathBuf};

/// How a file is written.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct WriteOptions {
    /// Replace an existing file (never an input file).
    pub force: bool,
    /// Files that must never be written to (a dataset's files, the file converted, …).
    pub inputs: Vec<PathBuf>,
}

impl WriteOptions {
    /// Options with `force` and no protected inputs.
    pub fn new(force: bool) -> Self {
        WriteOptions {
            force,
            inputs: Vec::new(),
        }
    }

    /// Options that protect the files of the dataset in `dir` (see [`dataset_files`]).
    pub fn protecting_dataset(dir: &Path, force: bool) -> Self {
        WriteOptions {
            force,
            inputs: dataset_files(dir),
        }
    }

    /// These options, also protecting `paths`.
    pub fn protecting(mut self, paths: impl IntoIterator<Item = PathBuf>) -> Self {
        self.inputs.extend(paths);
        self
    }
}

/// The files of the dataset in `dir` that a writer must never replace: `dataset.toml`,
/// `captures.csv`, `corners.csv` and `truth.toml`.
pub fn dataset_files(dir: &Path) -> Vec<PathBuf> {
    use crate::dataset::{CAPTURES_CSV, CORNERS_CSV, DATASET_TOML, TRUTH_TOML};
    [DATASET_TOML, CAPTURES_CSV, CORNERS_CSV, TRUTH_TOML]
        .iter()
        .map(|f| dir.join(f))
        .collect()
}

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
            | WriteError::InTheWay { path, .. } => path,
        }
    }
}

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

/// Whether `a` and `b` name the same file: the same path after resolving symbolic links
/// and `..` (for a path that does not exist: its resolved directory and its name), or, on
/// Unix, the same device and inode.
pub fn same_file(a: &Path, b: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if let (Ok(x), Ok(y)) = (std::fs::metadata(a), std::fs::metadata(b))
            && x.dev() == y.dev()
            && x.ino() == y.ino()
        {
            return true;
        }
    }
    match (resolve(a), resolve(b)) {
        (Some(x), Some(y)) => x == y,
        _ => a == b,
    }
}

/// `p` with symbolic links and `..` resolved, also when `p` itself does not exist (then
/// its directory is resolved and its name kept; a dangling symbolic link is followed to
/// where it points).
fn resolve(p: &Path) -> Option<PathBuf> {
    if let Ok(c) = p.canonicalize() {
        return Some(c);
    }
    if let Ok(target) = std::fs::read_link(p) {
        let dir = parent_dir(p);
        let target = if target.is_absolute() {
            target
        } else {
            dir.join(target)
        };
        // One level: a chain of dangling links resolves no further than this.
        let parent = parent_dir(&target).canonicalize().ok()?;
        return Some(parent.join(target.file_name()?));
    }
    Some(parent_dir(p).canonicalize().ok()?.join(p.file_name()?))
}

/// The nearest existing ancestor of `path` that is not a directory (a file where a
/// directory would have to be created), if any.
pub fn file_in_the_way(path: &Path) -> Option<PathBuf> {
    for dir in path.ancestors().skip(1) {
        if dir.as_os_str().is_empty() {
            return None;
        }
        match std::fs::metadata(dir) {
            Ok(m) if m.is_dir() => return None,
            Ok(_) => return Some(dir.to_path_buf()),
            // Missing (to be created), or below a file (found further up).
            Err(_) => continue,
        }
    }
    None
}

/// Checks, before anything is written, every output of a command against every input in
/// `options.inputs` (and against existing files unless `force`): `files` are files to
/// write, `dirs` directories to write into (each must be a directory or not exist, and not
/// be an input). The one check every command makes up front.
pub fn check_outputs(
    files: &[&Path],
    dirs: &[&Path],
    options: &WriteOptions,
) -> Result<(), WriteError> {
    for file in files {
        check_writable(file, options)?;
    }
    for dir in dirs {
        check_dir(dir, options)?;
    }
    Ok(())
}

/// `dir` may be written into: not an input, a directory or absent, no file in the way.
fn check_dir(dir: &Path, options: &WriteOptions) -> Result<(), WriteError> {
    if let Some(input) = options.inputs.iter().find(|i| same_file(i, dir)) {
        return Err(WriteError::Input {
            path: input.clone(),
        });
    }
    match std::fs::metadata(dir) {
        Ok(m) if m.is_dir() => Ok(()),
        Ok(_) => Err(WriteError::InTheWay {
            path: dir.to_path_buf(),
            in_the_way: dir.to_path_buf(),
        }),
        Err(_) => match file_in_the_way(dir) {
            Some(in_the_way) => Err(WriteError::InTheWay {
                path: dir.to_path_buf(),
                in_the_way,
            }),
            None => Ok(()),
        },
    }
}

/// The prefix of this process's temporary files and staging directories.
fn temp_prefix() -> String {
    format!("{TEMP_PREFIX}{}-", std::process::id())
}

/// Every temporary name starts with this, then the writing process's id and a dash.
pub const TEMP_PREFIX: &str = ".naocalib-";

/// Whether the process `pid` still runs (unknown: assume it does).
fn alive(pid: u32) -> bool {
    #[cfg(unix)]
    {
        let Ok(pid) = libc::pid_t::try_from(pid) else {
            return true;
        };
        // SAFETY: signal 0 only checks whether the process exists; nothing is sent.
        let r = unsafe { libc::kill(pid, 0) };
        r == 0 || io::Error::last_os_error().raw_os_error() != Some(libc::ESRCH)
    }
    #[cfg(not(unix))]
    {
        let _ = pid;
        true
    }
}

/// Removes from `dir` the temporary files and staging directories (`.naocalib-<pid>-…`)
/// left by processes that no longer run (killed part-way); those of running processes are
/// kept. Each directory is swept once per process. Returns how many were removed.
pub fn sweep_stale(dir: &Path) -> usize {
    use std::sync::Mutex;
    static SWEPT: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());
    let key = dir.canonicalize().unwrap_or_else(|_| dir.to_path_buf());
    if let Ok(mut swept) = SWEPT.lock() {
        if swept.contains(&key) {
            return 0;
        }
        swept.push(key);
    }
    let Ok(entries) = std::fs::read_dir(dir) else {
        return 0;
    };
    let mut removed = 0;
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(rest) = name.to_str().and_then(|n| n.strip_prefix(TEMP_PREFIX)) else {
            continue;
        };
        let Some(pid) = rest.split('-').next().and_then(|p| p.parse::<u32>().ok()) else {
            continue;
        };
        if pid == std::process::id() || alive(pid) {
            continue;
        }
        let path = entry.path();
        let gone = match entry.file_type() {
            Ok(t) if t.is_dir() => std::fs::remove_dir_all(&path),
            _ => std::fs::remove_file(&path),
        };
        if gone.is_ok() {
            removed += 1;
        }
    }
    removed
}

fn parent_dir(p: &Path) -> &Path {
    match p.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir,
        _ => Path::new("."),
    }
}

/// Checks, without writing, that [`write_atomic`] would not refuse `path`: not an input,
/// not existing unless `force`, not a directory or other non-file. For writers of several
/// files that must refuse before writing any.
pub fn check_writable(path: &Path, options: &WriteOptions) -> Result<(), WriteError> {
    if let Some(input) = options.inputs.iter().find(|i| same_file(i, path)) {
        return Err(WriteError::Input {
            path: input.clone(),
        });
    }
    if let Some(in_the_way) = file_in_the_way(path) {
        return Err(WriteError::InTheWay {
            path: path.to_path_buf(),
            in_the_way,
        });
    }
    if let Ok(meta) = path.symlink_metadata() {
        if !options.force {
            return Err(WriteError::Exists {
                path: path.to_path_buf(),
            });
        }
        let kind = meta.file_type();
        if !(kind.is_file() || kind.is_symlink()) {
            return Err(WriteError::NotAFile {
                path: path.to_path_buf(),
            });
        }
    }
    Ok(())
}

/// Writes `contents` to `path` atomically (temporary file in the same directory, synced,
/// then renamed; the directory is created if missing). Refuses a path that is one of
/// `options.inputs`, and an existing one unless `options.force`; on any failure, what was
/// at `path` is untouched and no temporary file is left.
pub fn write_atomic(
    path: &Path,
    contents: &[u8],
    options: &WriteOptions,
) -> Result<(), WriteError> {
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
) -> Result<(), WriteError> {
    check_writable(path, options)?;
    let dir = parent_dir(path);
    let io_err = |action, error| WriteError::Io {
        path: path.to_path_buf(),
        action,
        error,
    };
    std::fs::create_dir_all(dir).map_err(|e| match file_in_the_way(path) {
        Some(in_the_way) => WriteError::InTheWay {
            path: path.to_path_buf(),
            in_the_way,
        },
        None => io_err("create the directory for", e),
    })?;
    sweep_stale(dir);
    let suffix = path
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_else(|| ".tmp".into());
    let mut builder = tempfile::Builder::new();
    let prefix = temp_prefix();
    builder.prefix(&prefix).suffix(&suffix);
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        // Like any new file: read-write for everyone the umask allows (tempfile's default
        // is owner-only).
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    // Dropping `tmp` (on any error below) removes the temporary file.
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
        io::ErrorKind::AlreadyExists if !options.force => WriteError::Exists {
            path: path.to_path_buf(),
        },
        _ => io_err("write", e.error),
    })
}

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

/// A set of files written together (`solve --plots`, `--export`, `batch --out`, a simulated
/// dataset): written into a staging directory beside `target` (`.naocalib-<pid>-stage-…`
/// in its parent) and published into `target` by [`Staged::publish`], which checks every
/// file first (inputs, existing files, a file in the way) and then moves them by renames.
/// A refusal or an error before that leaves `target` as it was; dropping an unpublished
/// stage removes it, and the stage of a killed process is removed by the next run
/// ([`sweep_stale`]). When `target` does not exist, it is created by one rename.
#[derive(Debug)]
pub struct Staged {
    target: PathBuf,
    stage: Option<tempfile::TempDir>,
    options: WriteOptions,
}

impl Staged {
    /// A stage for the directory `target`, refusing at once what [`check_outputs`] would
    /// (an input, a file where the directory should be).
    pub fn new(target: &Path, options: &WriteOptions) -> Result<Self, WriteError> {
        check_dir(target, options)?;
        let parent = parent_dir(target);
        let io_err = |action, error| WriteError::Io {
            path: target.to_path_buf(),
            action,
            error,
        };
        std::fs::create_dir_all(parent).map_err(|e| io_err("create the directory for", e))?;
        sweep_stale(parent);
        sweep_stale(target);
        let prefix = format!("{}stage-", temp_prefix());
        let mut builder = tempfile::Builder::new();
        builder.prefix(&prefix);
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            // Like any new directory: what the umask allows.
            builder.permissions(std::fs::Permissions::from_mode(0o777));
        }
        let stage = builder
            .tempdir_in(parent)
            .map_err(|e| io_err("create a staging directory for", e))?;
        Ok(Staged {
            target: target.to_path_buf(),
            stage: Some(stage),
            options: options.clone(),
        })
    }

    /// Where the files are written before they are published.
    pub fn dir(&self) -> &Path {
        self.stage.as_ref().map_or(&self.target, |s| s.path())
    }

    /// The directory the files are published into.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Options to write into [`Staged::dir`]: the inputs stay protected; existing files
    /// are judged at [`Staged::publish`].
    pub fn options(&self) -> WriteOptions {
        WriteOptions {
            force: true,
            inputs: self.options.inputs.clone(),
        }
    }

    /// `path` (a file written into [`Staged::dir`]) where it will be after publishing.
    pub fn published(&self, path: &Path) -> PathBuf {
        match path.strip_prefix(self.dir()) {
            Ok(rel) => self.target.join(rel),
            Err(_) => path.to_path_buf(),
        }
    }

    /// Moves every staged file into the target, after checking all of them, and returns
    /// their final paths (sorted).
    pub fn publish(mut self) -> Result<Vec<PathBuf>, WriteError> {
        let Some(stage) = self.stage.take() else {
            return Ok(Vec::new());
        };
        let mut files = Vec::new();
        list_files(stage.path(), Path::new(""), &mut files).map_err(|e| WriteError::Io {
            path: self.target.clone(),
            action: "list the staged files for",
            error: e,
        })?;
        files.sort();
        let targets: Vec<PathBuf> = files.iter().map(|r| self.target.join(r)).collect();
        for t in &targets {
            check_writable(t, &self.options)?;
        }
        if self.target.symlink_metadata().is_err() {
            let kept = stage.keep();
            return match std::fs::rename(&kept, &self.target) {
                Ok(()) => Ok(targets),
                Err(error) => {
                    let _ = std::fs::remove_dir_all(&kept);
                    Err(WriteError::Io {
                        path: self.target.clone(),
                        action: "create",
                        error,
                    })
                }
            };
        }
        for (rel, t) in files.iter().zip(&targets) {
            let io_err = |action, error| WriteError::Io {
                path: t.clone(),
                action,
                error,
            };
            if let Some(dir) = t.parent() {
                std::fs::create_dir_all(dir).map_err(|e| io_err("create the directory for", e))?;
            }
            let from = stage.path().join(rel);
            if self.options.force {
                std::fs::rename(&from, t).map_err(|e| io_err("write", e))?;
            } else {
                // A link fails if the file appeared meanwhile: never replaced without force.
                std::fs::hard_link(&from, t).map_err(|e| match e.kind() {
                    io::ErrorKind::AlreadyExists => WriteError::Exists { path: t.clone() },
                    _ => io_err("write", e),
                })?;
            }
        }
        Ok(targets)
    }
}

/// The files under `dir` (recursively), as paths relative to `dir` under `rel`.
fn list_files(dir: &Path, rel: &Path, out: &mut Vec<PathBuf>) -> io::Result<()> {
    for entry in std::fs::read_dir(dir.join(rel))? {
        let entry = entry?;
        let path = rel.join(entry.file_name());
        if entry.file_type()?.is_dir() {
            list_files(dir, &path, out)?;
        } else {
            out.push(path);
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn writes_refuses_and_forces() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.csv");
        write_atomic(&path, b"one", &WriteOptions::default()).unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"one");
        let e = write_atomic(&path, b"two", &WriteOptions::default()).unwrap_err();
        assert_eq!(
            e.to_string(),
            format!(
                "{}: already exists; use --force to overwrite",
                path.display()
            )
        );
        assert_eq!(std::fs::read(&path).unwrap(), b"one");
        write_atomic(&path, b"two", &WriteOptions::new(true)).unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"two");
        assert_eq!(
            names(dir.path()),
            ["a.csv"],
            "no temporary file left behind"
        );
    }

    #[cfg(unix)]
    #[test]
    fn written_files_get_the_usual_permissions() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.csv");
        write_atomic(&path, b"x", &WriteOptions::default()).unwrap();
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
    fn creates_the_directory() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("x/y/a.json");
        write_atomic(&path, b"{}", &WriteOptions::default()).unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"{}");
    }

    #[test]
    fn a_failed_fill_leaves_the_old_file_and_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.png");
        std::fs::write(&path, b"old").unwrap();
        let e = write_atomic_with(&path, &WriteOptions::new(true), |tmp| {
            std::fs::write(tmp, b"half")?;
            Err(io::Error::other("encoder failed"))
        })
        .unwrap_err();
        assert!(matches!(e, WriteError::Io { .. }), "{e}");
        assert_eq!(
            e.to_string(),
            format!("{}: cannot write: encoder failed", path.display())
        );
        assert!(
            std::error::Error::source(&e).is_none(),
            "the OS error is printed once"
        );
        assert_eq!(std::fs::read(&path).unwrap(), b"old");
        assert_eq!(names(dir.path()), ["a.png"]);
    }

    #[test]
    fn refuses_inputs_even_with_force_through_links_and_dots() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path().join("data");
        std::fs::create_dir(&d).unwrap();
        let input = d.join("captures.csv");
        std::fs::write(&input, b"in").unwrap();
        let options = WriteOptions::protecting_dataset(&d, true);
        let dotted = d.join("../data/./captures.csv");
        let e = write_atomic(&dotted, b"x", &options).unwrap_err();
        assert!(matches!(e, WriteError::Input { .. }), "{e}");
        assert!(
            e.to_string()
                .ends_with("is an input file; refusing to overwrite it")
        );
        #[cfg(unix)]
        {
            let link = dir.path().join("link.csv");
            std::os::unix::fs::symlink(&input, &link).unwrap();
            let e = write_atomic(&link, b"x", &options).unwrap_err();
            assert!(matches!(e, WriteError::Input { .. }), "{e}");
            let linked_dir = dir.path().join("alias");
            std::os::unix::fs::symlink(&d, &linked_dir).unwrap();
            let e = write_atomic(&linked_dir.join("captures.csv"), b"x", &options).unwrap_err();
            assert!(matches!(e, WriteError::Input { .. }), "{e}");
            let hard = dir.path().join("hard.csv");
            std::fs::hard_link(&input, &hard).unwrap();
            let e = write_atomic(&hard, b"x", &options).unwrap_err();
            assert!(matches!(e, WriteError::Input { .. }), "{e}");
            // A dangling link to a protected file that does not exist yet.
            let truth = dir.path().join("truth-link.toml");
            std::os::unix::fs::symlink(d.join("truth.toml"), &truth).unwrap();
            let e = write_atomic(&truth, b"x", &options).unwrap_err();
            assert!(matches!(e, WriteError::Input { .. }), "{e}");
        }
        assert_eq!(std::fs::read(&input).unwrap(), b"in");
        // Another file in the same directory is fine.
        write_atomic(&d.join("result.json"), b"{}", &options).unwrap();
    }

    #[test]
    fn refuses_to_replace_a_directory() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.json");
        std::fs::create_dir(&path).unwrap();
        let e = write_atomic(&path, b"x", &WriteOptions::new(true)).unwrap_err();
        assert!(matches!(e, WriteError::NotAFile { .. }), "{e}");
        assert!(path.is_dir());
        assert_eq!(names(dir.path()), ["out.json"]);
    }

    #[test]
    fn missing_parent_that_is_a_file_is_in_the_way() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("f"), b"").unwrap();
        let e =
            write_atomic(&dir.path().join("f/a.csv"), b"x", &WriteOptions::default()).unwrap_err();
        assert!(matches!(e, WriteError::InTheWay { .. }), "{e}");
    }

    #[test]
    fn a_stage_publishes_all_or_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("set");
        // A new directory: one rename.
        let stage = Staged::new(&target, &WriteOptions::default()).unwrap();
        write_atomic(&stage.dir().join("a.txt"), b"a", &stage.options()).unwrap();
        write_atomic(&stage.dir().join("sub/b.txt"), b"b", &stage.options()).unwrap();
        assert!(!target.exists(), "nothing before publishing");
        let files = stage.publish().unwrap();
        assert_eq!(files, [target.join("a.txt"), target.join("sub/b.txt")]);
        assert_eq!(names(dir.path()), ["set"]);
        // Into an existing directory with one file already there: refused, nothing moved.
        let stage = Staged::new(&target, &WriteOptions::default()).unwrap();
        write_atomic(&stage.dir().join("c.txt"), b"c", &stage.options()).unwrap();
        write_atomic(&stage.dir().join("sub/b.txt"), b"B", &stage.options()).unwrap();
        let e = stage.publish().unwrap_err();
        assert!(matches!(e, WriteError::Exists { .. }), "{e}");
        assert_eq!(names(&target), ["a.txt", "sub"]);
        assert_eq!(names(dir.path()), ["set"], "the stage is removed");
        // With force: replaced.
        let stage = Staged::new(&target, &WriteOptions::new(true)).unwrap();
        write_atomic(&stage.dir().join("sub/b.txt"), b"B", &stage.options()).unwrap();
        stage.publish().unwrap();
        assert_eq!(std::fs::read(target.join("sub/b.txt")).unwrap(), b"B");
        // Dropped unpublished (an error part-way): nothing left.
        let stage = Staged::new(&target, &WriteOptions::new(true)).unwrap();
        write_atomic(&stage.dir().join("a.txt"), b"x", &stage.options()).unwrap();
        drop(stage);
        assert_eq!(std::fs::read(target.join("a.txt")).unwrap(), b"a");
        assert_eq!(names(dir.path()), ["set"]);
    }

    #[test]
    fn a_file_in_the_way_is_named() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("f");
        std::fs::write(&file, b"").unwrap();
        let e = check_writable(&file.join("x/a.csv"), &WriteOptions::default()).unwrap_err();
        assert!(matches!(e, WriteError::InTheWay { .. }), "{e}");
        assert!(e.to_string().contains("a file is in the way"), "{e}");
        let e = Staged::new(&file, &WriteOptions::new(true)).unwrap_err();
        assert!(
            e.to_string().starts_with(&format!(
                "{}: exists and is not a directory",
                file.display()
            )),
            "{e}"
        );
    }
}
