//! A set of files written together: staged beside their target, published at once.

use std::io;
use std::path::{Path, PathBuf};

use super::stale::temp_prefix;
use super::{WriteError, WriteOptions, check_dir, check_writable, parent_dir, sweep_stale};

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
    /// A stage for the directory `target`, refusing at once what
    /// [`check_outputs`](super::check_outputs) would (an input, a file where the directory
    /// should be).
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
        // An existing directory is replaced by exchange with the stage, which must then be
        // beside the directory itself (through a symbolic link, beside where it leads).
        let real = target.canonicalize().ok().filter(|r| r.is_dir());
        let parent = match real.as_deref().and_then(Path::parent) {
            Some(home) => {
                sweep_stale(home);
                home
            }
            None => parent,
        };
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
        live()
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .push((stage.path().to_path_buf(), target.to_path_buf()));
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

    /// Writes `contents` as the file `rel` of the set (into [`Staged::dir`]); an error
    /// names the file where it would be published, never the staging directory.
    pub fn write(&self, rel: &Path, contents: &[u8]) -> Result<(), WriteError> {
        super::write_atomic(&self.dir().join(rel), contents, &self.options())
            .map_err(|e| self.named(e))
    }

    /// `e` (an error of writing into [`Staged::dir`]) naming the files where they would be
    /// published: a user hears of the output they asked for, not of a staging directory.
    pub fn named(&self, e: WriteError) -> WriteError {
        e.map_paths(|p| self.published(p))
    }

    /// Moves every staged file into the target, after checking all of them, and returns
    /// their final paths (sorted).
    pub fn publish(mut self) -> Result<Vec<PathBuf>, WriteError> {
        forget(&self.stage);
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
            super::step();
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
        if exchange(stage.path(), &self.target, &files) {
            return Ok(targets);
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
            super::step();
        }
        Ok(targets)
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        forget(&self.stage);
    }
}

/// The stages of this process not yet published or dropped: (stage, target).
fn live() -> &'static std::sync::Mutex<Vec<(PathBuf, PathBuf)>> {
    static LIVE: std::sync::Mutex<Vec<(PathBuf, PathBuf)>> = std::sync::Mutex::new(Vec::new());
    &LIVE
}

/// Takes the stage `stage` off the live ones.
fn forget(stage: &Option<tempfile::TempDir>) {
    if let Some(stage) = stage {
        live()
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .retain(|(s, _)| s != stage.path());
    }
}

/// `path` where it will be once its stage is published: a path inside a live stage of
/// this process ([`Staged::dir`]) named in its target, any other path as it is. Every
/// error of the crate's writer names its file so, and so may any error that names a file
/// a writer was given: a user hears of the output they asked for, never of a staging
/// directory.
pub fn published(path: &Path) -> PathBuf {
    let live = live().lock().unwrap_or_else(|e| e.into_inner());
    live.iter()
        .find_map(|(stage, target)| path.strip_prefix(stage).ok().map(|rel| target.join(rel)))
        .unwrap_or_else(|| path.to_path_buf())
}

/// Publishes the staged `files` in `stage` into the existing directory `target` at once:
/// the stage is completed with every other entry of `target` (files hard-linked, so they
/// stay the same files; directories and symbolic links made alike), given `target`'s
/// permissions, and the two directories are exchanged by one `renameat2(RENAME_EXCHANGE)`
/// — a reader, or a kill, sees the old set or the new one, never a mix. An entry that
/// appeared in `target` meanwhile is moved across after the exchange; the old directory
/// is then removed. `false` (with `target` untouched) where this cannot be done: not
/// Linux, a file system without the exchange, `target` a mount point or holding what is
/// neither file, directory nor link; the caller then moves the files one by one.
fn exchange(stage: &Path, target: &Path, files: &[PathBuf]) -> bool {
    #[cfg(target_os = "linux")]
    {
        use std::os::unix::ffi::OsStrExt as _;
        // Through a symbolic link: the directory it names (exchanged beside it, if the
        // stage is there too).
        let Ok(real) = target.canonicalize() else {
            return false;
        };
        if real.parent() != stage.canonicalize().ok().as_deref().and_then(Path::parent) {
            return false;
        }
        if mirror(&real, stage, Path::new(""), files).is_err() {
            return false;
        }
        if let Ok(meta) = std::fs::metadata(&real) {
            use std::os::unix::fs::MetadataExt as _;
            let _ = std::fs::set_permissions(stage, meta.permissions());
            let _ = std::os::unix::fs::chown(stage, Some(meta.uid()), Some(meta.gid()));
        }
        super::step();
        let (Ok(a), Ok(b)) = (
            std::ffi::CString::new(stage.as_os_str().as_bytes()),
            std::ffi::CString::new(real.as_os_str().as_bytes()),
        ) else {
            return false;
        };
        // SAFETY: two valid C strings; the call only renames.
        let r = unsafe {
            libc::syscall(
                libc::SYS_renameat2,
                libc::AT_FDCWD,
                a.as_ptr(),
                libc::AT_FDCWD,
                b.as_ptr(),
                libc::RENAME_EXCHANGE,
            )
        };
        if r != 0 {
            return false;
        }
        super::step();
        // `stage` now holds the old set: what appeared there after it was mirrored goes
        // across, the rest is removed (as a stale stage would be after a kill).
        let _ = carry_over(stage, &real, Path::new(""));
        true
    }
    #[cfg(not(target_os = "linux"))]
    {
        let _ = (stage, target, files);
        false
    }
}

/// Completes the stage `stage` with every entry of `real` under `rel` that is not staged
/// (`files`): files hard-linked, directories made with the same permissions, symbolic
/// links made alike. An error for what is neither.
#[cfg(target_os = "linux")]
fn mirror(real: &Path, stage: &Path, rel: &Path, files: &[PathBuf]) -> io::Result<()> {
    for entry in std::fs::read_dir(real.join(rel))? {
        let entry = entry?;
        let path = rel.join(entry.file_name());
        let (from, to) = (real.join(&path), stage.join(&path));
        let kind = entry.file_type()?;
        if kind.is_dir() {
            if to.symlink_metadata().is_err() {
                std::fs::create_dir(&to)?;
                std::fs::set_permissions(&to, std::fs::metadata(&from)?.permissions())?;
            }
            mirror(real, stage, &path, files)?;
        } else if files.contains(&path) {
            // The new file replaces it.
        } else if kind.is_file() {
            std::fs::hard_link(&from, &to)?;
        } else if kind.is_symlink() {
            std::os::unix::fs::symlink(std::fs::read_link(&from)?, &to)?;
        } else {
            return Err(io::Error::from(io::ErrorKind::Unsupported));
        }
    }
    Ok(())
}

/// Moves into `real` the entries of `old` under `rel` that `real` lacks (written into the
/// directory between the mirror and the exchange), then removes `old`.
#[cfg(target_os = "linux")]
fn carry_over(old: &Path, real: &Path, rel: &Path) -> io::Result<()> {
    for entry in std::fs::read_dir(old.join(rel))? {
        let entry = entry?;
        let path = rel.join(entry.file_name());
        let there = real.join(&path);
        if there.symlink_metadata().is_err() {
            let _ = std::fs::rename(old.join(&path), &there);
        } else if entry.file_type()?.is_dir() {
            carry_over(old, real, &path)?;
        }
    }
    if rel.as_os_str().is_empty() {
        std::fs::remove_dir_all(old)?;
    }
    Ok(())
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
    use crate::output::tests::names;
    use crate::output::write_atomic;

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

    /// Publishing into an existing directory replaces the set and keeps everything else
    /// there as it was: other files (the same files: hard links, inodes and modes kept),
    /// subdirectories, symbolic links, the directory's permissions.
    #[cfg(unix)]
    #[test]
    fn publishing_over_a_set_keeps_the_rest_of_the_directory() {
        use std::os::unix::fs::{MetadataExt, PermissionsExt};
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("set");
        std::fs::create_dir_all(target.join("sub/deeper")).unwrap();
        std::fs::write(target.join("a.txt"), b"old").unwrap();
        std::fs::write(target.join("mine.txt"), b"mine").unwrap();
        std::fs::write(target.join("sub/deeper/mine.txt"), b"deep").unwrap();
        std::os::unix::fs::symlink("mine.txt", target.join("link")).unwrap();
        std::fs::set_permissions(&target, std::fs::Permissions::from_mode(0o750)).unwrap();
        let inode = |p: &Path| std::fs::metadata(p).unwrap().ino();
        let mine = inode(&target.join("mine.txt"));
        let stage = Staged::new(&target, &WriteOptions::new(true)).unwrap();
        stage.write(Path::new("a.txt"), b"new").unwrap();
        stage.write(Path::new("sub/b.txt"), b"b").unwrap();
        stage.publish().unwrap();
        assert_eq!(std::fs::read(target.join("a.txt")).unwrap(), b"new");
        assert_eq!(std::fs::read(target.join("sub/b.txt")).unwrap(), b"b");
        assert_eq!(inode(&target.join("mine.txt")), mine);
        assert_eq!(
            std::fs::read(target.join("sub/deeper/mine.txt")).unwrap(),
            b"deep"
        );
        assert_eq!(
            std::fs::read_link(target.join("link")).unwrap(),
            Path::new("mine.txt")
        );
        let mode = std::fs::metadata(&target).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode, 0o750);
        assert_eq!(names(dir.path()), ["set"], "no stage left");
    }

    /// A staged file that cannot be written is named where it would be published.
    #[test]
    fn a_staged_write_error_names_the_output() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("set");
        let stage = Staged::new(&target, &WriteOptions::new(true)).unwrap();
        std::fs::create_dir_all(stage.dir().join("a.txt")).unwrap();
        let e = stage.write(Path::new("a.txt"), b"x").unwrap_err();
        assert_eq!(e.path(), target.join("a.txt"), "{e}");
        assert!(!e.to_string().contains(crate::output::TEMP_PREFIX), "{e}");
    }
}
