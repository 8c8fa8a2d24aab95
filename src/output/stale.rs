//! Temporary names (`.naocalib-<pid>-…`) and the sweep of those a killed process left.

use std::io;
use std::path::{Path, PathBuf};

/// The prefix of this process's temporary files and staging directories.
pub(super) fn temp_prefix() -> String {
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
