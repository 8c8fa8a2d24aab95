//! Every check says what the run would do: `capture --check` applies each condition the
//! run applies (the chest button, a motor's status, …); a motor's firmware status is
//! named as such, not reported as heat; a camera setting for a camera the run does not
//! have is refused, naming the cameras it has.

use std::process::Output;

use crate::capture::{Bench, finish, plan_file};
use crate::util::{assert_clean_failure, stderr};

/// `capture --check` of a one-stance plan against a simulated robot started with
/// `robot_args`; its output.
fn check(b: &Bench, robot_args: &[&str]) -> Output {
    let plan = b.path("plan.csv");
    plan_file(&plan, 1, 3);
    let mut args = vec!["--speed", "0"];
    args.extend(robot_args);
    let robot = b.robot("a.sock", "a.csv", &args);
    let mut cmd = crate::util::naocalib();
    cmd.arg("capture")
        .arg(&plan)
        .arg("--config")
        .arg(b.config())
        .arg("--lola")
        .arg(b.path("a.sock"))
        .arg("--camera")
        .arg(b.fixed_camera())
        .arg("--check")
        .arg(b.path("check"));
    let out = cmd.output().unwrap();
    finish(robot);
    out
}

/// The line of the check table for `item`.
fn line(out: &Output, item: &str) -> String {
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .find(|l| l.get(4..).is_some_and(|r| r.starts_with(item)))
        .unwrap_or_else(|| panic!("no line {item}: {}", String::from_utf8_lossy(&out.stdout)))
        .to_string()
}

/// The chest button held from the first message: the dry run says not ready (it would
/// stop the run at once), and the run itself refuses before anything moves.
#[test]
fn the_dry_run_says_not_ready_with_the_chest_button_held_and_the_run_agrees() {
    let b = Bench::new();
    let out = check(&b, &["--chest-at", "0"]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let chest = line(&out, "chest button");
    assert!(chest.starts_with("NO "), "{chest}");
    let watched = line(&out, "watched");
    assert!(
        watched.starts_with("NO ") && watched.contains("chest button"),
        "{watched}"
    );
    let err = stderr(&out);
    assert!(
        err.contains("not ready") && !err.contains("the day can start"),
        "{err}"
    );

    // The run on the same robot: refused before anything is sent.
    let plan = b.path("plan.csv");
    let robot = b.robot("b.sock", "b.csv", &["--speed", "0", "--chest-at", "0"]);
    let out = b
        .capture(&plan, "ds", "b.sock", &b.fixed_camera(), &[])
        .output()
        .unwrap();
    assert_clean_failure(&out, &["chest button", "nothing was moved"]);
    finish(robot);
    let record = naocalib::robot::simulated::read_record(&b.path("b.csv")).unwrap();
    assert!(record.is_empty(), "{} commands sent", record.len());
}

/// A motor whose status goes to 2 during the dry run's second (the run would stop on it)
/// and one at status 1 (the run would rest): the dry run says so, naming the status.
#[test]
fn the_dry_run_watches_every_message_as_the_run_does() {
    for (status, words) in [
        ("LKneePitch=2@40", "LKneePitch reports status 2"),
        ("RAnklePitch=1@40..60", "RAnklePitch reports status 1"),
    ] {
        let b = Bench::new();
        let out = check(&b, &["--status", status]);
        assert_eq!(out.status.code(), Some(1), "{status}: {}", stderr(&out));
        let watched = line(&out, "watched");
        assert!(
            watched.starts_with("NO ") && watched.contains(words),
            "{status}: {watched}"
        );
    }
    // A robot with nothing to say: every check holds.
    let b = Bench::new();
    let out = check(&b, &[]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(line(&out, "watched").starts_with("ok "));
    assert!(line(&out, "chest button").starts_with("ok "));
}

/// LKneePitch reports status 1 (the firmware reducing its stiffness) for 1500 cycles mid-
/// run, its temperature low: the run rests and says the status, not a temperature as if
/// it were hot; then goes on and completes.
#[test]
fn a_firmware_status_is_named_not_reported_as_heat() {
    let b = Bench::new();
    let plan = b.path("plan.csv");
    plan_file(&plan, 3, 11);
    let robot = b.robot(
        "a.sock",
        "a.csv",
        &["--speed", "0", "--status", "LKneePitch=1@300..1800"],
    );
    let out = b
        .capture(&plan, "ds", "a.sock", &b.fixed_camera(), &[])
        .output()
        .unwrap();
    finish(robot);
    let err = stderr(&out);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("LKneePitch reports status 1 (the firmware reduces its stiffness"),
        "{err}"
    );
    assert!(
        !err.contains("°C: resting until the motors cool"),
        "reported as heat: {err}"
    );
}

/// `--camera-setting upper.exposure=5000` for a run with only a lower camera (a setting
/// for a camera not given, or the other camera's name by mistake): refused by the run and
/// by the dry run, naming the cameras the run has; a setting without a camera's name is
/// for every camera given and is accepted.
#[test]
fn a_setting_for_a_camera_the_run_does_not_have_is_refused() {
    let b = Bench::new();
    let plan = b.path("plan.csv");
    plan_file(&plan, 1, 3);
    let words = [
        "--camera-setting upper",
        "this run has no upper camera",
        "its cameras: lower",
    ];
    let out = b
        .capture(
            &plan,
            "ds",
            "none.sock",
            &b.fixed_camera(),
            &["--camera-setting", "upper.exposure=5000"],
        )
        .output()
        .unwrap();
    assert_clean_failure(&out, &words);
    assert!(!b.path("ds").exists());
    let mut cmd = crate::util::naocalib();
    let out = cmd
        .arg("capture")
        .arg(&plan)
        .arg("--config")
        .arg(b.config())
        .arg("--lola")
        .arg(b.path("none.sock"))
        .arg("--camera")
        .arg(format!("lower={}", b.fixed_camera()))
        .arg("--camera-setting")
        .arg("upper.gain=100")
        .arg("--check")
        .arg(b.path("check"))
        .output()
        .unwrap();
    assert_clean_failure(&out, &words);
    // Without a camera's name: for the lower camera, accepted (the run gets as far as
    // LoLA, which is not there).
    let out = b
        .capture(
            &plan,
            "ds",
            "none.sock",
            &b.fixed_camera(),
            &["--camera-setting", "exposure=5000"],
        )
        .output()
        .unwrap();
    assert_clean_failure(&out, &["cannot connect to LoLA"]);
}
