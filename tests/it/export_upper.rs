//! The upper camera's correction in every team format that has one, fresh and `--update`d:
//! the exported keys, rebuilt with that team's own formula (cited below, with file, line
//! and commit), give naocalib's corrected upper-camera rotation — the model's own chain —
//! for random offsets of real sizes and large ones; `--update` changes the upper keys only
//! when the upper camera was calibrated; `import` reads them back.
//!
//! The teams' code:
//! - B-Human 2025 Code Release (BHumanCodeRelease d89d603f): `Src/Representations/
//!   Perception/ImagePreprocessing/CameraMatrix.cpp` lines 301–304 and 311–312,
//!   `RobotCameraMatrix::computeRobotCameraMatrix`: for `CameraInfo::upper`,
//!   `rotateY(tiltNeckToUpperCamera + cameraRotationCorrections[upper].y())`, then
//!   `rotateX(….x())`, `rotateZ(….z())`; `Config/Robots/Default/robotDimensions.cfg` line 44:
//!   `tiltNeckToUpperCamera = 1.2deg`. Up to 2018 (CodeRelease 2018, e4d7a489): lines
//!   302–304, `upperCameraRotationCorrection` (`CameraCalibration.h` line 17).
//! - NomadZ 2023 code release (2a597da): `Src/Representations/Perception/CameraMatrix.cpp`
//!   lines 582–586: `rotateY(headTiltToUpperCameraTilt + upperCameraTiltCorrection)`,
//!   `rotateX(upperCameraRollCorrection)`, `rotateZ(upperCameraPanCorrection)`, radians;
//!   `headTiltToUpperCameraTilt = 0.020943951; // 1.2 degree` (`Config/Robots/Default/
//!   robotDimensions.cfg`).
//! - NaoTH (79e1e750b): `NaoTHSoccer/Source/Motion/Motion.cpp` lines 473–482 build the top
//!   camera matrix with `CameraGeometry::calculateCameraMatrixFromChestPose`
//!   (`NaoTHSoccer/Source/Tools/CameraGeometry.cpp` lines 324–334: `rotateZ(headYaw +
//!   head_rot.z)`, `rotateY(headPitch + head_rot.y)`, `rotateX(head_rot.x)`, then
//!   `rotateZ(cam_rot.z)`, `rotateY(cam_rot.y + rotationY)`, `rotateX(cam_rot.x)`) with the
//!   top camera's `rotationY` of 1.2° (`Framework/Commons/Source/Tools/NaoInfo.h` line 39)
//!   and `cam_rot[Top]` = `cam_rot.top.x/y/z` (`NaoTHSoccer/Source/Representations/
//!   Modeling/CameraMatrixOffset.h` lines 37–39).
//! - HULKs (21e8a3de9): `crates/control/src/camera_matrix_calculator.rs` lines 67–73:
//!   `head_to_top_camera = head_to_camera(top camera_pitch, …)`, lines 214–219:
//!   `head_to_camera(pitch) = Rx(−pitch) · Ry(−π/2) · Rx(π/2) · T(−p)`, lines 104–108:
//!   `correction_in_camera_top = Rotation3::from_euler_angles(x, y, z)`, lines 115–116:
//!   `to_corrected(correction_in_robot, correction_in_camera_top)`
//!   (`crates/projection/src/camera_matrix.rs` line 91: correction · head_to_camera);
//!   `etc/parameters/default.json` line 90: the top `camera_pitch` is −1.2 (deg).
//! - rUNSWift 2025 release (ccdd7f7): `robot_ws/src/motion/motion_port/include/perception/
//!   kinematics/Kinematics.cpp` line 54 `camera_top_angle = DEG2RAD(1.2)`, line 63 `a3Top =
//!   camera_top_angle − π`, lines 378–388 the nine `camera{Pitch,Yaw,Roll}TopWhenLooking
//!   {Left,Straight,Right}` (Yaw → coffsetX, Pitch → coffsetY, Roll → coffsetZ, degrees),
//!   lines 401–427 their linear interpolation in the head yaw (±70°), lines 448–451:
//!   `[8] = DH(0, 0, d2, HeadYaw)`, `[9] = DH(0, −π/2, 0, a3Top + HeadPitch)`, `[10] = DH(0,
//!   −π/2, l10Top, π/2 + coffsetX)`, `[11] = DH(0, −π/2 + coffsetY, d11Top, coffsetZ)`;
//!   `robot_ws/src/motion/motion_port/launch/motion_launch.py` lines 117–130 read them
//!   from the head's config, `[kinematics]`.

use std::f64::consts::{FRAC_PI_2, PI};
use std::path::{Path, PathBuf};

use naocalib::export::{self, Calibration, Entry, Format, Unchanged, Updated};
use naocalib::model::{CameraId, Joint, JointAngles, Param, RobotGeometry};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

type M3 = [[f64; 3]; 3];

fn mul(a: &M3, b: &M3) -> M3 {
    std::array::from_fn(|i| std::array::from_fn(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
}

fn transpose(a: &M3) -> M3 {
    std::array::from_fn(|i| std::array::from_fn(|j| a[j][i]))
}

fn rx(t: f64) -> M3 {
    let (s, c) = t.sin_cos();
    [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]]
}

fn ry(t: f64) -> M3 {
    let (s, c) = t.sin_cos();
    [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]
}

fn rz(t: f64) -> M3 {
    let (s, c) = t.sin_cos();
    [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
}

fn product(ms: &[M3]) -> M3 {
    ms.iter().fold(rx(0.0), |m, r| mul(&m, r))
}

fn assert_close(a: &M3, b: &M3, what: &str) {
    for i in 0..3 {
        for j in 0..3 {
            assert!(
                (a[i][j] - b[i][j]).abs() < 1e-9,
                "{what}: {a:?} != {b:?} at ({i},{j})"
            );
        }
    }
}

/// An "optical" camera frame (z forward, x right, y down) in naocalib's camera frame.
const OPTICAL: M3 = [[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]];

/// The upper camera's tilt the teams hard-code (deg).
const UPPER_TILT_DEG: f64 = 1.2;

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/teams")
        .join(name)
}

/// A calibration of both cameras: the upper camera's pitch correction down to −10° as on
/// SPQR's robots (or up to 25° for the exactness), the lower camera's −2° to −8°, head
/// offsets of a few degrees, legs up to 2°; all estimated and determined.
fn calibration(rng: &mut impl Rng, large: bool) -> Calibration {
    crate::util::converged_calibration(export::Posture::Lying, |p| {
        let value = match p {
            Param::UpperCamYaw | Param::UpperCamPitch | Param::UpperCamRoll if large => {
                rng.random_range(-25.0..25.0)
            }
            Param::UpperCamPitch => rng.random_range(-10.2..-2.2),
            Param::UpperCamYaw | Param::UpperCamRoll => rng.random_range(-2.7..2.7),
            Param::CamPitch => rng.random_range(-8.0..-2.0),
            Param::CamYaw | Param::CamRoll => rng.random_range(-2.0..2.0),
            Param::HeadYaw | Param::HeadPitch => rng.random_range(-5.0..5.0),
            _ => crate::util::plausible_value(rng, p, 2.0),
        };
        Entry {
            param: p,
            value,
            std: Some(0.05),
            fixed: false,
        }
    })
}

/// naocalib's corrected upper camera → head-yaw-frame rotation (naocalib's camera frame):
/// the model's upper camera chain for head angles `yaw`, `pitch` (rad), with the
/// calibration's upper-camera offsets and, when `head`, its head offsets.
fn naocalib_upper(cal: &Calibration, yaw: f64, pitch: f64, head: bool) -> M3 {
    let mut params = vec![0.0; Param::ALL.len()];
    let mut which = vec![
        Param::UpperCamYaw,
        Param::UpperCamPitch,
        Param::UpperCamRoll,
    ];
    if head {
        which.extend([Param::HeadYaw, Param::HeadPitch]);
    }
    for p in which {
        params[p.index()] = cal.value(p).to_radians();
    }
    let mut joints = JointAngles::default();
    joints.set(Joint::HeadYaw, yaw);
    joints.set(Joint::HeadPitch, pitch);
    let geometry = RobotGeometry::default();
    geometry
        .camera_chain_of(CameraId::Upper, &joints)
        .eval(&params)
        .rotation
}

/// The upper camera's rotation as the team's code builds it from the keys in `text`
/// (format `format`), for head angles `yaw`, `pitch` (rad): the team's head chain (NaoTH's
/// with its `head_rot` keys) and its camera chain, in naocalib's camera frame. Keys are
/// read from the text (for B-Human with its config reader).
fn team_upper(format: &'static dyn Format, text: &str, yaw: f64, pitch: f64) -> M3 {
    let tilt = UPPER_TILT_DEG.to_radians();
    let head = mul(&rz(yaw), &ry(pitch));
    match format.name() {
        "bhuman-camera" | "bhuman-camera-2016" => {
            let [x, y, z] = export::bhuman::Camera::stored(text, Path::new("-"), CameraId::Upper)
                .unwrap()
                .expect("the upper camera's correction")
                .map(f64::to_radians);
            product(&[head, ry(tilt + y), rx(x), rz(z)])
        }
        "nomadz-camera" => {
            let key = |name: &str| cfg_number(text, name);
            product(&[
                head,
                ry(tilt + key("upperCameraTiltCorrection")),
                rx(key("upperCameraRollCorrection")),
                rz(key("upperCameraPanCorrection")),
            ])
        }
        "naoth-camera" => {
            let key = |name: &str| ini_number(text, name).unwrap_or(0.0);
            product(&[
                rz(yaw + key("head_rot.z")),
                ry(pitch + key("head_rot.y")),
                rx(key("head_rot.x")),
                rz(key("cam_rot.top.z")),
                ry(key("cam_rot.top.y") + tilt),
                rx(key("cam_rot.top.x")),
            ])
        }
        "hulks-head" => {
            let json: serde_json::Value = serde_json::from_str(text).unwrap();
            let c: Vec<f64> =
                json["camera_matrix_parameters"]["calibration"]["correction_in_camera_top"]
                    .as_array()
                    .expect("correction_in_camera_top")
                    .iter()
                    .map(|v| v.as_f64().unwrap())
                    .collect();
            // Top camera_pitch −1.2°: head_to_camera(−1.2°) maps head → optical camera.
            let camera_pitch = -tilt;
            let uncorrected = product(&[rx(-camera_pitch), ry(-FRAC_PI_2), rx(FRAC_PI_2)]);
            let correction = product(&[rz(c[2]), ry(c[1]), rx(c[0])]);
            let head_to_camera = mul(&correction, &uncorrected);
            // Optical camera → head, then into naocalib's camera frame.
            product(&[head, transpose(&head_to_camera), transpose(&OPTICAL)])
        }
        "runswift-camera" => {
            let key = |name: &str| ini_number(text, name).unwrap().to_radians();
            // Kinematics.cpp 401–427: interpolation towards left (yaw > 0) or right.
            let limit = 70f64.to_radians();
            let (side, t) = if yaw >= 0.0 {
                ("Left", (yaw / limit).min(1.0))
            } else {
                ("Right", (-yaw / limit).min(1.0))
            };
            let mix = |axis: &str| {
                key(&format!("camera{axis}TopWhenLookingStraight")) * (1.0 - t)
                    + key(&format!("camera{axis}TopWhenLooking{side}")) * t
            };
            let (cx, cy, cz) = (mix("Yaw"), mix("Pitch"), mix("Roll"));
            let dh = |alpha: f64, theta: f64| mul(&rx(alpha), &rz(theta));
            let chain = product(&[
                rz(yaw),
                dh(-FRAC_PI_2, tilt - PI + pitch),
                dh(-FRAC_PI_2, FRAC_PI_2 + cx),
                dh(-FRAC_PI_2 + cy, cz),
            ]);
            mul(&chain, &transpose(&OPTICAL))
        }
        other => panic!("{other} has no upper camera"),
    }
}

/// `name = number;` of a config text.
fn cfg_number(text: &str, name: &str) -> f64 {
    text.lines()
        .find(|l| l.trim_start().starts_with(&format!("{name} =")))
        .unwrap_or_else(|| panic!("no {name} in {text}"))
        .split('=')
        .nth(1)
        .unwrap()
        .trim()
        .trim_end_matches(';')
        .parse()
        .unwrap()
}

/// `name=number` of an INI text.
fn ini_number(text: &str, name: &str) -> Option<f64> {
    text.lines()
        .find_map(|l| l.strip_prefix(&format!("{name}=")))
        .map(|v| v.trim().parse().unwrap())
}

/// Every format with an upper camera, with its fixture (a robot's file).
const UPPER_FORMATS: [(&'static dyn Format, &str); 6] = [
    (&export::bhuman::Camera, "bhuman/cameraCalibration.cfg"),
    (
        &export::bhuman::Camera2016,
        "bhuman2016/cameraCalibration.cfg",
    ),
    (&export::hulks::Head, "hulks/head.json"),
    (&export::naoth::Camera, "naoth/CameraMatrixOffset.cfg"),
    (&export::nomadz::Camera, "nomadz/cameraCalibration.cfg"),
    (&export::runswift::Camera, "runswift/nao.cfg"),
];

/// Whether the team's chain carries the head offsets (NaoTH's `head_rot` in the camera
/// file); the others' head offsets are in their joint calibration, applied to the joint
/// angles before the camera matrix.
fn with_head(format: &'static dyn Format) -> bool {
    format.name() == "naoth-camera"
}

#[test]
fn every_upper_camera_key_fresh_and_updated_is_naocalibs_rotation_through_the_teams_code() {
    let mut rng = ChaCha8Rng::seed_from_u64(320);
    let dir = tempfile::tempdir().unwrap();
    let mut checked = 0;
    for k in 0..30 {
        let cal = calibration(&mut rng, k % 3 == 2);
        for (format, name) in UPPER_FORMATS {
            let fresh = format.write(&cal);
            let path = dir.path().join(format!("{k}-{}", name.replace('/', "_")));
            std::fs::copy(fixture(name), &path).unwrap();
            crate::util::updated(&cal, format, &path);
            let updated = std::fs::read_to_string(&path).unwrap();
            for (what, text) in [("fresh", &fresh), ("updated", &updated)] {
                let yaw = rng.random_range(-2.0..2.0);
                let pitch = rng.random_range(-0.6..0.5);
                // NaoTH's fresh file has head_rot.x = 0 and the head offsets; its updated
                // file keeps the robot's head roll, which the update folds in.
                let ours = naocalib_upper(&cal, yaw, pitch, with_head(format));
                let team = team_upper(format, text, yaw, pitch);
                assert_close(&team, &ours, &format!("{} {what} #{k}", format.name()));
                checked += 1;
            }
            // Import reads the upper camera back.
            let (_, values) = export::import(&path, Some(format)).unwrap();
            for p in [
                Param::UpperCamYaw,
                Param::UpperCamPitch,
                Param::UpperCamRoll,
            ] {
                let v = values.iter().find(|(q, _)| *q == p).unwrap().1;
                assert!(
                    (v - cal.value(p)).abs() < 1e-9,
                    "{} #{k}: {p} {v} vs {}",
                    format.name(),
                    cal.value(p)
                );
            }
        }
    }
    assert_eq!(checked, 30 * 6 * 2);
}

/// A calibration of the lower camera only: the upper camera's offsets held (a dataset
/// without upper captures) or not determined.
fn lower_only(rng: &mut impl Rng, held: bool) -> Calibration {
    let mut cal = calibration(rng, false);
    for e in &mut cal.parameters {
        if e.param.name().starts_with("UpperCam") {
            if held {
                (e.value, e.fixed, e.std) = (0.0, true, Some(0.0));
            } else {
                e.std = None;
            }
        }
    }
    cal
}

#[test]
fn update_changes_the_upper_keys_only_when_the_upper_camera_was_calibrated() {
    let mut rng = ChaCha8Rng::seed_from_u64(321);
    let dir = tempfile::tempdir().unwrap();
    for held in [true, false] {
        let cal = lower_only(&mut rng, held);
        for (format, name) in UPPER_FORMATS {
            let path = dir
                .path()
                .join(format!("{held}-{}", name.replace('/', "_")));
            std::fs::copy(fixture(name), &path).unwrap();
            let before = export::import(&path, Some(format)).unwrap().1;
            crate::util::updated(&cal, format, &path);
            let after = export::import(&path, Some(format)).unwrap().1;
            for p in [
                Param::UpperCamYaw,
                Param::UpperCamPitch,
                Param::UpperCamRoll,
            ] {
                let value = |v: &[(Param, f64)]| v.iter().find(|(q, _)| *q == p).unwrap().1;
                assert!(
                    (value(&before) - value(&after)).abs() < 1e-12,
                    "{} held={held}: {p} changed",
                    format.name()
                );
            }
            // The lower camera was calibrated: its keys are the calibration's.
            let lower = after.iter().find(|(q, _)| *q == Param::CamPitch).unwrap().1;
            let expected = if with_head(format) {
                // NaoTH folds the robot's head roll into the import: compare the rotation.
                None
            } else {
                Some(cal.value(Param::CamPitch))
            };
            if let Some(e) = expected {
                assert!((lower - e).abs() < 1e-9, "{}: CamPitch", format.name());
            }
            // Fresh, the upper camera is zero (B-Human, NomadZ) or absent.
            let fresh = dir.path().join(format!("fresh-{held}-{}", format.name()));
            std::fs::write(&fresh, format.write(&cal)).unwrap();
            for (p, v) in export::import(&fresh, Some(format)).unwrap().1 {
                if p.name().starts_with("UpperCam") {
                    assert_eq!(v, 0.0, "{} fresh: {p}", format.name());
                }
            }
        }
    }
    // An upper camera only partly determined is refused by the formats that mix its
    // offsets, and nothing is written.
    let mut cal = calibration(&mut rng, false);
    for e in &mut cal.parameters {
        if e.param == Param::UpperCamRoll {
            e.std = None;
        }
    }
    for (format, name) in [
        (&export::hulks::Head as &dyn Format, "hulks/head.json"),
        (&export::naoth::Camera, "naoth/CameraMatrixOffset.cfg"),
        (&export::runswift::Camera, "runswift/nao.cfg"),
    ] {
        let path = dir
            .path()
            .join(format!("partly-{}", name.replace('/', "_")));
        std::fs::copy(fixture(name), &path).unwrap();
        let e = export::update(&cal, Some(format), &path, &[])
            .unwrap_err()
            .to_string();
        assert!(e.contains("upper camera's offsets are only partly"), "{e}");
        assert_eq!(
            std::fs::read(&path).unwrap(),
            std::fs::read(fixture(name)).unwrap()
        );
    }
}

#[test]
fn an_update_with_the_upper_camera_alone_leaves_the_lower_keys() {
    let mut rng = ChaCha8Rng::seed_from_u64(322);
    let mut cal = calibration(&mut rng, false);
    for e in &mut cal.parameters {
        if !e.param.name().starts_with("UpperCam") {
            (e.fixed, e.std) = (true, Some(0.0));
        }
    }
    let dir = tempfile::tempdir().unwrap();
    for (format, name) in UPPER_FORMATS {
        let path = dir.path().join(name.replace('/', "_"));
        std::fs::copy(fixture(name), &path).unwrap();
        let before = export::import(&path, Some(format)).unwrap().1;
        let (_, outcome) = export::update(&cal, Some(format), &path, &[]).unwrap();
        assert!(matches!(outcome, Updated::Written { .. }), "{outcome:?}");
        let after = export::import(&path, Some(format)).unwrap().1;
        for (p, v) in &before {
            if p.name().starts_with("UpperCam") {
                continue;
            }
            let w = after.iter().find(|(q, _)| q == p).unwrap().1;
            assert!((v - w).abs() < 1e-12, "{}: {p} kept", format.name());
        }
        let (_, again) = export::update(&cal, Some(format), &path, &[]).unwrap();
        assert_eq!(again, Updated::Unchanged(Unchanged::AlreadyHolds));
    }
}

#[test]
fn solve_start_from_a_robots_imported_upper_camera_starts_there() {
    // A simulated robot with upper-camera captures (team-sized offsets, hidden), and its
    // B-Human camera file holding an upper-camera correction of real size.
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("robot");
    let out = crate::util::naocalib()
        .args([
            "simulate",
            "--stances",
            "6",
            "--upper-stances",
            "3",
            "--heads",
            "2",
            "--team-offsets",
            "--seed",
            "323",
        ])
        .arg(&data)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", crate::util::stderr(&out));
    let camera = dir.path().join("cameraCalibration.cfg");
    std::fs::write(
        &camera,
        "cameraRotationCorrections = {\n  upper = {x = 1.4deg; y = -8.5deg; z = 0.3deg;};\n  \
         lower = {x = 0.3deg; y = -5.9deg; z = 0deg;};\n};\nbodyRotationCorrection = {x = 0deg; y = 0deg;};\n",
    )
    .unwrap();
    let robot = dir.path().join("robot.toml");
    let out = crate::util::naocalib()
        .arg("import")
        .arg(&camera)
        .arg("--out")
        .arg(&robot)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", crate::util::stderr(&out));
    let imported = export::read_calibration(&robot).unwrap();
    assert_eq!(imported.value(Param::UpperCamPitch), -8.5);
    assert_eq!(imported.value(Param::UpperCamRoll), 1.4);
    assert_eq!(imported.value(Param::UpperCamYaw), 0.3);
    let out = crate::util::naocalib()
        .arg("solve")
        .arg(&data)
        .arg("--start-from")
        .arg(&robot)
        // The robot's head offsets are not in its camera file: estimated here.
        .args(["--free", "head", "--json"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", crate::util::stderr(&out));
    let result: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    // The robot's upper camera is where the change is measured from; the estimate is the
    // data's (the truth, hidden from the solve).
    let truth = naocalib::dataset::Dataset::load(&data)
        .unwrap()
        .truth
        .unwrap();
    for (p, previous) in [
        (Param::UpperCamYaw, 0.3),
        (Param::UpperCamPitch, -8.5),
        (Param::UpperCamRoll, 1.4),
    ] {
        let change = &result["changes"][p.name()];
        assert_eq!(change["previous"], previous, "{p}: {change}");
        let now = result["parameters"][p.name()]["value"].as_f64().unwrap();
        let true_value = p.unit().to_report(truth.values[p.index()]);
        assert!(
            (now - true_value).abs() < 0.05,
            "{p}: {now} vs {true_value}"
        );
    }
}

#[test]
fn a_runswift_key_missing_beside_the_others_is_runswifts_default_zero() {
    // One of rUNSWift's own 2025 head configs misspells one top key
    // (`cameraRollWhenLookingStraight`): rUNSWift then runs that entry at its default, 0.
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(fixture("runswift/nao.cfg")).unwrap();
    let path = dir.path().join("head.cfg");
    std::fs::write(
        &path,
        text.replace(
            "cameraRollTopWhenLookingStraight=-0.4",
            "cameraRollWhenLookingStraight=-0.4",
        ),
    )
    .unwrap();
    let with_zero = dir.path().join("zero.cfg");
    std::fs::write(
        &with_zero,
        text.replace(
            "cameraRollTopWhenLookingStraight=-0.4",
            "cameraRollTopWhenLookingStraight=0",
        ),
    )
    .unwrap();
    let (_, read) = export::import(&path, None).unwrap();
    let (_, zero) = export::import(&with_zero, None).unwrap();
    assert_eq!(read, zero);
    assert!(read.iter().any(|(p, _)| *p == Param::UpperCamRoll));
}
