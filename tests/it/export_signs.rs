//! The joint offsets' sign, proven through each team's own compensation: for random α and
//! logged angles θ (true = θ + α, naocalib's convention), the value a team file stores,
//! applied as that team's code applies it, gives the true angle from the sensor reading,
//! and a command that makes the motor reach the desired true angle. Every exported joint
//! value, every joint format, fresh and `--update`d (raw and already-corrected angles).
//!
//! The teams' code:
//! - B-Human 2025 Code Release: `Src/Modules/Infrastructure/JointAnglesProvider/
//!   JointAnglesProvider.cpp`, line 15: `jointAngles.angles[joint] -=
//!   theJointCalibration.offsets[joint]`; `Src/Modules/Infrastructure/RobotProvider/
//!   NaoProvider.cpp`, line 471: request `+ theJointCalibration.offsets[joint]`.
//! - HULKs (commit 21e8a3de9): `crates/control/src/sensor_data_receiver.rs`, line 155:
//!   `sensor_data.positions - joint_calibration_offsets`; `crates/control/src/motion/
//!   command_sender.rs`, line 52: `motor_commands.positions + joint_calibration_offsets`.
//! - NomadZ 2023 code release: `Src/Modules/Infrastructure/NaoProvider.cpp`, line 173:
//!   `sensors[j++] - theJointCalibration.joints[i].offset`; line 123: request
//!   `+ theJointCalibration.joints[i].offset`.

use std::path::Path;

use naocalib::dataset::{AngleKind, AngleSource};
use naocalib::export::{self, Calibration, Entry, Format, bhuman, hulks, nomadz};
use naocalib::model::Param;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A converged calibration with random leg and head offsets (deg, up to 2°) estimated.
fn calibration(rng: &mut impl Rng) -> Calibration {
    // The lying offsets themselves (the standing ones are tested in export_posture.rs).
    crate::util::converged_calibration(export::Posture::Lying, |p| Entry {
        param: p,
        value: crate::util::plausible_value(rng, p, 2.0),
        std: Some(0.05),
        fixed: false,
    })
}

/// The stored value (rad) of each joint a team file carries, by naocalib parameter.
fn stored(format: &'static dyn Format, text: &str) -> Vec<(Param, f64)> {
    let path = Path::new("-");
    match format.name() {
        "bhuman-joints" => bhuman::Joints::stored(text, path)
            .unwrap()
            .into_iter()
            .filter_map(|(n, v)| bhuman::joint_param(&n).map(|p| (p, v.to_radians())))
            .collect(),
        "hulks-body" => hulks::Body::stored(text, path).unwrap(),
        "nomadz-joints" => nomadz::Joints::stored(text, path)
            .unwrap()
            .into_iter()
            .filter_map(|(n, e)| bhuman::joint_param(&n).map(|p| (p, e.offset.to_radians())))
            .collect(),
        _ => unreachable!(),
    }
}

/// A fixture of tests/fixtures/teams.
fn fixture(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/teams")
        .join(name)
}

const JOINT_FORMATS: [&'static dyn Format; 3] = [
    &export::bhuman::Joints,
    &export::hulks::Body,
    &export::nomadz::Joints,
];

/// The team's compensation (all three alike, cited above): corrected reading and command.
fn team_reading(sensor: f64, stored: f64) -> f64 {
    sensor - stored
}
fn team_command(request: f64, stored: f64) -> f64 {
    request + stored
}

/// Checks that `stored` values, applied by the team's code on a robot whose true angle is
/// `sensor + alpha`, read the true angle and command it (rad).
fn check_through_team(rng: &mut impl Rng, alpha: f64, stored: f64, what: &str) {
    for _ in 0..20 {
        // A raw sensor reading θ; the true angle is θ + α.
        let theta = rng.random_range(-1.5..1.5);
        let truth = theta + alpha;
        let reading = team_reading(theta, stored);
        assert!(
            (reading - truth).abs() < 1e-12,
            "{what}: team reads {reading}, true angle {truth}"
        );
        // The motor servoes its raw sensor to the command: true angle = command + α.
        let q = rng.random_range(-1.5..1.5);
        let reached = team_command(q, stored) + alpha;
        assert!(
            (reached - q).abs() < 1e-12,
            "{what}: commanded {q}, reached {reached}"
        );
    }
}

#[test]
fn fresh_joint_files_compensate_through_each_teams_code() {
    let mut rng = ChaCha8Rng::seed_from_u64(24);
    for _ in 0..10 {
        let cal = calibration(&mut rng);
        for format in JOINT_FORMATS {
            let values = stored(format, &format.write(&cal));
            // Every offset naocalib estimates is in the file: legs and head.
            let offsets: Vec<Param> = naocalib::model::Joint::ALL
                .iter()
                .map(|j| j.offset())
                .collect();
            for p in &offsets {
                let s = values
                    .iter()
                    .find(|(q, _)| q == p)
                    .unwrap_or_else(|| panic!("{}: {p} missing", format.name()))
                    .1;
                let alpha = cal.value(*p).to_radians();
                check_through_team(&mut rng, alpha, s, &format!("{} {p}", format.name()));
            }
        }
    }
}

#[test]
fn updated_joint_files_compensate_for_raw_and_corrected_angles() {
    let mut rng = ChaCha8Rng::seed_from_u64(25);
    let fixtures: [(&dyn Format, &str); 4] = [
        (&export::bhuman::Joints, "bhuman/jointCalibration.cfg"),
        (&export::bhuman::Joints, "bhuman2024/jointCalibration.cfg"),
        (&export::hulks::Body, "hulks/body.json"),
        (&export::nomadz::Joints, "nomadz/jointCalibration.cfg"),
    ];
    for (format, name) in fixtures {
        let original = std::fs::read_to_string(fixture(name)).unwrap();
        let old = stored(format, &original);
        for kind in [AngleKind::Raw, AngleKind::Corrected] {
            let mut cal = calibration(&mut rng);
            cal.angles = Some(AngleSource {
                kind,
                corrected_by: (kind == AngleKind::Corrected).then(|| name.to_string()),
            });
            let text = format.update(&original, Path::new(name), &cal).unwrap();
            let new = stored(format, &text);
            for (p, s_new) in &new {
                let s_old = old.iter().find(|(q, _)| q == p).map_or(0.0, |(_, s)| *s);
                let estimate = cal.value(*p).to_radians();
                // The robot's true offset: for raw angles the estimate itself; for angles
                // the old file corrected (logged = raw − s_old), true = raw − s_old + est.
                let alpha = match kind {
                    AngleKind::Raw => estimate,
                    AngleKind::Corrected => estimate - s_old,
                };
                let what = format!("{} {name} {kind:?} {p}", format.name());
                // HULKs stores radians written from degrees: equal to rounding.
                let tol = 1e-12;
                let expect = -alpha;
                assert!((s_new - expect).abs() < tol, "{what}: {s_new} != {expect}");
                check_through_team(&mut rng, alpha, -alpha, &what);
            }
        }
    }
}

#[test]
fn a_fresh_joint_file_of_corrected_angles_is_refused() {
    let mut rng = ChaCha8Rng::seed_from_u64(26);
    let mut cal = calibration(&mut rng);
    cal.angles = Some(AngleSource {
        kind: AngleKind::Corrected,
        corrected_by: None,
    });
    let dir = tempfile::tempdir().unwrap();
    for format in JOINT_FORMATS {
        let path = dir.path().join("joints");
        let e = export::export(&cal, format, &path, &export::WriteOptions::default()).unwrap_err();
        assert!(e.to_string().contains("--update"), "{e}");
        assert!(!path.exists());
    }
    // Camera files do not depend on the joint calibration.
    let path = dir.path().join("camera.cfg");
    export::export(
        &cal,
        &export::bhuman::Camera,
        &path,
        &export::WriteOptions::default(),
    )
    .unwrap();
}
