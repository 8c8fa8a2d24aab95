//! Detection on robots as they are: lower-camera tilt corrections of −3° to −8°,
//! roll ±3°, leg offsets ±2°, hidden from detection. Every fully visible board is found,
//! no vertex gets a wrong (row, col), and `solve --detect`'s data recover the truth.

use std::path::Path;

use crate::util::solve;
use naocalib::dataset::{Corner, Dataset};
use naocalib::detect::{self, DetectOptions, ImageResult, Outcome};
use naocalib::model::{FixedSet, Model, PARAMETER_COUNT, Param, Side, Unit};
use naocalib::sim::render::{ImageOutput, RenderOptions};
use naocalib::sim::{SimOptions, simulate};
use naocalib::solve::{Problem, backend};

/// A robot as SPL teams' files describe them: lower-camera tilt `pitch` and roll `roll`
/// (deg), every leg joint off by `legs` (deg) with alternating signs, small board offsets.
pub fn robot(pitch: f64, roll: f64, legs: f64) -> [f64; PARAMETER_COUNT] {
    let mut t = [0.0; PARAMETER_COUNT];
    let mut set = |p: Param, v: f64| t[p.index()] = p.unit().from_report(v);
    set(Param::CamPitch, pitch);
    set(Param::CamRoll, roll);
    set(Param::CamYaw, 0.7);
    use Param::*;
    let joints = [Side::Left, Side::Right]
        .into_iter()
        .flat_map(Side::leg_joints)
        .map(|j| j.offset());
    for (k, p) in joints.enumerate() {
        let sign = if k % 3 == 1 { -1.0 } else { 1.0 };
        set(p, sign * legs * (0.5 + 0.5 * ((k % 4) as f64 / 3.0)));
    }
    set(LBoardRotZ, 0.4);
    set(RBoardRotZ, -0.3);
    set(LBoardTransX, 1.2);
    set(RBoardTransY, -0.8);
    t
}

/// Renders `stances × heads × 2` captures of the robot `truth` into `dir` (blur σ 0.8 px,
/// grey noise σ 2, clutter), optionally with boards near and across the border.
pub fn rendered(
    dir: &Path,
    truth: [f64; PARAMETER_COUNT],
    seed: u64,
    stances: usize,
    heads: usize,
    near_border: bool,
) -> Dataset {
    let options = SimOptions {
        seed,
        stances,
        heads,
        px_noise: 0.0,
        joint_noise: 0.0,
        truth: Some(truth),
        near_border,
        images: Some(ImageOutput {
            dir: dir.to_path_buf(),
            options: RenderOptions {
                blur: 0.8,
                noise: 2.0,
                seed,
                ..RenderOptions::default()
            },
            force: false,
        }),
        ..SimOptions::default()
    };
    let mut dataset = simulate(&Model::default(), &options).expect("simulated");
    dataset.dir = dir.to_path_buf();
    dataset
}

/// What detection made of a rendered set, against its truth.
#[derive(Debug, Default, Clone, Copy)]
pub struct Score {
    /// Boards with every vertex at least 3 px inside the image, and how many were found.
    pub full: usize,
    pub full_found: usize,
    /// Vertices at least 3 px inside the image, and how many were found.
    pub inside: usize,
    pub inside_found: usize,
    /// Vertices found, and how many of them are more than 1.5 px from the truth of their
    /// (row, col) (a wrong number).
    pub found: usize,
    pub wrong: usize,
}

impl std::ops::AddAssign for Score {
    fn add_assign(&mut self, o: Score) {
        self.full += o.full;
        self.full_found += o.full_found;
        self.inside += o.inside;
        self.inside_found += o.inside_found;
        self.found += o.found;
        self.wrong += o.wrong;
    }
}

/// Scores `results` against the dataset's true corners (which detection never saw).
pub fn score(dataset: &Dataset, results: &[ImageResult]) -> Score {
    let model = &dataset.model;
    let truth = dataset.corners_by_capture();
    let mut s = Score::default();
    let grid = model.board.vertices().count();
    for r in results {
        let expected: &[Corner] = truth.get(&r.capture).map(|v| v.as_slice()).unwrap_or(&[]);
        let inside: Vec<&Corner> = expected
            .iter()
            .filter(|t| model.camera.contains(t.pixel, 3.0))
            .collect();
        let got: &[Corner] = match &r.outcome {
            Outcome::Found { corners, .. } => corners,
            _ => &[],
        };
        if inside.len() == grid {
            s.full += 1;
            if got.is_empty() {
                eprintln!("fully visible board not found: {r}");
            } else {
                s.full_found += 1;
            }
        }
        s.inside += inside.len();
        s.inside_found += inside
            .iter()
            .filter(|t| got.iter().any(|c| c.vertex == t.vertex))
            .count();
        for c in got {
            s.found += 1;
            let ok = expected.iter().any(|t| {
                t.vertex == c.vertex
                    && (c.pixel[0] - t.pixel[0]).hypot(c.pixel[1] - t.pixel[1]) < 1.5
            });
            if !ok {
                s.wrong += 1;
                eprintln!("WRONG: {r}: vertex {:?} at {:?}", c.vertex, c.pixel);
            }
        }
    }
    s
}

#[test]
fn tilted_robots_every_visible_board_found_none_misnumbered() {
    let tmp = tempfile::tempdir().unwrap();
    let mut total = Score::default();
    for (k, (pitch, roll, legs)) in [(-3.0, 3.0, 2.0), (-5.0, -3.0, -2.0), (-8.0, 3.0, 2.0)]
        .into_iter()
        .enumerate()
    {
        let seed = 250 + k as u64;
        let dataset = rendered(
            &tmp.path().join(k.to_string()),
            robot(pitch, roll, legs),
            seed,
            8,
            2,
            false,
        );
        let results = detect::detect_dataset(&dataset, &DetectOptions::default(), &|_| {});
        let s = score(&dataset, &results);
        eprintln!("tilt {pitch}°, roll {roll}°, legs {legs}°: {s:?}");
        total += s;
    }
    assert_eq!(total.wrong, 0, "{total:?}");
    assert!(total.full >= 80, "{total:?}");
    assert!(
        total.full_found as f64 >= 0.99 * total.full as f64,
        "{total:?}"
    );
}

#[test]
fn tilted_robots_near_the_border_none_misnumbered() {
    let tmp = tempfile::tempdir().unwrap();
    let mut total = Score::default();
    for (k, (pitch, roll, legs)) in [(-5.5, 2.0, 1.5), (-8.0, -3.0, -2.0)]
        .into_iter()
        .enumerate()
    {
        let seed = 260 + k as u64;
        let dataset = rendered(
            &tmp.path().join(k.to_string()),
            robot(pitch, roll, legs),
            seed,
            6,
            3,
            true,
        );
        let results = detect::detect_dataset(&dataset, &DetectOptions::default(), &|_| {});
        let s = score(&dataset, &results);
        eprintln!("near the border, tilt {pitch}°: {s:?}");
        total += s;
    }
    assert_eq!(total.wrong, 0, "{total:?}");
    assert!(
        total.inside_found as f64 >= 0.95 * total.inside as f64,
        "{total:?}"
    );
}

#[test]
fn solve_from_detected_tilted_robot_recovers_the_truth() {
    let tmp = tempfile::tempdir().unwrap();
    let truth = robot(-7.2, -2.5, 2.0);
    let mut dataset = rendered(tmp.path(), truth, 271, 24, 3, false);
    let results = detect::detect_dataset(&dataset, &DetectOptions::default(), &|_| {});
    let s = score(&dataset, &results);
    eprintln!("tilt −7.2°: {s:?}");
    assert_eq!(s.wrong, 0, "{s:?}");
    dataset.corners = detect::corners(&results);
    let problem = Problem::from_dataset(&dataset, FixedSet::default()).unwrap();
    let solver = backend(naocalib::solve::backend_names()[0], false).unwrap();
    let solution = solve(&problem, solver.as_ref()).unwrap();
    assert!(solution.is_calibration());
    for p in Param::ALL.iter().take(21) {
        let est = solution.report_value(*p);
        let tru = p.unit().to_report(truth[p.index()]);
        let tol = match p.unit() {
            Unit::Deg => 0.03,
            _ => 0.15,
        };
        assert!(
            (est - tru).abs() < tol,
            "{}: estimated {est:.4}, true {tru:.4} (σ {:.4})",
            p.name(),
            solution.report_std(*p)
        );
    }
}

/// Every board OpenCV's chessboard finder gets with its exhaustive settings (whole image,
/// no fast check) in the images of `dataset` is found; returns (boards OpenCV got, found).
fn opencv_boards_are_found(dataset: &Dataset) -> (usize, usize) {
    let results = detect::detect_dataset(dataset, &DetectOptions::default(), &|_| {});
    let s = score(dataset, &results);
    assert_eq!(s.wrong, 0, "{s:?}");
    let grid = detect::board_grid(&dataset.model);
    let (mut got, mut found) = (0, 0);
    for (capture, r) in dataset.captures.iter().zip(&results) {
        let path = dataset.dir.join(capture.image.as_ref().unwrap());
        let grey = detect::read_grey(&path).unwrap();
        let opencv =
            detect::find::find_board_with(&grey, grid, None, detect::cv::Search::Exhaustive)
                .unwrap();
        if opencv.is_some() {
            got += 1;
            match &r.outcome {
                Outcome::Found { corners, .. } if corners.len() >= 20 => found += 1,
                _ => eprintln!("OpenCV finds the board, naocalib does not: {r}"),
            }
        }
    }
    (got, found)
}

#[test]
fn every_board_opencvs_exhaustive_finder_gets_is_found() {
    let tmp = tempfile::tempdir().unwrap();
    // Random robots of the simulator (camera ±3°, joints σ 1°), ordinary 640×480 images.
    for seed in [281, 282] {
        let dir = tmp.path().join(seed.to_string());
        let options = SimOptions {
            seed,
            stances: 8,
            heads: 3,
            px_noise: 0.0,
            images: Some(ImageOutput {
                dir: dir.clone(),
                options: RenderOptions {
                    seed,
                    ..RenderOptions::default()
                },
                force: false,
            }),
            ..SimOptions::default()
        };
        let mut dataset = simulate(&Model::default(), &options).unwrap();
        dataset.dir = dir;
        let (got, found) = opencv_boards_are_found(&dataset);
        eprintln!("640×480 seed {seed}: OpenCV (exhaustive) {got}, naocalib {found} of them");
        assert!(got >= 40, "{got}");
        assert_eq!(found, got);
    }
}

#[test]
fn every_board_opencvs_exhaustive_finder_gets_is_found_at_1280x960() {
    let tmp = tempfile::tempdir().unwrap();
    let model = Model {
        camera: naocalib::sim::camera::CameraPreset::V6Hd.camera(),
        ..Model::default()
    };
    let options = SimOptions {
        seed: 291,
        stances: 4,
        heads: 2,
        px_noise: 0.0,
        truth: Some(robot(-5.0, 2.0, 1.5)),
        images: Some(ImageOutput {
            dir: tmp.path().to_path_buf(),
            options: RenderOptions {
                seed: 291,
                ..RenderOptions::default()
            },
            force: false,
        }),
        ..SimOptions::default()
    };
    let mut dataset = simulate(&model, &options).unwrap();
    dataset.dir = tmp.path().to_path_buf();
    let (got, found) = opencv_boards_are_found(&dataset);
    eprintln!("1280×960, tilt −5°: OpenCV (exhaustive) {got}, naocalib {found} of them");
    assert!(got >= 10, "{got}");
    assert_eq!(found, got);
}

/// `solve --detect`'s guard: a capture numbered one row and one column off (the issue's
/// failure: 15 vertices) stands out after the fit and is named; clean data name none.
#[test]
fn the_guard_names_a_capture_numbered_wrongly() {
    let options = SimOptions {
        seed: 301,
        px_noise: 0.1,
        truth: Some(robot(-5.5, 1.0, 1.0)),
        ..SimOptions::default()
    };
    let mut dataset = simulate(&Model::default(), &options).unwrap();
    let solver = backend(naocalib::solve::backend_names()[0], false).unwrap();
    let fit = |dataset: &Dataset| {
        let problem = Problem::from_dataset(dataset, FixedSet::default()).unwrap();
        solve(&problem, solver.as_ref()).unwrap()
    };
    assert!(detect::guard::suspects(&fit(&dataset)).is_empty());
    let bad = dataset.captures[17].id;
    dataset
        .corners
        .retain(|c| c.capture != bad || (c.vertex.row + 1 < 4 && c.vertex.col + 1 < 6));
    for c in dataset.corners.iter_mut().filter(|c| c.capture == bad) {
        c.vertex.row += 1;
        c.vertex.col += 1;
    }
    let suspects = detect::guard::suspects(&fit(&dataset));
    eprintln!("{suspects:?}");
    assert_eq!(suspects.len(), 1, "{suspects:?}");
    assert_eq!(suspects[0].capture, bad);
    assert!(suspects[0].to_string().contains(&format!("capture {bad}")));
}
