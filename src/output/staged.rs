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
}
