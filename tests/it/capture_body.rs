//! `naocalib capture` and the robot as a whole, against `simulate-robot`: a robot that does
//! not lie on its back is not made stiff; rolling over, the chest button, a motor's status
//! and a low battery end the run at rest with the stiffness ramped down and the captures
//! so far a valid dataset; `capture --check` moves nothing and says what holds.

use naocalib::dataset::Dataset;
use naocalib::model::Model;
use naocalib::robot::CaptureOptions;
use naocalib::robot::capture::{predicted_steps, read_plan};
use naocalib::robot::lola::CYCLE_S;
use naocalib::robot::simulated::{RecordRow, read_record};

use crate::capture::{Bench, captures_of, check_safety, finish, plan_file};
use crate::util::{assert_clean_failure, stderr};

/// The run's stiffness ramp-down at its end never rises again (the knee's stiffness from its
/// last full value to 0).
fn ramps_down_steadily(record: &[RecordRow]) {
    let top = naocalib::robot::motion::MotionOptions::default().stiffness;
    let from = record
        .iter()
        .rposition(|r| (r.stiffness[10] - top).abs() < 1e-6)
        .expect("full stiffness");
    for w in record[from..].windows(2) {
        assert!(
            w[1].stiffness[10] <= w[0].stiffness[10],
            "cycle {}: the stiffness rose on the way down",
            w[1].cycle
        );
    }
}

/// Standing, on its front, on its side: capture refuses with how the robot lies, before
/// anything is sent (the robot is told nothing, no dataset is made).
#[test]
fn a_robot_not_on_its_back_is_not_made_stiff() {
    for (lying, words) in [
        ("standing", "the robot lies upright"),
        ("front", "the robot lies on its front"),
        ("left-side", "the robot lies on its left side"),
    ] {
        let b = Bench::new();
        let plan = b.path("plan.csv");
        plan_file(&plan, 2, 31);
        let robot = b.robot("a.sock", "a.csv", &["--speed", "0", "--lying", lying]);
        let out = b
            .capture(&plan, "ds", "a.sock", &b.fixed_camera(), &[])
            .output()
            .unwrap();
        assert_clean_failure(&out, &[words, "lying on its back", "nothing was moved"]);
        finish(robot);
        let record = read_record(&b.path("a.csv")).unwrap();
        assert!(record.is_empty(), "{lying}: {} commands sent", record.len());
        assert!(!b.path("ds").exists(), "{lying}: a dataset was made");
    }
}

/// Rolling over, the chest button, a motor's status 2 and a low battery, each in the
/// middle of a run: the run stops with what happened and what to do, the robot returns to
/// rest and its stiffness is ramped down (every safety rule holds on what it was told),
/// and the captures taken before are a valid dataset.
#[test]
fn rolling_over_the_chest_button_a_status_and_a_low_battery_end_the_run_at_rest() {
    // The fault comes after the ramp-up and the first two stances by the plan's timing,
    // with half as much again for settling (at 10 times real time, so that a picture, taken
    // in real time, passes few cycles).
    let scratch = Bench::new();
    let plan = scratch.path("plan.csv");
    plan_file(&plan, 6, 32);
    let options = CaptureOptions::default();
    let rows = read_plan(&plan).unwrap();
    let steps = predicted_steps(&Model::default(), &rows, &options);
    let at = (options.motion.ramp_cycles as f64 + 1.5 * (steps[0] + steps[1]) / CYCLE_S) as u64;
    let at = at.to_string();
    let status = format!("RKneePitch=2@{at}");
    for (fault, value, message) in [
        ("--roll-at", at.as_str(), "the robot rolled over"),
        ("--chest-at", at.as_str(), "the chest button was pressed"),
        ("--status", status.as_str(), "RKneePitch reports status 2"),
        (
            "--low-battery-at",
            at.as_str(),
            "the battery is at 3 % (limit 5 %)",
        ),
    ] {
        let b = Bench::new();
        let plan = b.path("plan.csv");
        plan_file(&plan, 6, 32);
        let robot = b.robot("a.sock", "a.csv", &["--speed", "10", fault, value]);
        let out = b
            .capture(&plan, "ds", "a.sock", &b.fixed_camera(), &[])
            .output()
            .unwrap();
        assert_clean_failure(&out, &[message, "--resume"]);
        finish(robot);
        let record = read_record(&b.path("a.csv")).unwrap();
        check_safety(&record, true);
        ramps_down_steadily(&record);
        let taken = captures_of(&b.path("ds"));
        eprintln!("{fault}: {} captures before the stop", taken.len());
        assert!(
            !taken.is_empty() && taken.len() < 6,
            "{fault}: {} captures: {}",
            taken.len(),
            stderr(&out)
        );
        assert_eq!(
            Dataset::load_without_corners(&b.path("ds"))
                .unwrap()
                .captures
                .len(),
            taken.len()
        );
    }
}

/// `capture --check DIR` with a robot on its back and a good camera: every check holds,
/// the camera's picture is saved, exit 0, and the robot is told nothing but to hold what
/// it reports. A robot standing on a low battery, seen by a camera that is too dark: each
/// failing check says so, exit 1. Nothing moves in either.
#[test]
fn the_dry_run_moves_nothing_and_says_what_holds() {
    let b = Bench::new();
    let plan = b.path("plan.csv");
    plan_file(&plan, 2, 33);
    let robot = b.robot("a.sock", "a.csv", &["--speed", "0"]);
    let check = b.path("check");
    let out = crate::util::naocalib()
        .arg("capture")
        .arg(&plan)
        .arg("--config")
        .arg(b.config())
        .arg("--lola")
        .arg(b.path("a.sock"))
        .arg("--camera")
        .arg(b.fixed_camera())
        .arg("--check")
        .arg(&check)
        .output()
        .unwrap();
    let table = String::from_utf8_lossy(&out.stdout).to_string();
    assert!(out.status.success(), "{table}{}", stderr(&out));
    for item in [
        "plan",
        "lower camera",
        "LoLA",
        "joint readings",
        "lying",
        "battery",
        "motors",
        "stiffness",
    ] {
        assert!(
            table
                .lines()
                .any(|l| l.starts_with("ok ") && l.contains(item)),
            "{item}: {table}"
        );
    }
    assert!(table.contains("640×480, brightness 128 of 255"), "{table}");
    assert!(check.join("lower.png").exists());
    finish(robot);
    let record = read_record(&b.path("a.csv")).unwrap();
    assert!(record.len() >= 80, "{} messages answered", record.len());
    for r in &record {
        assert!(
            r.stiffness.iter().all(|&s| s == 0.0),
            "cycle {}: stiff",
            r.cycle
        );
        assert_eq!(r.position, record[0].reading, "cycle {}: moved", r.cycle);
    }

    let dark = b.path("dark.png");
    let image = naocalib::sim::render::GreyImage {
        width: 640,
        height: 480,
        pixels: vec![6; 640 * 480],
    };
    std::fs::write(&dark, image.to_png().unwrap()).unwrap();
    let robot = b.robot(
        "b.sock",
        "b.csv",
        &["--speed", "0", "--lying", "standing", "--battery", "3"],
    );
    let out = crate::util::naocalib()
        .arg("capture")
        .arg(&plan)
        .arg("--config")
        .arg(b.config())
        .arg("--lola")
        .arg(b.path("b.sock"))
        .arg("--camera")
        .arg(format!("command:cp '{}' {{path}}", dark.display()))
        .arg("--check")
        .arg(&check)
        .output()
        .unwrap();
    let table = String::from_utf8_lossy(&out.stdout).to_string();
    assert_eq!(out.status.code(), Some(1), "{table}{}", stderr(&out));
    for (item, text) in [
        ("lower camera", "brightness 6 of 255"),
        (
            "lower camera",
            "near black (mean brightness 6 of 255, at least 30 needed)",
        ),
        ("lying", "the robot lies upright"),
        ("battery", "3 % (at least 5 %)"),
    ] {
        let line = table
            .lines()
            .find(|l| l.get(4..).is_some_and(|r| r.starts_with(item)))
            .unwrap();
        assert!(line.starts_with("NO "), "{line}");
        assert!(line.contains(text), "{line}");
    }
    assert!(stderr(&out).contains("not ready (nothing was moved)"));
    finish(robot);
    let record = read_record(&b.path("b.csv")).unwrap();
    assert!(record.iter().all(|r| r.stiffness.iter().all(|&s| s == 0.0)));
}

/// A robot that falls silent mid-run: the run stops, and the stiffness is still ramped
/// down (sent blind, holding the posture) rather than left at the measuring stiffness.
#[test]
fn a_silent_robot_is_still_ramped_down() {
    let b = Bench::new();
    let plan = b.path("plan.csv");
    plan_file(&plan, 2, 34);
    let robot = b.robot(
        "a.sock",
        "a.csv",
        &["--speed", "0", "--silent-after", "300"],
    );
    let out = b
        .capture(&plan, "ds", "a.sock", &b.fixed_camera(), &[])
        .output()
        .unwrap();
    assert_clean_failure(&out, &["no message from LoLA for 25 cycles", "--resume"]);
    finish(robot);
    let record = read_record(&b.path("a.csv")).unwrap();
    let after: Vec<&RecordRow> = record.iter().filter(|r| r.cycle >= 300).collect();
    assert!(after.len() as u32 >= naocalib::robot::motion::MIN_RAMP_CYCLES);
    assert_eq!(after.last().unwrap().stiffness[10], 0.0, "left stiff");
    ramps_down_steadily(&record);
}
