//! Pictures turned by 180°: whether a camera's boards are where the model puts them, or
//! only where it puts them with the pictures turned back (the sensor's flip not as the
//! camera needs it: the V6's upper camera gives its picture turned unless both flips of
//! its sensor, UVC extension unit 3 selectors 12 and 13, are set).
//!
//! Turning a picture by 180° about its centre is rolling the camera by 180° about its
//! optical axis: every board of the camera's pictures lies mirrored through the image
//! centre, and tilted the other way. The 7 × 5 pattern looks the same turned by 180°, so
//! detection finds and numbers a board in a turned picture as readily as in an upright
//! one (near the image centre, at nearly the same vertices); what gives the turn away is
//! the camera's boards together — where they lie and which side of each is near. Per
//! camera, two hypotheses are fitted over all its boards, each with the camera's three
//! rotation offsets and the legs' joint offsets free from the prediction (the rest held
//! there): the pictures as taken ("upright"), and the pictures turned back (every vertex
//! mirrored through the image centre, the pattern's numbering turned with it when the
//! pattern looks the same turned). A camera's pictures are turned when the turned
//! hypothesis explains its boards far better: [`RATIO`] times smaller RMS, the upright
//! one leaving more than [`MIN_UPRIGHT_PX`] and the turned one turning the camera by at
//! most [`MAX_FIT_DEG`] — a margin that the offsets real robots carry (legs up to 2°,
//! camera pitch corrections to −10°, head and board offsets) stay far from on upright
//! pictures (`tests` over simulated robots).
//!
//! Then each picture on its own ([`judge_pictures`]): a board that fits turned back far
//! better than as taken, the model fitted to its camera's other boards, is named and left
//! out; a camera with fewer than [`MIN_BOARDS`] boards cannot be judged, and says so.

mod fit;
pub mod verdict;

pub use verdict::{
    MAX_BOARDS, MAX_FIT_DEG, MIN_BOARDS, MIN_UPRIGHT_PX, PictureTurn, RATIO, Turned,
};

use fit::{Seen, fit, fit_params, residuals, rms, turn_back};

use super::outcome::{ImageResult, Outcome};
use crate::dataset::Dataset;
use crate::model::{CameraId, PARAMETER_COUNT};

/// Both hypotheses for every camera with boards in `results` (what detection found in
/// `dataset`), fitted from the prediction `params`; in camera order.
pub fn judge(
    dataset: &Dataset,
    results: &[ImageResult],
    params: &[f64; PARAMETER_COUNT],
) -> Vec<Turned> {
    let model = &dataset.model;
    let by_id: std::collections::HashMap<u64, &crate::dataset::Capture> =
        dataset.captures.iter().map(|c| (c.id, c)).collect();
    let mut out = Vec::new();
    for camera in CameraId::ALL {
        let upright: Vec<Seen> = results
            .iter()
            .filter_map(|r| {
                let Outcome::Found { corners, .. } = &r.outcome else {
                    return None;
                };
                let capture = by_id.get(&r.capture).filter(|c| c.camera == camera)?;
                Some(Seen {
                    chains: model.chains_for(camera, capture.side, &capture.joints),
                    vertices: corners.iter().map(|c| (c.vertex, c.pixel)).collect(),
                })
            })
            .collect();
        if upright.is_empty() {
            continue;
        }
        let boards = upright.len();
        // At most [`MAX_BOARDS`] of them, spread over the captures: the cost stays bounded.
        let upright: Vec<Seen> = if boards > MAX_BOARDS {
            let keep: Vec<usize> = (0..MAX_BOARDS).map(|k| k * boards / MAX_BOARDS).collect();
            upright
                .into_iter()
                .enumerate()
                .filter(|(i, _)| keep.contains(i))
                .map(|(_, s)| s)
                .collect()
        } else {
            upright
        };
        let turned: Vec<Seen> = upright
            .iter()
            .map(|s| turn_back(model, camera, s, params))
            .collect();
        let (upright_px, _) = fit(model, camera, &upright, params);
        let (turned_px, turned_deg) = fit(model, camera, &turned, params);
        out.push(Turned {
            camera,
            boards,
            upright_px,
            turned_px,
            turned_deg,
            width: model.intrinsics(camera).width,
        });
    }
    out
}

/// The cameras whose pictures [`judge`] calls turned.
pub fn turned_cameras(
    dataset: &Dataset,
    results: &[ImageResult],
    params: &[f64; PARAMETER_COUNT],
) -> Vec<Turned> {
    judge(dataset, results, params)
        .into_iter()
        .filter(Turned::is_turned)
        .collect()
}

/// How many times a board's RMS as taken must exceed its RMS turned back for its picture
/// to be called turned on its own, the model fitted to its camera's other boards (upright
/// boards of simulated robots with offsets as the teams' files show them stay below 1,
/// turned ones near the image centre, where both hypotheses are close, reach 2.6: `tests`).
pub const PICTURE_RATIO: f64 = 2.0;

/// Rounds of the per-picture judgement: the boards called turned are left out of the fit
/// and the rest judged again.
const PICTURE_ROUNDS: usize = 3;

/// Each picture with a board judged on its own, per camera not judged turned as a whole
/// (those are [`turned_cameras`]): the model fitted to the camera's boards as taken
/// (camera rotation and leg offsets free from the prediction `params`, the boards already
/// called turned left out), each board is turned when it fits turned back by 180°
/// [`PICTURE_RATIO`] times better than as taken, leaving more than [`MIN_UPRIGHT_PX`] as taken; a
/// camera with fewer than [`MIN_BOARDS`] boards gets every picture [`PictureTurn::Unjudged`].
/// The captures with a verdict, in the order of `results`.
pub fn judge_pictures(
    dataset: &Dataset,
    results: &[ImageResult],
    params: &[f64; PARAMETER_COUNT],
) -> Vec<(u64, PictureTurn)> {
    fitted_pictures(dataset, results, params)
        .into_iter()
        .filter_map(|(id, judged)| match judged {
            Err(boards) => Some((id, PictureTurn::Unjudged { boards })),
            Ok((upright_px, turned_px, true)) => Some((
                id,
                PictureTurn::Turned {
                    upright_px,
                    turned_px,
                },
            )),
            Ok(_) => None,
        })
        .collect()
}

/// A board's RMS as taken and turned back and whether it is called turned; or, when its
/// camera has too few boards, their number.
type Judged = Result<(f64, f64, bool), usize>;

/// Every board of `results` judged as [`judge_pictures`] says, in the order of `results`.
fn fitted_pictures(
    dataset: &Dataset,
    results: &[ImageResult],
    params: &[f64; PARAMETER_COUNT],
) -> Vec<(u64, Judged)> {
    let model = &dataset.model;
    let by_id: std::collections::HashMap<u64, &crate::dataset::Capture> =
        dataset.captures.iter().map(|c| (c.id, c)).collect();
    let mut out = Vec::new();
    for camera in CameraId::ALL {
        let boards: Vec<(u64, Seen)> = results
            .iter()
            .filter_map(|r| {
                let Outcome::Found { corners, .. } = &r.outcome else {
                    return None;
                };
                let capture = by_id.get(&r.capture).filter(|c| c.camera == camera)?;
                Some((
                    r.capture,
                    Seen {
                        chains: model.chains_for(camera, capture.side, &capture.joints),
                        vertices: corners.iter().map(|c| (c.vertex, c.pixel)).collect(),
                    },
                ))
            })
            .collect();
        if boards.len() < MIN_BOARDS {
            out.extend(boards.iter().map(|(id, _)| (*id, Err(boards.len()))));
            continue;
        }
        let scale = f64::from(model.intrinsics(camera).width) / 640.0;
        let mut judged: Vec<(f64, f64, bool)> = vec![(0.0, 0.0, false); boards.len()];
        for _ in 0..PICTURE_ROUNDS {
            let kept: Vec<Seen> = boards
                .iter()
                .zip(&judged)
                .filter(|(_, j)| !j.2)
                .map(|((_, s), _)| Seen {
                    chains: s.chains.clone(),
                    vertices: s.vertices.clone(),
                })
                .collect();
            if kept.len() < MIN_BOARDS {
                break;
            }
            // At most [`MAX_BOARDS`] of them, spread over the captures.
            let step = kept.len().div_ceil(MAX_BOARDS);
            let fitted: Vec<Seen> = kept.into_iter().step_by(step).collect();
            let (_, _, at) = fit_params(model, camera, &fitted, params);
            let mut changed = false;
            for ((_, seen), j) in boards.iter().zip(judged.iter_mut()) {
                let upright_px = rms(&residuals(model, &seen.chains, &seen.vertices, &at));
                let back = turn_back(model, camera, seen, &at);
                let turned_px = rms(&residuals(model, &back.chains, &back.vertices, &at));
                let is =
                    upright_px > MIN_UPRIGHT_PX * scale && upright_px > PICTURE_RATIO * turned_px;
                changed |= is != j.2;
                *j = (upright_px, turned_px, is);
            }
            if !changed {
                break;
            }
        }
        out.extend(boards.iter().zip(judged).map(|((id, _), j)| (*id, Ok(j))));
    }
    let order: std::collections::HashMap<u64, usize> = results
        .iter()
        .enumerate()
        .map(|(k, r)| (r.capture, k))
        .collect();
    out.sort_by_key(|(id, _)| order.get(id).copied().unwrap_or(usize::MAX));
    out
}

/// The cameras that detection's `results` say are turned (each once, in the order met).
pub fn of_results(results: &[ImageResult]) -> Vec<Turned> {
    let mut out: Vec<Turned> = Vec::new();
    for r in results {
        if let Outcome::Turned { turned, .. } = &r.outcome
            && !out.iter().any(|t| t.camera == turned.camera)
        {
            out.push(*turned);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dataset::Corner;
    use crate::detect::numbering::turn_deg;
    use crate::detect::predict;
    use crate::model::{Model, Vertex};
    use crate::sim::{SimOptions, simulate};

    /// A simulated robot with offsets as the teams' files show them: lower and upper
    /// captures, the vertices in view, as detection would report them.
    fn robot(seed: u64, stances: usize, upper: usize, heads: usize) -> Dataset {
        let mut model = Model::default();
        model.upper_camera = Some(model.camera);
        let options = SimOptions {
            seed,
            stances,
            heads,
            upper_stances: upper,
            px_noise: 0.3,
            team_offsets: true,
            ..SimOptions::default()
        };
        let mut d = simulate(&model, &options).unwrap();
        let camera_of: std::collections::HashMap<u64, CameraId> =
            d.captures.iter().map(|c| (c.id, c.camera)).collect();
        d.corners.retain(|c| {
            model
                .intrinsics(camera_of[&c.capture])
                .contains(c.pixel, 3.0)
        });
        d
    }

    /// What detection makes of `dataset`'s corners, with the pictures of `turned` turned by
    /// 180° (numbered by the prediction, as detection numbers the symmetric pattern).
    fn found(dataset: &Dataset, turned: Option<CameraId>) -> Vec<ImageResult> {
        found_turning(dataset, |c| Some(c.camera) == turned)
    }

    /// What detection makes of `dataset`'s corners, the pictures of the captures `turned`
    /// says turned by 180°.
    fn found_turning(
        dataset: &Dataset,
        turned: impl Fn(&crate::dataset::Capture) -> bool,
    ) -> Vec<ImageResult> {
        let model = &dataset.model;
        let by = dataset.corners_by_capture();
        dataset
            .captures
            .iter()
            .filter_map(|c| {
                let corners = by.get(&c.id)?;
                if corners.len() < 6 {
                    return None;
                }
                let mut corners: Vec<Corner> = corners.to_vec();
                if turned(c) {
                    let i = model.intrinsics(c.camera);
                    let (w, h) = (f64::from(i.width) - 1.0, f64::from(i.height) - 1.0);
                    for k in &mut corners {
                        k.pixel = [w - k.pixel[0], h - k.pixel[1]];
                    }
                    let pred = predict(model, c, &[0.0; PARAMETER_COUNT]).unwrap();
                    let at = |v: Vertex| pred[(v.row * model.board.cols() + v.col) as usize];
                    let p: Vec<[f64; 2]> = corners.iter().map(|k| at(k.vertex)).collect();
                    let f: Vec<[f64; 2]> = corners.iter().map(|k| k.pixel).collect();
                    if turn_deg(&f, &p).unwrap().abs() > 90.0 {
                        for k in &mut corners {
                            k.vertex = Vertex {
                                row: model.board.rows() - 1 - k.vertex.row,
                                col: model.board.cols() - 1 - k.vertex.col,
                            };
                        }
                    }
                }
                Some(ImageResult {
                    capture: c.id,
                    image: None,
                    outcome: Outcome::Found {
                        corners,
                        order: None,
                        whole_image: false,
                        numbered: String::new(),
                        dropped: Vec::new(),
                    },
                })
            })
            .collect()
    }

    /// Every camera's verdict for `dataset` with the pictures of `turned` turned.
    fn verdicts(dataset: &Dataset, turned: Option<CameraId>) -> Vec<Turned> {
        judge(dataset, &found(dataset, turned), &[0.0; PARAMETER_COUNT])
    }

    /// Robots with offsets as the teams' files show them (hidden from the judge, which
    /// predicts with the nominal model), with few and with many boards per camera: upright
    /// pictures are never called turned, pictures turned by 180° always, each camera on its
    /// own; and the margins both ways stay wide (the ratio of the two hypotheses' RMS is
    /// at least 3 times the threshold away).
    #[test]
    fn turned_pictures_are_told_from_upright_ones_on_robots_as_they_are() {
        let (mut upright_worst, mut turned_worst) = (0.0f64, f64::INFINITY);
        for (seed, (stances, upper, heads)) in
            (0..9).zip([(2, 1, 2), (3, 2, 2), (1, 1, 3)].into_iter().cycle())
        {
            let d = robot(seed, stances, upper, heads);
            for v in verdicts(&d, None) {
                assert!(!v.is_turned(), "seed {seed}: upright called turned: {v:?}");
                upright_worst = upright_worst.max(v.upright_px / v.turned_px);
            }
            for camera in CameraId::ALL {
                for v in verdicts(&d, Some(camera)) {
                    assert_eq!(
                        v.is_turned(),
                        v.camera == camera,
                        "seed {seed}, {camera:?} turned: {v:?}"
                    );
                    if v.camera == camera {
                        turned_worst = turned_worst.min(v.upright_px / v.turned_px);
                        assert!(v.turned_deg <= MAX_FIT_DEG, "{v:?}");
                    }
                }
            }
        }
        eprintln!("upright: ratio at most {upright_worst:.3}; turned: at least {turned_worst:.1}");
        assert!(upright_worst * 3.0 < 1.0 / RATIO, "{upright_worst}");
        assert!(turned_worst > 3.0 * RATIO, "{turned_worst}");
    }

    /// A few upper pictures turned among upright ones: the camera is not called turned,
    /// but each of those pictures is, on its own, and no upright one; with only two upper
    /// pictures, both turned, each says it cannot be judged (never that the turn is ruled
    /// out).
    #[test]
    fn each_picture_is_judged_on_its_own() {
        let mut checked = 0;
        for seed in 0..4 {
            let d = robot(seed, 2, 8, 2);
            let upper: Vec<u64> = d
                .captures
                .iter()
                .filter(|c| c.camera == CameraId::Upper)
                .map(|c| c.id)
                .collect();
            let found_upper = found(&d, None)
                .iter()
                .filter(|r| upper.contains(&r.capture))
                .count();
            if found_upper < 8 {
                continue;
            }
            let turned: Vec<u64> = upper.iter().copied().step_by(5).take(3).collect();
            let results = found_turning(&d, |c| turned.contains(&c.id));
            let params = [0.0; PARAMETER_COUNT];
            assert!(
                turned_cameras(&d, &results, &params).is_empty(),
                "seed {seed}"
            );
            // No upright picture is called turned; every turned one whose board lies
            // clearly off as taken is (one near the image centre fits both ways).
            for (id, judged) in fitted_pictures(&d, &results, &params) {
                let Ok((upright_px, turned_px, called)) = judged else {
                    panic!("seed {seed}: capture {id} not judged")
                };
                if turned.contains(&id) {
                    if upright_px > 3.0 * MIN_UPRIGHT_PX {
                        assert!(called, "seed {seed}: {id} {upright_px} {turned_px}");
                        checked += 1;
                    }
                } else {
                    assert!(
                        !called,
                        "seed {seed}: upright {id} {upright_px} {turned_px}"
                    );
                }
            }
            let said = judge_pictures(&d, &results, &params);
            assert!(said.iter().all(|(id, _)| turned.contains(id)), "{said:?}");
        }
        assert!(checked >= 6, "{checked} turned pictures clearly off");
        // Two upper pictures, both turned: not judged, and said so.
        let d = robot(1, 2, 8, 2);
        let is_upper = |id: u64| {
            d.captures
                .iter()
                .any(|c| c.id == id && c.camera == CameraId::Upper)
        };
        let mut results = found(&d, Some(CameraId::Upper));
        let two: Vec<u64> = results
            .iter()
            .map(|r| r.capture)
            .filter(|&id| is_upper(id))
            .take(2)
            .collect();
        results.retain(|r| !is_upper(r.capture) || two.contains(&r.capture));
        assert!(turned_cameras(&d, &results, &[0.0; PARAMETER_COUNT]).is_empty());
        let verdicts = judge_pictures(&d, &results, &[0.0; PARAMETER_COUNT]);
        let upper: Vec<&PictureTurn> = verdicts
            .iter()
            .filter(|(id, _)| is_upper(*id))
            .map(|(_, v)| v)
            .collect();
        assert_eq!(upper.len(), 2, "{verdicts:?}");
        for v in upper {
            assert!(matches!(v, PictureTurn::Unjudged { .. }), "{v:?}");
            assert!(v.to_string().contains("cannot be judged"), "{v}");
        }
    }

    #[test]
    fn the_message_names_the_camera_its_table_and_the_flip() {
        let t = Turned {
            camera: CameraId::Upper,
            boards: 12,
            upright_px: 80.0,
            turned_px: 1.5,
            turned_deg: 9.0,
            width: 640,
        };
        assert!(t.is_turned());
        let said = t.to_string();
        for needle in [
            "upper camera",
            "turned by 180°",
            "flip = true",
            "[upper_camera]",
            "selectors 12 and 13",
            "no calibration",
        ] {
            assert!(said.contains(needle), "{needle}: {said}");
        }
        let lower = Turned {
            camera: CameraId::Lower,
            ..t
        };
        assert!(
            lower.to_string().contains("`flip = false` in [camera]"),
            "{lower}"
        );
        // Too few boards, an upright fit already close, no clear winner, or a turned fit
        // that needs the camera turned far: not called turned.
        for not in [
            Turned {
                boards: MIN_BOARDS - 1,
                ..t
            },
            Turned {
                upright_px: 2.9,
                turned_px: 0.1,
                ..t
            },
            Turned {
                turned_px: 80.0 / RATIO + 0.1,
                ..t
            },
            Turned {
                turned_deg: MAX_FIT_DEG + 1.0,
                ..t
            },
        ] {
            assert!(!not.is_turned(), "{not:?}");
        }
        // In a picture twice as wide, twice the pixels.
        assert!(
            !Turned {
                width: 1280,
                upright_px: 5.9,
                turned_px: 0.1,
                ..t
            }
            .is_turned()
        );
    }
}
