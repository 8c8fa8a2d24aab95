//! However capture ends, the robot ends limp: capture killed by SIGKILL in every phase of a
//! run (the stiffness ramp-up, the arms on their way beyond the head, a move, a stance
//! settled, a picture under way, the ramp-down) or aborted in a move or a picture leaves the
//! simulated robot to the rest guard, which takes it to rest and ramps its stiffness to 0
//! within 2 s; a picture whose header claims an enormous size is
//! refused unread (no abort), and the run stops at rest.

use std::process::{Child, Output, Stdio};
use std::time::{Duration, Instant};

use naocalib::model::{Joint, JointAngles};
use naocalib::plan::PlannedCapture;
use naocalib::robot::capture::guard::{FASTEST_HEAD, FASTEST_LEG};
use naocalib::robot::capture::rest_posture;
use naocalib::robot::lola::{self, CYCLE_S, JOINTS};
use naocalib::robot::motion::{MIN_RAMP_CYCLES, MotionOptions};
use naocalib::robot::simulated::{RecordRow, read_record, read_state};

use crate::capture::{Bench, check_safety, finish, moved_motors, plan_file};
use crate::util::{assert_clean_failure, stderr};

/// The phases of a run in which capture is killed.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Phase {
    RampUp,
    ArmsMoving,
    Moving,
    Settled,
    Picture,
    RampDown,
}

/// How capture is ended from outside.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Death {
    /// SIGKILL, as the kernel's out-of-memory killer sends it.
    Kill,
    /// SIGABRT, what `abort()` raises.
    Abort,
}

/// What the test sees of the run from outside: the robot's state file, the camera's log
/// of pictures begun, the captures written.
struct Seen {
    stiffness: f64,
    joints: JointAngles,
    /// The arm joints, in `body::ARM_JOINTS` order.
    arms: Vec<f64>,
    pictures: usize,
    captures: usize,
}

fn look(b: &Bench) -> Option<Seen> {
    let state = read_state(&b.path("state.json")).ok()?;
    let stiffness = Joint::ALL
        .iter()
        .map(|&j| state.stiffness.get(lola::index(j)).copied().unwrap_or(0.0))
        .fold(0.0, f64::max);
    let joints = JointAngles::from_fn(|j| state.joints[j.index()]);
    let pictures = std::fs::read_to_string(b.path("pictures.log"))
        .map(|t| t.lines().count())
        .unwrap_or(0);
    let captures = std::fs::read_to_string(b.path("ds/captures.csv"))
        .map(|t| t.lines().count().saturating_sub(1))
        .unwrap_or(0);
    Some(Seen {
        stiffness,
        joints,
        arms: state.arms,
        pictures,
        captures,
    })
}

/// Whether the run is in `phase` (stance `target`, its picture the second one begun; the
/// first is the one checked before anything moves; `start` the legs' and head's posture
/// and `arms` the arms' when the run began).
fn in_phase(
    phase: Phase,
    s: &Seen,
    (start, arms): (&JointAngles, &[f64]),
    target: &JointAngles,
) -> bool {
    let top = MotionOptions::default().stiffness;
    let off = |a: &JointAngles, b: &JointAngles| {
        (*a - *b).iter().map(|(_, d)| d.abs()).fold(0.0, f64::max)
    };
    match phase {
        Phase::RampUp => s.pictures == 1 && s.stiffness > 0.2 && s.stiffness < 0.6,
        // Stiff, the arms a good way from where they lay and not yet there, the legs not
        // yet moved.
        Phase::ArmsMoving => {
            let moved = s
                .arms
                .iter()
                .zip(arms)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            s.pictures == 1
                && s.stiffness > top - 1e-3
                && moved > 0.3
                && moved < 1.0
                && off(&s.joints, start) < 0.01
        }
        Phase::Moving => {
            s.pictures == 1 && s.stiffness > top - 1e-3 && off(&s.joints, start) > 0.05
        }
        Phase::Settled => s.pictures == 1 && off(&s.joints, target) < 0.002,
        Phase::Picture => s.pictures == 2 && s.captures == 0,
        Phase::RampDown => s.captures == 1 && s.stiffness > 0.1 && s.stiffness < 0.6,
    }
}

/// Capture of a one-stance plan against a robot at twice real time that serves two
/// clients (capture, then the guard), its camera logging each picture it begins and taking
/// 0.6 s over it; capture ended by `death` as soon as the run is in `phase`. Capture's
/// output and the robot's record.
fn kill_in(phase: Phase, death: Death) -> (Output, Vec<RecordRow>, PlannedCapture) {
    let b = Bench::new();
    let plan = b.path("plan.csv");
    let row = plan_file(&plan, 1, 7).remove(0);
    let robot = b.robot("a.sock", "a.csv", &["--speed", "2", "--clients", "2"]);
    b.fixed_camera();
    let camera = format!(
        "command:echo x >> '{}'; sleep 0.6; cp '{}' {{path}}",
        b.path("pictures.log").display(),
        b.path("fixed.png").display()
    );
    let mut capture = b
        .capture(&plan, "ds", "a.sock", &camera, &[])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let began = Instant::now();
    let (start, arms) = loop {
        if let Some(s) = look(&b) {
            break (s.joints, s.arms);
        }
        assert!(began.elapsed() < Duration::from_secs(60), "no state");
        std::thread::sleep(Duration::from_millis(5));
    };
    loop {
        if let Some(s) = look(&b)
            && in_phase(phase, &s, (&start, &arms), &row.joints)
        {
            break;
        }
        assert!(
            capture.try_wait().unwrap().is_none(),
            "{phase:?}: capture ended before the phase came"
        );
        assert!(
            began.elapsed() < Duration::from_secs(60),
            "{phase:?} never came"
        );
        std::thread::sleep(Duration::from_millis(1));
    }
    match death {
        Death::Kill => capture.kill().unwrap(),
        // SAFETY: a signal to the child this test started and has not yet reaped.
        Death::Abort => assert_eq!(
            unsafe { libc::kill(capture.id() as libc::pid_t, libc::SIGABRT) },
            0
        ),
    }
    let out = capture.wait_with_output().unwrap();
    finish_robot(robot);
    (out, read_record(&b.path("a.csv")).unwrap(), row)
}

fn finish_robot(robot: Child) {
    let out = finish(robot);
    assert!(out.status.success(), "robot: {}", stderr(&out));
}

/// What the guard told the robot: from the stiffness and posture the robot held when
/// capture died, towards rest at the speed limits, the stiffness ramped down to 0 step by
/// step, all within 2 s of capture's last message.
fn check_guard(phase: Phase, record: &[RecordRow]) {
    let capture: Vec<&RecordRow> = record.iter().filter(|r| r.client == 0).collect();
    let guard: Vec<&RecordRow> = record.iter().filter(|r| r.client == 1).collect();
    let (Some(last), Some(first)) = (capture.last(), guard.first()) else {
        panic!(
            "{phase:?}: {} messages from capture, {} from the guard",
            capture.len(),
            guard.len()
        );
    };
    let end = guard.last().unwrap();
    let top = MotionOptions::default().stiffness;
    let knee = lola::index(Joint::LKneePitch);
    // The phase as capture's last command shows it.
    let s = last.stiffness[knee];
    match phase {
        Phase::RampUp | Phase::RampDown => assert!(s > 0.0 && s < top, "{phase:?}: {s}"),
        _ => assert!((s - top).abs() < 1e-6, "{phase:?}: {s}"),
    }
    // Taken over from what the robot held: no step in stiffness or posture.
    let most_ds = 1.0 / MIN_RAMP_CYCLES as f64 + 1e-6;
    for k in 0..JOINTS {
        assert!(
            (first.stiffness[k] - last.stiffness[k]).abs() <= most_ds,
            "{phase:?}: {} taken over at {} (held {})",
            lola::JOINT_NAMES[k],
            first.stiffness[k],
            last.stiffness[k]
        );
    }
    // The first command one step at most from where the joints were read, then none
    // beyond the speed limits (the run's, or the fastest a run may be told when those
    // would not reach rest in time).
    let motors: Vec<(usize, f64)> = moved_motors()
        .into_iter()
        .map(|(k, _)| {
            let head = k < 2;
            (k, if head { FASTEST_HEAD } else { FASTEST_LEG })
        })
        .collect();
    for &(k, speed) in &motors {
        let step = (first.position[k] - first.reading[k]).abs();
        assert!(
            step <= speed * CYCLE_S * 1.0001 + 1e-5,
            "{phase:?}: {} first commanded {:.3}° from its reading",
            lola::JOINT_NAMES[k],
            step.to_degrees()
        );
    }
    for w in guard.windows(2) {
        for &(k, speed) in &motors {
            let step = (w[1].position[k] - w[0].position[k]).abs();
            assert!(
                step <= speed * CYCLE_S * 1.0001 + 1e-5,
                "{phase:?}: cycle {}: {} stepped {:.3}°",
                w[1].cycle,
                lola::JOINT_NAMES[k],
                step.to_degrees()
            );
        }
    }
    // The arms stay where they were read, wherever capture left them (limp, they lie
    // on the floor).
    for k in naocalib::robot::arms::indices() {
        for r in &guard {
            assert!(
                (r.position[k] - first.position[k]).abs() < 1e-9,
                "{phase:?}: cycle {}: the guard moved {}",
                r.cycle,
                lola::JOINT_NAMES[k]
            );
        }
    }
    for w in guard.windows(2) {
        for k in 0..JOINTS {
            assert!(
                w[1].stiffness[k] <= w[0].stiffness[k] + 1e-9,
                "{phase:?}: the stiffness rose"
            );
            assert!(
                w[0].stiffness[k] - w[1].stiffness[k] <= most_ds,
                "{phase:?}: cycle {}: {}'s stiffness stepped from {} to {}",
                w[1].cycle,
                lola::JOINT_NAMES[k],
                w[0].stiffness[k],
                w[1].stiffness[k]
            );
        }
    }
    assert!(
        end.stiffness.iter().all(|&s| s == 0.0),
        "{phase:?}: ends at {:?}",
        end.stiffness
    );
    // Towards rest, there at the end.
    let rest = rest_posture();
    let off = |r: &RecordRow| {
        Joint::ALL
            .iter()
            .map(|&j| (r.position[lola::index(j)] - rest.get(j)).abs())
            .fold(0.0, f64::max)
    };
    for w in guard.windows(2) {
        assert!(off(w[1]) <= off(w[0]) + 1e-6, "{phase:?}: away from rest");
    }
    assert!(
        off(end) < 1e-6,
        "{phase:?}: ends {:.3} rad from rest",
        off(end)
    );
    // Within 2 s of capture's last message (the robot runs on between clients).
    let seconds = (end.cycle - last.cycle) as f64 * CYCLE_S;
    eprintln!(
        "{phase:?}: taken over at stiffness {s:.2}, limp at rest {seconds:.2} s after \
         capture's last message ({} messages from the guard)",
        guard.len()
    );
    assert!(
        seconds <= 2.0,
        "{phase:?}: limp {seconds:.2} s after capture died"
    );
}

/// SIGKILL in each phase of a run: the guard takes the robot to rest and ramps its
/// stiffness to 0 within 2 s, and says so.
#[test]
fn capture_killed_in_any_phase_leaves_the_robot_at_rest_and_limp_within_2_s() {
    for phase in [
        Phase::RampUp,
        Phase::ArmsMoving,
        Phase::Moving,
        Phase::Settled,
        Phase::Picture,
        Phase::RampDown,
    ] {
        let (out, record, _) = kill_in(phase, Death::Kill);
        use std::os::unix::process::ExitStatusExt as _;
        assert_eq!(out.status.signal(), Some(libc::SIGKILL), "{phase:?}");
        check_guard(phase, &record);
        let err = stderr(&out);
        assert!(
            err.contains("the rest guard took it over"),
            "{phase:?}: {err}"
        );
    }
}

/// An abort (SIGABRT: what `abort()` raises, and how a Rust process ends when an
/// allocation fails) while a leg moves and while a picture is under way: the guard takes
/// the robot to rest and ramps its stiffness to 0 within 2 s, as after SIGKILL (how the
/// kernel's out-of-memory killer ends a process).
#[test]
fn capture_aborted_in_a_move_or_a_picture_leaves_the_robot_at_rest_and_limp_within_2_s() {
    use std::os::unix::process::ExitStatusExt as _;
    for phase in [Phase::Moving, Phase::Picture] {
        let (out, record, _) = kill_in(phase, Death::Abort);
        let err = stderr(&out);
        assert_eq!(
            out.status.signal(),
            Some(libc::SIGABRT),
            "{phase:?}: {:?} {err}",
            out.status
        );
        check_guard(phase, &record);
        assert!(
            err.contains("the rest guard took it over"),
            "{phase:?}: {err}"
        );
    }
}

/// A PNG of a few kilobytes whose header claims 1 000 000 × 1 000 000 pixels.
fn enormous_png() -> Vec<u8> {
    let mut bytes = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut bytes, 1_000_000, 1_000_000);
        encoder.set_color(png::ColorType::Grayscale);
        let mut writer = encoder.write_header().unwrap();
        writer
            .write_chunk(
                png::chunk::IDAT,
                &[0x78, 0x9c, 0x03, 0x00, 0x00, 0x00, 0x00, 0x01],
            )
            .unwrap();
    }
    bytes.resize(4096, 0);
    bytes
}

/// A baseline JPEG whose frame header claims 65 000 × 65 000 pixels.
fn enormous_jpeg() -> Vec<u8> {
    let mut b = vec![0xff, 0xd8];
    // SOF0: length 11, 8 bits, height, width, one component.
    b.extend([0xff, 0xc0, 0x00, 0x0b, 0x08]);
    b.extend(65_000u16.to_be_bytes());
    b.extend(65_000u16.to_be_bytes());
    b.extend([0x01, 0x01, 0x11, 0x00]);
    b.resize(4096, 0);
    b
}

/// The run's second picture claims an enormous size (PNG, JPEG): it is refused before
/// anything is allocated for it, the run stops at rest with the stiffness ramped down,
/// and capture exits 1 with what was wrong — no abort.
#[test]
fn a_picture_claiming_an_enormous_size_is_refused_unread_and_the_run_stops_at_rest() {
    for (bytes, size) in [
        (enormous_png(), "1000000×1000000"),
        (enormous_jpeg(), "65000×65000"),
    ] {
        let b = Bench::new();
        let picture = b.path("huge.bin");
        std::fs::write(&picture, &bytes).unwrap();
        let plan = b.path("plan.csv");
        plan_file(&plan, 2, 24);
        let robot = b.robot("a.sock", "a.csv", &["--speed", "0"]);
        b.fixed_camera();
        let camera = b.after_first(
            &b.path("fixed.png"),
            &format!("cp '{}' {{path}}", picture.display()),
        );
        let out = b
            .capture(&plan, "ds", "a.sock", &camera, &[])
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(1), "{size}: {}", stderr(&out));
        assert_clean_failure(
            &out,
            &[
                "the picture of capture",
                size,
                "the camera's intrinsics are for 640×480",
                "--resume",
            ],
        );
        finish_robot(robot);
        let record = read_record(&b.path("a.csv")).unwrap();
        check_safety(&record, true);
        assert!(
            record.iter().all(|r| r.client == 0),
            "{size}: the guard took over"
        );
    }
}
