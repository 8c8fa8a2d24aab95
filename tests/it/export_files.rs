//! A robot's files as a hostile user or a second run would treat them: `export --update`
//! never changes a file of another layout, never loses the robot's original, is idempotent
//! (also for angles already corrected by the file), updates through a symbolic link and
//! keeps hard links, mode and owner, refuses a read-only file and says when it has nothing
//! to write; `import` recognises naocalib's own exports, refuses a duplicate JSON key, an
//! implausible `jointPlay`, a FIFO and a too deeply nested file with a clear message, and
//! accepts a byte-order mark; `solve --start-from` refuses a start value beyond the
//! physical bounds instead of moving a joint by it.

use std::os::unix::fs::{MetadataExt, PermissionsExt};
use std::path::{Path, PathBuf};
use std::time::Duration;

use naocalib::dataset::{AngleKind, AngleSource};
use naocalib::export::{self, Calibration, Entry, FORMATS, Format, Unchanged, Updated};
use naocalib::model::Param;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::util::{naocalib, stderr};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/teams")
        .join(name)
}

/// Every robot layout's fixture, in its format.
const FIXTURES: [(&'static dyn Format, &str); 10] = [
    (&export::bhuman::Camera, "bhuman/cameraCalibration.cfg"),
    (
        &export::bhuman::Camera2016,
        "bhuman2016/cameraCalibration.cfg",
    ),
    (&export::bhuman::Joints, "bhuman/jointCalibration.cfg"),
    (&export::hulks::Head, "hulks/head.json"),
    (&export::hulks::Body, "hulks/body.json"),
    (&export::naoth::Camera, "naoth/CameraMatrixOffset.cfg"),
    (&export::nomadz::Camera, "nomadz/cameraCalibration.cfg"),
    (&export::nomadz::Joints, "nomadz/jointCalibration.cfg"),
    (&export::runswift::Camera, "runswift/nao.cfg"),
    (&export::bhuman::Joints, "bhuman2024/jointCalibration.cfg"),
];

/// A converged calibration of real sizes: lower camera tilt −2° to −8°, legs up to 2°,
/// play estimated, head held.
fn calibration(rng: &mut impl Rng) -> Calibration {
    crate::util::converged_calibration(export::Posture::Lying, |p| {
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

/// `name`'s fixture copied into `dir` (under a flat name).
fn copy(dir: &Path, name: &str) -> PathBuf {
    let path = dir.join(name.replace('/', "_"));
    std::fs::copy(fixture(name), &path).unwrap();
    path
}

fn backup_of(path: &Path, k: usize) -> PathBuf {
    let mut s = path.as_os_str().to_owned();
    s.push(if k == 1 {
        ".bak".to_string()
    } else {
        format!(".bak.{k}")
    });
    PathBuf::from(s)
}

#[test]
fn an_update_of_a_file_in_another_layout_is_refused_untouched() {
    let mut rng = ChaCha8Rng::seed_from_u64(350);
    let cal = calibration(&mut rng);
    let dir = tempfile::tempdir().unwrap();
    let mut refused = 0;
    for &spec in FORMATS.iter().filter(|f| f.robot()) {
        for (owner, name) in FIXTURES {
            if owner == spec {
                continue;
            }
            let path = copy(dir.path(), name);
            let original = std::fs::read(&path).unwrap();
            let e = export::update(&cal, Some(spec), &path, &[])
                .expect_err(&format!("--format {} on {name}", spec.name()))
                .to_string();
            assert!(
                e.contains(&format!("not a {} file", spec.name()))
                    && e.contains(&format!("looks like a {} file", owner.name())),
                "{} on {name}: {e}",
                spec.name()
            );
            assert_eq!(std::fs::read(&path).unwrap(), original, "{name} untouched");
            assert!(!backup_of(&path, 1).exists(), "{name}: no backup");
            refused += 1;
        }
    }
    // Every updatable format on every fixture but its own (B-Human's joint layout has two).
    let updatable = FORMATS.iter().filter(|f| f.robot()).count();
    assert_eq!(
        refused,
        (updatable - 1) * FIXTURES.len(),
        "every foreign pair"
    );
    // From the command line: exit 1, the file named, nothing written.
    let result = dir.path().join("cal.json");
    std::fs::write(&result, serde_json::to_string(&cal.to_json()).unwrap()).unwrap();
    for (format, name) in [
        ("naoth-camera", "bhuman/cameraCalibration.cfg"),
        ("naoth-camera", "hulks/head.json"),
    ] {
        let path = copy(dir.path(), name);
        let out = naocalib()
            .arg("export")
            .arg(&result)
            .args(["--format", format, "--update"])
            .arg(&path)
            .output()
            .unwrap();
        crate::util::assert_clean_failure(&out, &["not a naoth-camera file", "nothing written"]);
        assert_eq!(
            std::fs::read(&path).unwrap(),
            std::fs::read(fixture(name)).unwrap()
        );
    }
}

#[test]
fn the_robots_original_is_never_lost_and_updates_are_idempotent() {
    let mut rng = ChaCha8Rng::seed_from_u64(351);
    let dir = tempfile::tempdir().unwrap();
    for (format, name) in FIXTURES {
        let path = copy(dir.path(), name).canonicalize().unwrap();
        let original = std::fs::read(&path).unwrap();
        let (first, second) = (calibration(&mut rng), calibration(&mut rng));
        let b1 = crate::util::updated(&first, format, &path);
        assert_eq!(b1, backup_of(&path, 1));
        let after_first = std::fs::read(&path).unwrap();
        // The same calibration again: nothing to write, no backup.
        let (_, again) = export::update(&first, Some(format), &path, &[]).unwrap();
        assert_eq!(again, Updated::Unchanged(Unchanged::AlreadyHolds), "{name}");
        assert_eq!(std::fs::read(&path).unwrap(), after_first);
        assert!(!backup_of(&path, 2).exists(), "{name}");
        // Another calibration: the original stays in FILE.bak, the first update in .bak.2.
        let b2 = crate::util::updated(&second, format, &path);
        assert_eq!(b2, backup_of(&path, 2), "{name}");
        assert_eq!(
            std::fs::read(backup_of(&path, 1)).unwrap(),
            original,
            "{name}"
        );
        assert_eq!(std::fs::read(&b2).unwrap(), after_first, "{name}");
    }
}

#[test]
fn an_update_of_corrected_angles_is_applied_once() {
    let mut rng = ChaCha8Rng::seed_from_u64(352);
    let dir = tempfile::tempdir().unwrap();
    for (format, name) in [
        (
            &export::bhuman::Joints as &dyn Format,
            "bhuman/jointCalibration.cfg",
        ),
        (&export::hulks::Body, "hulks/body.json"),
        (&export::nomadz::Joints, "nomadz/jointCalibration.cfg"),
    ] {
        let path = copy(dir.path(), name).canonicalize().unwrap();
        let mut cal = calibration(&mut rng);
        cal.angles = Some(AngleSource {
            kind: AngleKind::Corrected,
            corrected_by: Some(name.into()),
        });
        let knee = |path: &Path| {
            let (_, v) = export::import(path, Some(format)).unwrap();
            v.iter().find(|(p, _)| *p == Param::LKneePitch).unwrap().1
        };
        let before = knee(&path);
        crate::util::updated(&cal, format, &path);
        let once = std::fs::read(&path).unwrap();
        // α = −stored: stored_new = stored_old − α_est, so α_new = α_old + α_est.
        let expected = before + cal.value(Param::LKneePitch);
        assert!((knee(&path) - expected).abs() < 1e-9, "{name}");
        for _ in 0..2 {
            let (_, again) = export::update(&cal, Some(format), &path, &[]).unwrap();
            assert_eq!(
                again,
                Updated::Unchanged(Unchanged::AlreadyApplied {
                    backup: backup_of(&path, 1)
                }),
                "{name}"
            );
            assert_eq!(std::fs::read(&path).unwrap(), once, "{name}: applied once");
        }
        assert!((knee(&path) - expected).abs() < 1e-9, "{name}");
        // A new calibration of angles corrected by the updated file composes with it.
        let mut next = calibration(&mut rng);
        next.angles = cal.angles.clone();
        crate::util::updated(&next, format, &path);
        let composed = expected + next.value(Param::LKneePitch);
        assert!((knee(&path) - composed).abs() < 1e-9, "{name}");
    }
    // From the command line: the second run says so and writes nothing.
    let cli = dir.path().join("cli");
    std::fs::create_dir(&cli).unwrap();
    let path = copy(&cli, "bhuman/jointCalibration.cfg");
    let mut cal = calibration(&mut rng);
    cal.angles = Some(AngleSource {
        kind: AngleKind::Corrected,
        corrected_by: None,
    });
    let result = dir.path().join("corrected.toml");
    std::fs::write(&result, cal.to_toml()).unwrap();
    let run = || {
        naocalib()
            .arg("export")
            .arg(&result)
            .arg("--update")
            .arg(&path)
            .output()
            .unwrap()
    };
    let out = run();
    assert!(out.status.success(), "{}", stderr(&out));
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(
        said.starts_with("updated ") && !said.contains("through") && said.contains(".bak"),
        "{said}"
    );
    let once = std::fs::read(&path).unwrap();
    let out = run();
    assert!(out.status.success(), "{}", stderr(&out));
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(
        said.contains("not updated") && said.contains("already applied"),
        "{said}"
    );
    assert_eq!(std::fs::read(&path).unwrap(), once);
    assert!(!backup_of(&path, 2).exists());
}

#[test]
fn links_mode_and_owner_are_kept_and_a_read_only_file_is_refused() {
    let mut rng = ChaCha8Rng::seed_from_u64(353);
    let cal = calibration(&mut rng);
    let dir = tempfile::tempdir().unwrap();
    let format: &dyn Format = &export::bhuman::Joints;
    let name = "bhuman/jointCalibration.cfg";

    // A symbolic link: the file it points to is updated, the link stays a link.
    let shared = dir.path().join("shared");
    std::fs::create_dir(&shared).unwrap();
    let real = copy(&shared, name);
    let link = dir.path().join("jointCalibration.cfg");
    std::os::unix::fs::symlink(&real, &link).unwrap();
    let (_, updated) = export::update(&cal, Some(format), &link, &[]).unwrap();
    let Updated::Written { file, backup, .. } = updated else {
        panic!("{updated:?}")
    };
    assert_eq!(file, real.canonicalize().unwrap());
    assert!(link.symlink_metadata().unwrap().file_type().is_symlink());
    assert_ne!(
        std::fs::read(&real).unwrap(),
        std::fs::read(fixture(name)).unwrap()
    );
    assert_eq!(
        std::fs::read(&backup).unwrap(),
        std::fs::read(fixture(name)).unwrap()
    );
    // From the command line, the message names the file written through the link.
    let result = dir.path().join("cal.toml");
    std::fs::write(&result, calibration(&mut rng).to_toml()).unwrap();
    let out = naocalib()
        .arg("export")
        .arg(&result)
        .arg("--update")
        .arg(&link)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(
        said.contains(&format!("through {}", file.display())),
        "{said}"
    );
    assert!(link.symlink_metadata().unwrap().file_type().is_symlink());

    // Hard links: every name sees the update.
    let a = copy(dir.path(), name);
    let b = dir.path().join("second_name.cfg");
    std::fs::hard_link(&a, &b).unwrap();
    crate::util::updated(&cal, format, &a);
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
    assert_eq!(
        std::fs::metadata(&a).unwrap().ino(),
        std::fs::metadata(&b).unwrap().ino()
    );
    assert_ne!(
        std::fs::read(&a).unwrap(),
        std::fs::read(fixture(name)).unwrap()
    );

    // Mode and owner (the owner only where this process may give one: as root).
    let path = dir.path().join("mode.cfg");
    std::fs::copy(fixture(name), &path).unwrap();
    std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o640)).unwrap();
    let root = unsafe { libc::geteuid() } == 0;
    if root {
        std::os::unix::fs::chown(&path, Some(4321), Some(4322)).unwrap();
    }
    let before = std::fs::metadata(&path).unwrap();
    let backup = crate::util::updated(&cal, format, &path);
    for file in [&path, &backup] {
        let after = std::fs::metadata(file).unwrap();
        assert_eq!(after.mode() & 0o7777, 0o640, "{}", file.display());
        assert_eq!((after.uid(), after.gid()), (before.uid(), before.gid()));
    }
    assert_ne!(
        std::fs::metadata(&path).unwrap().ino(),
        before.ino(),
        "atomic: renamed"
    );

    // Read-only: refused, untouched, no backup.
    let ro = dir.path().join("ro.cfg");
    std::fs::copy(fixture(name), &ro).unwrap();
    std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o444)).unwrap();
    let e = export::update(&cal, Some(format), &ro, &[])
        .unwrap_err()
        .to_string();
    assert!(e.contains("read-only") && e.contains("ro.cfg"), "{e}");
    assert_eq!(
        std::fs::read(&ro).unwrap(),
        std::fs::read(fixture(name)).unwrap()
    );
    assert!(!backup_of(&ro, 1).exists());
}

#[test]
fn a_calibration_that_determines_nothing_in_the_file_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(354);
    // Only the legs estimated: nothing a camera file carries.
    let mut legs = calibration(&mut rng);
    for e in &mut legs.parameters {
        if e.param.name().contains("Cam") {
            e.std = None;
        }
    }
    for (format, name) in FIXTURES.iter().filter(|(f, _)| !f.joints()) {
        let path = copy(dir.path(), name);
        let (_, outcome) = export::update(&legs, Some(*format), &path, &[]).unwrap();
        assert_eq!(
            outcome,
            Updated::Unchanged(Unchanged::NothingDetermined),
            "{name}"
        );
        assert_eq!(
            std::fs::read(&path).unwrap(),
            std::fs::read(fixture(name)).unwrap()
        );
        assert!(!backup_of(&path, 1).exists(), "{name}: no backup");
    }
    // From the command line: an imported calibration determines nothing.
    let camera = copy(dir.path(), "nomadz/cameraCalibration.cfg");
    let imported = dir.path().join("robot.toml");
    let out = naocalib()
        .arg("import")
        .arg(&camera)
        .arg("--out")
        .arg(&imported)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let out = naocalib()
        .arg("export")
        .arg(&imported)
        .arg("--update")
        .arg(&camera)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(
        said.contains("not updated") && said.contains("determines none"),
        "{said}"
    );
    assert!(!backup_of(&camera, 1).exists());
}

#[test]
fn deeply_nested_files_are_refused_with_a_message() {
    let dir = tempfile::tempdir().unwrap();
    let depth = 200_000;
    let cfg = dir.path().join("deep_cameraCalibration.cfg");
    std::fs::write(
        &cfg,
        format!(
            "cameraRotationCorrections = {}1;{}\n",
            "{a = ".repeat(depth),
            "};".repeat(depth)
        ),
    )
    .unwrap();
    let json = dir.path().join("deep_head.json");
    std::fs::write(
        &json,
        format!(
            "{{\"correction_in_camera_bottom\": {}1{}}}",
            "[".repeat(depth),
            "]".repeat(depth)
        ),
    )
    .unwrap();
    let toml = dir.path().join("deep.toml");
    std::fs::write(
        &toml,
        format!(
            "format = \"naocalib-calibration\"\nx = {}1{}\n",
            "[".repeat(depth),
            "]".repeat(depth)
        ),
    )
    .unwrap();
    let cal = dir.path().join("cal.toml");
    let mut rng = ChaCha8Rng::seed_from_u64(355);
    std::fs::write(&cal, calibration(&mut rng).to_toml()).unwrap();
    for (file, format, needle) in [
        (&cfg, "bhuman-camera", "nested deeper than 64"),
        (&json, "hulks-head", "nested deeper than 64"),
    ] {
        let out = naocalib()
            .arg("import")
            .arg(file)
            .args(["--format", format, "--out"])
            .arg(dir.path().join("x.toml"))
            .timeout(Duration::from_secs(60))
            .output()
            .unwrap();
        crate::util::assert_clean_failure(&out, &[needle, &file.display().to_string()]);
        let out = naocalib()
            .arg("export")
            .arg(&cal)
            .args(["--format", format, "--update"])
            .arg(file)
            .timeout(Duration::from_secs(60))
            .output()
            .unwrap();
        crate::util::assert_clean_failure(&out, &[needle]);
    }
    let out = naocalib()
        .arg("export")
        .arg(&toml)
        .args(["--out"])
        .arg(dir.path().join("y.toml"))
        .timeout(Duration::from_secs(60))
        .output()
        .unwrap();
    crate::util::assert_clean_failure(&out, &["deep.toml"]);
}

#[test]
fn naocalibs_own_exports_are_recognised() {
    let mut rng = ChaCha8Rng::seed_from_u64(356);
    let cal = calibration(&mut rng);
    for &spec in FORMATS.iter().filter(|f| f.robot()) {
        let text = spec.write(&cal);
        assert_eq!(
            export::recognised(&text),
            Some(spec),
            "{}:\n{text}",
            spec.name()
        );
    }
    // And from the command line, without --format.
    let dir = tempfile::tempdir().unwrap();
    for name in ["naoth-camera", "runswift-camera", "nomadz-camera"] {
        let format = export::named(name).unwrap();
        let path = dir.path().join(format!("{name}.cfg"));
        std::fs::write(&path, format.write(&cal)).unwrap();
        let out = naocalib()
            .arg("import")
            .arg(&path)
            .arg("--out")
            .arg(dir.path().join(format!("{name}.toml")))
            .output()
            .unwrap();
        assert!(out.status.success(), "{name}: {}", stderr(&out));
        assert!(
            stderr(&out).contains(&format!("({name})")),
            "{}",
            stderr(&out)
        );
    }
}

#[test]
fn a_hulks_file_with_a_duplicate_key_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let head = dir.path().join("head.json");
    let text = std::fs::read_to_string(fixture("hulks/head.json")).unwrap();
    let twice = text.replacen(
        "\"correction_in_camera_top\"",
        "\"correction_in_camera_bottom\": [0.1, 0.1, 0.1],\n      \"correction_in_camera_top\"",
        1,
    );
    std::fs::write(&head, &twice).unwrap();
    let body = dir.path().join("body.json");
    let text = std::fs::read_to_string(fixture("hulks/body.json")).unwrap();
    let twice_body = text.replacen("{", "{\n  \"joint_calibration_offsets\": {},", 1);
    assert_ne!(twice_body, text);
    std::fs::write(&body, &twice_body).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(357);
    let cal = calibration(&mut rng);
    for (path, format) in [
        (&head, &export::hulks::Head as &dyn Format),
        (&body, &export::hulks::Body),
    ] {
        let e = export::import(path, Some(format)).unwrap_err().to_string();
        assert!(e.contains("given twice") && e.contains("line "), "{e}");
        let e = export::update(&cal, Some(format), path, &[])
            .unwrap_err()
            .to_string();
        assert!(e.contains("given twice"), "{e}");
    }
}

#[test]
fn an_implausible_joint_play_is_refused_and_start_from_never_moves_a_joint_by_it() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(fixture("nomadz/jointCalibration.cfg")).unwrap();
    let (at, _) = text.match_indices("lKneePitch").next().unwrap();
    let play_at = at + text[at..].find("jointPlay = ").unwrap() + "jointPlay = ".len();
    let play_end = play_at + text[play_at..].find(';').unwrap();
    for bad in ["-3", "50"] {
        let path = dir.path().join(format!("joints{bad}.cfg"));
        std::fs::write(
            &path,
            format!("{}{bad}{}", &text[..play_at], &text[play_end..]),
        )
        .unwrap();
        let out = naocalib()
            .arg("import")
            .arg(&path)
            .arg("--out")
            .arg(dir.path().join("robot.toml"))
            .output()
            .unwrap();
        crate::util::assert_clean_failure(
            &out,
            &[
                "lKneePitch.jointPlay",
                &format!("= {bad} deg"),
                "0 … 5",
                "line ",
            ],
        );
        assert!(!dir.path().join("robot.toml").exists());
    }
    // A calibration holding such a value (edited by hand) is no start: refused, no solve.
    let data = dir.path().join("robot");
    crate::util::simulate_small(&data, 357);
    let mut rng = ChaCha8Rng::seed_from_u64(358);
    let mut cal = calibration(&mut rng);
    for e in &mut cal.parameters {
        if e.param == Param::LKneePitchPlay {
            (e.value, e.fixed, e.std) = (-3.0, true, Some(0.0));
        }
    }
    let start = dir.path().join("start.toml");
    std::fs::write(&start, cal.to_toml()).unwrap();
    let out = naocalib()
        .arg("solve")
        .arg(&data)
        .arg("--start-from")
        .arg(&start)
        .output()
        .unwrap();
    crate::util::assert_clean_failure(&out, &["LKneePitchPlay = -3", "start.toml", "0 … 5"]);
    assert!(out.stdout.is_empty(), "no result");
}

#[test]
fn a_byte_order_mark_is_accepted_and_kept() {
    let dir = tempfile::tempdir().unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(359);
    let cal = calibration(&mut rng);
    for (format, name) in FIXTURES {
        let path = dir.path().join(name.replace('/', "_"));
        let text = std::fs::read_to_string(fixture(name)).unwrap();
        std::fs::write(&path, format!("\u{feff}{text}")).unwrap();
        let (recognised, values) = export::import(&path, None).unwrap();
        assert_eq!(recognised, format, "{name}");
        assert_eq!(
            values,
            export::import(&fixture(name), Some(format)).unwrap().1
        );
        crate::util::updated(&cal, format, &path);
        let updated = std::fs::read_to_string(&path).unwrap();
        assert!(updated.starts_with('\u{feff}'), "{name}: the mark is kept");
        assert!(!updated[3..].contains('\u{feff}'));
    }
}

#[test]
fn a_fifo_is_refused_without_hanging() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("cameraCalibration.cfg");
    let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o644) }, 0);
    let mut rng = ChaCha8Rng::seed_from_u64(360);
    let cal = dir.path().join("cal.toml");
    std::fs::write(&cal, calibration(&mut rng).to_toml()).unwrap();
    let x = dir.path().join("x.toml");
    let y = dir.path().join("y.toml");
    let runs: [[&std::ffi::OsStr; 4]; 3] = [
        [
            "import".as_ref(),
            fifo.as_ref(),
            "--out".as_ref(),
            x.as_ref(),
        ],
        [
            "export".as_ref(),
            cal.as_ref(),
            "--update".as_ref(),
            fifo.as_ref(),
        ],
        [
            "export".as_ref(),
            fifo.as_ref(),
            "--out".as_ref(),
            y.as_ref(),
        ],
    ];
    for args in runs {
        let out = naocalib()
            .args(args)
            .timeout(Duration::from_secs(30))
            .output()
            .unwrap();
        crate::util::assert_clean_failure(&out, &["not a regular file", "cameraCalibration.cfg"]);
    }
}
