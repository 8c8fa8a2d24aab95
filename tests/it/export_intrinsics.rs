//! The cameras' intrinsics in the teams' files: B-Human's (2025, SPQR)
//! `cameraIntrinsics.cfg`, fresh and updated, turns into naocalib's focal lengths and
//! centre through B-Human's own formulas; `import` reads it back as the prior of a
//! calibration held at it, and `--start-from` starts a dataset's corrections there; a
//! calibration without intrinsics writes no such file.

use std::collections::BTreeMap;
use std::path::Path;

use naocalib::calibration::{Calibration, Prior};
use naocalib::export::{self, Entry, Format, bhuman};
use naocalib::model::{Camera, CameraId, Model, Param};

/// B-Human's default file (`Config/Robots/Default/cameraIntrinsics.cfg`, Code Release
/// 2025, commit d89d603f), byte for byte.
const BHUMAN_DEFAULT: &str = "cameras = {
  upper = {
    openingAngleWidth = 54.7deg;
    openingAngleHeight = 42.5deg;
    opticalCenter = { x = 0.5; y = 0.5; };
  };
  lower = {
    openingAngleWidth = 54.7deg;
    openingAngleHeight = 42.5deg;
    opticalCenter = { x = 0.5; y = 0.5; };
  };
};
";

/// The a-priori intrinsics of both cameras: the paper's lower camera, a V6-like upper one.
fn priors() -> BTreeMap<CameraId, Prior> {
    BTreeMap::from([
        (CameraId::Lower, Prior::of(&Camera::default())),
        (
            CameraId::Upper,
            Prior {
                width: 640,
                height: 480,
                fx: 598.0,
                fy: 598.0,
                cx: 320.0,
                cy: 240.0,
            },
        ),
    ])
}

/// A converged calibration of both cameras' intrinsics (the corrections in `values`, the
/// parameters not named held at zero), carrying `priors()`.
fn with_intrinsics(values: &[(Param, f64)]) -> Calibration {
    let mut cal = crate::util::converged_calibration(export::Posture::Lying, |p| {
        let value = values.iter().find(|(q, _)| *q == p).map(|(_, v)| *v);
        Entry {
            param: p,
            value: value.unwrap_or(0.0),
            std: Some(if value.is_some() { 0.2 } else { 0.0 }),
            fixed: value.is_none(),
        }
    });
    cal.cameras = priors();
    cal
}

/// B-Human's camera of a `cameraIntrinsics.cfg` at `width × height`, through its formulas:
/// `CameraInfo::updateFocalLength` (`CameraInfo.cpp` lines 14, 18: `f = width / (2·tan(
/// openingAngleWidth / 2))`) and `CameraProvider::setupCamera` (`CameraProvider.cpp` lines
/// 216–217: the optical centre times the image size): `[fx, fy, cx, cy]`.
fn bhuman_camera(text: &str, camera: CameraId, width: f64, height: f64) -> [f64; 4] {
    let mut section = text
        .split(&format!("{} = {{", camera.name()))
        .nth(1)
        .expect("the camera's section");
    section = section.split("};\n  ").next().unwrap();
    let value = |key: &str| -> f64 {
        let rest = section.split(&format!("{key} = ")).nth(1).expect(key);
        let number = rest.split([';', ' ']).next().unwrap();
        number.trim_end_matches("deg").parse().expect(key)
    };
    let f = |size: f64, deg: f64| size / (2.0 * (deg.to_radians() / 2.0).tan());
    [
        f(width, value("openingAngleWidth")),
        f(height, value("openingAngleHeight")),
        value("x") * width,
        value("y") * height,
    ]
}

#[test]
fn a_fresh_bhuman_intrinsics_file_is_naocalibs_intrinsics_through_bhumans_code() {
    let corrections = [
        (Param::Fx, 9.0),
        (Param::Fy, -6.0),
        (Param::Cx, 4.0),
        (Param::Cy, -7.5),
        (Param::UpperFx, -11.0),
        (Param::UpperFy, 8.0),
        (Param::UpperCx, -9.0),
        (Param::UpperCy, 6.5),
    ];
    let cal = with_intrinsics(&corrections);
    let text = bhuman::Intrinsics.write(&cal);
    assert_eq!(
        export::recognised(&text),
        Some(&bhuman::Intrinsics as &dyn Format)
    );
    // The upper camera first, as B-Human's CameraInfo::Camera.
    assert!(text.find("upper = {").unwrap() < text.find("lower = {").unwrap());
    for camera in CameraId::ALL {
        let prior = priors()[&camera];
        let want = cal.intrinsics(camera).unwrap().value;
        let got = bhuman_camera(&text, camera, prior.width as f64, prior.height as f64);
        for (g, w) in got.iter().zip(&want) {
            assert!((g - w).abs() < 1e-9, "{camera}: {got:?} vs {want:?}");
        }
        // At half the resolution (B-Human's lower camera may run at 320 × 240) the same
        // camera scaled.
        let half = bhuman_camera(
            &text,
            camera,
            prior.width as f64 / 2.0,
            prior.height as f64 / 2.0,
        );
        for (h, w) in half.iter().zip(&want) {
            assert!((h - w / 2.0).abs() < 1e-9);
        }
    }
    // import reads it back as the prior of a calibration held at it …
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("cameraIntrinsics.cfg");
    std::fs::write(&path, &text).unwrap();
    let (imported, read) = export::import_calibration(&[path], None).unwrap();
    assert_eq!(read[0].1, "bhuman-intrinsics");
    for camera in CameraId::ALL {
        let i = imported.intrinsics(camera).unwrap();
        let want = cal.intrinsics(camera).unwrap().value;
        for (v, w) in i.value.iter().zip(&want) {
            assert!((v - w).abs() < 1e-9, "{camera}: {i:?}");
        }
        assert!(
            i.calibrated.iter().all(|c| !c),
            "held at the robot's values"
        );
    }
    // … from which a dataset of the priors starts at the corrections.
    let model = Model {
        upper_camera: Some(Camera {
            fx: 598.0,
            fy: 598.0,
            cx: 320.0,
            cy: 240.0,
            ..Camera::default()
        }),
        ..Model::default()
    };
    let start = imported.start_values(&model);
    for (p, v) in corrections {
        let got = start.iter().find(|(q, _)| *q == p).unwrap().1;
        assert!((got - v).abs() < 1e-9, "{p}: {got} vs {v}");
    }
    // A calibration without intrinsics writes no such file, and refuses a fresh one.
    let mut none = with_intrinsics(&[]);
    none.cameras.clear();
    assert!(
        export::every_file(&none, dir.path())
            .iter()
            .all(|(f, _)| !f.intrinsics())
    );
    let e = export::export(
        &none,
        &bhuman::Intrinsics,
        &dir.path().join("fresh.cfg"),
        &export::WriteOptions::default(),
    )
    .unwrap_err();
    assert!(e.to_string().contains("no camera intrinsics"), "{e}");
}

#[test]
fn an_update_of_bhumans_default_changes_only_what_was_calibrated() {
    // Only the upper camera's focal length in x and centre in y determined here.
    let mut cal = with_intrinsics(&[(Param::UpperFx, 20.0), (Param::UpperCy, -4.0)]);
    let updated = bhuman::Intrinsics
        .update(BHUMAN_DEFAULT, Path::new("cameraIntrinsics.cfg"), &cal)
        .unwrap();
    let changed: Vec<(&str, &str)> = BHUMAN_DEFAULT
        .lines()
        .zip(updated.lines())
        .filter(|(a, b)| a != b)
        .collect();
    assert_eq!(changed.len(), 2, "{updated}");
    assert!(changed[0].1.contains("openingAngleWidth") && changed[1].1.contains("y = "));
    let upper = bhuman_camera(&updated, CameraId::Upper, 640.0, 480.0);
    assert!(
        (upper[0] - 618.0).abs() < 1e-9 && (upper[3] - 236.0).abs() < 1e-9,
        "{upper:?}"
    );
    // The lower camera is B-Human's default still.
    assert_eq!(
        bhuman_camera(&updated, CameraId::Lower, 640.0, 480.0),
        bhuman_camera(BHUMAN_DEFAULT, CameraId::Lower, 640.0, 480.0)
    );
    // Nothing calibrated: the file stays as it is.
    cal = with_intrinsics(&[]);
    let same = bhuman::Intrinsics
        .update(BHUMAN_DEFAULT, Path::new("cameraIntrinsics.cfg"), &cal)
        .unwrap();
    assert_eq!(same, BHUMAN_DEFAULT);
    // An implausible opening angle is refused, naming the key.
    let bad = BHUMAN_DEFAULT.replacen("54.7deg", "540deg", 1);
    let e = bhuman::Intrinsics
        .read_cameras(&bad, Path::new("cameraIntrinsics.cfg"))
        .unwrap_err();
    assert!(
        e.to_string()
            .contains("cameraIntrinsics.cfg: line 3: cameras.upper.openingAngleWidth"),
        "{e}"
    );
}

/// `solve --free intrinsics --export` of a dataset of both cameras writes
/// `cameraIntrinsics.cfg` with the calibrated intrinsics, and naocalib's own TOML carries
/// the priors they are relative to.
#[test]
fn solve_with_free_intrinsics_exports_the_intrinsics_file() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("both");
    let out = crate::util::naocalib()
        .args([
            "simulate",
            "--stances",
            "8",
            "--heads",
            "2",
            "--upper-stances",
            "2",
        ])
        .args(["--seed", "5"])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", crate::util::stderr(&out));
    let files = tmp.path().join("files");
    let out = crate::util::naocalib()
        .args(["solve", "--free", "intrinsics", "--export"])
        .arg(&files)
        .arg(&dir)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", crate::util::stderr(&out));
    let own = export::read_calibration(&files.join("calibration.toml")).unwrap();
    assert_eq!(own.cameras.len(), 2);
    let text = std::fs::read_to_string(files.join("cameraIntrinsics.cfg")).unwrap();
    for camera in CameraId::ALL {
        let want = own.intrinsics(camera).unwrap();
        let got = bhuman_camera(&text, camera, 640.0, 480.0);
        for (g, w) in got.iter().zip(&want.value) {
            assert!((g - w).abs() < 1e-6, "{camera}: {got:?} {want:?}");
        }
    }
}
