//! `naocalib capture --camera v4l2:PATH` against an emulated NAO V6 camera at the system-call
//! boundary (`tests/fixtures/v6cam/v6cam.c`, compiled here and preloaded): the same V4L2
//! code that runs on the robot. The upper picture upright whatever the flip registers
//! held; every setting read back, one that does not stick or a dark first picture refused
//! before anything moves; a manual exposure that takes effect; a stalled camera ending the
//! run at rest with the stiffness down; short, flagged and stale frames never saved.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

use naocalib::dataset::Dataset;
use naocalib::model::{CameraId, Joint, Side};
use naocalib::plan::PlannedCapture;
use naocalib::robot::capture::rest_posture;
use naocalib::robot::lola::{self, CYCLE_S};
use naocalib::robot::motion::MotionOptions;
use naocalib::robot::simulated::{RecordRow, read_record};

use crate::capture::{Bench, check_safety, finish, moved_motors, plan_file};
use crate::capture_cameras::{plan_with_cameras, two_camera_model};
use crate::util::{assert_clean_failure, stderr};

/// The emulated camera's library, compiled once (`cc -shared -fPIC`).
fn library() -> &'static Path {
    static LIB: OnceLock<(tempfile::TempDir, PathBuf)> = OnceLock::new();
    &LIB.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap();
        let lib = dir.path().join("libv6cam.so");
        let source = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/v6cam/v6cam.c");
        let out = Command::new("cc")
            .args(["-shared", "-fPIC", "-O1", "-o"])
            .arg(&lib)
            .arg(&source)
            .arg("-ldl")
            .output()
            .expect("cc runs");
        assert!(out.status.success(), "cc: {}", stderr(&out));
        (dir, lib)
    })
    .1
}

/// The emulated cameras of a bench: `video-top` and `video-bottom` in its directory, their
/// registers in `v6cam/`.
struct Cameras {
    top: PathBuf,
    bottom: PathBuf,
    state: PathBuf,
}

impl Cameras {
    fn new(b: &Bench) -> Cameras {
        let state = b.path("v6cam");
        std::fs::create_dir_all(&state).unwrap();
        Cameras {
            top: b.path("video-top"),
            bottom: b.path("video-bottom"),
            state,
        }
    }

    /// Sets a camera's persisted registers before the run: flips, the driver's exposure,
    /// the sensor's exposure, gain, auto exposure (0 auto, 1 manual).
    fn preset(&self, top: bool, flip: u8, exposure: u32, sensor: u32, gain: u32, auto: u8) {
        let name = if top { "video-top" } else { "video-bottom" };
        std::fs::write(
            self.state.join(format!("{name}.state")),
            format!("{flip} {flip} {exposure} {sensor} {gain} {auto} 1 2500 30\n"),
        )
        .unwrap();
    }

    /// A camera's persisted registers: (horizontal flip, vertical flip, exposure, gain).
    fn registers(&self, top: bool) -> (u32, u32, u32, u32) {
        let name = if top { "video-top" } else { "video-bottom" };
        let text = std::fs::read_to_string(self.state.join(format!("{name}.state"))).unwrap();
        let v: Vec<u32> = text
            .split_whitespace()
            .map(|x| x.parse().unwrap())
            .collect();
        (v[0], v[1], v[2], v[4])
    }

    /// `cmd` with the library preloaded and the emulator's `knobs`.
    fn preload<'a>(&self, cmd: &'a mut Command, knobs: &[(&str, &str)]) -> &'a mut Command {
        cmd.env("LD_PRELOAD", library())
            .env(
                "V6CAM_DEVICES",
                format!("{}:{}", self.top.display(), self.bottom.display()),
            )
            .env("V6CAM_STATE_DIR", &self.state);
        for (k, v) in knobs {
            cmd.env(k, v);
        }
        cmd
    }

    fn lower(&self) -> String {
        format!("lower=v4l2:{}", self.bottom.display())
    }

    fn upper(&self) -> String {
        format!("upper=v4l2:{}", self.top.display())
    }
}

/// The mean grey level of a quadrant (`top`, `left`) of a saved picture.
fn quadrant(pixels: &[u8], width: usize, top: bool, left: bool) -> f64 {
    let height = pixels.len() / width;
    let rows = if top {
        0..height / 2
    } else {
        height / 2..height
    };
    let cols = if left { 0..width / 2 } else { width / 2..width };
    let mut sum = 0u64;
    let mut n = 0u64;
    for y in rows {
        for x in cols.clone() {
            sum += u64::from(pixels[y * width + x]);
            n += 1;
        }
    }
    sum as f64 / n as f64
}

/// The grey pixels of a saved PNG and its width.
fn grey_png(path: &Path) -> (Vec<u8>, usize) {
    let bytes = std::fs::read(path).unwrap();
    let (_, size) = naocalib::robot::camera::header_size(&bytes).unwrap();
    let ((w, _), grey) = naocalib::robot::camera::decode_grey(&bytes, size).unwrap();
    (grey, w as usize)
}

/// Every saved picture of the dataset at `dir` is the emulated scene, upright (darker at
/// the top and on the left) at `level` (its bottom-right quadrant; exposure × gain / 2500)
/// for the camera: never a black (short, flagged or stale) frame.
fn check_pictures(dir: &Path, lower_level: f64, upper_level: f64) -> usize {
    let ds = Dataset::load_without_corners(dir).unwrap();
    for c in &ds.captures {
        let (grey, w) = grey_png(&ds.image_path(c).unwrap());
        let level = match c.camera {
            CameraId::Lower => lower_level,
            CameraId::Upper => upper_level,
        };
        let br = quadrant(&grey, w, false, false);
        let tl = quadrant(&grey, w, true, true);
        let tr = quadrant(&grey, w, true, false);
        let bl = quadrant(&grey, w, false, true);
        assert!(
            (br - level).abs() < 1.0,
            "capture {} ({}): bottom right {br}, expected {level}",
            c.id,
            c.camera
        );
        assert!(
            (br - tr - 25.0).abs() < 1.0
                && (br - bl - 5.0).abs() < 1.0
                && (br - tl - 30.0).abs() < 1.0,
            "capture {} ({}): not upright: quadrants tl {tl} tr {tr} bl {bl} br {br}",
            c.id,
            c.camera
        );
    }
    ds.captures.len()
}

/// A plan of `n` rows, those in `upper` for the upper camera.
fn plan(b: &Bench, n: usize, seed: u64, upper: &[usize]) -> PathBuf {
    let path = b.path("plan.csv");
    let rows = plan_file(&b.path("lower-only.csv"), n, seed);
    plan_with_cameras(&path, &rows, upper);
    path
}

/// Both cameras with their flip registers the wrong way round before the run, and the
/// driver holding the exposure about to be set while the sensor runs auto exposure's: the
/// run writes the flips (upper 1, lower 0) and reads them back, switches to manual
/// exposure and writes another value first, so that every picture is upright and exposed
/// as set (rUNSWift's values: upper 700 × 800, lower 1700 × 250); the registers keep the
/// settings; frames exposed before the stream started are dropped.
#[test]
fn the_upper_picture_is_upright_and_exposed_as_set_whatever_the_registers_held() {
    let b = Bench::with_model(two_camera_model());
    let cams = Cameras::new(&b);
    cams.preset(true, 0, 700, 300, 800, 0);
    cams.preset(false, 1, 1700, 300, 250, 0);
    let plan = plan(&b, 4, 41, &[1, 3]);
    let robot = b.robot("a.sock", "a.csv", &["--speed", "0"]);
    let mut cmd = b.capture(
        &plan,
        "ds",
        "a.sock",
        &cams.lower(),
        &["--camera", &cams.upper()],
    );
    let out = cams.preload(&mut cmd, &[]).output().unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    finish(robot);
    check_safety(&read_record(&b.path("a.csv")).unwrap(), true);
    let err = stderr(&out);
    assert!(
        err.contains("upper camera")
            && err.contains("1280×960 at 30 frames/s, flip 1, exposure 700, gain 800"),
        "{err}"
    );
    assert!(
        err.contains("lower camera") && err.contains("flip 0, exposure 1700, gain 250"),
        "{err}"
    );
    assert_eq!(check_pictures(&b.path("ds"), 170.0, 224.0), 4);
    assert_eq!(cams.registers(true), (1, 1, 700, 800));
    assert_eq!(cams.registers(false), (0, 0, 1700, 250));
    // The dataset says how its pictures were taken: the settings read back, per camera.
    let toml = b.path("ds/dataset.toml");
    let recorded = naocalib::dataset::read_camera_settings(&toml).unwrap();
    let of = |c: CameraId| recorded.iter().find(|(id, _)| *id == c).unwrap().1;
    let (upper, lower) = (of(CameraId::Upper), of(CameraId::Lower));
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
    assert_eq!(
        (lower.flip, lower.exposure, lower.gain, lower.fps),
        (Some(false), Some(1700), Some(250), Some(30))
    );
    let text = std::fs::read_to_string(&toml).unwrap();
    assert!(
        text.contains("as capture wrote and read them back"),
        "{text}"
    );
}

/// One refused run: the emulator's knobs, capture's extra flags, what its message says.
type Case<'a> = (&'a [(&'a str, &'a str)], &'a [&'a str], &'a [&'a str]);

/// A setting that does not stick (the driver ignores the flip, or the exposure), a size the
/// camera does not stream, and a first picture that is near black or saturated each stop
/// the run before anything moves, naming the camera and the control or brightness.
#[test]
fn a_setting_that_does_not_stick_or_a_dark_first_picture_stops_before_anything_moves() {
    let b = Bench::with_model(two_camera_model());
    let cams = Cameras::new(&b);
    let plan = plan(&b, 2, 42, &[1]);
    let cases: [Case; 4] = [
        (
            &[("V6CAM_IGNORE", "flip")],
            &[],
            &[
                "upper camera",
                "flip (horizontal",
                "set to 1 but reads back 0",
                "nothing was moved",
            ],
        ),
        (
            &[("V6CAM_IGNORE", "exposure")],
            &["--camera-setting", "lower.exposure=900"],
            &[
                "lower camera",
                "exposure was set to 900",
                "nothing was moved",
            ],
        ),
        (
            &[],
            &[
                "--camera-setting",
                "exposure=100",
                "--camera-setting",
                "gain=32",
            ],
            &[
                "near black",
                "mean brightness 0 of 255",
                "raise the exposure",
                "exposure 100, gain 32",
            ],
        ),
        (
            &[],
            &["--camera-setting", "upper.exposure=1048575"],
            &["upper camera", "saturated", "lower the exposure"],
        ),
    ];
    let upper = cams.upper();
    for (k, (knobs, extra, needles)) in cases.iter().enumerate() {
        cams.preset(true, 0, 512, 300, 16, 0);
        let mut args = vec!["--camera", &upper[..]];
        args.extend_from_slice(extra);
        // No robot serves this socket: a run that got as far as LoLA would fail there,
        // with another message.
        let mut cmd = b.capture(&plan, &format!("ds{k}"), "none.sock", &cams.lower(), &args);
        let out = cams.preload(&mut cmd, knobs).output().unwrap();
        assert_clean_failure(&out, needles);
        assert!(!stderr(&out).contains("none.sock"), "{}", stderr(&out));
        assert!(!b.path(&format!("ds{k}/captures.csv")).exists());
    }
}

/// Short frames (half their bytes) and frames flagged corrupt are dropped and taken again:
/// the run completes and no saved picture is one of them (they are black).
#[test]
fn short_and_flagged_frames_are_never_saved() {
    let b = Bench::new();
    let cams = Cameras::new(&b);
    let plan = plan(&b, 3, 43, &[]);
    let robot = b.robot("a.sock", "a.csv", &["--speed", "0"]);
    let mut cmd = b.capture(&plan, "ds", "a.sock", &cams.lower(), &[]);
    let knobs = [
        ("V6CAM_SHORT", "2"),
        ("V6CAM_ERROR", "3"),
        ("V6CAM_STALE", "1"),
    ];
    let out = cams.preload(&mut cmd, &knobs).output().unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    finish(robot);
    assert_eq!(check_pictures(&b.path("ds"), 170.0, 0.0), 3);
}

/// The camera stalls at the second capture (its third stream, the first being the check
/// before anything moves): the frame wait (0.1 s) runs out, the stream is restarted once,
/// then the run ends at rest with the stiffness ramped down — within 2 s of the stance
/// settling (when the picture is asked for), counted in the robot's cycles (the stance is
/// the rest posture, so that the way back takes no time and what is counted is the
/// camera's part and the ramp-down) — the
/// process exits non-zero naming the camera, and the capture before it is a valid dataset.
#[test]
fn a_stalled_camera_ends_the_run_at_rest_with_the_stiffness_down() {
    let b = Bench::new();
    let cams = Cameras::new(&b);
    let path = b.path("plan.csv");
    let mut rows = plan_file(&b.path("random.csv"), 1, 44);
    rows.push(PlannedCapture {
        camera: CameraId::Lower,
        side: Side::Left,
        joints: rest_posture(),
    });
    std::fs::write(&path, naocalib::plan::render_csv(&rows)).unwrap();
    let robot = b.robot("a.sock", "a.csv", &[]);
    let mut cmd = b.capture(
        &path,
        "ds",
        "a.sock",
        &cams.lower(),
        &["--frame-timeout", "0.1"],
    );
    let out = cams
        .preload(&mut cmd, &[("V6CAM_STALL_STREAM", "3")])
        .output()
        .unwrap();
    assert_clean_failure(
        &out,
        &[
            "lower camera",
            "stalled",
            "no frame within 0.1 s",
            "valid dataset",
        ],
    );
    finish(robot);
    let record = read_record(&b.path("a.csv")).unwrap();
    check_safety(&record, true);
    assert_eq!(check_pictures(&b.path("ds"), 170.0, 0.0), 1);
    // The robot at the second stance (rest) after it left rest for the first.
    let at_rest = |r: &RecordRow| {
        Joint::ALL
            .iter()
            .all(|&j| (r.position[lola::index(j)] - rest_posture().get(j)).abs() < 1e-6)
    };
    assert!(record.iter().any(|r| !at_rest(r)), "the robot moved");
    // The robot stays at rest from its arrival at the stalled stance to the end; the stall
    // begins when the stance has settled (its readings steady over the settling window),
    // when the picture is asked for.
    let arrived = record.len() - record.iter().rev().take_while(|r| at_rest(r)).count();
    let m = MotionOptions::default();
    let window = m.settle_cycles as usize;
    let steady = |end: usize| {
        moved_motors().iter().all(|&(k, _)| {
            let r = record[end - window..end].iter().map(|r| r.reading[k]);
            let (lo, hi) = r.fold((f64::MAX, f64::MIN), |(lo, hi), x| (lo.min(x), hi.max(x)));
            hi - lo <= m.settle_threshold
        })
    };
    let settled = (arrived + window..record.len())
        .find(|&i| steady(i))
        .expect("the stance settled");
    let cycles = record.len() - settled;
    assert!(
        cycles as f64 * CYCLE_S <= 2.0,
        "{cycles} cycles ({:.2} s) from the stalled stance settling to the stiffness off \
         ({} cycles from reaching it)",
        cycles as f64 * CYCLE_S,
        record.len() - arrived
    );
    assert_eq!(
        record.last().unwrap().stiffness[lola::index(Joint::LKneePitch)],
        0.0
    );
}
