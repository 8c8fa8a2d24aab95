//! Which file a path names: links and `..` resolved, and what is in the way of a
//! directory to create.

use std::path::{Path, PathBuf};

/// Whether `a` and `b` name the same file: the same path after resolving symbolic links
/// and `..` (for a path that does not exist: its resolved directory and its name), or, on
/// Unix, the same device and inode.
pub fn same_file(a: &Path, b: &Path) -> bool {
    if let (Some(x), Some(y)) = (identity(a), identity(b))
        && x == y
    {
        return true;
    }
    match (resolve(a), resolve(b)) {
        (Some(x), Some(y)) => x == y,
        _ => a == b,
    }
}

/// The device and inode of the file `p` names, links followed (Unix; `None` where they
/// cannot be read, and elsewhere).
pub fn identity(p: &Path) -> Option<(u64, u64)> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        std::fs::metadata(p).ok().map(|m| (m.dev(), m.ino()))
    }
    #[cfg(not(unix))]
    {
        let _ = p;
        None
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

/// The nearest of `path`'s directories (and `path` itself with `itself`) that is a
/// symbolic link to nothing, with where it points, before the first existing directory:
/// a directory would have to be made through it.
pub fn dangling_link_on_the_way(path: &Path, itself: bool) -> Option<(PathBuf, PathBuf)> {
    for dir in path.ancestors().skip(usize::from(!itself)) {
        if dir.as_os_str().is_empty() {
            return None;
        }
        match std::fs::metadata(dir) {
            Ok(_) => return None,
            Err(_) => {
                if let Ok(target) = std::fs::read_link(dir) {
                    return Some((dir.to_path_buf(), target));
                }
            }
        }
    }
    None
}

/// The directory `p` is in (`.` for a bare name).
pub(super) fn parent_dir(p: &Path) -> &Path {
    match p.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir,
        _ => Path::new("."),
    }
}
