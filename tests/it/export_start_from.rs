//! `solve --start-from`: on a simulated robot whose head offsets are several degrees (and
//! known from its B-Human `jointCalibration.cfg`), a solve that holds them at the imported
//! values exports a camera correction that, applied by B-Human's camera matrix after the
//! head joints corrected with those offsets, reproduces the true camera pose; a solve with
//! the head at zero does not (it counts the head offsets twice once loaded).

use std::path::Path;

use naocalib::export::{self, Calibration, Format, bhuman};
use naocalib::model::{
    CameraId, FixedSet, Joint, JointAngles, Model, PARAMETER_COUNT, Param, RobotGeometry,
};
use naocalib::sim::{SimOptions, simulate};
use naocalib::solve::{Problem, UncertaintyOptions, backend, calibrate};

type M3 = [[f64; 3]; 3];

fn mul(a: &M3, b: &M3) -> M3 {
    std::array::from_fn(|i| std::array::from_fn(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
}

fn rot(axis: usize, t: f64) -> M3 {
    let (s, c) = t.sin_cos();
    match axis {
        0 => [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]],
        1 => [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]],
        _ => [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]],
    }
}

/// The angle (deg) of the rotation `aᵀ·b`.
fn angle_between(a: &M3, b: &M3) -> f64 {
    let trace: f64 = (0..3)
        .map(|i| (0..3).map(|k| a[k][i] * b[k][i]).sum::<f64>())
        .sum();
    ((trace - 1.0) / 2.0).clamp(-1.0, 1.0).acos().to_degrees()
}

/// B-Human's camera rotation (torso → lower camera) for logged head angles, its
/// `jointCalibration` head offsets `stored` (deg) and its camera correction `[x, y, z]`
/// (deg): corrected head angles = logged − stored (JointAnglesProvider.cpp:15), then
/// `rotateZ(headYaw)·rotateY(headPitch)` (CameraMatrix.cpp:288–289) and
/// `rotateY(tilt + y)·rotateX(x)·rotateZ(z)` (CameraMatrix.cpp:309–312).
fn bhuman_camera(yaw: f64, pitch: f64, stored: [f64; 2], c: [f64; 3]) -> M3 {
    let [x, y, z] = c.map(f64::to_radians);
    let head = mul(
        &rot(2, yaw - stored[0].to_radians()),
        &rot(1, pitch - stored[1].to_radians()),
    );
    let tilt = 39.7f64.to_radians();
    mul(&mul(&mul(&head, &rot(1, tilt + y)), &rot(0, x)), &rot(2, z))
}

#[test]
fn start_from_holds_the_robots_head_offsets_so_the_camera_correction_fits_the_framework() {
    // The robot as it is: head offsets of a few degrees, lower-camera tilt correction −5°.
    let mut truth = [0.0; PARAMETER_COUNT];
    for (p, deg) in [
        (Param::HeadYaw, 2.6f64),
        (Param::HeadPitch, -1.8),
        (Param::CamPitch, -5.1),
        (Param::CamRoll, 1.3),
        (Param::CamYaw, -0.7),
        (Param::LHipPitch, 0.9),
        (Param::RKneePitch, -1.2),
        (Param::LAnkleRoll, 0.5),
    ] {
        truth[p.index()] = deg.to_radians();
    }
    let options = SimOptions {
        seed: 11,
        stances: 8,
        heads: 3,
        truth: Some(truth),
        ..SimOptions::default()
    };
    let dataset = simulate(&Model::default(), &options).unwrap();

    // The robot's jointCalibration.cfg holds −α of the head (and of nothing else here).
    let dir = tempfile::tempdir().unwrap();
    let joints_file = dir.path().join("jointCalibration.cfg");
    let mut text = String::from("offsets = {\n");
    for (name, p) in bhuman::BHUMAN_JOINTS {
        let stored = match p {
            Some(Param::HeadYaw) => -2.6,
            Some(Param::HeadPitch) => 1.8,
            _ => 0.0,
        };
        text.push_str(&format!("  {name} = {stored}deg;\n"));
    }
    text.push_str("};\n");
    std::fs::write(&joints_file, text).unwrap();
    let (imported, _) = export::import_calibration(&[joints_file], None).unwrap();
    assert!(
        (imported.value(Param::HeadYaw) - 2.6).abs() < 1e-12,
        "alpha = -stored"
    );
    let stored = [-2.6, 1.8];

    let lm = backend("lm", false).unwrap();
    let solve = |start: Option<&Calibration>| {
        let mut problem = Problem::from_dataset(&dataset, FixedSet::default()).unwrap();
        if let Some(cal) = start {
            let values: Vec<_> = cal
                .parameters
                .iter()
                .filter(|e| e.is_determined())
                .map(|e| (e.param, e.value))
                .collect();
            problem.start_from(&values, false);
        }
        let solution = calibrate(&problem, lm.as_ref(), &UncertaintyOptions::plain()).unwrap();
        let cal = Calibration::from_solution(&solution, None);
        let text = bhuman::Camera.write(&cal);
        (
            cal,
            bhuman::Camera::stored(&text, Path::new("-"), CameraId::Lower)
                .unwrap()
                .unwrap(),
        )
    };
    let (held, correction) = solve(Some(&imported));
    assert!(
        (held.value(Param::HeadYaw) - 2.6).abs() < 1e-9,
        "held at the robot's value"
    );
    assert!(held.get(Param::HeadYaw).unwrap().fixed);
    let (_, at_zero) = solve(None);

    // Compare with the true camera pose over head postures the robot uses.
    let geometry = RobotGeometry::default();
    let mut worst_held: f64 = 0.0;
    let mut best_zero = f64::INFINITY;
    for (yaw, pitch) in [(0.0, 0.0), (0.5, 0.3), (-0.7, -0.2), (1.0, 0.4)] {
        let mut joints = JointAngles::default();
        joints.set(Joint::HeadYaw, yaw);
        joints.set(Joint::HeadPitch, pitch);
        let true_pose = geometry.camera_chain(&joints).eval(&truth).rotation;
        worst_held = worst_held.max(angle_between(
            &bhuman_camera(yaw, pitch, stored, correction),
            &true_pose,
        ));
        best_zero = best_zero.min(angle_between(
            &bhuman_camera(yaw, pitch, stored, at_zero),
            &true_pose,
        ));
    }
    assert!(
        worst_held < 0.05,
        "held head offsets: {worst_held}° from the truth"
    );
    assert!(best_zero > 1.0, "head at zero double-counts: {best_zero}°");
}
