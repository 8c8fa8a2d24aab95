//! `naocalib capture` with both cameras: each plan row's picture from the camera its
//! `camera` column names (`--camera lower=… --camera upper=…`, `{camera}` in a command),
//! checked against each camera's size; the dataset written carries the camera column; the
//! simulated robot renders both cameras; plans that name a camera not given, or a robot
//! without an upper camera, are refused before anything moves.

use std::path::Path;

use naocalib::dataset::Dataset;
use naocalib::model::{Camera, CameraId, Model, Side};
use naocalib::plan::PlannedCapture;
use naocalib::robot::capture::unsafe_posture;
use naocalib::robot::simulated::read_record;

use crate::capture::{Bench, check_safety, finish, plan_file};
use crate::util::{assert_clean_failure, stderr};

/// The robot's model with an upper camera of its own size (1280×960), so that a picture
/// from the wrong camera shows.
pub(crate) fn two_camera_model() -> Model {
    Model {
        upper_camera: Some(Camera {
            width: 1280,
            height: 960,
            fx: 1125.0,
            fy: 1125.0,
            cx: 640.0,
            cy: 480.0,
            distortion: [0.0; 5],
        }),
        ..Model::default()
    }
}

/// Writes `rows` as a plan whose rows in `upper` are the upper camera's (the plan's
/// `camera` column).
pub(crate) fn plan_with_cameras(path: &Path, rows: &[PlannedCapture], upper: &[usize]) {
    let rows: Vec<PlannedCapture> = rows
        .iter()
        .enumerate()
        .map(|(k, r)| PlannedCapture {
            camera: if upper.contains(&k) {
                CameraId::Upper
            } else {
                r.camera
            },
            ..*r
        })
        .collect();
    std::fs::write(path, naocalib::plan::render_csv(&rows)).unwrap();
}

/// A grey PNG of `width`×`height`.
fn grey(path: &Path, width: u32, height: u32, value: u8) -> Vec<u8> {
    let bytes = naocalib::sim::render::GreyImage {
        width,
        height,
        pixels: vec![value; (width * height) as usize],
    }
    .to_png()
    .unwrap();
    std::fs::write(path, &bytes).unwrap();
    bytes
}

/// A plan of four stances, rows 1 and 3 for the upper camera, captured with one command
/// per camera that copies `{camera}.png`: every row's picture comes from its camera, the
/// dataset says which, and it loads; the safety rules hold.
#[test]
fn each_rows_picture_comes_from_the_camera_it_names() {
    let b = Bench::with_model(two_camera_model());
    let plan = b.path("plan.csv");
    let rows = plan_file(&b.path("lower-only.csv"), 4, 31);
    plan_with_cameras(&plan, &rows, &[1, 3]);
    let lower = grey(&b.path("lower.png"), 640, 480, 60);
    let upper = grey(&b.path("upper.png"), 1280, 960, 200);
    let command = format!("command:cp '{}'/{{camera}}.png {{path}}", b.dir().display());
    let robot = b.robot("a.sock", "a.csv", &["--speed", "0"]);
    let out = b
        .capture(
            &plan,
            "ds",
            "a.sock",
            &format!("lower={command}"),
            &["--camera", &format!("upper={command}")],
        )
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    finish(robot);
    check_safety(&read_record(&b.path("a.csv")).unwrap(), true);
    let ds = Dataset::load_without_corners(&b.path("ds")).unwrap();
    assert_eq!(ds.captures.len(), 4);
    assert!(ds.model.upper_camera.is_some());
    for c in &ds.captures {
        let expected = if [1, 3].contains(&c.id) {
            CameraId::Upper
        } else {
            CameraId::Lower
        };
        assert_eq!(c.camera, expected, "capture {}", c.id);
        let picture = std::fs::read(ds.image_path(c).unwrap()).unwrap();
        let wanted = match expected {
            CameraId::Upper => &upper,
            CameraId::Lower => &lower,
        };
        assert!(
            picture == *wanted,
            "capture {}: the other camera's picture",
            c.id
        );
    }
    let csv = std::fs::read_to_string(b.path("ds/captures.csv")).unwrap();
    assert!(csv.starts_with("capture,board,image,camera,"), "{csv}");
}

/// The camera a picture comes from is checked by its size: with the cameras swapped, the
/// first upper row's picture is refused and the run stops at rest.
#[test]
fn a_picture_of_the_other_cameras_size_stops_the_run() {
    let b = Bench::with_model(two_camera_model());
    let plan = b.path("plan.csv");
    let rows = plan_file(&b.path("lower-only.csv"), 2, 32);
    plan_with_cameras(&plan, &rows, &[1]);
    grey(&b.path("lower.png"), 640, 480, 60);
    let command = |name: &str| format!("command:cp '{}'/{name}.png {{path}}", b.dir().display());
    let robot = b.robot("a.sock", "a.csv", &["--speed", "0"]);
    let out = b
        .capture(
            &plan,
            "ds",
            "a.sock",
            &format!("lower={}", command("lower")),
            &["--camera", &format!("upper={}", command("lower"))],
        )
        .output()
        .unwrap();
    assert_clean_failure(
        &out,
        &[
            "the picture of capture 1",
            "is 640×480 pixels; the camera's intrinsics are for 1280×960",
        ],
    );
    finish(robot);
    check_safety(&read_record(&b.path("a.csv")).unwrap(), true);
}

/// Refused before anything moves (no robot is contacted): a plan with upper rows and only
/// the lower camera given (a single `--camera SPEC` is the lower camera), the same camera
/// given twice, and a plan with upper rows for a robot without `[upper_camera]`.
#[test]
fn a_plan_needing_a_camera_not_given_is_refused_before_anything_moves() {
    let b = Bench::with_model(two_camera_model());
    let plan = b.path("plan.csv");
    let rows = plan_file(&b.path("lower-only.csv"), 3, 33);
    plan_with_cameras(&plan, &rows, &[2]);
    let fixed = b.fixed_camera();
    let out = b
        .capture(&plan, "ds", "nobody.sock", &fixed, &[])
        .output()
        .unwrap();
    assert_clean_failure(
        &out,
        &[
            "plan.csv line 4",
            "capture 2 is for the upper camera",
            "--camera upper=SPEC",
            "nothing was moved",
        ],
    );
    assert!(!b.path("ds").exists());
    let out = b
        .capture(
            &plan,
            "ds",
            "nobody.sock",
            &fixed,
            &["--camera", &format!("lower={fixed}")],
        )
        .output()
        .unwrap();
    assert_clean_failure(&out, &["the lower camera is given twice"]);
    let lower_only = Bench::new();
    let out = lower_only
        .capture(
            &plan,
            "ds",
            "nobody.sock",
            &fixed,
            &["--camera", &format!("upper={fixed}")],
        )
        .output()
        .unwrap();
    assert_clean_failure(
        &out,
        &[
            "plan.csv line 4, field camera",
            "[upper_camera]",
            "nothing was moved",
        ],
    );
}

/// Up to `take` postures of the measured leg `side` in which the upper camera sees a whole
/// sandal (the simulator's search over `pool` stances, at zero offsets) and that capture
/// finds safe (2° from every limit); written as lower-camera rows, for the caller to mark.
fn safe_upper_stances(
    model: &Model,
    side: Side,
    pool: usize,
    take: usize,
    rng: &mut rand_chacha::ChaCha8Rng,
) -> Vec<PlannedCapture> {
    let zero = [0.0; naocalib::model::PARAMETER_COUNT];
    naocalib::sim::choose_stances_for(model, CameraId::Upper, side, &zero, pool, 1, false, rng)
        .unwrap()
        .iter()
        .flat_map(|s| s.postures.iter().map(|p| (s.side, *p)))
        .filter(|(_, j)| unsafe_posture(model, j, 2f64.to_radians()).is_none())
        .map(|(side, joints)| PlannedCapture {
            camera: CameraId::Lower,
            side,
            joints,
        })
        .take(take)
        .collect()
}

/// Stances in which the upper camera sees a whole sandal (the simulator's search), and
/// lower-camera ones: the simulated robot renders each through the camera its row names
/// (`simulate-robot snap … --camera {camera}`), and every picture shows the sandal at its
/// camera's size.
#[test]
fn the_simulated_robot_renders_both_cameras() {
    use rand::SeedableRng;
    let model = Model {
        upper_camera: Some(naocalib::sim::camera::CameraPreset::V6.camera()),
        ..Model::default()
    };
    let b = Bench::with_model(model);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(34);
    let mut upper: Vec<PlannedCapture> = Vec::new();
    for side in Side::BOTH {
        upper.extend(safe_upper_stances(&model, side, 20, 1, &mut rng));
    }
    assert_eq!(upper.len(), 2, "two safe upper stances");
    let mut rows = plan_file(&b.path("lower-only.csv"), 2, 35);
    rows.extend(upper);
    let plan = b.path("plan.csv");
    plan_with_cameras(&plan, &rows, &[2, 3]);
    let robot = b.robot("a.sock", "a.csv", &["--speed", "0"]);
    let out = b.capture_both(&plan, "ds", "a.sock").output().unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    finish(robot);
    let ds = Dataset::load_without_corners(&b.path("ds")).unwrap();
    assert_eq!(ds.captures.len(), 4);
    for c in &ds.captures {
        let png = std::fs::read(ds.image_path(c).unwrap()).unwrap();
        let mut reader = png::Decoder::new(std::io::Cursor::new(png))
            .read_info()
            .unwrap();
        let mut pixels = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut pixels).unwrap();
        let size = ds.model.intrinsics(c.camera);
        assert_eq!((info.width, info.height), (size.width, size.height));
        let dark = pixels.iter().filter(|&&g| g < 60).count();
        let bright = pixels.iter().filter(|&&g| g > 180).count();
        assert!(
            dark > 2000 && bright > 2000,
            "capture {} ({}): {dark} dark, {bright} bright",
            c.id,
            c.camera
        );
    }
}

/// Plan (`naocalib plan`, lower camera) plus stances for the upper camera (the
/// simulator's search) → `simulate-robot` with a robot as the teams' files show them
/// (upper camera pitch −8.5°, roll 2°, yaw 1°; hidden) → `capture` with both cameras →
/// `solve --detect`: the upper camera's rotations and the paper's parameters recovered
/// within 4 σ.
#[cfg(feature = "detect")]
#[test]
fn both_cameras_end_to_end_recover_the_robots_truth() {
    use naocalib::model::Param;
    use rand::SeedableRng;
    let model = Model {
        upper_camera: Some(naocalib::sim::camera::CameraPreset::V6.camera()),
        ..Model::default()
    };
    let b = Bench::with_model(model);
    let mut rows = crate::capture::designed_plan(&b, &b.path("lower.csv"), 40, 41, "paper");
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(42);
    let first_upper = rows.len();
    for side in Side::BOTH {
        rows.extend(safe_upper_stances(&model, side, 120, 5, &mut rng));
    }
    let upper: Vec<usize> = (first_upper..rows.len()).collect();
    assert!(upper.len() >= 8, "{} upper stances", upper.len());
    let plan = b.path("plan.csv");
    plan_with_cameras(&plan, &rows, &upper);
    let mut truth = naocalib::sim::draw_truth(&mut rand_chacha::ChaCha8Rng::seed_from_u64(43));
    for (p, deg) in [
        (Param::UpperCamPitch, -8.5),
        (Param::UpperCamRoll, 2.0),
        (Param::UpperCamYaw, 1.0),
    ] {
        truth[p.index()] = f64::to_radians(deg);
    }
    crate::util::write_truth(&b.path("truth.toml"), &truth);
    let truth_arg = b.path("truth.toml");
    let robot = b.robot(
        "a.sock",
        "a.csv",
        // Paced (10× real time), so that a busy machine does not starve it into LoLA's
        // silence limit.
        &["--speed", "10", "--truth", truth_arg.to_str().unwrap()],
    );
    let out = b.capture_both(&plan, "ds", "a.sock").output().unwrap();
    let err = stderr(&out);
    assert!(out.status.success(), "{err}");
    finish(robot);
    check_safety(&read_record(&b.path("a.csv")).unwrap(), true);
    let ds = Dataset::load_without_corners(&b.path("ds")).unwrap();
    let taken_upper = ds
        .captures
        .iter()
        .filter(|c| c.camera == CameraId::Upper)
        .count();
    eprintln!(
        "{} captures, {taken_upper} upper, of {} planned; {err}",
        ds.captures.len(),
        rows.len()
    );
    assert!(taken_upper >= 8, "{taken_upper} upper captures: {err}");
    let out = crate::util::naocalib()
        .args(["solve", "--detect", "--json"])
        .arg(b.path("ds"))
        .output()
        .unwrap();
    assert!(out.status.success(), "solve: {}", stderr(&out));
    let result: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let mut checked = Param::ALL[..naocalib::model::PAPER_PARAMETERS].to_vec();
    checked.extend([
        Param::UpperCamYaw,
        Param::UpperCamPitch,
        Param::UpperCamRoll,
    ]);
    crate::capture::assert_recovers(&result, &truth, &checked);
}
