//! `naocalib export --update` and `naocalib import` on robots' files in each team's layout
//! (tests/fixtures/teams, written in those layouts): an update changes exactly the
//! calibrated entries and keeps every other line byte for byte, leaves FILE.bak, and
//! refuses a corrupt or unparsable file untouched; import → export round-trips every value;
//! docs/EXPORTS.md lists exactly the registry's formats.

use std::path::{Path, PathBuf};

use naocalib::export::{self, Calibration, Entry, FORMATS, Format};
use naocalib::model::Param;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::util::naocalib;

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/teams")
        .join(name)
}

/// A converged calibration: camera offsets of real sizes (tilt −2° to −8°), leg offsets
/// up to 2° and play up to 1° estimated; the head held at zero (not estimated).
fn calibration(rng: &mut impl Rng) -> Calibration {
    crate::util::converged_calibration(export::Posture::Standing, |p| {
        let name = p.name();
        let (value, fixed) = match p {
            Param::CamPitch => (rng.random_range(-8.0..-2.0), false),
            Param::CamYaw | Param::CamRoll => (rng.random_range(-2.0..2.0), false),
            Param::HeadYaw | Param::HeadPitch => (0.0, true),
            _ if name.ends_with("Play") => (rng.random_range(0.1..1.0), false),
            _ => (crate::util::plausible_value(rng, p, 2.0), false),
        };
        Entry {
            param: p,
            value,
            std: Some(if fixed { 0.0 } else { 0.05 }),
            fixed,
        }
    })
}

/// Each layout's fixture, and the keys an update may change in it (a changed line must
/// contain one of them).
const CASES: [(&'static dyn Format, &str, &[&str]); 9] = [
    (
        &export::bhuman::Camera,
        "bhuman/cameraCalibration.cfg",
        &["lower = {", "upper = {"],
    ),
    (
        &export::bhuman::Camera2016,
        "bhuman2016/cameraCalibration.cfg",
        &[
            "x = -0.6deg",
            "y = -3.9deg",
            "z = 0.25deg",
            "x = 0.8deg",
            "y = -2.2deg",
            "z = 0deg",
        ],
    ),
    (
        &export::bhuman::Joints,
        "bhuman/jointCalibration.cfg",
        &["Hip", "Knee", "Ankle"],
    ),
    (
        &export::bhuman::Joints,
        "bhuman2024/jointCalibration.cfg",
        &["Hip", "Knee", "Ankle"],
    ),
    (
        &export::nomadz::Camera,
        "nomadz/cameraCalibration.cfg",
        &["cameraTilt", "cameraRoll", "cameraPan", "upperCamera"],
    ),
    (
        &export::nomadz::Joints,
        "nomadz/jointCalibration.cfg",
        &["offset = ", "jointPlay = "],
    ),
    (&export::hulks::Head, "hulks/head.json", &["        "]),
    (
        &export::naoth::Camera,
        "naoth/CameraMatrixOffset.cfg",
        &["cam_rot.bottom.", "cam_rot.top."],
    ),
    (
        &export::runswift::Camera,
        "runswift/nao.cfg",
        &["Bottom=", "TopWhenLooking"],
    ),
];

/// The values of a file, as import reads them.
fn imported(format: &'static dyn Format, path: &Path) -> Vec<(Param, f64)> {
    export::import(path, Some(format)).unwrap().1
}

#[test]
fn update_changes_exactly_the_calibrated_entries_and_keeps_a_backup() {
    let mut rng = ChaCha8Rng::seed_from_u64(240);
    let dir = tempfile::tempdir().unwrap();
    for (format, name, keys) in CASES {
        let cal = calibration(&mut rng);
        let path = dir.path().join(name.replace('/', "_"));
        let original = std::fs::read_to_string(fixture(name)).unwrap();
        std::fs::write(&path, &original).unwrap();
        assert_eq!(
            export::recognised(&original).map(|f| f.robot()),
            Some(true),
            "{name} is recognised"
        );
        let before = imported(format, &path);
        let backup = crate::util::updated(&cal, format, &path);
        assert_eq!(
            std::fs::read_to_string(&backup).unwrap(),
            original,
            "{name}: .bak"
        );
        assert!(backup.to_string_lossy().ends_with(".bak"));
        let updated = std::fs::read_to_string(&path).unwrap();
        assert_ne!(updated, original, "{name}: something changed");
        // Same lines, and every changed line holds a calibrated entry.
        let (a, b): (Vec<&str>, Vec<&str>) =
            (original.lines().collect(), updated.lines().collect());
        assert_eq!(a.len(), b.len(), "{name}: lines");
        for (old, new) in a.iter().zip(&b) {
            if old != new {
                assert!(
                    keys.iter().any(|k| old.contains(k)),
                    "{name}: a line that is not calibrated changed: {old:?} -> {new:?}"
                );
            }
        }
        // Read back: the calibrated values are the calibration's, the others as before.
        let after = imported(format, &path);
        let fresh = imported(format, &write_fresh(&cal, format, dir.path()));
        for (p, v) in &after {
            let expected = if cal.determined_here(*p).is_some() {
                fresh.iter().find(|(q, _)| q == p).unwrap().1
            } else {
                before.iter().find(|(q, _)| q == p).unwrap().1
            };
            assert!(
                (v - expected).abs() < 1e-9,
                "{name}: {p} = {v}, expected {expected}"
            );
        }
        // What naocalib does not read is kept too.
        match format.name() {
            "hulks-head" => {
                let (o, u): (serde_json::Value, serde_json::Value) = (
                    serde_json::from_str(&original).unwrap(),
                    serde_json::from_str(&updated).unwrap(),
                );
                let c = |v: &serde_json::Value, k: &str| {
                    v["camera_matrix_parameters"]["calibration"][k].clone()
                };
                // The upper camera was calibrated too (its values are checked above).
                assert_ne!(
                    c(&o, "correction_in_camera_top"),
                    c(&u, "correction_in_camera_top")
                );
                assert_eq!(c(&o, "correction_in_robot"), c(&u, "correction_in_robot"));
            }
            "nomadz-joints" => {
                let read =
                    |t: &str| naocalib::export::nomadz::Joints::stored(t, Path::new("-")).unwrap();
                for ((name, o), (_, u)) in read(&original).iter().zip(read(&updated)) {
                    assert_eq!(
                        (o.min_angle, o.max_angle),
                        (u.min_angle, u.max_angle),
                        "{name}"
                    );
                    if naocalib::export::bhuman::joint_param(name).is_none() {
                        assert_eq!(*o, u, "{name}: arms and hands kept");
                    }
                }
            }
            _ => {}
        }
        // The head offsets were not estimated: kept.
        for p in [Param::HeadYaw, Param::HeadPitch] {
            assert_eq!(
                after.iter().find(|(q, _)| *q == p),
                before.iter().find(|(q, _)| *q == p),
                "{name}: {p} kept"
            );
        }
    }
}

/// Writes `cal` fresh in `format` into `dir` and returns the path.
fn write_fresh(cal: &Calibration, format: &'static dyn Format, dir: &Path) -> PathBuf {
    let path = dir.join(format!("fresh-{}", format.name()));
    std::fs::write(&path, format.write(cal)).unwrap();
    path
}

#[test]
fn hulks_body_update_inserts_missing_joints_and_keeps_other_keys() {
    let mut rng = ChaCha8Rng::seed_from_u64(241);
    let cal = calibration(&mut rng);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("body.P0000073A03S83I00015.json");
    let original = std::fs::read_to_string(fixture("hulks/body.json")).unwrap();
    std::fs::write(&path, &original).unwrap();
    crate::util::updated(&cal, &export::hulks::Body, &path);
    let updated = std::fs::read_to_string(&path).unwrap();
    let json: serde_json::Value = serde_json::from_str(&updated).unwrap();
    assert_eq!(json["walking_engine"]["foot_lift_apex"], 0.012, "{updated}");
    for (group, joint, p) in [
        ("left_leg", "knee_pitch", Param::LKneePitch),
        ("left_leg", "ankle_roll", Param::LAnkleRoll),
        ("right_leg", "hip_pitch", Param::RHipPitch),
    ] {
        let stored = json["joint_calibration_offsets"][group][joint]
            .as_f64()
            .unwrap();
        // The standing offset: the calibration estimated compliance and play.
        let alpha = cal.robot_value(p).unwrap();
        assert_ne!(alpha, cal.value(p));
        assert!(
            (stored + alpha.to_radians()).abs() < 1e-15,
            "{group}.{joint}"
        );
    }
    // The head was not estimated: not added.
    assert!(json["joint_calibration_offsets"].get("head").is_none());
    // Lines of the original not holding a replaced value are all still there, in order.
    let mut rest = updated.lines();
    for line in original
        .lines()
        .filter(|l| !l.contains("hip_yaw_pitch") && !l.contains("knee_pitch"))
    {
        let trimmed = line.trim_end_matches(',');
        assert!(
            rest.any(|l| l.trim_end_matches(',') == trimmed),
            "{line:?} kept"
        );
    }
}

#[test]
fn corrupt_and_unparsable_files_are_refused_untouched() {
    let mut rng = ChaCha8Rng::seed_from_u64(242);
    let cal = calibration(&mut rng);
    let dir = tempfile::tempdir().unwrap();
    let cases: [(&dyn Format, &str, &[&str]); 3] = [
        (
            &export::nomadz::Camera,
            "nomadz_corrupt/cameraCalibration.cfg",
            &["line 1", "cameraTiltCorrection", "plausible"][..],
        ),
        (
            &export::bhuman::Camera,
            "broken/cameraCalibration.cfg",
            &["line 5", "missing '}'"][..],
        ),
        (&export::hulks::Body, "broken/body.json", &["line 3"][..]),
    ];
    for (format, name, needles) in cases {
        let path = dir.path().join(name.replace('/', "_"));
        let original = std::fs::read(fixture(name)).unwrap();
        std::fs::write(&path, &original).unwrap();
        let e = export::update(&cal, Some(format), &path, &[])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains(&path.display().to_string()),
            "{name}: names the file: {e}"
        );
        for n in needles {
            assert!(e.contains(n), "{name}: {e} lacks {n}");
        }
        assert_eq!(std::fs::read(&path).unwrap(), original, "{name} untouched");
        let mut bak = path.clone().into_os_string();
        bak.push(".bak");
        assert!(!PathBuf::from(bak).exists(), "{name}: no backup written");
        assert!(export::import(&path, Some(format)).is_err());
    }
}

#[test]
fn import_then_export_round_trips_every_value_of_every_layout() {
    let dir = tempfile::tempdir().unwrap();
    for (format, name, _) in CASES.iter().copied().chain([(
        &export::hulks::Body as &dyn Format,
        "hulks/body.json",
        &[][..],
    )]) {
        let (recognised, values) = export::import(&fixture(name), None).unwrap();
        assert_eq!(recognised, format, "{name} recognised");
        let (cal, _) = export::import_calibration(&[fixture(name)], None).unwrap();
        // Written fresh and read again: every value the file held.
        let back = imported(format, &write_fresh(&cal, format, dir.path()));
        for (p, v) in &values {
            let w = back.iter().find(|(q, _)| q == p).map(|(_, w)| *w);
            assert!(
                w.is_some_and(|w| (w - v).abs() < 1e-9),
                "{name}: {p} {v} -> {w:?}"
            );
        }
        // Joints: α = −stored.
        if format.name() == "bhuman-joints" && name.starts_with("bhuman/") {
            let knee = values
                .iter()
                .find(|(p, _)| *p == Param::RKneePitch)
                .unwrap()
                .1;
            assert!((knee - 1.9336).abs() < 1e-12, "alpha = -stored: {knee}");
        }
    }
}

#[test]
fn import_and_update_from_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    let camera = dir.path().join("cameraCalibration.cfg");
    let joints = dir.path().join("jointCalibration.cfg");
    std::fs::copy(fixture("bhuman/cameraCalibration.cfg"), &camera).unwrap();
    std::fs::copy(fixture("bhuman/jointCalibration.cfg"), &joints).unwrap();
    let cal = dir.path().join("robot.toml");
    let out = naocalib()
        .args(["import"])
        .arg(&camera)
        .arg(&joints)
        .arg("--out")
        .arg(&cal)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let read = export::read_calibration(&cal).unwrap();
    assert!((read.value(Param::CamPitch) + 5.6208).abs() < 1e-12);
    assert!(
        (read.value(Param::HeadYaw) + 3.2104).abs() < 1e-12,
        "alpha = -stored"
    );
    assert!(read.get(Param::HeadYaw).unwrap().fixed);
    assert!(read.get(Param::LBoardRotZ).unwrap().std.is_none());

    // An update with an imported calibration determines nothing: the file stays as it was.
    let out = naocalib()
        .args(["export"])
        .arg(&cal)
        .arg("--update")
        .arg(&joints)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(
        std::fs::read(&joints).unwrap(),
        std::fs::read(fixture("bhuman/jointCalibration.cfg")).unwrap()
    );

    // A corrupt file: exit 1, file and line named, nothing written.
    let corrupt = dir.path().join("nomadz.cfg");
    std::fs::copy(fixture("nomadz_corrupt/cameraCalibration.cfg"), &corrupt).unwrap();
    let out = naocalib()
        .arg("import")
        .arg(&corrupt)
        .arg("--out")
        .arg(dir.path().join("x.toml"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("line 1") && err.contains("nomadz.cfg"),
        "{err}"
    );
    assert!(!dir.path().join("x.toml").exists());
}

/// docs/EXPORTS.md's table of formats is the one [`export::table`] renders from the list
/// (`NAOCALIB_BLESS=1 cargo test --test it docs_table` rewrites it); `export --help` and
/// `solve --help` name every format of the list.
#[test]
fn docs_table_and_help_follow_the_format_list() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/EXPORTS.md");
    let docs = std::fs::read_to_string(&path).unwrap();
    let start = docs
        .find("| `--format` |")
        .expect("docs/EXPORTS.md has the table");
    let end = docs[start..]
        .find("\n\n")
        .map_or(docs.len(), |n| start + n + 1);
    let table = export::table();
    assert_eq!(table.lines().count(), FORMATS.len() + 2, "a row per format");
    if docs[start..end] != table && std::env::var_os("NAOCALIB_BLESS").is_some() {
        std::fs::write(&path, format!("{}{table}{}", &docs[..start], &docs[end..])).unwrap();
    } else {
        let (docs, list): (Vec<&str>, Vec<&str>) =
            (docs[start..end].lines().collect(), table.lines().collect());
        for k in 0..docs.len().max(list.len()) {
            assert_eq!(
                docs.get(k),
                list.get(k),
                "docs/EXPORTS.md's table, row {k}, is not the list's \
                 (`NAOCALIB_BLESS=1 cargo test --test it docs_table` rewrites it)"
            );
        }
    }
    let help = naocalib().args(["export", "--help"]).output().unwrap();
    let help = String::from_utf8_lossy(&help.stdout);
    for f in FORMATS {
        let line = format!("{}: {} ({})", f.name(), f.description(), f.file());
        assert!(help.contains(&line), "--help lists {line}");
    }
    // solve --export writes one file per format: its help names them all.
    let help = naocalib().args(["solve", "--help"]).output().unwrap();
    let help = String::from_utf8_lossy(&help.stdout);
    for f in FORMATS {
        assert!(help.contains(f.file()), "solve --help names {}", f.file());
    }
}

/// The format a file name implies: the most specific rule of the list, the first of the
/// list among equals; other names need --format, and the error says which names work.
#[test]
fn a_file_name_implies_its_format() {
    for (name, expected) in [
        ("calibration.toml", Some("toml")),
        ("dir.cfg/CAL.TOML", Some("toml")),
        ("head.json", Some("json")),
        ("hulks/body.json", Some("json")),
        ("cameraCalibration.cfg", Some("bhuman-camera")),
        ("nomadz/cameraCalibration.cfg", Some("bhuman-camera")),
        ("my_camera.cfg", Some("bhuman-camera")),
        ("jointCalibration.cfg", Some("bhuman-joints")),
        ("cameraJoint.cfg", Some("bhuman-camera")),
        ("CameraMatrixOffset.cfg", Some("naoth-camera")),
        ("naoth/cameramatrixoffset.CFG", Some("naoth-camera")),
        ("xCameraMatrixOffset.cfg", Some("bhuman-camera")),
        ("kinematics.cfg", None),
        ("nao.cfg", None),
        ("camera.ini", None),
        ("calibration", None),
        ("/", None),
    ] {
        assert_eq!(
            export::from_path(Path::new(name)).map(|f| f.name()),
            expected,
            "{name}"
        );
    }
    let e = export::ExportError::UnknownFormat {
        path: PathBuf::from("nao.cfg"),
    };
    assert_eq!(
        e.to_string(),
        "nao.cfg: unknown export format (use .toml, .json, cameraCalibration.cfg or \
         jointCalibration.cfg, or give --format)"
    );
}

#[test]
fn solve_records_corrected_angles_and_update_composes_with_the_robots_file() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("robot");
    crate::util::simulate_small(&data, 6);
    // The logged angles were corrected by the robot's jointCalibration.cfg.
    let toml_path = data.join("dataset.toml");
    let toml = std::fs::read_to_string(&toml_path).unwrap();
    let corrected = "angles = \"corrected\"\ncorrected_by = \"jointCalibration.cfg\"\n";
    let toml = if toml.contains("angles = \"raw\"") {
        toml.replace("angles = \"raw\"\n", corrected)
    } else {
        format!("{toml}\n[joints]\n{corrected}")
    };
    std::fs::write(&toml_path, toml).unwrap();
    let out = naocalib()
        .arg("solve")
        .arg(&data)
        .arg("--json")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let result: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(result["angles"], "corrected");
    assert_eq!(result["corrected_by"], "jointCalibration.cfg");
    let result_path = dir.path().join("result.json");
    std::fs::write(&result_path, &out.stdout).unwrap();

    // A fresh joint file cannot be right: refused.
    let fresh = dir.path().join("fresh_jointCalibration.cfg");
    let out = naocalib()
        .arg("export")
        .arg(&result_path)
        .args(["--format", "bhuman-joints", "--out"])
        .arg(&fresh)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--update"));
    assert!(!fresh.exists());

    // --update composes stored_new = stored_old − α.
    let joints = dir.path().join("jointCalibration.cfg");
    std::fs::copy(fixture("bhuman/jointCalibration.cfg"), &joints).unwrap();
    let old = export::bhuman::Joints::stored(&std::fs::read_to_string(&joints).unwrap(), &joints)
        .unwrap();
    let out = naocalib()
        .arg("export")
        .arg(&result_path)
        .arg("--update")
        .arg(&joints)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let new = export::bhuman::Joints::stored(&std::fs::read_to_string(&joints).unwrap(), &joints)
        .unwrap();
    let mut checked = 0;
    for ((name, s_old), (_, s_new)) in old.iter().zip(&new) {
        match export::bhuman::joint_param(name) {
            Some(p) if result["parameters"][p.name()]["fixed"] != true => {
                let alpha = result["parameters"][p.name()]["value"].as_f64().unwrap();
                assert!((s_new - (s_old - alpha)).abs() < 1e-9, "{name}");
                checked += 1;
            }
            _ => assert_eq!(s_old, s_new, "{name} kept"),
        }
    }
    assert_eq!(checked, 12, "every leg joint");
}

#[test]
fn solve_start_from_reports_the_change_since_the_previous_calibration() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("robot");
    crate::util::simulate_small(&data, 8);
    let previous = dir.path().join("previous");
    let out = naocalib()
        .arg("solve")
        .arg(&data)
        .arg("--export")
        .arg(&previous)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let cal = previous.join("calibration.toml");
    // The same data again: nothing changed, every z near zero.
    let out = naocalib()
        .arg("solve")
        .arg(&data)
        .arg("--start-from")
        .arg(&cal)
        .arg("--json")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let result: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let changes = result["changes"].as_object().unwrap();
    assert_eq!(changes.len(), 21, "every parameter of the paper's set");
    for (name, c) in changes {
        let z = c["z"].as_f64().unwrap();
        assert!(z.abs() < 0.01, "{name}: z = {z}");
    }
    let out = naocalib()
        .arg("solve")
        .arg(&data)
        .arg("--start-from")
        .arg(&cal)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("Change since the previous calibration"),
        "{text}"
    );
}
