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

/// The camera a picture comes from is checked by its size: with the upper camera giving
/// the lower one's picture once the run is under way (its first picture, checked before
/// anything moved, was its own), the first upper row's picture is refused and the run
/// stops at rest.
#[test]
fn a_picture_of_the_other_cameras_size_stops_the_run() {
    let b = Bench::with_model(two_camera_model());
    let plan = b.path("plan.csv");
    let rows = plan_file(&b.path("lower-only.csv"), 2, 32);
    plan_with_cameras(&plan, &rows, &[1]);
    let lower = b.path("lower.png");
    grey(&lower, 640, 480, 60);
    grey(&b.path("upper.png"), 1280, 960, 60);
    let upper = b.after_first(
        &b.path("upper.png"),
        &format!("cp '{}' {{path}}", lower.display()),
    );
    let robot = b.robot("a.sock", "a.csv", &["--speed", "0"]);
    let out = b
        .capture(
            &plan,
            "ds",
            "a.sock",
            &format!("lower=command:cp '{}' {{path}}", lower.display()),
            &["--camera", &format!("upper={upper}")],
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
        // Exposed as the team settings expose it.
        let light = naocalib::robot::camera::settings::Brightness::of_grey(&pixels);
        assert!(light.check(None).is_ok(), "capture {}: {light:?}", c.id);
    }
    let recorded = naocalib::dataset::read_camera_settings(&b.path("ds/dataset.toml")).unwrap();
    assert_eq!(recorded.len(), 2);
    for (camera, s) in recorded {
        assert_eq!(s.flip, Some(camera == CameraId::Upper), "{camera}");
    }
}

/// Each `command:` camera is given its camera's settings through its placeholders — the
/// team defaults, upper flipped 700 × 800, lower unflipped 1700 × 250, and what
/// `--camera-setting` changes — and the dataset records them in each camera's table (the
/// keys capture reads), saying they were given to the command. `--resume` with other
/// settings is refused before anything moves, naming the camera, the control and both
/// values; with the same settings it goes on.
#[test]
fn command_cameras_get_their_settings_and_the_dataset_records_them() {
    let b = Bench::with_model(two_camera_model());
    let plan = b.path("plan.csv");
    let rows = plan_file(&b.path("lower-only.csv"), 2, 36);
    plan_with_cameras(&plan, &rows, &[1]);
    grey(&b.path("lower.png"), 640, 480, 90);
    grey(&b.path("upper.png"), 1280, 960, 90);
    let log = b.path("given.txt");
    let command = format!(
        "command:echo {{camera}} {{flip}} {{exposure}} {{gain}} {{white_balance_k}} {{fps}} \
         {{width}} {{height}} >> '{}'; cp '{}'/{{camera}}.png {{path}}",
        log.display(),
        b.dir().display()
    );
    let robot = b.robot("a.sock", "a.csv", &["--speed", "0", "--clients", "2"]);
    let out = b
        .capture(
            &plan,
            "ds",
            "a.sock",
            &format!("lower={command}"),
            &[
                "--camera",
                &format!("upper={command}"),
                "--camera-setting",
                "lower.white_balance_k=4000",
            ],
        )
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let given = std::fs::read_to_string(&log).unwrap();
    let lines: Vec<&str> = given.lines().collect();
    // The first pictures, checked before anything moves, then one per row.
    assert_eq!(lines.len(), 4, "{given}");
    for line in &lines {
        assert!(
            *line == "lower 0 1700 250 4000 30 640 480"
                || *line == "upper 1 700 800 auto 30 1280 960",
            "{line}"
        );
    }
    let toml = b.path("ds/dataset.toml");
    let recorded = naocalib::dataset::read_camera_settings(&toml).unwrap();
    let of = |c: CameraId| recorded.iter().find(|(id, _)| *id == c).unwrap().1;
    let lower = of(CameraId::Lower);
    assert_eq!(
        (
            lower.flip,
            lower.exposure,
            lower.gain,
            lower.white_balance_k,
            lower.fps
        ),
        (Some(false), Some(1700), Some(250), Some(4000), Some(30))
    );
    let upper = of(CameraId::Upper);
    assert_eq!(
        (
            upper.flip,
            upper.exposure,
            upper.gain,
            upper.white_balance_k,
            upper.fps
        ),
        (Some(true), Some(700), Some(800), None, Some(30))
    );
    let text = std::fs::read_to_string(&toml).unwrap();
    assert!(
        text.contains("the upper camera's command was given"),
        "{text}"
    );
    let ds = Dataset::load_without_corners(&b.path("ds")).unwrap();
    assert_eq!(ds.model, two_camera_model());
    // Other settings (the robot's dataset.toml given with --config again, and
    // --camera-setting): refused, nothing moved (the robot is not contacted).
    for (setting, words) in [
        (
            "upper.exposure=1000",
            ["upper camera", "exposure 700", "with 1000"],
        ),
        (
            "lower.white_balance_k=5000",
            ["lower camera", "white_balance_k 4000 K", "with 5000 K"],
        ),
        (
            "lower.fps=30",
            ["lower camera", "white_balance_k 4000 K", "with automatic"],
        ),
    ] {
        let upper = format!("upper={command}");
        let mut args = vec!["--camera", &upper, "--resume"];
        if setting != "lower.fps=30" {
            args.extend(["--camera-setting", "lower.white_balance_k=4000"]);
        }
        args.extend(["--camera-setting", setting]);
        let out = b
            .capture(
                &plan,
                "ds",
                "nobody.sock",
                &format!("lower={command}"),
                &args,
            )
            .output()
            .unwrap();
        let mut needles = vec!["ds/dataset.toml line", "nothing was moved"];
        needles.extend(words);
        assert_clean_failure(&out, &needles);
    }
    // The same settings: it goes on.
    let out = b
        .capture(
            &plan,
            "ds",
            "a.sock",
            &format!("lower={command}"),
            &[
                "--camera",
                &format!("upper={command}"),
                "--resume",
                "--camera-setting",
                "lower.white_balance_k=4000",
            ],
        )
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    finish(robot);
}

/// The simulated robot's cameras set as capture sets them: at the team defaults every
/// picture is exposed; at the old settings (exposure 100, gain 32) the first picture is
/// near black and the run stops before anything moves; a flip that would turn a camera's
/// pictures upside down is refused before anything moves. The robot is not contacted.
#[test]
fn the_simulated_cameras_at_the_old_settings_or_unflipped_stop_the_run_before_anything_moves() {
    let b = Bench::with_model(two_camera_model());
    let plan = b.path("plan.csv");
    let rows = plan_file(&b.path("lower-only.csv"), 2, 37);
    plan_with_cameras(&plan, &rows, &[1]);
    let robot = b.robot("a.sock", "a.csv", &["--speed", "0"]);
    let snap = b.snap_camera();
    let run = |extra: &[&str]| {
        let mut args = vec!["--camera", &format!("upper={snap}")]
            .into_iter()
            .map(String::from)
            .collect::<Vec<_>>();
        args.extend(extra.iter().map(|s| s.to_string()));
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        b.capture(&plan, "ds", "a.sock", &format!("lower={snap}"), &args)
            .output()
            .unwrap()
    };
    let out = run(&[
        "--camera-setting",
        "exposure=100",
        "--camera-setting",
        "gain=32",
    ]);
    assert_clean_failure(
        &out,
        &[
            "the lower camera's first picture is near black",
            "now exposure 100, gain 32",
            "raise the exposure or the gain",
            "nothing was moved",
        ],
    );
    for (setting, words) in [
        (
            "upper.flip=false",
            ["upper camera's flip is false", "upside down"],
        ),
        (
            "lower.flip=true",
            ["lower camera's flip is true", "upside down"],
        ),
    ] {
        let out = run(&["--camera-setting", setting]);
        let mut needles = vec!["nothing was moved"];
        needles.extend(words);
        assert_clean_failure(&out, &needles);
    }
    assert!(!b.path("ds/dataset.toml").exists(), "no dataset was begun");
    // SIGTERM: the robot, never contacted, writes its (empty) record.
    unsafe {
        libc::kill(robot.id() as libc::pid_t, libc::SIGTERM);
    }
    finish(robot);
    assert!(read_record(&b.path("a.csv")).unwrap().is_empty());
}

/// A `command:` camera's first picture is checked before anything moves, as a V4L2
/// camera's is: a picture of another size, one that does not decode, a near black one —
/// each refused with the camera and what to change; no dataset begun, LoLA not contacted.
#[test]
fn a_command_cameras_first_picture_is_checked_before_anything_moves() {
    let b = Bench::new();
    let plan = b.path("plan.csv");
    plan_file(&plan, 2, 38);
    let corrupt_jpeg: Vec<u8> = [0xff, 0xd8, 0xff, 0xe0]
        .into_iter()
        .chain((0..2000).map(|k| (k * 7 % 251) as u8))
        .collect();
    std::fs::write(b.path("corrupt.jpg"), corrupt_jpeg).unwrap();
    grey(&b.path("small.png"), 320, 240, 90);
    grey(&b.path("dark.png"), 640, 480, 4);
    for (name, message) in [
        (
            "small.png",
            "the lower camera's first picture is 320×240 pixels; the dataset's intrinsics are for 640×480",
        ),
        (
            "corrupt.jpg",
            "the lower camera's first picture is not a readable JPEG",
        ),
        (
            "dark.png",
            "the lower camera's first picture is near black (mean brightness 4 of 255",
        ),
    ] {
        let camera = format!("command:cp '{}' {{path}}", b.path(name).display());
        let out = b
            .capture(&plan, "ds", "nobody.sock", &camera, &[])
            .output()
            .unwrap();
        assert_clean_failure(&out, &[message, "nothing was moved"]);
        assert!(!stderr(&out).contains("LoLA"), "{}", stderr(&out));
        assert!(
            !b.path("ds/dataset.toml").exists(),
            "{name}: a dataset was begun"
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
