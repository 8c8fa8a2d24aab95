//! The teams' formats: each exported camera correction, rebuilt with that team's own
//! formula (cited below), gives naocalib's corrected camera rotation for random offsets;
//! every format round-trips (write, read back, same values).

use std::f64::consts::{FRAC_PI_2, PI};
use std::path::Path;

use naocalib::export::{self, Calibration, Entry, Format, bhuman, hulks, naoth, nomadz, runswift};
use naocalib::model::{CameraId, JointAngles, Param, RobotGeometry};
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

fn assert_close(a: &M3, b: &M3, what: &str) {
    for i in 0..3 {
        for j in 0..3 {
            assert!(
                (a[i][j] - b[i][j]).abs() < 1e-12,
                "{what}: {a:?} != {b:?} at ({i},{j})"
            );
        }
    }
}

/// An "optical" camera frame (z forward, x right, y down) in naocalib's camera frame (x
/// forward, y left, z up): its axes as columns.
const OPTICAL: M3 = [[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]];

const TILT_DEG: f64 = 39.7;

/// A calibration with random values for every parameter (camera offsets up to
/// `camera_deg`), all determined and converged.
fn random_calibration(rng: &mut impl Rng, camera_deg: f64) -> Calibration {
    // The lying offsets themselves (the standing ones are tested in export_posture.rs).
    crate::util::converged_calibration(export::Posture::Lying, |p| {
        // The upper camera's intrinsics held, drawing nothing (the same draws as before
        // they were parameters): the intrinsics files are tested in export_intrinsics.rs.
        if p.is_upper_projection() {
            return Entry {
                param: p,
                value: 0.0,
                std: Some(0.0),
                fixed: true,
            };
        }
        let value = match p {
            Param::CamYaw | Param::CamPitch | Param::CamRoll => {
                rng.random_range(-camera_deg..camera_deg)
            }
            // Within the physical bounds (naocalib::model::bounds).
            _ if naocalib::model::bounds::bound(p).min == 0.0 => {
                crate::util::plausible_value(rng, p, 1.5)
            }
            _ => crate::util::plausible_value(rng, p, 3.0),
        };
        Entry {
            param: p,
            value,
            std: Some(rng.random_range(0.01..0.2)),
            fixed: false,
        }
    })
}

/// naocalib's own corrected camera rotation (camera → head, naocalib's camera frame) for
/// the offsets of `cal` and head pitch `head_pitch`: the model's camera chain itself.
fn naocalib_camera(cal: &Calibration, head_pitch: f64) -> M3 {
    let mut params = vec![0.0; Param::ALL.len()];
    for p in [Param::CamYaw, Param::CamPitch, Param::CamRoll] {
        params[p.index()] = cal.value(p).to_radians();
    }
    let mut joints = JointAngles::default();
    joints.set(naocalib::model::Joint::HeadPitch, head_pitch);
    let geometry = RobotGeometry::default();
    assert!((geometry.lower_camera_tilt.to_degrees() - TILT_DEG).abs() < 1e-12);
    geometry.camera_chain(&joints).eval(&params).rotation
}

fn calibrations() -> Vec<Calibration> {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    // Realistic offsets, and large ones: the conversions are exact, not small-angle.
    (0..40)
        .map(|k| random_calibration(&mut rng, if k % 2 == 0 { 4.0 } else { 25.0 }))
        .collect()
}

#[test]
fn bhuman_camera_convention() {
    // B-Human (BHumanCodeRelease d89d603f), Src/Representations/Perception/
    // ImagePreprocessing/CameraMatrix.cpp lines 309–312, RobotCameraMatrix::
    // computeRobotCameraMatrix: rotateY(tiltNeckToLowerCamera + cameraRotationCorrections
    // [lower].y()); rotateX(….x()); rotateZ(….z()) (the array read from cameraCalibration.cfg,
    // Src/Representations/Configuration/CameraCalibration.h line 17); camera frame x
    // forward, y left, z up (naocalib's).
    for cal in calibrations() {
        let text = bhuman::Camera.write(&cal);
        let [x, y, z] = bhuman::Camera::stored(&text, Path::new("-"), CameraId::Lower)
            .unwrap()
            .unwrap()
            .map(f64::to_radians);
        let team = mul(&mul(&ry(TILT_DEG.to_radians() + y), &rx(x)), &rz(z));
        assert_close(&team, &naocalib_camera(&cal, 0.0), "B-Human");
    }
}

#[test]
fn nomadz_camera_convention() {
    // NomadZ, Src/Representations/Perception/CameraMatrix.cpp, lines 589–591: rotateY(
    // headTiltToCameraTilt + cameraTiltCorrection); rotateX(cameraRollCorrection);
    // rotateZ(cameraPanCorrection), radians (Src/Representations/Configuration/
    // CameraCalibration.h); camera frame x forward, y left, z up. The keys are read from the
    // text here, not through naocalib's importer.
    for cal in calibrations() {
        let text = nomadz::Camera.write(&cal);
        let key = |name: &str| -> f64 {
            let line = text
                .lines()
                .find(|l| l.trim_start().starts_with(&format!("{name} =")))
                .unwrap_or_else(|| panic!("no {name} in {text}"));
            line.split('=')
                .nth(1)
                .unwrap()
                .trim()
                .trim_end_matches(';')
                .parse()
                .unwrap()
        };
        let (tilt, roll, pan) = (
            key("cameraTiltCorrection"),
            key("cameraRollCorrection"),
            key("cameraPanCorrection"),
        );
        let team = mul(&mul(&ry(TILT_DEG.to_radians() + tilt), &rx(roll)), &rz(pan));
        assert_close(&team, &naocalib_camera(&cal, 0.0), "NomadZ");
    }
}

#[test]
fn naoth_camera_convention() {
    // NaoTH, NaoTHSoccer/Source/Tools/CameraGeometry.cpp, CameraGeometry::
    // calculateCameraMatrix: chest.translate(offset); chest.rotateZ(cam_rot.z)
    // .rotateY(cam_rot.y + rotationOffsetY).rotateX(cam_rot.x); camera frame x forward,
    // y left, z up (CameraGeometry::relativePointToImage divides by x).
    for cal in calibrations() {
        let text = naoth::Camera.write(&cal);
        assert!(text.contains("[CameraMatrixOffset]"), "{text}");
        let [x, y, z] = naoth::Camera::stored(&text, Path::new("-"), CameraId::Lower)
            .unwrap()
            .unwrap();
        let team = mul(&mul(&rz(z), &ry(y + TILT_DEG.to_radians())), &rx(x));
        assert_close(&team, &naocalib_camera(&cal, 0.0), "NaoTH");
    }
}

#[test]
fn hulks_camera_convention() {
    // HULKs (commit 21e8a3de9), crates/control/src/camera_matrix_calculator.rs lines
    // 214–219: head_to_camera(pitch) = Rx(−pitch) · Ry(−π/2) · Rx(π/2) · T(−p), and lines
    // 109–113: the bottom correction is Rotation3::from_euler_angles(x, y, z); mapping head
    // coordinates into the camera
    // frame, where a camera pitched *down* has a negative pitch (crates/projection/tests/
    // projection.rs, pixel_to_ground_with_z_pitch_45_degree_down passes −π/4); and
    // crates/projection/src/camera_matrix.rs line 91, CameraMatrix::to_corrected:
    // corrected head_to_camera = correction_in_camera * head_to_camera, the correction
    // being nalgebra's Rotation3::from_euler_angles(x, y, z) = Rz(z)·Ry(y)·Rx(x) [rad].
    let pitch = -TILT_DEG.to_radians();
    let uncorrected = mul(&mul(&rx(-pitch), &ry(-FRAC_PI_2)), &rx(FRAC_PI_2));
    // The frames: HULKs' camera is the optical frame, tilted like naocalib's.
    assert_close(
        &transpose(&uncorrected),
        &mul(&ry(TILT_DEG.to_radians()), &OPTICAL),
        "HULKs camera frame",
    );
    for cal in calibrations() {
        let text = hulks::Head.write(&cal);
        let [x, y, z] = hulks::Head::stored(&text, Path::new("-"), CameraId::Lower)
            .unwrap()
            .unwrap();
        let correction = mul(&mul(&rz(z), &ry(y)), &rx(x));
        let head_to_camera = mul(&correction, &uncorrected);
        assert_close(
            &transpose(&head_to_camera),
            &mul(&naocalib_camera(&cal, 0.0), &OPTICAL),
            "HULKs",
        );
    }
}

#[test]
fn runswift_camera_convention() {
    // rUNSWift (2025 release ccdd7f7), robot_ws/src/motion/motion_port/include/perception/
    // kinematics/Kinematics.cpp lines 477–479 (the offsets in degrees) and 490–492,
    // Kinematics::updateDHChain:
    // transformLBot[9] = DH(0, −π/2, 0, a3Bot + HeadPitch) with a3Bot = camera_bottom_angle
    // − π; [10] = DH(0, −π/2, l10Bot, π/2 + DEG2RAD(cameraYawBottom)); [11] = DH(0, −π/2 +
    // DEG2RAD(cameraPitchBottom), d11Bot, DEG2RAD(cameraRollBottom)); createDHMatrix(a, α,
    // d, θ) rotates by Rx(α)·Rz(θ) (include/utils/matrix_helpers.tcc line 53).
    let dh = |alpha: f64, theta: f64| mul(&rx(alpha), &rz(theta));
    let tilt = TILT_DEG.to_radians();
    let mut rng = ChaCha8Rng::seed_from_u64(8);
    for cal in calibrations() {
        let text = runswift::Camera.write(&cal);
        assert!(text.contains("[kinematics]") && text.contains("cameraPitchBottom="));
        let [yaw, pitch, roll] = runswift::Camera::stored(&text, Path::new("-"), CameraId::Lower)
            .unwrap()
            .unwrap()
            .map(f64::to_radians);
        // The head pitch turns both chains alike.
        let head_pitch = rng.random_range(-0.6..0.5);
        let team = mul(
            &mul(
                &dh(-FRAC_PI_2, tilt - PI + head_pitch),
                &dh(-FRAC_PI_2, FRAC_PI_2 + yaw),
            ),
            &dh(-FRAC_PI_2 + pitch, roll),
        );
        assert_close(
            &team,
            &mul(&naocalib_camera(&cal, head_pitch), &OPTICAL),
            "rUNSWift",
        );
    }
}

#[test]
fn joint_formats_round_trip() {
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    let cal = random_calibration(&mut rng, 4.0);
    let legs: Vec<Param> = naocalib::model::Joint::ALL
        .iter()
        .map(|j| j.offset())
        .collect();

    // B-Human: degrees, exactly, stored = -alpha (the sign is proven in export_signs.rs).
    let text = bhuman::Joints.write(&cal);
    let back = bhuman::Joints::stored(&text, Path::new("-")).unwrap();
    assert_eq!(back.len(), 27, "the 2025 layout, waistYaw included");
    for (name, param) in bhuman::BHUMAN_JOINTS {
        let value = back.iter().find(|(n, _)| n == name).unwrap().1;
        assert_eq!(value, param.map_or(0.0, |p| -cal.value(p)), "{name}");
    }

    // HULKs: radians, every calibrated joint.
    let text = hulks::Body.write(&cal);
    let back = hulks::Body::stored(&text, Path::new("-")).unwrap();
    assert_eq!(back.len(), legs.len());
    for (param, value) in back {
        assert_eq!(value, -cal.value(param).to_radians(), "{param}");
    }
    let head = hulks::Head::stored(&hulks::Head.write(&cal), Path::new("-"), CameraId::Lower)
        .unwrap()
        .unwrap();
    assert_eq!(head, export::camera::hulks(&cal, CameraId::Lower));

    // NomadZ: offset and jointPlay in degrees; jointPlay from the play family.
    let text = nomadz::Joints.write(&cal);
    let back = nomadz::Joints::stored(&text, Path::new("-")).unwrap();
    assert_eq!(back.len(), 26);
    for ((name, param), (read_name, entry)) in bhuman::BHUMAN_JOINTS.iter().zip(&back) {
        assert_eq!(name, read_name);
        assert_eq!(entry.offset, param.map_or(0.0, |p| -cal.value(p)), "{name}");
        let play = param.and_then(nomadz::play_param);
        assert_eq!(
            entry.joint_play,
            play.map_or(0.0, |p| cal.value(p)),
            "{name}"
        );
        assert!(entry.min_angle <= entry.max_angle);
    }
    let knee = back.iter().find(|(n, _)| n == "lKneePitch").unwrap().1;
    assert_eq!(knee.joint_play, cal.value(Param::LKneePitchPlay));
    assert_ne!(knee.joint_play, 0.0);

    // Camera formats read back what was written.
    let naoth = naoth::Camera::stored(&naoth::Camera.write(&cal), Path::new("-"), CameraId::Lower)
        .unwrap()
        .unwrap();
    assert_eq!(naoth, export::camera::naoth(&cal, CameraId::Lower));
    let runswift = runswift::Camera::stored(
        &runswift::Camera.write(&cal),
        Path::new("-"),
        CameraId::Lower,
    )
    .unwrap()
    .unwrap();
    assert_eq!(
        runswift,
        export::camera::runswift(&cal, CameraId::Lower).map(f64::to_degrees)
    );
}

#[test]
fn every_format_is_written_by_export_all_and_says_its_units() {
    let mut rng = ChaCha8Rng::seed_from_u64(10);
    let cal = random_calibration(&mut rng, 3.0);
    let dir = tempfile::tempdir().unwrap();
    let files = export::export_all(&cal, dir.path(), &export::WriteOptions::default()).unwrap();
    // Every format but the five of the intrinsics (B-Human's, NomadZ's two, NaoTH's two),
    // which it does not carry.
    let formats: Vec<_> = export::FORMATS.iter().filter(|f| !f.intrinsics()).collect();
    assert_eq!(files.len(), formats.len());
    assert_eq!(formats.len(), export::FORMATS.len() - 5);
    for &&format in &formats {
        let file = format.file();
        assert_eq!(export::named(format.name()), Some(format));
        let text = std::fs::read_to_string(dir.path().join(file)).unwrap();
        assert!(!text.contains("NOT A CALIBRATION"), "{file}");
        if !file.ends_with(".json") {
            assert!(
                text.contains("true angle = logged angle + alpha") && text.contains("store -alpha"),
                "{file} states the rule"
            );
            assert!(text.contains("Units:"), "{file} states its units");
        }
    }
}

/// What NaoTH's `CameraMatrixOffset.cfg` calibrates: the lower camera and the head offsets.
const NAOTH_HEAD_AND_CAMERA: [Param; 5] = [
    Param::CamYaw,
    Param::CamPitch,
    Param::CamRoll,
    Param::HeadYaw,
    Param::HeadPitch,
];

/// NaoTH's whole head → camera rotation, through the head keys as well
/// (NaoTHSoccer/Source/Tools/CameraGeometry.cpp lines 324–334, commit 79e1e750b):
/// `Rz(HeadYaw + head_rot.z) · Ry(HeadPitch + head_rot.y) · Rx(head_rot.x) · Rz(z) ·
/// Ry(y + tilt) · Rx(x)`. A robot's file (the fixture, with a head roll `head_rot.x` of
/// 1.2° as real files have) updated with calibrations that estimated the head offsets
/// gives naocalib's chain, head offsets included; and importing that file gives back the
/// calibration's camera and head offsets. Keys read from the text, not by the importer.
#[test]
fn naoth_head_keys_through_naoths_camera_matrix() {
    let fixture = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/teams/naoth/CameraMatrixOffset.cfg");
    let dir = tempfile::tempdir().unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(91);
    for k in 0..20 {
        // Real sizes and large ones (the conversion is exact), within the ±30° the reader
        // accepts once the head roll is folded in.
        let cal = random_calibration(&mut rng, if k % 2 == 0 { 4.0 } else { 15.0 });
        let path = dir.path().join(format!("CameraMatrixOffset{k}.cfg"));
        std::fs::copy(&fixture, &path).unwrap();
        crate::util::updated(&cal, &export::naoth::Camera, &path);
        let text = std::fs::read_to_string(&path).unwrap();
        let key = |name: &str| -> f64 {
            text.lines()
                .find_map(|l| l.strip_prefix(&format!("{name}=")))
                .unwrap_or_else(|| panic!("no {name} in {text}"))
                .parse()
                .unwrap()
        };
        assert_eq!(key("head_rot.x"), 0.0213, "the head roll is kept");
        for head_pitch in [-0.4, 0.0, 0.3] {
            let team = [
                rz(key("head_rot.z")),
                ry(head_pitch + key("head_rot.y")),
                rx(key("head_rot.x")),
                rz(key("cam_rot.bottom.z")),
                ry(key("cam_rot.bottom.y") + TILT_DEG.to_radians()),
                rx(key("cam_rot.bottom.x")),
            ]
            .iter()
            .fold(rx(0.0), |m, r| mul(&m, r));
            // naocalib's chain with its head offsets (q = θ + α).
            let mut params = vec![0.0; Param::ALL.len()];
            for p in NAOTH_HEAD_AND_CAMERA {
                params[p.index()] = cal.value(p).to_radians();
            }
            let mut joints = JointAngles::default();
            joints.set(naocalib::model::Joint::HeadPitch, head_pitch);
            let ours = RobotGeometry::default()
                .camera_chain(&joints)
                .eval(&params)
                .rotation;
            for i in 0..3 {
                for j in 0..3 {
                    assert!(
                        (team[i][j] - ours[i][j]).abs() < 1e-9,
                        "NaoTH: {team:?} != {ours:?}"
                    );
                }
            }
        }
        let (_, imported) = export::import(&path, Some(&export::naoth::Camera)).unwrap();
        for p in NAOTH_HEAD_AND_CAMERA {
            let v = imported.iter().find(|(q, _)| *q == p).unwrap().1;
            assert!(
                (v - cal.value(p)).abs() < 1e-9,
                "{p}: {v} vs {}",
                cal.value(p)
            );
        }
    }
}
