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

// ---- Every team's file of the intrinsics, on a robot as the teams' defaults show them ----

/// HULKs' head file with its defaults' intrinsics (`etc/parameters/default.json`, lines
/// 88–98, commit 21e8a3de9: `focal_lengths` and `cc_optical_center` of both cameras) beside
/// a robot's camera corrections.
const HULKS_HEAD: &str = r#"{
  "camera_matrix_parameters": {
    "vision_top": {
      "focal_lengths": [0.96666, 1.28574],
      "cc_optical_center": [0.5, 0.5]
    },
    "vision_bottom": {
      "focal_lengths": [0.96666, 1.28574],
      "cc_optical_center": [0.5, 0.5]
    },
    "calibration": {
      "correction_in_camera_bottom": [-0.0641, 0.0963, 0.0332],
      "correction_in_camera_top": [-0.0859, 0.0995, 0.0447]
    }
  }
}
"#;

/// NomadZ's default `upperCameraInfo.cfg` (`Config/Robots/Default/`, commit 2a597dac),
/// byte for byte.
const NOMADZ_UPPER: &str = "camera = upper;
width = 640;
height = 480;
openingAngleWidth = 0.9546951; // 54.7deg;
openingAngleHeight = 0.7417649; // 42.5deg;
opticalCenter = { x = 320; y = 240; };
";

/// NomadZ's default `lowerCameraInfo.cfg` (the lower camera at 320 × 240), byte for byte.
const NOMADZ_LOWER: &str = "camera = lower;
width = 320;
height = 240;
openingAngleWidth = 0.9546951; // 54.7deg;
openingAngleHeight = 0.7417649; // 42.5deg;
opticalCenter = { x = 160; y = 120; };
";

/// NaoTH's `Config/platform/Nao6/CameraInfoTop.cfg` (commit 79e1e750b), byte for byte.
const NAOTH_TOP: &str = "[CameraInfoTop]\n\nopeningAngleDiagonal = 67.4\n";

/// NaoTH's `CameraInfoBottom.cfg`, byte for byte.
const NAOTH_BOTTOM: &str = "[CameraInfoBottom]\n\nopeningAngleDiagonal = 67.4\n";

/// A robot as the teams' defaults show it: focal lengths 1–3 % off the a-priori values
/// (562.5 px lower, 598 px upper) and the centres up to 10 px off the middle.
const ROBOT: [(Param, f64); 8] = [
    (Param::Fx, 13.5),  // +2.4 %
    (Param::Fy, -6.75), // −1.2 %
    (Param::Cx, 9.5),
    (Param::Cy, -8.0),
    (Param::UpperFx, -17.3), // −2.9 %
    (Param::UpperFy, 8.4),   // +1.4 %
    (Param::UpperCx, -10.0),
    (Param::UpperCy, 6.5),
];

/// The value of `key` (`opticalCenter.x` for the centre's) in a B-Human-style config file
/// (NomadZ's): the first entry line `key = …;` outside comments, read as NomadZ's
/// `InText::readDouble` reads a float (no unit).
fn cfg_number(text: &str, key: &str) -> f64 {
    let (key, inner) = key
        .split_once('.')
        .map_or((key, None), |(k, i)| (k, Some(i)));
    let line = text
        .lines()
        .map(str::trim)
        .filter(|l| !l.starts_with("//"))
        .find(|l| {
            l.strip_prefix(key)
                .is_some_and(|rest| rest.trim_start().starts_with('='))
        })
        .unwrap_or_else(|| panic!("{key} in {text}"));
    let mut value = line.split_once('=').unwrap().1;
    if let Some(inner) = inner {
        let at = value.find(&format!("{inner} =")).expect(inner);
        value = value[at..].split_once('=').unwrap().1;
    }
    value.split(';').next().unwrap().trim().parse().expect(key)
}

/// NomadZ's camera of a `CameraInfo` file, through its code: `width`, `height`, the focal
/// length `width / (2·tan(openingAngleWidth / 2))` (`CameraInfo.cpp`, line 22), the
/// vertical one of the field of view `tan(openingAngleHeight / 2) = (height / 2) / f_h`
/// (`Transformations.cpp`, lines 351–352) and the centre in px: `(w, h, [fx, fy, cx, cy])`.
fn nomadz_camera(text: &str) -> (u32, u32, [f64; 4]) {
    let w = cfg_number(text, "width");
    let h = cfg_number(text, "height");
    let fx = w / (2.0 * (cfg_number(text, "openingAngleWidth") / 2.0).tan());
    let fy = h / (2.0 * (cfg_number(text, "openingAngleHeight") / 2.0).tan());
    (
        w as u32,
        h as u32,
        [
            fx,
            fy,
            cfg_number(text, "opticalCenter.x"),
            cfg_number(text, "opticalCenter.y"),
        ],
    )
}

/// HULKs' camera of a head file, through its code: the head file merged over HULKs'
/// defaults (`directory.rs` lines 84–91, `json.rs` lines 3–14; `default.json` lines
/// 91–97: `focal_lengths` `[0.96666, 1.28574]`, `cc_optical_center` `[0.5, 0.5]`), then
/// `focal_lengths` and `cc_optical_center` times 640 × 480 (`camera_matrix_calculator.rs`
/// line 66, `camera_matrix.rs` lines 49–54): `[fx, fy, cx, cy]` of `vision_top` (the
/// upper camera) or `vision_bottom`.
fn hulks_camera(text: &str, camera: CameraId) -> [f64; 4] {
    let v: serde_json::Value = serde_json::from_str(text).unwrap();
    let key = match camera {
        CameraId::Upper => "vision_top",
        CameraId::Lower => "vision_bottom",
    };
    let vision = &v["camera_matrix_parameters"][key];
    let default = |k: &str, n: usize| match k {
        "focal_lengths" => [0.96666, 1.28574][n],
        _ => 0.5,
    };
    let at = |k: &str, n: usize| vision[k][n].as_f64().unwrap_or_else(|| default(k, n));
    [
        at("focal_lengths", 0) * 640.0,
        at("focal_lengths", 1) * 480.0,
        at("cc_optical_center", 0) * 640.0,
        at("cc_optical_center", 1) * 480.0,
    ]
}

/// NaoTH's focal length of a `CameraInfo` file at 640 × 480, through its code:
/// `CameraInfo::getFocalLength` (`CameraInfo.cpp`, lines 19–26), half the diagonal over
/// `tan(openingAngleDiagonal / 2)`, the angle in degrees in the file
/// (`PARAMETER_ANGLE_REGISTER`, `ParameterList.h` line 92).
fn naoth_focal_length(text: &str) -> f64 {
    let line = text
        .lines()
        .find(|l| l.trim_start().starts_with("openingAngleDiagonal"))
        .expect("openingAngleDiagonal");
    let deg: f64 = line.split_once('=').unwrap().1.trim().parse().unwrap();
    0.5 * 640f64.hypot(480.0) / (0.5 * deg.to_radians()).tan()
}

fn close(got: &[f64], want: &[f64], what: &str) {
    for (g, w) in got.iter().zip(want) {
        assert!((g - w).abs() < 1e-9, "{what}: {got:?} vs {want:?}");
    }
}

/// The lines of `after` that differ from `before` (same number of lines).
fn changed_lines<'a>(before: &str, after: &'a str) -> Vec<&'a str> {
    assert_eq!(before.lines().count(), after.lines().count(), "{after}");
    before
        .lines()
        .zip(after.lines())
        .filter(|(a, b)| a != b)
        .map(|(_, b)| b)
        .collect()
}

/// Every intrinsics key naocalib writes — fresh, and into the teams' own default files
/// with `--update` — is naocalib's camera (`fx`, `fy`, `cx`, `cy` at the team's image
/// size) through that team's own formula, on a robot whose focal lengths are 1–3 % and
/// centres up to 10 px off the a-priori camera; NaoTH, which has one focal length and a
/// fixed centre, gets the mean of `fx` and `fy`. `import` reads each back.
#[test]
fn every_intrinsics_key_of_every_team_file_is_naocalibs_camera_through_the_teams_code() {
    use naocalib::export::{hulks, naoth, nomadz};
    let cal = with_intrinsics(&ROBOT);
    let at = |camera: CameraId, w: u32, h: u32| cal.intrinsics(camera).unwrap().scaled_to(w, h);
    let nomadz_files = [
        (nomadz::CameraInfo(CameraId::Upper), NOMADZ_UPPER),
        (nomadz::CameraInfo(CameraId::Lower), NOMADZ_LOWER),
    ];
    let naoth_files = [
        (naoth::CameraInfo(CameraId::Upper), NAOTH_TOP),
        (naoth::CameraInfo(CameraId::Lower), NAOTH_BOTTOM),
    ];
    let path = Path::new("robot.cfg");
    // Fresh files and updates of the teams' defaults hold the same camera.
    let hulks_texts = [
        hulks::Head.write(&cal),
        hulks::Head.update(HULKS_HEAD, path, &cal).unwrap(),
    ];
    for (k, text) in hulks_texts.iter().enumerate() {
        assert_eq!(export::recognised(text), Some(&hulks::Head as &dyn Format));
        for camera in CameraId::ALL {
            close(
                &hulks_camera(text, camera),
                &at(camera, 640, 480),
                &format!("hulks {k} {camera}"),
            );
        }
    }
    // The update changed the eight numbers of the intrinsics only.
    let changed = changed_lines(HULKS_HEAD, &hulks_texts[1]);
    assert_eq!(changed.len(), 4, "{changed:?}");
    assert!(
        changed
            .iter()
            .all(|l| l.contains("focal_lengths") || l.contains("cc_optical"))
    );
    for (format, default) in nomadz_files {
        let fresh = format.write(&cal);
        let updated = format.update(default, path, &cal).unwrap();
        assert_eq!(export::recognised(&fresh), Some(&format as &dyn Format));
        assert_eq!(export::recognised(default), Some(&format as &dyn Format));
        for (k, text) in [&fresh, &updated].into_iter().enumerate() {
            let (w, h, camera) = nomadz_camera(text);
            // A fresh file at NomadZ's default resolution of the camera, an updated one at
            // the file's own.
            assert_eq!((w, h), nomadz::default_image(format.0), "{k}: {text}");
            close(
                &camera,
                &at(format.0, w, h),
                &format!("{} {k}", format.name()),
            );
        }
        let changed = changed_lines(default, &updated);
        assert_eq!(changed.len(), 3, "{changed:?}");
        // A comment beside a value is kept as it was.
        assert!(updated.contains("; // 54.7deg;"), "{updated}");
    }
    for (format, default) in naoth_files {
        let fresh = format.write(&cal);
        let updated = format.update(default, path, &cal).unwrap();
        assert_eq!(export::recognised(default), Some(&format as &dyn Format));
        let [fx, fy, _, _] = at(format.0, 640, 480);
        for text in [&fresh, &updated] {
            let f = naoth_focal_length(text);
            assert!(
                (f - (fx + fy) / 2.0).abs() < 1e-9,
                "{f} vs {fx}, {fy}: {text}"
            );
        }
        assert_eq!(changed_lines(default, &updated).len(), 1);
        // The header says what NaoTH cannot take.
        assert!(
            fresh.contains("cannot take") && fresh.contains("centre"),
            "{fresh}"
        );
    }
    // Every fresh file reads back as the camera it carries (at the file's image size).
    let dir = tempfile::tempdir().unwrap();
    let mut files = Vec::new();
    for format in [
        &nomadz::CameraInfo(CameraId::Upper) as &dyn Format,
        &nomadz::CameraInfo(CameraId::Lower),
    ] {
        let file = dir.path().join(format.file().replace('/', "-"));
        std::fs::write(&file, format.write(&cal)).unwrap();
        files.push(file);
    }
    let (imported, read) = export::import_calibration(&files, None).unwrap();
    assert_eq!(
        read.iter().map(|r| r.1).collect::<Vec<_>>(),
        ["nomadz-upper-camera-info", "nomadz-lower-camera-info"]
    );
    for camera in CameraId::ALL {
        let i = imported.intrinsics(camera).unwrap();
        let (w, h) = nomadz::default_image(camera);
        assert_eq!((i.prior.width, i.prior.height), (w, h));
        close(&i.value, &at(camera, w, h), &format!("import {camera}"));
    }
    let head = dir.path().join("head.json");
    std::fs::write(&head, &hulks_texts[0]).unwrap();
    let (imported, _) = export::import_calibration(&[head], None).unwrap();
    for camera in CameraId::ALL {
        let i = imported.intrinsics(camera).unwrap();
        close(
            &i.value,
            &at(camera, 640, 480),
            &format!("import hulks {camera}"),
        );
    }
    let top = dir.path().join("CameraInfoTop.cfg");
    std::fs::write(&top, naoth::CameraInfo(CameraId::Upper).write(&cal)).unwrap();
    let (imported, read) = export::import_calibration(&[top], None).unwrap();
    assert_eq!(read[0].1, "naoth-camera-info-top");
    let i = imported.intrinsics(CameraId::Upper).unwrap();
    let [fx, fy, _, _] = at(CameraId::Upper, 640, 480);
    close(
        &i.value,
        &[(fx + fy) / 2.0, (fx + fy) / 2.0, 319.5, 239.5],
        "import naoth",
    );
}

/// `--update` changes only the intrinsics that were calibrated: with the upper camera's
/// focal length in x and the lower camera's centre in y estimated (every other value
/// held), each team's default file changes in those keys alone — and what HULKs' file
/// lacks is inserted with HULKs' defaults beside it.
#[test]
fn an_update_changes_only_the_intrinsics_that_were_calibrated_in_every_teams_file() {
    use naocalib::export::{hulks, naoth, nomadz};
    let cal = with_intrinsics(&[(Param::UpperFx, -17.3), (Param::Cy, -8.0)]);
    let path = Path::new("robot.cfg");
    let upper = cal.intrinsics(CameraId::Upper).unwrap();
    let lower = cal.intrinsics(CameraId::Lower).unwrap();
    assert_eq!(upper.calibrated, [true, false, false, false]);
    assert_eq!(lower.calibrated, [false, false, false, true]);
    // HULKs: one number of each camera's arrays.
    let updated = hulks::Head.update(HULKS_HEAD, path, &cal).unwrap();
    let changed = changed_lines(HULKS_HEAD, &updated);
    assert_eq!(changed.len(), 2, "{updated}");
    let top = hulks_camera(&updated, CameraId::Upper);
    let bottom = hulks_camera(&updated, CameraId::Lower);
    let default = hulks_camera(HULKS_HEAD, CameraId::Upper);
    close(
        &top,
        &[
            upper.scaled_to(640, 480)[0],
            default[1],
            default[2],
            default[3],
        ],
        "top",
    );
    close(
        &bottom,
        &[
            default[0],
            default[1],
            default[2],
            lower.scaled_to(640, 480)[3],
        ],
        "bottom",
    );
    // A head file without intrinsics gets them inserted, HULKs' defaults beside what was
    // calibrated, every line of it kept (a closing brace gains the comma before the new key).
    let fixture = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/teams/hulks/head.json"),
    )
    .unwrap();
    let inserted = hulks::Head.update(&fixture, path, &cal).unwrap();
    close(
        &hulks_camera(&inserted, CameraId::Upper),
        &top,
        "inserted top",
    );
    close(
        &hulks_camera(&inserted, CameraId::Lower),
        &bottom,
        "inserted bottom",
    );
    let mut lines = inserted.lines();
    for line in fixture.lines() {
        assert!(
            lines.any(|l| l == line || l == format!("{line},")),
            "{line:?} lost: {inserted}"
        );
    }
    // B-Human: the upper opening angle's line and the lower centre's.
    let updated = bhuman::Intrinsics
        .update(BHUMAN_DEFAULT, path, &cal)
        .unwrap();
    let changed = changed_lines(BHUMAN_DEFAULT, &updated);
    assert_eq!(changed.len(), 2);
    assert!(changed[0].contains("openingAngleWidth") && changed[1].contains("opticalCenter"));
    // NomadZ: the upper file's openingAngleWidth, the lower file's centre in y (at its
    // 320 × 240).
    let updated = nomadz::CameraInfo(CameraId::Upper)
        .update(NOMADZ_UPPER, path, &cal)
        .unwrap();
    assert_eq!(
        changed_lines(NOMADZ_UPPER, &updated),
        [format!(
            "openingAngleWidth = {}; // 54.7deg;",
            upper.opening_angles()[0].to_radians()
        )]
    );
    let updated = nomadz::CameraInfo(CameraId::Lower)
        .update(NOMADZ_LOWER, path, &cal)
        .unwrap();
    let (_, _, camera) = nomadz_camera(&updated);
    let (_, _, before) = nomadz_camera(NOMADZ_LOWER);
    close(
        &camera,
        &[
            before[0],
            before[1],
            before[2],
            lower.scaled_to(320, 240)[3],
        ],
        "nomadz lower",
    );
    assert_eq!(changed_lines(NOMADZ_LOWER, &updated).len(), 1);
    // NaoTH: the top camera's diagonal; the bottom file unchanged (NaoTH takes no centre).
    let updated = naoth::CameraInfo(CameraId::Upper)
        .update(NAOTH_TOP, path, &cal)
        .unwrap();
    assert_eq!(changed_lines(NAOTH_TOP, &updated).len(), 1);
    let [fx, fy, _, _] = upper.scaled_to(640, 480);
    assert!((naoth_focal_length(&updated) - (fx + fy) / 2.0).abs() < 1e-9);
    let same = naoth::CameraInfo(CameraId::Lower)
        .update(NAOTH_BOTTOM, path, &cal)
        .unwrap();
    assert_eq!(same, NAOTH_BOTTOM);
    // With nothing calibrated every file stays as it is.
    let held = with_intrinsics(&[]);
    assert_eq!(
        hulks::Head.update(HULKS_HEAD, path, &held).unwrap(),
        HULKS_HEAD
    );
    for (format, text) in [
        (
            &nomadz::CameraInfo(CameraId::Upper) as &dyn Format,
            NOMADZ_UPPER,
        ),
        (&nomadz::CameraInfo(CameraId::Lower), NOMADZ_LOWER),
        (&naoth::CameraInfo(CameraId::Upper), NAOTH_TOP),
    ] {
        assert_eq!(
            format.update(text, path, &held).unwrap(),
            text,
            "{}",
            format.name()
        );
    }
    // A file of the other camera, or an implausible value, is refused naming file and line.
    let e = nomadz::CameraInfo(CameraId::Upper)
        .read_cameras(&NOMADZ_UPPER.replace("0.9546951", "54.7"), path)
        .unwrap_err();
    assert!(
        e.to_string()
            .contains("robot.cfg: line 4: openingAngleWidth"),
        "{e}"
    );
    assert!(!(&nomadz::CameraInfo(CameraId::Upper) as &dyn Format).matches(NOMADZ_LOWER));
    let e = hulks::Head
        .read_cameras(&HULKS_HEAD.replacen("0.96666", "96.666", 1), path)
        .unwrap_err();
    assert!(
        e.to_string()
            .contains("line 4: camera_matrix_parameters.vision_top.focal_lengths"),
        "{e}"
    );
    // A directory export writes a camera's file only when the calibration carries it.
    let mut lower_only = with_intrinsics(&[(Param::Fx, 5.0)]);
    lower_only.cameras.remove(&CameraId::Upper);
    let names: Vec<&str> = export::every_file(&lower_only, Path::new("d"))
        .iter()
        .filter(|(f, _)| f.intrinsics())
        .map(|(f, _)| f.name())
        .collect();
    assert_eq!(
        names,
        [
            "bhuman-intrinsics",
            "naoth-camera-info-bottom",
            "nomadz-lower-camera-info"
        ]
    );
}

/// A dataset of both cameras (V6 cameras) whose true intrinsics are those of [`ROBOT`],
/// simulated through the command line into `tmp/robot`.
fn robot_dataset(tmp: &Path) -> std::path::PathBuf {
    let simulate = |dir: &Path, truth: Option<&Path>| {
        let mut cmd = crate::util::naocalib();
        cmd.args([
            "simulate",
            "--camera",
            "v6",
            "--stances",
            "8",
            "--heads",
            "2",
        ])
        .args(["--upper-stances", "2", "--seed", "5"])
        .arg("--board")
        .arg(crate::util::paper_board());
        if let Some(truth) = truth {
            cmd.arg("--truth").arg(truth);
        }
        let out = cmd.arg(dir).output().unwrap();
        assert!(out.status.success(), "{}", crate::util::stderr(&out));
    };
    let drawn = tmp.join("drawn");
    simulate(&drawn, None);
    let mut truth = std::fs::read_to_string(drawn.join("truth.toml")).unwrap();
    for (p, px) in ROBOT {
        let key = format!("\n{} = ", p.name());
        match truth.find(&key) {
            Some(at) => {
                let at = at + key.len();
                let end = at + truth[at..].find('\n').unwrap();
                truth.replace_range(at..end, &px.to_string());
            }
            // A truth.toml lists the upper camera's intrinsics only when one is not zero.
            None => {
                let at = truth.find("[parameters]\n").expect("[parameters]") + 13;
                truth.insert_str(at, &format!("{} = {px}\n", p.name()));
            }
        }
    }
    let truth_file = tmp.join("truth.toml");
    std::fs::write(&truth_file, truth).unwrap();
    let robot = tmp.join("robot");
    simulate(&robot, Some(&truth_file));
    robot
}

/// `solve --json --free intrinsics` carries the cameras' a-priori intrinsics, so that
/// `export RESULT.json` writes every team's intrinsics file from it as from naocalib's own
/// calibration file; the table and the HTML report give each camera's intrinsics as the
/// teams read them, with σ, and — from `--start-from` a robot's files — the change since
/// them. With the intrinsics held, none of it appears.
#[test]
fn a_solve_json_with_free_intrinsics_exports_and_reports_the_cameras_intrinsics() {
    let tmp = tempfile::tempdir().unwrap();
    let robot = robot_dataset(tmp.path());
    let run = |args: &[&str]| {
        let out = crate::util::naocalib()
            .args(args)
            .arg(&robot)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{args:?}: {}",
            crate::util::stderr(&out)
        );
        String::from_utf8(out.stdout).unwrap()
    };
    let json_text = run(&["solve", "--free", "intrinsics", "--json"]);
    let json: serde_json::Value = serde_json::from_str(&json_text).unwrap();
    assert_eq!(json["cameras"]["lower"]["width"], 640, "{json_text}");
    assert!(json["cameras"]["upper"]["fx"].as_f64().unwrap() > 500.0);
    let result = tmp.path().join("result.json");
    std::fs::write(&result, &json_text).unwrap();
    let cal = export::read_calibration(&result).unwrap();
    assert_eq!(cal.cameras.len(), 2);
    // The true intrinsics are recovered (noise 0.1 px): within 5σ of the truth.
    for camera in CameraId::ALL {
        let i = cal.intrinsics(camera).unwrap();
        let truth: Vec<f64> = naocalib::calibration::intrinsics::params(camera)
            .iter()
            .map(|p| ROBOT.iter().find(|(q, _)| q == p).unwrap().1)
            .collect();
        for (k, truth) in truth.iter().enumerate() {
            let err = i.value[k] - i.prior.values()[k] - truth;
            assert!(err.abs() < 5.0 * i.std[k].unwrap(), "{camera} {k}: {i:?}");
        }
    }
    // Every team file of the intrinsics, from the solve's JSON.
    let files = tmp.path().join("files");
    let out = crate::util::naocalib()
        .arg("export")
        .arg(&result)
        .arg("--dir")
        .arg(&files)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", crate::util::stderr(&out));
    let bhuman = std::fs::read_to_string(files.join("cameraIntrinsics.cfg")).unwrap();
    let head = std::fs::read_to_string(files.join("hulks/head.json")).unwrap();
    for camera in CameraId::ALL {
        let i = cal.intrinsics(camera).unwrap();
        close(
            &bhuman_camera(&bhuman, camera, 640.0, 480.0),
            &i.value,
            "bhuman",
        );
        close(&hulks_camera(&head, camera), &i.value, "hulks");
    }
    for name in ["upperCameraInfo.cfg", "lowerCameraInfo.cfg"] {
        let text = std::fs::read_to_string(files.join("nomadz").join(name)).unwrap();
        let (w, h, camera) = nomadz_camera(&text);
        let which = if name.starts_with("upper") {
            CameraId::Upper
        } else {
            CameraId::Lower
        };
        close(
            &camera,
            &cal.intrinsics(which).unwrap().scaled_to(w, h),
            name,
        );
    }
    assert!(files.join("naoth/CameraInfoTop.cfg").exists());
    // The table: each camera's opening angles, focal lengths and centre offset with σ.
    let table = run(&["solve", "--free", "intrinsics"]);
    for camera in CameraId::ALL {
        let i = cal.intrinsics(camera).unwrap();
        let heading = format!("Intrinsics of the {camera} camera at 640×480 px");
        let section = table
            .split(&heading)
            .nth(1)
            .unwrap_or_else(|| panic!("{table}"));
        let row = |quantity: &str| -> Vec<String> {
            let line = section.lines().find(|l| l.starts_with(quantity)).unwrap();
            line[quantity.len()..]
                .split_whitespace()
                .map(String::from)
                .collect()
        };
        let [aw, _] = i.opening_angles();
        let [sw, _] = i.opening_angles_std().map(Option::unwrap);
        assert_eq!(
            row("opening angle width")[..2],
            [format!("{aw:.4}"), format!("{sw:.4}")]
        );
        let [ox, _] = i.centre_offset();
        assert_eq!(row("centre offset x")[0], format!("{ox:.4}"));
        assert_eq!(
            row("focal length y")[1],
            format!("{:.4}", i.std[1].unwrap())
        );
    }
    // From a robot's previous files (B-Human's defaults, imported): the previous values
    // and the change, in the table and the report.
    let team = tmp.path().join("cameraIntrinsics.cfg");
    std::fs::write(&team, BHUMAN_DEFAULT).unwrap();
    let current = tmp.path().join("current.toml");
    let out = crate::util::naocalib()
        .arg("import")
        .arg(&team)
        .arg("--out")
        .arg(&current)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", crate::util::stderr(&out));
    let report = tmp.path().join("report.html");
    let table = run(&[
        "solve",
        "--free",
        "intrinsics",
        "--start-from",
        current.to_str().unwrap(),
        "--report",
        report.to_str().unwrap(),
    ]);
    let section = table
        .split("Intrinsics of the lower camera")
        .nth(1)
        .unwrap();
    let line = section
        .lines()
        .find(|l| l.starts_with("opening angle width"))
        .unwrap();
    let cells: Vec<&str> = line.split_whitespace().collect();
    // quantity (3 words), value, σ, previous, change, unit.
    assert_eq!(cells[5], "54.7000", "{line}");
    let change: f64 = cells[6].parse().unwrap();
    let value: f64 = cells[3].parse().unwrap();
    assert!((value - 54.7 - change).abs() < 2e-4, "{line}");
    let line = section
        .lines()
        .find(|l| l.starts_with("focal length x"))
        .unwrap();
    let cells: Vec<&str> = line.split_whitespace().collect();
    let bhuman_fx = naocalib::calibration::intrinsics::focal_length(640, 54.7);
    assert_eq!(cells[5], format!("{bhuman_fx:.4}"), "{line}");
    // The change of the correction Fx: from the robot's camera made relative to the
    // dataset's a-priori one.
    let changes = table
        .split("Change since the previous calibration")
        .nth(1)
        .unwrap();
    let line = changes.lines().find(|l| l.starts_with("Fx ")).unwrap();
    let previous: f64 = line.split_whitespace().nth(1).unwrap().parse().unwrap();
    let prior = cal.cameras[&CameraId::Lower].fx;
    assert!((previous - (bhuman_fx - prior)).abs() < 1e-4, "{line}");
    let html = std::fs::read_to_string(&report).unwrap();
    assert!(html.contains("id=\"intrinsics-lower\"") && html.contains("id=\"intrinsics-upper\""));
    assert!(
        html.contains("<td>54.7000</td>"),
        "the previous opening angle"
    );
    // Held (the default): no cameras in the JSON, no intrinsics in the table or report.
    let held = run(&["solve", "--json"]);
    assert!(!held.contains("\"cameras\""), "{held}");
    let report = tmp.path().join("held.html");
    let table = run(&["solve", "--report", report.to_str().unwrap()]);
    assert!(!table.contains("Intrinsics of"), "{table}");
    assert!(
        !std::fs::read_to_string(&report)
            .unwrap()
            .contains("intrinsics-")
    );
}
