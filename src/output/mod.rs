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
//!
//! The parts: the refusals ([`WriteError`]), which file a path names (`paths.rs`), the
//! temporary names and their sweep (`stale.rs`), changing an existing file in place of
//! its kind (`rewrite.rs`) and the staged set of files (`staged.rs`).

mod error;
mod paths;
mod rewrite;
mod staged;
mod stale;

use std::io::{self, Write as _};
use std::path::{Path, PathBuf};

pub use error::WriteError;
use paths::{dangling_link_on_the_way, parent_dir};
pub use paths::{file_in_the_way, identity, same_file};
pub use rewrite::{check_rewritable, rewrite, write_new_like};
pub use staged::Staged;
pub use staged::published;
use stale::temp_prefix;
pub use stale::{TEMP_PREFIX, sweep_stale};

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

    /// These options, also protecting `paths`.
    pub fn protecting(mut self, paths: impl IntoIterator<Item = PathBuf>) -> Self {
        self.inputs.extend(paths);
        self
    }
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
        // A symbolic link to nowhere (the directory or one on its way): the directory it
        // names is not made through it.
        Err(_) => match (dangling_link_on_the_way(dir, true), file_in_the_way(dir)) {
            (Some((link, target)), _) => Err(WriteError::DanglingLink {
                path: dir.to_path_buf(),
                link,
                target,
            }),
            (None, Some(in_the_way)) => Err(WriteError::InTheWay {
                path: dir.to_path_buf(),
                in_the_way,
            }),
            (None, None) => Ok(()),
        },
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
    if let Some((link, target)) = dangling_link_on_the_way(path, false) {
        return Err(WriteError::DanglingLink {
            path: path.to_path_buf(),
            link,
            target,
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

/// Like [`write_atomic`], but without syncing the file before the rename: for a file
/// rewritten many times a second and read at once by another process (the simulated
/// robot's state), whose last version a crash may lose at no cost. Readers still see the
/// old file or the new one, and the same refusals hold.
pub fn write_atomic_unsynced(
    path: &Path,
    contents: &[u8],
    options: &WriteOptions,
) -> Result<(), WriteError> {
    write_atomic_with(path, options, |tmp| {
        std::fs::OpenOptions::new()
            .write(true)
            .open(tmp)?
            .write_all(contents)
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
    // A file of a staged set is named where it will be published, never in its stage.
    write_into(path, options, fill).map_err(|e| e.map_paths(published))
}

/// [`write_atomic_with`], its errors naming the paths as written to.
fn write_into(
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
    })?;
    step();
    Ok(())
}

/// The environment variable of the fault-injection hook (`step`): its number `k` makes the
/// process kill itself (SIGKILL) after the `k`-th step of writing (a file written, a
/// staged set published, a file of a set moved). Tests run a command with `k` = 1, 2, …
/// to check that a kill at every step leaves the old files or the new ones, never a mix.
pub const KILL_AFTER_STEP: &str = "NAOCALIB_KILL_AFTER_STEP";

/// One step of writing done (see [`KILL_AFTER_STEP`]); without the variable, nothing.
pub(crate) fn step() {
    use std::sync::OnceLock;
    use std::sync::atomic::{AtomicU64, Ordering};
    static LIMIT: OnceLock<Option<u64>> = OnceLock::new();
    static STEPS: AtomicU64 = AtomicU64::new(0);
    let limit = LIMIT.get_or_init(|| std::env::var(KILL_AFTER_STEP).ok()?.parse().ok());
    if let Some(limit) = *limit
        && STEPS.fetch_add(1, Ordering::SeqCst) + 1 >= limit
    {
        #[cfg(unix)]
        // SAFETY: the process signals itself; SIGKILL cannot be caught.
        unsafe {
            libc::kill(libc::getpid(), libc::SIGKILL);
        }
        std::process::abort();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The names in `dir`, sorted.
    pub(super) fn names(dir: &Path) -> Vec<String> {
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

    #[test]
    fn an_unsynced_write_refuses_and_forces_the_same() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("state.json");
        write_atomic_unsynced(&path, b"one", &WriteOptions::default()).unwrap();
        assert!(write_atomic_unsynced(&path, b"two", &WriteOptions::default()).is_err());
        assert_eq!(std::fs::read(&path).unwrap(), b"one");
        write_atomic_unsynced(&path, b"two", &WriteOptions::new(true)).unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"two");
        let input = WriteOptions::new(true).protecting([path.clone()]);
        assert!(write_atomic_unsynced(&path, b"three", &input).is_err());
        assert_eq!(names(dir.path()), ["state.json"]);
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
        // A dataset's files, protected by name: `truth.toml` does not exist yet.
        let protected = ["dataset.toml", "captures.csv", "corners.csv", "truth.toml"];
        let options = WriteOptions::new(true).protecting(protected.map(|f| d.join(f)));
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
