//! Detection on hard rendered sets: boards near and across the image border
//! (`simulate --images --near-border`). Every fully visible board is found, almost every
//! vertex in the image too, none is placed more than 1 px from its true position or given
//! the wrong (row, col), and the calibration from these images is as good as from the
//! true corners with 0.05 px noise.

use std::path::Path;

use crate::util::solve;
use naocalib::dataset::{Corner, Dataset};
use naocalib::detect::{self, DetectOptions, Outcome};
use naocalib::model::{FixedSet, Model, Param};
use naocalib::sim::render::{ImageOutput, RenderOptions};
use naocalib::sim::{SimOptions, simulate};
use naocalib::solve::{Problem, backend};
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

/// A hard set: `stances × 3 × 2` rendered captures with boards near and across the border.
fn hard_set(dir: &Path, seed: u64, stances: usize) -> Dataset {
    let options = SimOptions {
        seed,
        stances,
        heads: 3,
        px_noise: 0.0,
        near_border: true,
        images: Some(ImageOutput {
            dir: dir.to_path_buf(),
            options: RenderOptions {
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

/// What detection made of a hard set, against the truth.
#[derive(Debug, Default)]
struct Score {
    /// Boards with all vertices at least 3 px inside the image, and how many were found.
    full: usize,
    full_found: usize,
    /// Boards partly outside the image, and how many gave vertices.
    partial: usize,
    partial_found: usize,
    /// Vertices at least 3 px inside the image, and how many of them were found.
    inside: usize,
    inside_found: usize,
    /// Vertices found, the sum of their squared errors, the largest error.
    found: usize,
    sum2: f64,
    worst: f64,
}

fn score(dataset: &Dataset, corners: &[Corner], results: &[detect::ImageResult]) -> Score {
    let model = &dataset.model;
    let truth = dataset.corners_by_capture();
    let mut s = Score::default();
    for r in results {
        let expected = &truth[&r.capture];
        let inside: Vec<&Corner> = expected
            .iter()
            .filter(|t| model.camera.contains(t.pixel, 3.0))
            .collect();
        let full = inside.len() == model.board.vertices().count();
        let got: Vec<&Corner> = corners.iter().filter(|c| c.capture == r.capture).collect();
        if full {
            s.full += 1;
            s.full_found += matches!(r.outcome, Outcome::Found { .. }) as usize;
        } else {
            s.partial += 1;
            s.partial_found += !got.is_empty() as usize;
        }
        s.inside += inside.len();
        s.inside_found += inside
            .iter()
            .filter(|t| got.iter().any(|c| c.vertex == t.vertex))
            .count();
        if std::env::var_os("NAOCALIB_DEBUG").is_some() {
            for t in inside
                .iter()
                .filter(|t| !got.iter().any(|c| c.vertex == t.vertex))
            {
                let w = model.camera.width as f64 - 1.0;
                let h = model.camera.height as f64 - 1.0;
                let d = t.pixel[0]
                    .min(t.pixel[1])
                    .min(w - t.pixel[0])
                    .min(h - t.pixel[1]);
                eprintln!(
                    "missed {} {:?} {:.1} px from the border ({} found)",
                    r.capture,
                    t.vertex,
                    d,
                    got.len()
                );
            }
        }
        for c in got {
            let t = expected
                .iter()
                .find(|t| t.vertex == c.vertex)
                .unwrap_or_else(|| panic!("{r}: vertex {:?} is not in the image", c.vertex));
            let e = (c.pixel[0] - t.pixel[0]).hypot(c.pixel[1] - t.pixel[1]);
            assert!(
                e < 1.0,
                "{r}: vertex {:?} detected at {:?}, true {:?} ({e:.2} px: wrong (row, col) \
                 or biased)",
                c.vertex,
                c.pixel,
                t.pixel
            );
            s.found += 1;
            s.sum2 += e * e;
            s.worst = s.worst.max(e);
        }
    }
    s
}

#[test]
fn boards_near_and_across_the_border() {
    let tmp = tempfile::tempdir().unwrap();
    let mut total = Score::default();
    for seed in [31, 32] {
        let dataset = hard_set(&tmp.path().join(seed.to_string()), seed, 8);
        let results = detect::detect_dataset(&dataset, &DetectOptions::default(), &|_| {});
        for r in &results {
            if !matches!(r.outcome, Outcome::Found { .. }) {
                eprintln!("seed {seed}: {r}");
            }
        }
        let s = score(&dataset, &detect::corners(&results), &results);
        eprintln!("seed {seed}: {s:?}");
        total.full += s.full;
        total.full_found += s.full_found;
        total.partial += s.partial;
        total.partial_found += s.partial_found;
        total.inside += s.inside;
        total.inside_found += s.inside_found;
        total.found += s.found;
        total.sum2 += s.sum2;
        total.worst = total.worst.max(s.worst);
    }
    let rms = (total.sum2 / total.found as f64).sqrt();
    eprintln!(
        "fully visible boards found {}/{}, partly visible boards with vertices {}/{}, \
         vertices ≥ 3 px inside found {}/{}, RMS {rms:.4} px, worst {:.3} px",
        total.full_found,
        total.full,
        total.partial_found,
        total.partial,
        total.inside_found,
        total.inside,
        total.worst
    );
    // The set must be hard: many boards cut by the border.
    assert!(total.partial >= 20, "{total:?}");
    assert!(
        total.full_found as f64 >= 0.99 * total.full as f64,
        "{total:?}"
    );
    assert!(
        total.inside_found as f64 >= 0.95 * total.inside as f64,
        "{total:?}"
    );
    assert!(rms <= 0.05, "RMS {rms} px");
}

/// The calibration from a hard set's images against the one from its true corners with
/// 0.05 px noise (the same vertices): the errors, in units of the reference's σ, are
/// alike.
#[test]
fn calibration_from_hard_images_matches_true_corners_with_small_noise() {
    let tmp = tempfile::tempdir().unwrap();
    let mut dataset = hard_set(tmp.path(), 41, 12);
    let truth = dataset.truth.clone().unwrap().values;
    let true_corners = dataset.corners_by_capture();
    let results = detect::detect_dataset(&dataset, &DetectOptions::default(), &|_| {});
    let detected = detect::corners(&results);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(41);
    let noise = Normal::new(0.0, 0.05).unwrap();
    let reference: Vec<Corner> = detected
        .iter()
        .map(|c| {
            let t = true_corners[&c.capture]
                .iter()
                .find(|t| t.vertex == c.vertex)
                .unwrap();
            Corner {
                pixel: [
                    t.pixel[0] + noise.sample(&mut rng),
                    t.pixel[1] + noise.sample(&mut rng),
                ],
                ..*c
            }
        })
        .collect();
    let solver = backend("lm", false).unwrap();
    let mut fit = |corners: Vec<Corner>| {
        dataset.corners = corners;
        let problem = Problem::from_dataset(&dataset, FixedSet::default()).unwrap();
        solve(&problem, solver.as_ref()).unwrap()
    };
    let from_images = fit(detected);
    let from_truth = fit(reference);
    let free: Vec<Param> = Param::ALL
        .iter()
        .copied()
        .filter(|p| from_truth.std[p.index()] > 0.0)
        .collect();
    let rms_z = |values: &[f64]| {
        (free
            .iter()
            .map(|p| ((values[p.index()] - truth[p.index()]) / from_truth.std[p.index()]).powi(2))
            .sum::<f64>()
            / free.len() as f64)
            .sqrt()
    };
    let (z_images, z_truth) = (rms_z(&from_images.values), rms_z(&from_truth.values));
    eprintln!(
        "{} vertices; RMS error in σ of the reference: images {z_images:.2}, true corners + \
         0.05 px {z_truth:.2}",
        from_images.observations
    );
    assert!(
        z_images <= 2.0 && z_images <= 1.5 * z_truth.max(1.0),
        "{z_images} vs {z_truth}"
    );
}
