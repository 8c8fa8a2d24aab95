//! The guard of a `command:` camera's processes: `naocalib camera-guard --parent PID --
//! LINE`, which capture starts for each picture in a process group of its own.
//!
//! The guard runs `sh -c LINE` in its own group, so that every process the command starts
//! (unless it leaves the group with `setsid` or `setpgid`) is in that group. It watches its
//! parent: when capture dies — also by SIGKILL, which capture cannot act on — the guard is
//! given another parent, sees it within [`POLL`], and kills the whole group. When the
//! command ends, the guard writes how on its standard output ([`Ended`]) and kills the
//! group, itself included, so that nothing the command left behind outlives the picture
//! either. (`PR_SET_PDEATHSIG` alone reaches only a direct child: a shell's background
//! children would be orphaned.) Capture itself kills the group when a picture takes too
//! long or the run stops.

use std::io::Write as _;
use std::time::Duration;

/// The hidden subcommand of naocalib that runs the guard.
pub const SUBCOMMAND: &str = "camera-guard";

/// How often the guard looks whether capture is still its parent.
pub const POLL: Duration = Duration::from_millis(5);

/// How a camera command ended, as the guard reports it (`exit CODE`, `signal N`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Ended {
    /// It exited with this code.
    Exit(i32),
    /// A signal ended it.
    Signal(i32),
    /// It could not be started.
    NotStarted,
}

impl Ended {
    /// How `status` says a process ended.
    pub fn of(status: std::process::ExitStatus) -> Ended {
        use std::os::unix::process::ExitStatusExt as _;
        match (status.code(), status.signal()) {
            (Some(code), _) => Ended::Exit(code),
            (None, Some(signal)) => Ended::Signal(signal),
            (None, None) => Ended::NotStarted,
        }
    }

    /// The guard's report (its first line), or `None` when it reported nothing (it was
    /// killed before the command ended).
    pub fn read(report: &str) -> Option<Ended> {
        let line = report.lines().next()?.trim();
        let (word, value) = line.split_once(' ').unwrap_or((line, ""));
        match (word, value.trim().parse::<i32>()) {
            ("exit", Ok(code)) => Some(Ended::Exit(code)),
            ("signal", Ok(signal)) => Some(Ended::Signal(signal)),
            ("not-started", _) => Some(Ended::NotStarted),
            _ => None,
        }
    }

    /// The report the guard writes.
    fn report(self) -> String {
        match self {
            Ended::Exit(code) => format!("exit {code}\n"),
            Ended::Signal(signal) => format!("signal {signal}\n"),
            Ended::NotStarted => "not-started\n".into(),
        }
    }
}

impl std::fmt::Display for Ended {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Ended::Exit(code) => write!(f, "exit status: {code}"),
            Ended::Signal(signal) => write!(f, "was killed by signal {signal}"),
            Ended::NotStarted => write!(f, "could not be started (sh -c)"),
        }
    }
}

/// Kills the caller's process group, the caller included.
fn kill_own_group() {
    // SAFETY: a signal to this process's own group.
    unsafe {
        libc::kill(0, libc::SIGKILL);
    }
}

/// Runs the guard: `line` with `sh -c` (standard input and output from nowhere, standard
/// error the guard's), in the guard's process group — made its own if it is not — while
/// `parent` is its parent. Reports how the command ended on standard output and kills the
/// group; when `parent` is gone first, kills the group at once. Returns only when the
/// group could not be killed.
pub fn run(parent: u32, line: &str) -> std::io::Error {
    // SAFETY: plain system calls on this process.
    unsafe {
        if libc::getpgrp() != libc::getpid() {
            libc::setpgid(0, 0);
        }
    }
    let parent_alive = || unsafe { libc::getppid() } as u32 == parent;
    if !parent_alive() {
        kill_own_group();
        return std::io::Error::other("capture is gone");
    }
    let child = std::process::Command::new("sh")
        .arg("-c")
        .arg(line)
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::null())
        .spawn();
    let ended = match child {
        Err(_) => Ended::NotStarted,
        Ok(mut child) => loop {
            match child.try_wait() {
                Ok(Some(status)) => break Ended::of(status),
                Ok(None) => {}
                Err(_) => break Ended::NotStarted,
            }
            if !parent_alive() {
                kill_own_group();
                return std::io::Error::other("capture is gone");
            }
            std::thread::sleep(POLL);
        },
    };
    let mut out = std::io::stdout().lock();
    let _ = out.write_all(ended.report().as_bytes());
    let _ = out.flush();
    kill_own_group();
    std::io::Error::other("the guard's group could not be killed")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reports_read_back_as_written() {
        for e in [
            Ended::Exit(0),
            Ended::Exit(3),
            Ended::Signal(9),
            Ended::NotStarted,
        ] {
            assert_eq!(Ended::read(&e.report()), Some(e));
        }
        assert_eq!(Ended::read(""), None);
        assert_eq!(Ended::read("exit x\n"), None);
        assert_eq!(Ended::read("hello"), None);
        assert_eq!(Ended::Exit(1).to_string(), "exit status: 1");
    }
}
