//! The arms out of the way: `naocalib capture` against `naocalib simulate-robot` lifts the
//! arms from beside the body to the plan's arm posture beyond the head after the stiffness
//! ramp and before the first leg move, never faster than the arm speed, holds them there,
//! and lays them back beside the body before the ramp-down; a plan with an arm angle
//! outside its limit is refused before anything moves; a plan without arm columns runs
//! with capture's posture.

use naocalib::body::ArmPosture;
use naocalib::model::Joint;
use naocalib::robot::arms;
use naocalib::robot::lola::{self, CYCLE_S};
use naocalib::robot::motion::{MIN_RAMP_CYCLES, MotionOptions};
use naocalib::robot::simulated::{RecordRow, read_record};

use crate::capture::{Bench, captures_of, check_safety, finish, plan_file};
use crate::util::{assert_clean_failure, stderr};

/// The arm posture commanded in a record row.
fn commanded(r: &RecordRow) -> ArmPosture {
    ArmPosture(arms::indices().map(|k| r.position[k]))
}

/// The arm posture read in a record row.
fn read(r: &RecordRow) -> ArmPosture {
    ArmPosture(arms::indices().map(|k| r.reading[k]))
}

/// What the record says of the arms: the cycle the arms were first commanded away from
/// where they lay, the cycle they first read within 2° of capture's posture, the cycle of
/// the first leg or head command away from the start, and the fastest arm step (rad/s).
fn arm_timeline(record: &[RecordRow]) -> (usize, usize, usize, f64) {
    let start = commanded(&record[0]);
    let lifted = record
        .iter()
        .position(|r| arms::distance(&commanded(r), &start) > 1e-6)
        .expect("the arms were moved");
    let placed = record
        .iter()
        .position(|r| arms::distance(&read(r), &ArmPosture::CAPTURE) < 2f64.to_radians())
        .expect("the arms reached capture's posture");
    let legs = record
        .iter()
        .position(|r| {
            Joint::ALL.iter().any(|&j| {
                (r.position[lola::index(j)] - record[0].position[lola::index(j)]).abs() > 1e-6
            })
        })
        .expect("the legs moved");
    let fastest = record
        .windows(2)
        .map(|w| arms::distance(&commanded(&w[1]), &commanded(&w[0])) / CYCLE_S)
        .fold(0.0, f64::max);
    (lifted, placed, legs, fastest)
}

#[test]
fn capture_lifts_the_arms_before_the_first_leg_move_at_bounded_speed_and_lays_them_back() {
    let b = Bench::new();
    let plan = b.path("plan.csv");
    plan_file(&plan, 2, 32);
    let robot = b.robot("a.sock", "a.csv", &["--speed", "0"]);
    let out = b
        .capture(&plan, "ds", "a.sock", &b.fixed_camera(), &[])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    finish(robot);
    let said = stderr(&out);
    assert_eq!(captures_of(&b.path("ds")).len(), 2, "{said}");
    assert!(said.contains("the arms are beyond the head"), "{said}");
    let record = read_record(&b.path("a.csv")).unwrap();
    check_safety(&record, true);
    // Laid down beside the body; limp until the ramp is done.
    assert!(arms::distance(&read(&record[0]), &ArmPosture::BESIDE_BODY) < 1f64.to_radians());
    let (lifted, placed, legs, fastest) = arm_timeline(&record);
    let o = MotionOptions::default();
    assert!(lifted as u32 >= MIN_RAMP_CYCLES, "lifted at cycle {lifted}");
    let arm = arms::indices()[0];
    assert!(
        record[lifted - 1].stiffness[arm] >= o.stiffness - 1e-6,
        "the arms moved before their stiffness was up"
    );
    assert!(
        placed < legs,
        "arms placed at {placed}, first leg move at {legs}"
    );
    assert!(
        fastest <= o.arm_speed * 1.0001 + 1e-6,
        "fastest arm step {:.1}°/s",
        fastest.to_degrees()
    );
    let seconds = (placed - lifted) as f64 * CYCLE_S;
    eprintln!(
        "arms: lifted at cycle {lifted}, beyond the head at {placed} ({seconds:.1} s), \
         first leg move at {legs}, fastest {:.1}°/s",
        fastest.to_degrees()
    );
    // Held beyond the head through every stance.
    let last_leg = record
        .iter()
        .rposition(|r| (r.position[10] - record[record.len() - 1].position[10]).abs() > 1e-6)
        .unwrap();
    let commanded_there = record
        .iter()
        .position(|r| arms::distance(&commanded(r), &ArmPosture::CAPTURE) < 1e-6)
        .unwrap();
    assert!(commanded_there < legs);
    for r in &record[commanded_there..last_leg] {
        assert!(
            arms::distance(&commanded(r), &ArmPosture::CAPTURE) < 1e-6,
            "cycle {}",
            r.cycle
        );
    }
    // Back beside the body before the stiffness ramps down, and limp at the end.
    let last = record.last().unwrap();
    assert_eq!(last.stiffness[arm], 0.0);
    let down = record
        .iter()
        .rposition(|r| (r.stiffness[arm] - o.stiffness).abs() < 1e-6)
        .unwrap();
    assert!(arms::distance(&commanded(&record[down]), &ArmPosture::BESIDE_BODY) < 1e-6);
    assert!(
        arms::distance(&read(&record[down]), &ArmPosture::BESIDE_BODY) < 2f64.to_radians(),
        "the arms read {:?} when the ramp-down began",
        read(&record[down])
    );
}

/// A plan whose arm angle is beyond its joint's limit is refused before any robot is
/// contacted, naming the file, the line and the joint; a plan without the arm columns
/// runs with capture's posture.
#[test]
fn a_plan_with_an_arm_beyond_its_limit_is_refused_and_one_without_arm_columns_runs() {
    let b = Bench::new();
    let plan = b.path("plan.csv");
    plan_file(&plan, 2, 32);
    let text = std::fs::read_to_string(&plan).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let col = header.iter().position(|h| *h == "LShoulderRoll").unwrap();
    let bad: Vec<String> = text
        .lines()
        .enumerate()
        .map(|(n, l)| {
            let mut f: Vec<&str> = l.split(',').collect();
            if n == 2 {
                f[col] = "1.5";
            }
            f.join(",")
        })
        .collect();
    std::fs::write(&plan, bad.join("\n") + "\n").unwrap();
    let out = b
        .capture(&plan, "ds", "nobody.sock", &b.fixed_camera(), &[])
        .output()
        .unwrap();
    assert_clean_failure(
        &out,
        &[
            "plan.csv line 3, field LShoulderRoll: 85.94° is outside the joint's limits",
            "nothing was moved",
        ],
    );
    assert!(!b.path("ds").exists());

    // Without the arm columns.
    let keep: Vec<usize> = (0..header.len())
        .filter(|&k| !naocalib::body::ARM_JOINTS.contains(&header[k]))
        .collect();
    let without: String = text
        .lines()
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            keep.iter().map(|&k| f[k]).collect::<Vec<_>>().join(",") + "\n"
        })
        .collect();
    assert!(!without.contains("ShoulderPitch"));
    std::fs::write(&plan, without).unwrap();
    let robot = b.robot("a.sock", "a.csv", &["--speed", "0"]);
    let out = b
        .capture(&plan, "ds", "a.sock", &b.fixed_camera(), &[])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    finish(robot);
    assert_eq!(captures_of(&b.path("ds")).len(), 2);
    let record = read_record(&b.path("a.csv")).unwrap();
    let (_, placed, legs, _) = arm_timeline(&record);
    assert!(placed < legs);
}
