//! `naocalib capture` against a small misbehaving robot written here: a Unix socket that
//! speaks LoLA's MessagePack and reports what the test tells it to — joint readings that
//! are not finite, out of range or jump, temperatures and currents that are not numbers, a
//! robot already stiff, a leg that sags while the stiffness rises — and records every
//! command it receives. Each case is checked on those commands. Also: the signals that end
//! the process and a lost terminal, pictures and datasets that look complete but are not,
//! and `simulate-robot`'s own inputs.

use std::io::{BufReader, Write as _};
use std::os::unix::net::UnixListener;
use std::path::Path;
use std::process::{Child, ExitStatus, Stdio};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use naocalib::dataset::Dataset;
use naocalib::model::{JOINT_COUNT, Joint, PARAMETER_COUNT};
use naocalib::robot::capture::rest_posture;
use naocalib::robot::lola::{self, ActuatorMessage, CYCLE_S, JOINTS, SensorFrame, SensorMessage};
use naocalib::robot::motion::MIN_RAMP_CYCLES;

use crate::capture::{Bench, captures_of, moved_motors, plan_file, wait_for_captures};
use crate::util::{assert_clean_failure, stderr};

/// The robot as the server plays it.
#[derive(Debug, Clone)]
struct Body {
    pos: [f32; JOINTS],
    stiffness: [f32; JOINTS],
    temperature: [f32; JOINTS],
    current: [f32; JOINTS],
}

impl Body {
    /// Lying on its back, limp, arms beside the body.
    fn lying() -> Body {
        let mut pos = [0.0; JOINTS];
        pos[2] = 1.5;
        pos[18] = 1.5;
        Body {
            pos,
            stiffness: [0.0; JOINTS],
            temperature: [40.0; JOINTS],
            current: [0.05; JOINTS],
        }
    }

    fn message(&self) -> SensorMessage {
        SensorMessage {
            stiffness: self.stiffness,
            position: self.pos,
            temperature: self.temperature,
            current: self.current,
            ..SensorMessage::on_back([0.0; JOINTS])
        }
    }

    /// Takes the answer: each joint stiff enough to hold itself (0.3) moves towards its
    /// command by at most 0.05 rad.
    fn follow(&mut self, answer: &ActuatorMessage) {
        for k in 0..JOINTS {
            self.stiffness[k] = answer.stiffness[k];
            if self.stiffness[k] >= 0.3 && answer.position[k].is_finite() {
                self.pos[k] += (answer.position[k] - self.pos[k]).clamp(-0.05, 0.05);
            }
        }
    }
}

/// A cycle as the robot saw it: what it reported, and what it was told.
#[derive(Debug, Clone)]
struct Cycle {
    sent: SensorMessage,
    answer: ActuatorMessage,
}

/// A fault: in cycle `n`, may change the body (for the cycles to come) and the message
/// about to be sent.
type Fault = Box<dyn FnMut(u64, &mut Body, &mut SensorMessage) + Send>;

fn frame(joints: SensorMessage) -> SensorFrame {
    SensorFrame {
        joints,
        gyroscope: [0.0; 3],
        sonar: [2.5, 2.5],
        fsr: [0.0; 8],
        robot_config: [
            "P0000074A05S94700015".into(),
            "6.0.0".into(),
            "P0000073A07S9BA00035".into(),
            "6.0.0".into(),
        ],
    }
}

/// The misbehaving robot: serves one client, one message per answer, as fast as it
/// answers.
struct Robot {
    handle: JoinHandle<Vec<Cycle>>,
}

impl Robot {
    fn start(socket: &Path, body: Body, fault: Fault) -> Robot {
        Robot::paced(socket, body, fault, Duration::ZERO)
    }

    /// A robot whose cycles last at least `period`.
    fn paced(socket: &Path, body: Body, fault: Fault, period: Duration) -> Robot {
        let listener = UnixListener::bind(socket).unwrap();
        let handle = std::thread::spawn(move || serve(listener, body, fault, period));
        Robot { handle }
    }

    /// What the robot was told, once the client is gone.
    fn cycles(self) -> Vec<Cycle> {
        self.handle.join().expect("the robot's thread")
    }
}

fn serve(listener: UnixListener, mut body: Body, mut fault: Fault, period: Duration) -> Vec<Cycle> {
    listener.set_nonblocking(true).unwrap();
    let start = Instant::now();
    let stream = loop {
        match listener.accept() {
            Ok((s, _)) => break s,
            Err(_) if start.elapsed() < Duration::from_secs(30) => {
                std::thread::sleep(Duration::from_millis(5))
            }
            Err(_) => return Vec::new(),
        }
    };
    stream.set_nonblocking(false).unwrap();
    stream
        .set_read_timeout(Some(Duration::from_secs(5)))
        .unwrap();
    let mut writer = stream.try_clone().unwrap();
    let mut reader = BufReader::new(stream);
    let mut out = Vec::new();
    for n in 0..200_000u64 {
        std::thread::sleep(period);
        let mut message = body.message();
        fault(n, &mut body, &mut message);
        if writer
            .write_all(&lola::encode(&frame(message.clone())))
            .is_err()
        {
            break;
        }
        match lola::decode_from::<ActuatorMessage>(&mut reader, 1, Duration::from_secs(5)) {
            Ok(answer) => {
                body.follow(&answer);
                out.push(Cycle {
                    sent: message,
                    answer,
                });
            }
            Err(_) => break,
        }
    }
    out
}

/// Waits for `child`, at most `seconds`: a hang fails the test.
fn wait(child: &mut Child, seconds: u64) -> ExitStatus {
    let start = Instant::now();
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            return status;
        }
        if start.elapsed() > Duration::from_secs(seconds) {
            let _ = child.kill();
            panic!("capture hangs");
        }
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// Plan of `n` stances, the robot with `body` and `fault` on `f.sock`, capture with the
/// fixed camera: capture's exit status, standard error and what the robot was told.
fn run(b: &Bench, n: usize, body: Body, fault: Fault) -> (ExitStatus, String, Vec<Cycle>) {
    let plan = b.path("plan.csv");
    if !plan.exists() {
        plan_file(&plan, n, 21);
    }
    let robot = Robot::start(&b.path("f.sock"), body, fault);
    let mut child = b
        .capture(&plan, "ds", "f.sock", &b.fixed_camera(), &[])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let status = wait(&mut child, 120);
    let err = stderr(&child.wait_with_output().unwrap());
    let _ = std::fs::remove_file(b.path("f.sock"));
    (status, err, robot.cycles())
}

/// The rules every command keeps, whatever the robot reports: finite; within the joints'
/// limits (4° tolerance); the first the posture the robot first reported and the
/// stiffness it reported; every step within the speed limits in every phase (the ramp
/// included); the stiffness never more than one ramp step (1/84) from the last.
fn check_commands(cycles: &[Cycle]) {
    assert!(!cycles.is_empty(), "the robot was told nothing");
    let motors = moved_motors();
    let most_ds = 1.0 / MIN_RAMP_CYCLES as f64 + 1e-6;
    let first = &cycles[0];
    for k in 0..JOINTS {
        assert!(
            (first.answer.stiffness[k] - first.sent.stiffness[k]).abs() as f64 <= most_ds,
            "{}: stiffness {} first commanded, {} reported",
            lola::JOINT_NAMES[k],
            first.answer.stiffness[k],
            first.sent.stiffness[k]
        );
    }
    for &(k, _) in &motors {
        assert_eq!(
            first.answer.position[k],
            first.sent.position[k],
            "{}: the first command is the posture first reported",
            lola::JOINT_NAMES[k]
        );
    }
    let tolerance = 4f64.to_radians();
    for (n, c) in cycles.iter().enumerate() {
        for k in 0..JOINTS {
            assert!(
                c.answer.position[k].is_finite() && c.answer.stiffness[k].is_finite(),
                "cycle {n}: {} commanded {} at stiffness {}",
                lola::JOINT_NAMES[k],
                c.answer.position[k],
                c.answer.stiffness[k]
            );
        }
        for j in Joint::ALL {
            let (lo, hi) = j.limits();
            let q = c.answer.position[lola::index(j)] as f64;
            assert!(
                q >= lo - tolerance && q <= hi + tolerance,
                "cycle {n}: {} commanded {:.1}°",
                j.name(),
                q.to_degrees()
            );
        }
    }
    for (n, w) in cycles.windows(2).enumerate() {
        for &(k, speed) in &motors {
            let step = (w[1].answer.position[k] - w[0].answer.position[k]).abs() as f64;
            assert!(
                step <= speed * CYCLE_S * 1.0001 + 1e-6,
                "cycle {}: {} stepped {:.3}° (limit {:.3}°)",
                n + 1,
                lola::JOINT_NAMES[k],
                step.to_degrees(),
                (speed * CYCLE_S).to_degrees()
            );
        }
        for k in 0..JOINTS {
            let ds = (w[1].answer.stiffness[k] - w[0].answer.stiffness[k]).abs() as f64;
            assert!(
                ds <= most_ds,
                "cycle {}: {}'s stiffness stepped by {ds}",
                n + 1,
                lola::JOINT_NAMES[k]
            );
        }
    }
}

/// The run ended at rest with every stiffness ramped down to 0.
fn check_ends_at_rest(cycles: &[Cycle]) {
    check_ends_limp(cycles, true);
}

/// The run ended with every stiffness ramped down to 0: at rest when `moved`, else (a
/// fault during the ramp-up) holding the posture first reported.
fn check_ends_limp(cycles: &[Cycle], moved: bool) {
    let last = &cycles.last().expect("commands").answer;
    assert!(last.stiffness.iter().all(|&s| s == 0.0), "{last:?}");
    let rest = rest_posture();
    for j in Joint::ALL {
        let k = lola::index(j);
        let q = last.position[k] as f64;
        let end = if moved {
            rest.get(j)
        } else {
            cycles[0].sent.position[k] as f64
        };
        assert!((q - end).abs() < 1e-6, "{} at {q}", j.name());
    }
}

fn knee() -> usize {
    lola::index(Joint::LKneePitch)
}

/// A joint reading that is not finite, during the ramp (74 cycles of NaN) and while
/// moving (infinity from then on): the run stops with the joint named, the commands
/// never take it up, and the robot ends at rest, limp — no spin, no panic.
#[test]
fn readings_that_are_not_finite_stop_the_run_without_being_followed() {
    for (from, to, value) in [
        (20, 94, f32::NAN),
        (30, u64::MAX, f32::INFINITY),
        (260, u64::MAX, f32::NEG_INFINITY),
    ] {
        let b = Bench::new();
        let fault: Fault = Box::new(move |n, _, m| {
            if (from..to).contains(&n) {
                m.position[knee()] = value;
            }
        });
        let (status, err, cycles) = run(&b, 2, Body::lying(), fault);
        assert_eq!(status.code(), Some(1), "{value} from {from}: {err}");
        assert!(!err.contains("panicked"), "{err}");
        assert!(
            err.contains(&format!(
                "implausible joint reading, again: LKneePitch reads {value}"
            )),
            "{err}"
        );
        check_commands(&cycles);
        check_ends_limp(&cycles, from > 100);
        assert!(
            cycles.len() < 3000,
            "{} cycles: the way out is bounded",
            cycles.len()
        );
    }
}

/// A knee that reads 172° (beyond its range by far), during the ramp and while moving: a
/// fault, nothing commanded there.
#[test]
fn a_reading_beyond_the_joints_range_is_a_fault() {
    for from in [60, 300] {
        let b = Bench::new();
        let fault: Fault = Box::new(move |n, _, m| {
            if n >= from {
                m.position[knee()] = 172f32.to_radians();
            }
        });
        let (status, err, cycles) = run(&b, 2, Body::lying(), fault);
        assert_eq!(status.code(), Some(1), "{err}");
        assert!(
            err.contains("LKneePitch reads 172.0°, outside its range"),
            "{err}"
        );
        check_commands(&cycles);
        check_ends_limp(&cycles, from > 100);
    }
}

/// LoLA's first message already implausible: nothing is commanded at all.
#[test]
fn an_implausible_first_message_commands_nothing() {
    let b = Bench::new();
    let fault: Fault = Box::new(|_, _, m| m.position[knee()] = f32::NAN);
    let (status, err, cycles) = run(&b, 2, Body::lying(), fault);
    assert_eq!(status.code(), Some(1), "{err}");
    assert!(
        err.contains("LKneePitch reads NaN in LoLA's first message; nothing was commanded"),
        "{err}"
    );
    assert!(cycles.is_empty(), "{} commands", cycles.len());
}

/// One-cycle 28.6° encoder glitches, one during the ramp and then one every 40 cycles
/// while moving and measuring: ignored and not followed; the run completes and the logged
/// angles are the robot's true ones (no glitch averaged in).
#[test]
fn a_one_cycle_glitch_is_ignored_and_not_followed() {
    let b = Bench::new();
    let fault: Fault = Box::new(|n, _, m| {
        if n == 40 || (n > 120 && n % 40 == 0) {
            m.position[knee()] += 0.5;
        }
    });
    let (status, err, cycles) = run(&b, 2, Body::lying(), fault);
    assert!(status.success(), "{err}");
    check_commands(&cycles);
    check_ends_at_rest(&cycles);
    let plan = naocalib::plan::read_csv(&b.path("plan.csv")).unwrap();
    let ds = Dataset::load_without_corners(&b.path("ds")).unwrap();
    assert_eq!(ds.captures.len(), 2);
    for c in &ds.captures {
        let planned = plan[c.id as usize].joints;
        for j in Joint::ALL {
            assert!(
                (c.joints.get(j) - planned.get(j)).abs() < 1e-5,
                "capture {}: {} logged {} for {}",
                c.id,
                j.name(),
                c.joints.get(j),
                planned.get(j)
            );
        }
    }
}

/// Temperatures or currents that are not numbers: the 80 °C and 2.5 A rules cannot hold,
/// so the run stops, at rest.
#[test]
fn temperatures_and_currents_that_are_not_numbers_stop_the_run() {
    for what in ["temperature", "current"] {
        let b = Bench::new();
        let hip = lola::index(Joint::LHipPitch);
        let fault: Fault = Box::new(move |n, _, m| {
            if n >= 150 {
                if what == "temperature" {
                    m.temperature[hip] = f32::NAN;
                } else {
                    m.current[hip] = f32::NAN;
                }
            }
        });
        let (status, err, cycles) = run(&b, 2, Body::lying(), fault);
        assert_eq!(status.code(), Some(1), "{err}");
        assert!(
            err.contains(&format!("LHipPitch reports a {what} of NaN")),
            "{err}"
        );
        check_commands(&cycles);
        check_ends_at_rest(&cycles);
    }
}

/// A robot already stiff (a previous run killed mid-stance): a leg raised at stiffness 0.9,
/// arms at 0.6. The leg drops whenever its stiffness falls below 0.5; the stiffness is
/// taken over from what the robot reports, never below it in one step, and the leg never
/// drops.
#[test]
fn a_robot_already_stiff_is_taken_over_without_dropping_a_leg() {
    let b = Bench::new();
    let mut body = Body::lying();
    let (hip, knee) = (lola::index(Joint::LHipPitch), knee());
    body.pos[hip] = -0.7;
    body.pos[knee] = 1.0;
    for j in Joint::ALL {
        body.stiffness[lola::index(j)] = 0.9;
    }
    for k in [2, 3, 4, 5, 18, 19, 20, 21] {
        body.stiffness[k] = 0.6;
    }
    let fault: Fault = Box::new(move |_, body, m| {
        if body.stiffness[hip] < 0.5 {
            body.pos[hip] = (body.pos[hip] + 0.02).min(0.0);
            m.position[hip] = body.pos[hip];
        }
    });
    let (status, err, cycles) = run(&b, 2, body, fault);
    assert!(status.success(), "{err}");
    check_commands(&cycles);
    check_ends_at_rest(&cycles);
    let first_move = cycles
        .iter()
        .position(|c| c.answer.position[hip] != -0.7)
        .unwrap();
    assert!(first_move as u32 >= MIN_RAMP_CYCLES);
    for c in &cycles[..first_move] {
        assert!(c.answer.stiffness[hip] >= 0.8 - 1e-6);
        assert_eq!(c.sent.position[hip], -0.7, "the leg dropped");
    }
}

/// A leg that sags while the stiffness rises (0.57° a cycle until the stiffness holds it):
/// the command holds the posture measured when the ramp started instead of following it.
#[test]
fn a_leg_sagging_during_the_ramp_does_not_drag_the_command() {
    let b = Bench::new();
    let mut body = Body::lying();
    let hip = lola::index(Joint::LHipPitch);
    body.pos[hip] = -0.8;
    let fault: Fault = Box::new(move |_, body, m| {
        if body.stiffness[hip] < 0.4 {
            body.pos[hip] += 0.01;
            m.position[hip] = body.pos[hip];
        }
    });
    let (status, err, cycles) = run(&b, 2, body, fault);
    assert!(status.success(), "{err}");
    check_commands(&cycles);
    let sagged = cycles
        .iter()
        .map(|c| c.sent.position[hip])
        .fold(-1.0, f32::max);
    assert!(sagged > -0.5, "the leg sagged to {sagged}");
    let start = cycles[0].sent.position[hip];
    for c in &cycles[..MIN_RAMP_CYCLES as usize] {
        assert_eq!(c.answer.position[hip], start);
    }
}

/// Every signal that would end the process — SIGHUP (the ssh session drops), SIGQUIT,
/// SIGINT, SIGTERM — ends in rest and a ramp-down, even when it comes twice.
#[test]
fn every_stop_signal_ends_at_rest_even_twice() {
    for signal in [libc::SIGHUP, libc::SIGQUIT, libc::SIGINT, libc::SIGTERM] {
        let b = Bench::new();
        let plan = b.path("plan.csv");
        plan_file(&plan, 6, 22);
        let robot = Robot::paced(
            &b.path("f.sock"),
            Body::lying(),
            Box::new(|_, _, _| {}),
            Duration::from_millis(1),
        );
        let mut child = b
            .capture(&plan, "ds", "f.sock", &b.fixed_camera(), &[])
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        wait_for_captures(&b.path("ds"), 1);
        for _ in 0..2 {
            unsafe {
                libc::kill(child.id() as i32, signal);
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        let status = wait(&mut child, 60);
        let err = stderr(&child.wait_with_output().unwrap());
        assert_eq!(status.code(), Some(2), "signal {signal}: {err}");
        assert!(err.contains("stopped by a signal"), "{err}");
        let cycles = robot.cycles();
        check_commands(&cycles);
        check_ends_at_rest(&cycles);
        let taken = captures_of(&b.path("ds"));
        assert!(!taken.is_empty() && taken.len() < 6, "{taken:?}");
    }
}

/// A pseudo-terminal for capture to run in (both ends close on exec, so that only capture
/// holds it): the master's descriptor and the terminal's.
fn terminal() -> (i32, std::os::fd::OwnedFd) {
    use std::os::fd::FromRawFd;
    let master = unsafe { libc::posix_openpt(libc::O_RDWR | libc::O_NOCTTY | libc::O_CLOEXEC) };
    assert!(master >= 0, "posix_openpt");
    assert_eq!(unsafe { libc::grantpt(master) }, 0);
    assert_eq!(unsafe { libc::unlockpt(master) }, 0);
    let mut name = [0 as libc::c_char; 128];
    assert_eq!(
        unsafe { libc::ptsname_r(master, name.as_mut_ptr(), name.len()) },
        0
    );
    let slave = unsafe {
        libc::open(
            name.as_ptr(),
            libc::O_RDWR | libc::O_NOCTTY | libc::O_CLOEXEC,
        )
    };
    assert!(slave >= 0, "open the terminal");
    // 80 × 24, so that the progress bar is drawn.
    let size = libc::winsize {
        ws_row: 24,
        ws_col: 80,
        ws_xpixel: 0,
        ws_ypixel: 0,
    };
    assert_eq!(unsafe { libc::ioctl(master, libc::TIOCSWINSZ, &size) }, 0);
    (master, unsafe { std::os::fd::OwnedFd::from_raw_fd(slave) })
}

/// `cmd` run in the terminal `slave` as its controlling terminal (a session of its own,
/// as a login shell's command is).
fn spawn_in_terminal(mut cmd: std::process::Command, slave: &std::os::fd::OwnedFd) -> Child {
    use std::os::unix::process::CommandExt as _;
    cmd.stdin(slave.try_clone().unwrap())
        .stdout(slave.try_clone().unwrap())
        .stderr(slave.try_clone().unwrap());
    unsafe {
        cmd.pre_exec(|| {
            if libc::setsid() < 0 || libc::ioctl(0, libc::TIOCSCTTY, 0) < 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
    cmd.spawn().unwrap()
}

/// The terminal is lost (the pseudo-terminal capture runs in is closed, as when the ssh
/// session drops): SIGHUP, then every message fails; the run still ends at rest, limp,
/// with exit code 2 (not a panic).
#[test]
fn a_lost_terminal_ends_at_rest() {
    let b = Bench::new();
    let plan = b.path("plan.csv");
    plan_file(&plan, 6, 23);
    let robot = Robot::paced(
        &b.path("f.sock"),
        Body::lying(),
        Box::new(|_, _, _| {}),
        Duration::from_millis(1),
    );
    let (master, slave) = terminal();
    let cmd = b.capture(&plan, "ds", "f.sock", &b.fixed_camera(), &[]);
    let mut child = spawn_in_terminal(cmd, &slave);
    drop(slave);
    // The terminal reads what capture writes until it is lost.
    let lost = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let reader = {
        let lost = lost.clone();
        std::thread::spawn(move || {
            let mut buf = [0u8; 4096];
            while !lost.load(std::sync::atomic::Ordering::Relaxed) {
                let mut fds = libc::pollfd {
                    fd: master,
                    events: libc::POLLIN,
                    revents: 0,
                };
                if unsafe { libc::poll(&mut fds, 1, 20) } > 0
                    && unsafe { libc::read(master, buf.as_mut_ptr().cast(), buf.len()) } <= 0
                {
                    break;
                }
            }
        })
    };
    wait_for_captures(&b.path("ds"), 1);
    lost.store(true, std::sync::atomic::Ordering::Relaxed);
    reader.join().unwrap();
    unsafe {
        libc::close(master);
    }
    let status = wait(&mut child, 60);
    assert_eq!(status.code(), Some(2), "{status:?}");
    let cycles = robot.cycles();
    check_commands(&cycles);
    check_ends_at_rest(&cycles);
}

/// A terminal that stops reading (a stalled or silently dropped ssh session: no SIGHUP,
/// its buffer full): the robot's cycles go on regardless; the run completes at rest.
#[test]
fn a_terminal_that_stops_reading_does_not_stall_the_robot() {
    let b = Bench::new();
    let plan = b.path("plan.csv");
    plan_file(&plan, 4, 26);
    let robot = Robot::paced(
        &b.path("f.sock"),
        Body::lying(),
        Box::new(|_, _, _| {}),
        Duration::from_millis(1),
    );
    let (master, slave) = terminal();
    // Fill the terminal: nobody reads it.
    {
        use std::os::fd::AsRawFd;
        let fd = slave.as_raw_fd();
        let flags = unsafe { libc::fcntl(fd, libc::F_GETFL) };
        unsafe { libc::fcntl(fd, libc::F_SETFL, flags | libc::O_NONBLOCK) };
        let junk = [b'x'; 1024];
        while unsafe { libc::write(fd, junk.as_ptr().cast(), junk.len()) } > 0 {}
        unsafe { libc::fcntl(fd, libc::F_SETFL, flags) };
    }
    let cmd = b.capture(&plan, "ds", "f.sock", &b.fixed_camera(), &[]);
    let mut child = spawn_in_terminal(cmd, &slave);
    drop(slave);
    // The robot is told everything, to the end of the ramp-down, while the terminal
    // stays full.
    let cycles = robot.cycles();
    check_commands(&cycles);
    check_ends_at_rest(&cycles);
    assert_eq!(captures_of(&b.path("ds")).len(), 4);
    unsafe {
        libc::close(master);
    }
    wait(&mut child, 60);
}

/// Pictures that `detect` could not use — a JPEG with valid magic bytes but corrupt data,
/// a PNG of the wrong size — coming once the run is under way (the first picture, checked
/// before anything moves, was fine) stop it at rest; nothing is counted as taken.
#[test]
fn pictures_that_do_not_decode_or_have_the_wrong_size_stop_the_run() {
    let corrupt_jpeg: Vec<u8> = [0xff, 0xd8, 0xff, 0xe0]
        .into_iter()
        .chain((0..2000).map(|k| (k * 7 % 251) as u8))
        .collect();
    let small_png = naocalib::sim::render::GreyImage {
        width: 320,
        height: 240,
        pixels: vec![90; 320 * 240],
    }
    .to_png()
    .unwrap();
    for (bytes, message) in [
        (corrupt_jpeg, "is not a readable JPEG"),
        (
            small_png,
            "is 320×240 pixels; the camera's intrinsics are for 640×480",
        ),
    ] {
        let b = Bench::new();
        let picture = b.path("bad.bin");
        std::fs::write(&picture, bytes).unwrap();
        let plan = b.path("plan.csv");
        plan_file(&plan, 2, 24);
        let robot = Robot::start(&b.path("f.sock"), Body::lying(), Box::new(|_, _, _| {}));
        b.fixed_camera();
        let camera = b.after_first(
            &b.path("fixed.png"),
            &format!("cp '{}' {{path}}", picture.display()),
        );
        let out = b
            .capture(&plan, "ds", "f.sock", &camera, &[])
            .output()
            .unwrap();
        assert_clean_failure(&out, &["the picture of capture 0", message, "--resume"]);
        let cycles = robot.cycles();
        check_commands(&cycles);
        check_ends_at_rest(&cycles);
        assert!(captures_of(&b.path("ds")).is_empty());
    }
}

/// `--resume` with another plan is refused before anything moves; a capture whose picture
/// is missing or unreadable is taken again, not counted as taken.
#[test]
fn resume_refuses_another_plan_and_retakes_missing_pictures() {
    let b = Bench::new();
    let (status, err, _) = run(&b, 4, Body::lying(), Box::new(|_, _, _| {}));
    assert!(status.success(), "{err}");
    assert_eq!(captures_of(&b.path("ds")).len(), 4);
    // Another plan with the same ids.
    let other = b.path("other.csv");
    plan_file(&other, 4, 99);
    let out = b
        .capture(
            &other,
            "ds",
            "nobody.sock",
            &b.fixed_camera(),
            &["--resume"],
        )
        .output()
        .unwrap();
    assert_clean_failure(
        &out,
        &["other.csv", "--resume needs the plan the run began with"],
    );
    // A run without --resume into the same directory: pointed to --resume.
    let out = b
        .capture(
            &b.path("plan.csv"),
            "ds",
            "nobody.sock",
            &b.fixed_camera(),
            &[],
        )
        .output()
        .unwrap();
    assert_clean_failure(&out, &["exists", "--resume"]);
    assert!(!stderr(&out).contains("--force"), "{}", stderr(&out));
    // Pictures lost or damaged.
    std::fs::remove_file(b.path("ds/images/0001.png")).unwrap();
    std::fs::write(b.path("ds/images/0002.png"), b"\x89PNG\r\n\x1a\nnot really").unwrap();
    let robot = Robot::start(&b.path("f.sock"), Body::lying(), Box::new(|_, _, _| {}));
    let out = b
        .capture(
            &b.path("plan.csv"),
            "ds",
            "f.sock",
            &b.fixed_camera(),
            &["--resume"],
        )
        .output()
        .unwrap();
    let err = stderr(&out);
    assert!(out.status.success(), "{err}");
    assert!(err.contains("capture 1 will be taken again"), "{err}");
    assert!(err.contains("capture 2 will be taken again"), "{err}");
    assert!(
        err.contains("2 captures taken in this run (2 before)"),
        "{err}"
    );
    check_commands(&robot.cycles());
    let mut ids = captures_of(&b.path("ds"));
    ids.sort();
    assert_eq!(ids, vec![0, 1, 2, 3]);
    let ds = Dataset::load_without_corners(&b.path("ds")).unwrap();
    for c in &ds.captures {
        let bytes = std::fs::read(ds.image_path(c).unwrap()).unwrap();
        naocalib::robot::camera::check_picture(&bytes, 640, 480).unwrap();
    }
}

/// Whether process `pid` is gone (or a zombie about to be reaped).
fn gone(pid: i32) -> bool {
    match std::fs::read_to_string(format!("/proc/{pid}/stat")) {
        Err(_) => true,
        Ok(stat) => stat
            .rsplit(')')
            .next()
            .is_some_and(|rest| rest.trim_start().starts_with('Z')),
    }
}

/// A camera command that takes too long once the run is under way is stopped with
/// everything it started, the run ends at rest, and the message gives the limit as set
/// (0.5 s).
#[test]
fn a_slow_camera_command_is_stopped_with_its_children() {
    let b = Bench::new();
    let plan = b.path("plan.csv");
    plan_file(&plan, 2, 25);
    let pidfile = b.path("sleep.pid");
    b.fixed_camera();
    let camera = b.after_first(
        &b.path("fixed.png"),
        &format!(
            "sleep 30 & echo $! > '{}'; wait; cp '{}' {{path}}",
            pidfile.display(),
            b.path("fixed.png").display()
        ),
    );
    let robot = Robot::start(&b.path("f.sock"), Body::lying(), Box::new(|_, _, _| {}));
    let out = b
        .capture(&plan, "ds", "f.sock", &camera, &["--camera-timeout", "0.5"])
        .output()
        .unwrap();
    assert_clean_failure(&out, &["took longer than 0.5 s"]);
    check_ends_at_rest(&robot.cycles());
    let pid: i32 = std::fs::read_to_string(&pidfile)
        .unwrap()
        .trim()
        .parse()
        .unwrap();
    let start = Instant::now();
    while !gone(pid) {
        assert!(
            start.elapsed() < Duration::from_secs(25),
            "the camera's `sleep 30` ({pid}) still runs"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// `simulate-robot snap PATH --state FILE` never writes its state file (nor the
/// `dataset.toml` it names); `--clients 0` and `--block J=nan` are refused at once.
#[test]
fn simulate_robot_refuses_to_overwrite_its_inputs_and_bad_options() {
    let b = Bench::new();
    let state = b.path("state.json");
    let s = naocalib::robot::simulated::State {
        config: Some(b.config()),
        truth: vec![0.0; PARAMETER_COUNT],
        joints: vec![0.0; JOINT_COUNT],
        cycle: 0,
        seed: 1,
        stiffness: Vec::new(),
        arms: Vec::new(),
    };
    let text = serde_json::to_vec(&s).unwrap();
    std::fs::write(&state, &text).unwrap();
    let config = std::fs::read(b.config()).unwrap();
    for target in [state.clone(), b.config()] {
        let out = crate::util::naocalib()
            .args(["simulate-robot", "snap"])
            .arg(&target)
            .arg("--state")
            .arg(&state)
            .output()
            .unwrap();
        assert_clean_failure(&out, &[target.file_name().unwrap().to_str().unwrap()]);
    }
    assert_eq!(std::fs::read(&state).unwrap(), text);
    assert_eq!(std::fs::read(b.config()).unwrap(), config);
    for (args, needle) in [
        (vec!["--clients", "0"], "--clients"),
        (
            vec!["--block", "LKneePitch=nan"],
            "'nan' is not a number of degrees",
        ),
        (
            vec!["--block", "LKneePitch=500"],
            "outside LKneePitch's range",
        ),
    ] {
        let out = crate::util::naocalib()
            .arg("simulate-robot")
            .arg("--lola")
            .arg(b.path("x.sock"))
            .args(args)
            .timeout(Duration::from_secs(20))
            .output()
            .unwrap();
        let err = stderr(&out);
        assert!(
            !out.status.success() && out.status.code().is_some(),
            "{err}"
        );
        // Refused, not killed by the 20 s guard: the exit has a code.
        assert!(!err.contains("panicked") && err.contains(needle), "{err}");
        assert!(!b.path("x.sock").exists());
    }
}
