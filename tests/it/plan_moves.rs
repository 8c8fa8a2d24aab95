//! Plans run as planned: every move of a planned schedule (rest → first capture, capture →
//! capture, last → rest) has a collision-free way through the route search `capture`
//! drives, the predicted duration counts every move, and `capture` on the simulated robot
//! skips no stance of a plan.

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use naocalib::body::{self as collision, BodyModel};
use naocalib::dataset::Dataset;
use naocalib::model::{Joint, JointAngles, Model};
use naocalib::plan::route::{self, Timing};
use naocalib::plan::{self, PlanOptions};

use crate::util::{naocalib, stderr};

/// Walks the straight move from `a` to `b` in steps of at most 0.005 rad (six times finer
/// than the route search checks) and names the first collision after the parts have
/// parted.
fn collision_on_the_way(model: &Model, a: &JointAngles, b: &JointAngles) -> Option<String> {
    let n = Joint::ALL
        .iter()
        .map(|&j| ((b.get(j) - a.get(j)).abs() / 0.005).ceil() as usize)
        .max()
        .unwrap_or(1)
        .max(1);
    let mut parted = false;
    for k in 0..=n {
        let t = k as f64 / n as f64;
        let mut p = *a;
        for j in Joint::ALL {
            p.set(j, a.get(j) + t * (b.get(j) - a.get(j)));
        }
        match collision::collision(&model.robot, &model.board, &BodyModel::default(), &p) {
            None => parted = true,
            Some(what) if parted => return Some(format!("{what} at {t:.3} of the way")),
            Some(_) => {}
        }
    }
    None
}

/// Every move of `postures` from rest and back: a way exists, and each of its straight
/// pieces is free when walked finely; returns the number of intermediate postures.
pub(crate) fn assert_every_move_is_free(model: &Model, postures: &[JointAngles]) -> usize {
    let rest = route::rest_posture();
    let moves = route::moves(model, &BodyModel::default(), &rest, postures);
    assert_eq!(moves.len(), postures.len() + 1);
    let mut at = rest;
    let mut via = 0;
    for (k, way) in moves.iter().enumerate() {
        let way = way
            .as_ref()
            .unwrap_or_else(|e| panic!("move {k} of {}: {e}", postures.len()));
        let target = postures.get(k).copied().unwrap_or(rest);
        assert_eq!(way.last(), Some(&target), "move {k} ends at its capture");
        via += way.len() - 1;
        for next in way {
            if let Some(what) = collision_on_the_way(model, &at, next) {
                panic!("move {k}: {what}");
            }
            at = *next;
        }
    }
    // The return to rest is one straight move (as `capture` makes it).
    assert_eq!(moves.last().unwrap().as_ref().unwrap().len(), 1);
    via
}

#[test]
fn every_move_of_planned_48_and_144_capture_plans_is_collision_free() {
    let model = Model::default();
    for captures in [48, 144] {
        let made;
        let plan = if captures == 144 {
            crate::util::paper_plan()
        } else {
            made = plan::plan(
                &model,
                &PlanOptions {
                    captures,
                    ..PlanOptions::default()
                },
            )
            .expect("plan");
            &made
        };
        let postures: Vec<JointAngles> = plan.captures.iter().map(|c| c.joints).collect();
        let via = assert_every_move_is_free(&model, &postures);
        // The predicted duration is that of these moves, every one of them counted: at
        // least the pictures and the straight moves' times.
        let timing = Timing::default();
        let rest = route::rest_posture();
        let direct: f64 = std::iter::once(&rest)
            .chain(&postures)
            .zip(postures.iter().chain(std::iter::once(&rest)))
            .map(|(a, b)| timing.motion(a, b))
            .sum();
        let pictures =
            captures as f64 * (timing.leg_settle.min(timing.head_settle) + timing.capture);
        assert!(plan.duration >= direct + pictures - 1e-9);
        let again = route::duration(&model, &BodyModel::default(), &timing, &rest, &postures);
        assert!((plan.duration - again).abs() < 1e-9);
        eprintln!(
            "{captures} captures: {via} intermediate postures, predicted {:.0} s",
            plan.duration
        );
        if captures == 144 {
            assert!(plan.duration <= 300.0, "{} s", plan.duration);
        }
    }
}

/// The moves a plan makes when its order ignores the collision model are refused by the
/// route search: the check above can fail.
#[test]
fn a_move_through_the_other_leg_has_no_way() {
    let model = Model::default();
    let rest = route::rest_posture();
    let mut crossed = rest;
    crossed.set(Joint::LHipRoll, -0.3);
    crossed.set(Joint::RHipRoll, 0.3);
    let moves = route::moves(&model, &BodyModel::default(), &rest, &[crossed]);
    assert!(moves[0].is_err());
    assert!(collision_on_the_way(&model, &rest, &crossed).is_some());
}

/// `naocalib plan` (48 captures) → `simulate-robot` → `capture`: no stance skipped, every
/// capture taken.
#[test]
fn capture_of_a_plan_skips_no_stance() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let cfg = dir.join("cfg");
    Dataset::new(&cfg, Model::default())
        .write(&cfg, false)
        .unwrap();
    let config = cfg.join("dataset.toml");
    let plan = dir.join("plan.csv");
    let out = naocalib()
        .arg("plan")
        .arg(&plan)
        .args([
            "--captures",
            "48",
            "--pool",
            "80",
            "--seed",
            "13",
            "--camera",
        ])
        .arg(&config)
        .output()
        .unwrap();
    assert!(out.status.success(), "plan: {}", stderr(&out));
    let (out, mut robot) = capture_with_fixed_camera(dir, &plan, &config);
    // The simulated robot ends with the connection.
    let start = Instant::now();
    while robot.try_wait().unwrap().is_none() {
        if start.elapsed() > Duration::from_secs(60) {
            let _ = robot.kill();
            panic!("the simulated robot did not exit");
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    let err = stderr(&out);
    assert!(out.status.success(), "capture: {err}");
    assert!(
        !err.contains("skipped:") && !err.contains("skipped capture"),
        "{err}"
    );
    let ds = Dataset::load_without_corners(&dir.join("ds")).unwrap();
    assert_eq!(ds.captures.len(), 48, "{err}");
}

/// Runs `capture PLAN DIR/ds` against a simulated robot at full speed with a camera that
/// copies one fixed picture; returns capture's output and the robot's process.
fn capture_with_fixed_camera(
    dir: &Path,
    plan: &Path,
    config: &Path,
) -> (std::process::Output, std::process::Child) {
    let bin = assert_cmd::cargo::cargo_bin("naocalib");
    let socket = dir.join("lola.sock");
    let robot = Command::new(&bin)
        .arg("simulate-robot")
        .arg("--lola")
        .arg(&socket)
        .arg("--config")
        .arg(config)
        .arg("--state")
        .arg(dir.join("state.json"))
        .args(["--speed", "0"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("robot started");
    let start = Instant::now();
    while !socket.exists() {
        assert!(start.elapsed() < Duration::from_secs(60), "no socket");
        std::thread::sleep(Duration::from_millis(10));
    }
    let png = dir.join("fixed.png");
    let image = naocalib::sim::render::GreyImage {
        width: 640,
        height: 480,
        pixels: vec![128; 640 * 480],
    };
    std::fs::write(&png, image.to_png().unwrap()).unwrap();
    let out = Command::new(&bin)
        .arg("capture")
        .arg(plan)
        .arg(dir.join("ds"))
        .arg("--config")
        .arg(config)
        .arg("--lola")
        .arg(&socket)
        .arg("--camera")
        .arg(format!("command:cp '{}' {{path}}", png.display()))
        .output()
        .unwrap();
    (out, robot)
}
