//! Sets of files replaced all or none: a process killed at any step of writing a set that
//! replaces an earlier one (`sandal OUT --force`, `export --dir X --force`) leaves the old
//! set or the new one, never a mix a robot or a maker could take for one set. The writer's
//! fault-injection hook (`NAOCALIB_KILL_AFTER_STEP=k`, [`naocalib::output::KILL_AFTER_STEP`])
//! kills the process after its k-th step; each test kills at every k until a run completes.

use assert_cmd::Command;
use std::collections::BTreeMap;
use std::os::unix::process::ExitStatusExt;
use std::path::{Path, PathBuf};

use naocalib::export::{Entry, Posture};
use naocalib::model::Param;
use naocalib::output::KILL_AFTER_STEP;

use crate::util::naocalib;

/// Every file under `dir` (relative path → content).
fn snapshot(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    fn walk(root: &Path, rel: &Path, out: &mut BTreeMap<PathBuf, Vec<u8>>) {
        for entry in std::fs::read_dir(root.join(rel)).unwrap() {
            let entry = entry.unwrap();
            let path = rel.join(entry.file_name());
            if entry.file_type().unwrap().is_dir() {
                walk(root, &path, out);
            } else {
                out.insert(path.clone(), std::fs::read(root.join(&path)).unwrap());
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(dir, Path::new(""), &mut out);
    out
}

/// Runs `command()` (which replaces the set of files in `dir`) killed after step k = 1,
/// 2, … until a run completes; after every kill `dir` must hold exactly the set before,
/// and after the run that completes the set written then. Returns the kills.
fn killed_at_every_step(command: impl Fn() -> Command, dir: &Path) -> usize {
    let before = snapshot(dir);
    let mut after_kills: Vec<BTreeMap<PathBuf, Vec<u8>>> = Vec::new();
    for k in 1..200 {
        let run = command()
            .env(KILL_AFTER_STEP, k.to_string())
            .output()
            .unwrap();
        if run.status.success() {
            let after = snapshot(dir);
            assert_ne!(after, before, "the completed run changed nothing");
            for (k, seen) in after_kills.iter().enumerate() {
                assert!(
                    *seen == before || *seen == after,
                    "killed after step {}: a mix of the old set and the new (files unlike \
                     the new set's: {:?})",
                    k + 1,
                    seen.keys()
                        .filter(|p| after.get(*p) != seen.get(*p))
                        .collect::<Vec<_>>()
                );
            }
            // A last run without the hook writes the same set (the kills left nothing in the way).
            let run = command().output().unwrap();
            assert!(
                run.status.success(),
                "{}",
                String::from_utf8_lossy(&run.stderr)
            );
            assert_eq!(snapshot(dir), after);
            return after_kills.len();
        }
        assert_eq!(
            run.status.signal(),
            Some(libc::SIGKILL),
            "step {k}: {}",
            String::from_utf8_lossy(&run.stderr)
        );
        after_kills.push(snapshot(dir));
    }
    panic!("no run completed");
}

/// `sandal OUT --force` over the sandals of another board, killed at every step: OUT holds
/// the left and right files of one board, never the left of one beside the right of the
/// other.
#[test]
fn sandal_force_is_all_or_none_under_a_kill_at_every_step() {
    let dir = tempfile::tempdir().unwrap();
    let config = dir.path().join("dataset.toml");
    std::fs::write(
        &config,
        "[camera]\nwidth = 640\nheight = 480\nfx = 562.5\nfy = 562.5\ncx = 320\ncy = 240\n\
         [board]\nsquares_x = 7\nsquares_y = 5\nsquare_mm = 20.0\n",
    )
    .unwrap();
    let out = dir.path().join("sandals");
    let first = naocalib()
        .arg("sandal")
        .arg(&out)
        .arg("--config")
        .arg(&config)
        .output()
        .unwrap();
    assert!(first.status.success());
    // A file of the maker's own beside the set stays.
    std::fs::write(out.join("notes.txt"), b"mine").unwrap();
    let kills = killed_at_every_step(
        || {
            let mut c = naocalib();
            c.arg("sandal").arg(&out).arg("--force");
            c
        },
        &out,
    );
    assert!(kills >= 2, "{kills} steps");
    assert_eq!(std::fs::read(out.join("notes.txt")).unwrap(), b"mine");
}

/// A calibration with every angle at `deg` and every length at `deg` mm.
fn calibration_file(dir: &Path, name: &str, deg: f64) -> PathBuf {
    let cal = crate::util::converged_calibration(Posture::Standing, |p| Entry {
        param: p,
        value: if p.name().ends_with("Play") { 0.5 } else { deg },
        std: Some(0.05),
        fixed: matches!(p, Param::HeadYaw | Param::HeadPitch),
    });
    let path = dir.join(name);
    std::fs::write(&path, cal.to_toml()).unwrap();
    path
}

/// `export RESULT --dir X --force` over an earlier export, killed at every step: X holds
/// one calibration's team files, never a new `cameraCalibration.cfg` beside an old
/// `jointCalibration.cfg`.
#[test]
fn export_dir_force_is_all_or_none_under_a_kill_at_every_step() {
    let dir = tempfile::tempdir().unwrap();
    let old = calibration_file(dir.path(), "old.toml", 0.5);
    let new = calibration_file(dir.path(), "new.toml", 0.25);
    let out = dir.path().join("robot");
    let first = naocalib()
        .arg("export")
        .arg(&old)
        .arg("--dir")
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        first.status.success(),
        "{}",
        String::from_utf8_lossy(&first.stderr)
    );
    let kills = killed_at_every_step(
        || {
            let mut c = naocalib();
            c.arg("export")
                .arg(&new)
                .arg("--dir")
                .arg(&out)
                .arg("--force");
            c
        },
        &out,
    );
    assert!(kills >= 2, "{kills} steps");
}
