//! Processes and robot state when a run ends badly: the simulated robot leaves its record
//! whenever a signal ends it (serving a client or awaiting one); a camera command capture
//! gave up on (a timeout, the run stopped, capture itself killed) is not left running;
//! `capture --resume` after a run killed mid-stance takes the stiffness over from what the
//! robot reports.

use std::process::{Child, Stdio};
use std::time::{Duration, Instant};

use naocalib::robot::simulated::read_record;

use crate::capture::{Bench, finish, plan_file, wait_for_captures};
use crate::util::stderr;

/// Sends `signal` to `child`.
fn signal(child: &Child, signal: i32) {
    // SAFETY: a signal to a process this test started.
    unsafe {
        libc::kill(child.id() as libc::pid_t, signal);
    }
}

/// A simulated robot ended by SIGTERM, SIGINT or SIGHUP writes its record: while it awaits
/// its second client after serving one (`--clients 2`), and before any client came.
#[test]
fn the_simulated_robot_leaves_its_record_when_a_signal_ends_it() {
    for (sig, served) in [
        (libc::SIGTERM, true),
        (libc::SIGINT, true),
        (libc::SIGHUP, false),
    ] {
        let b = Bench::new();
        let robot = b.robot("a.sock", "a.csv", &["--speed", "0", "--clients", "2"]);
        if served {
            let plan = b.path("plan.csv");
            plan_file(&plan, 1, 3);
            let out = b
                .capture(&plan, "ds", "a.sock", &b.fixed_camera(), &[])
                .output()
                .unwrap();
            assert!(out.status.success(), "{}", stderr(&out));
        }
        signal(&robot, sig);
        let out = finish(robot);
        assert!(out.status.success(), "signal {sig}: {}", stderr(&out));
        let record = read_record(&b.path("a.csv")).unwrap();
        assert_eq!(
            !record.is_empty(),
            served,
            "signal {sig}: {} rows",
            record.len()
        );
        assert!(!b.path("a.sock").exists(), "the socket is removed");
    }
}

/// How many processes named `marker` (their `argv[0]`) run.
fn running(marker: &str) -> usize {
    std::fs::read_dir("/proc")
        .unwrap()
        .flatten()
        .filter(|e| {
            std::fs::read(e.path().join("cmdline"))
                .is_ok_and(|c| c.split(|&b| b == 0).next() == Some(marker.as_bytes()))
        })
        .count()
}

/// Whether a process named `marker` (its `argv[0]`) runs.
fn runs(marker: &str) -> bool {
    running(marker) > 0
}

/// Waits up to 10 s for no process named `marker` to run.
fn gone(marker: &str) -> bool {
    let start = Instant::now();
    while runs(marker) {
        if start.elapsed() > Duration::from_secs(10) {
            return false;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    true
}

/// A camera command capture gives up on is gone with it: a shell running a child or a
/// single process the shell exec'd after a timeout; and when capture itself is killed by
/// SIGKILL while the picture is under way, a single exec'd process, a shell's child, and
/// a shell that forked a child into the background and waits on another (its guard kills
/// the command's whole process group).
#[test]
fn a_camera_command_capture_gave_up_on_does_not_run_on() {
    for (how, killed) in [
        ("exec", false),
        ("child", false),
        ("exec", true),
        ("child", true),
        ("fork", true),
    ] {
        let b = Bench::new();
        let plan = b.path("plan.csv");
        plan_file(&plan, 1, 3);
        // A "sleep" whose command line the test can find.
        let marker = b.path(&format!("naocalib-test-camera-{how}-{killed}"));
        std::os::unix::fs::symlink("/bin/sleep", &marker).unwrap();
        let camera = match how {
            "exec" => format!("command:exec '{}' 300 # {{path}}", marker.display()),
            "fork" => format!(
                "command:'{0}' 300 & '{0}' 301; : {{path}}",
                marker.display()
            ),
            _ => format!("command:'{}' 300; : {{path}}", marker.display()),
        };
        let robot = b.robot("a.sock", "a.csv", &["--speed", "0"]);
        let mut capture = b.capture(&plan, "ds", "a.sock", &camera, &["--camera-timeout", "1"]);
        let name = marker.display().to_string();
        if killed {
            let mut child = capture
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .spawn()
                .unwrap();
            let start = Instant::now();
            let started = if how == "fork" { 2 } else { 1 };
            while running(&name) < started {
                assert!(
                    start.elapsed() < Duration::from_secs(60),
                    "no picture taken"
                );
                std::thread::sleep(Duration::from_millis(10));
            }
            child.kill().unwrap();
            child.wait().unwrap();
        } else {
            let out = capture.output().unwrap();
            assert!(!out.status.success(), "{how}: the picture timed out");
        }
        assert!(
            gone(&name),
            "{how} (capture killed: {killed}): the camera runs on"
        );
        signal(&robot, libc::SIGTERM);
        finish(robot);
    }
}

/// `capture --resume` after a run killed mid-stance (SIGKILL: capture's own way out never
/// runs) against the same robot, which holds the last command (stiff at 0.8) until the
/// rest guard takes it over and ramps it down: over the whole record — the run, the guard,
/// the resumed run and the changes between them — no motor's stiffness steps by more than
/// one ramp step, and the resumed run takes the stiffness over from what the robot reports.
#[test]
fn resume_after_a_kill_takes_the_stiffness_over_from_the_robot() {
    use naocalib::robot::motion::{MIN_RAMP_CYCLES, MotionOptions};
    let b = Bench::new();
    let plan = b.path("plan.csv");
    plan_file(&plan, 4, 5);
    let robot = b.robot("a.sock", "a.csv", &["--speed", "4", "--clients", "3"]);
    let mut first = b
        .capture(&plan, "ds", "a.sock", &b.fixed_camera(), &[])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    wait_for_captures(&b.path("ds"), 1);
    first.kill().unwrap();
    // Its standard error closes once the guard, which shares it, is done.
    let killed = first.wait_with_output().unwrap();
    assert!(
        stderr(&killed).contains("the rest guard took it over"),
        "{}",
        stderr(&killed)
    );
    let out = b
        .capture(&plan, "ds", "a.sock", &b.fixed_camera(), &["--resume"])
        .output()
        .unwrap();
    assert!(out.status.success(), "resume: {}", stderr(&out));
    finish(robot);
    let record = read_record(&b.path("a.csv")).unwrap();
    let stiff = MotionOptions::default().stiffness;
    let step = stiff / MIN_RAMP_CYCLES as f64 + 1e-6;
    assert!(
        record
            .iter()
            .any(|r| r.stiffness.iter().any(|&s| s >= stiff - 1e-6)),
        "the robot was never stiff"
    );
    for w in record.windows(2) {
        for k in 0..w[0].stiffness.len() {
            let ds = (w[1].stiffness[k] - w[0].stiffness[k]).abs();
            assert!(
                ds <= step,
                "cycle {}: motor {k}'s stiffness stepped from {} to {}",
                w[1].cycle,
                w[0].stiffness[k],
                w[1].stiffness[k]
            );
        }
    }
}
