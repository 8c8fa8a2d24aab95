//! Pictures turned by 180° (a camera's sensor flip not as the camera needs): detection says
//! so for that camera, and `solve --detect` gives no calibration from them, naming the
//! camera and the flip; upright pictures of robots with offsets as the teams' files show
//! them are never called turned. The pictures are rendered by `naocalib simulate
//! --images` and turned here; the robots' truth is removed before anything reads the
//! dataset.

use std::path::Path;

use crate::util::{naocalib, read_grey_png, stderr, write_truth};
use naocalib::dataset::Dataset;
use naocalib::model::{CameraId, PARAMETER_COUNT, Param, ParamGroup};

/// A robot as the teams' files show its worst: upper camera pitch −10°, lower −8°, every
/// leg offset ±2°, head offsets and the upper camera's roll as large as seen.
fn worst_robot() -> [f64; PARAMETER_COUNT] {
    let mut t = [0.0; PARAMETER_COUNT];
    let deg = f64::to_radians;
    for (p, v) in [
        (Param::UpperCamPitch, -10.0),
        (Param::UpperCamRoll, 2.5),
        (Param::UpperCamYaw, -2.0),
        (Param::CamPitch, -8.0),
        (Param::CamYaw, 2.0),
        (Param::CamRoll, -2.0),
        (Param::HeadYaw, 5.0),
        (Param::HeadPitch, -4.0),
    ] {
        t[p.index()] = deg(v);
    }
    for (k, p) in Param::ALL
        .into_iter()
        .filter(|p| matches!(p.group(), ParamGroup::LeftLeg | ParamGroup::RightLeg))
        .enumerate()
    {
        t[p.index()] = deg(if k % 3 == 1 { -2.0 } else { 2.0 });
    }
    t
}

/// Renders a small two-camera dataset into `dir` (`how`: `--team-offsets` or `--truth
/// FILE`), and removes its truth.
fn render(dir: &Path, seed: u64, how: &[&str]) {
    render_upper(dir, seed, how, 2, 2);
}

/// [`render`] with `upper` upper stances and `heads` head postures, on the paper's board
/// (the seeds' counts of turned pictures named were drawn for it).
fn render_upper(dir: &Path, seed: u64, how: &[&str], upper: usize, heads: usize) {
    let out = naocalib()
        .args([
            "simulate",
            "--images",
            "--stances",
            "2",
            "--upper-stances",
            &upper.to_string(),
        ])
        .args(["--heads", &heads.to_string(), "--seed", &seed.to_string()])
        .args(how)
        .arg("--board")
        .arg(crate::util::paper_board())
        .arg(dir)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    std::fs::remove_file(dir.join(naocalib::dataset::TRUTH_TOML)).unwrap();
}

/// Turns every picture of `camera` in the dataset `dir` by 180°.
fn turn(dir: &Path, camera: CameraId) {
    turn_some(dir, |c| c.camera == camera);
}

/// Turns the pictures of the captures `which` says by 180°.
fn turn_some(dir: &Path, which: impl Fn(&naocalib::dataset::Capture) -> bool) {
    let dataset = Dataset::load_without_corners(dir).unwrap();
    for c in dataset.captures.iter().filter(|c| which(c)) {
        let path = dir.join(c.image.as_ref().unwrap());
        let mut picture = read_grey_png(&path);
        picture.pixels.reverse();
        std::fs::write(&path, picture.to_png().unwrap()).unwrap();
    }
}

/// Copies the dataset `from` into `to`.
fn copy(from: &Path, to: &Path) {
    std::fs::create_dir_all(to.join("images")).unwrap();
    for entry in walk(from) {
        let rel = entry.strip_prefix(from).unwrap();
        std::fs::copy(&entry, to.join(rel)).unwrap();
    }
}

/// The files under `dir`.
fn walk(dir: &Path) -> Vec<std::path::PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            out.extend(walk(&p));
        } else {
            out.push(p);
        }
    }
    out
}

#[test]
fn pictures_turned_by_180_give_no_calibration_and_name_the_camera_and_its_flip() {
    let tmp = tempfile::tempdir().unwrap();
    let truth = tmp.path().join("worst.toml");
    write_truth(&truth, &worst_robot());
    let truth = truth.to_str().unwrap().to_string();
    // The worst robot's upper pictures turned; a team-offsets robot's each camera's.
    let robots: [(u64, Vec<&str>, &[CameraId]); 2] = [
        (3, vec!["--truth", &truth], &[CameraId::Upper]),
        (
            5,
            vec!["--team-offsets"],
            &[CameraId::Lower, CameraId::Upper],
        ),
    ];
    for (seed, how, cameras) in robots {
        let upright = tmp.path().join(format!("upright-{seed}"));
        render(&upright, seed, &how);
        // Upright: never called turned; a calibration.
        let out = naocalib()
            .args(["solve", "--detect"])
            .arg(&upright)
            .output()
            .unwrap();
        let err = stderr(&out);
        assert!(out.status.success(), "seed {seed}: {err}");
        assert!(!err.contains("turned"), "seed {seed}: {err}");
        assert!(err.contains("0 not found"), "seed {seed}: {err}");

        for &camera in cameras {
            let turned = tmp.path().join(format!("{}-turned-{seed}", camera.name()));
            copy(&upright, &turned);
            turn(&turned, camera);
            // solve --detect: no calibration, the camera and its flip named.
            let out = naocalib()
                .args(["solve", "--detect"])
                .arg(&turned)
                .output()
                .unwrap();
            let err = stderr(&out);
            assert_eq!(out.status.code(), Some(1), "seed {seed}, {camera:?}: {err}");
            assert!(out.stdout.is_empty(), "a calibration was given");
            let (flip, table) = match camera {
                CameraId::Upper => ("flip = true", "[upper_camera]"),
                CameraId::Lower => ("flip = false", "[camera]"),
            };
            let the = format!("the {} camera's pictures are turned by 180°", camera.name());
            for needle in [
                the.as_str(),
                flip,
                table,
                "selectors 12 and 13",
                "no calibration",
            ] {
                assert!(err.contains(needle), "seed {seed}: {needle}: {err}");
            }
            let other = match camera {
                CameraId::Upper => "the lower camera's pictures",
                CameraId::Lower => "the upper camera's pictures",
            };
            assert!(!err.contains(other), "{err}");
            // detect: says so per image and for the camera, writes none of its vertices.
            if seed == 3 {
                let out = naocalib().arg("detect").arg(&turned).output().unwrap();
                let err = stderr(&out);
                assert_eq!(out.status.code(), Some(2), "{err}");
                assert!(
                    err.contains("not used: the upper camera's pictures are turned"),
                    "{err}"
                );
                assert!(err.contains(&the) && err.contains(flip), "{err}");
                let dataset = Dataset::load(&turned).unwrap();
                let upper: Vec<u64> = dataset
                    .captures
                    .iter()
                    .filter(|c| c.camera == CameraId::Upper)
                    .map(|c| c.id)
                    .collect();
                assert!(!dataset.corners.is_empty());
                assert!(dataset.corners.iter().all(|c| !upper.contains(&c.capture)));
            }
        }
    }
}

/// The upper captures of the dataset at `dir`.
fn upper_captures(dir: &Path) -> Vec<u64> {
    Dataset::load_without_corners(dir)
        .unwrap()
        .captures
        .iter()
        .filter(|c| c.camera == CameraId::Upper)
        .map(|c| c.id)
        .collect()
}

/// Three of sixteen upper pictures turned by 180° among upright ones: `detect` judges each
/// picture on its own — names the turned ones (not the upright), leaves their vertices out
/// of corners.csv — and the camera is not called turned. Two upper pictures, both turned:
/// each says whether it is turned cannot be judged; none says the turn was ruled out.
#[test]
fn each_picture_is_judged_on_its_own_and_too_few_boards_are_said_so() {
    let tmp = tempfile::tempdir().unwrap();
    let many = tmp.path().join("many");
    render_upper(&many, 5, &["--team-offsets"], 4, 2);
    let upper = upper_captures(&many);
    assert_eq!(upper.len(), 16);
    let turned: Vec<u64> = upper.iter().copied().step_by(5).take(3).collect();
    turn_some(&many, |c| turned.contains(&c.id));
    let out = naocalib().arg("detect").arg(&many).output().unwrap();
    let err = stderr(&out);
    assert!(out.status.success(), "{err}");
    assert!(!err.contains("ruled out"), "{err}");
    assert!(!err.contains("camera's pictures are turned"), "{err}");
    let named: Vec<u64> = err
        .lines()
        .filter(|l| l.contains("the picture is turned by 180°"))
        .filter_map(|l| l.strip_prefix("capture ")?.split(' ').next()?.parse().ok())
        .collect();
    assert!(
        named.iter().all(|id| turned.contains(id)),
        "{named:?}: {err}"
    );
    assert!(named.len() >= 2, "{named:?} of {turned:?}: {err}");
    let dataset = Dataset::load(&many).unwrap();
    assert!(dataset.corners.iter().all(|c| !named.contains(&c.capture)));
    assert!(
        err.contains("not used: their pictures on their own are turned"),
        "{err}"
    );

    let few = tmp.path().join("few");
    render_upper(&few, 3, &["--team-offsets"], 1, 1);
    let upper = upper_captures(&few);
    assert_eq!(upper.len(), 2);
    turn_some(&few, |c| c.camera == CameraId::Upper);
    let out = naocalib().arg("detect").arg(&few).output().unwrap();
    let err = stderr(&out);
    assert!(!err.contains("ruled out"), "{err}");
    for id in upper {
        let line = err
            .lines()
            .find(|l| l.starts_with(&format!("capture {id} ")))
            .unwrap_or_else(|| panic!("capture {id}: {err}"));
        assert!(
            !line.contains("found") || line.contains("cannot be judged"),
            "{line}"
        );
    }
    assert!(err.contains("cannot be judged"), "{err}");
}
