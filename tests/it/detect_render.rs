//! Detection on rendered images: sub-pixel accuracy against the model's projections, the
//! right (row, col) for every vertex whichever way OpenCV orders them, and the end-to-end
//! chain simulate --images → detect → solve.

use std::collections::HashSet;
use std::path::Path;

use crate::util::solve;
use naocalib::dataset::Dataset;
use naocalib::detect::assign::Order;
use naocalib::detect::{self, DetectOptions, Outcome, Summary};
use naocalib::model::{FixedSet, Model, Param, Vertex};
use naocalib::sim::render::{ImageOutput, RenderOptions};
use naocalib::sim::{SimOptions, simulate};
use naocalib::solve::{Problem, backend};

/// Simulates `stances × heads × 2` captures with images (blur σ 0.8 px, grey noise σ 2)
/// into `dir` and returns the dataset as written.
fn rendered(dir: &Path, model: &Model, seed: u64, stances: usize, heads: usize) -> Dataset {
    let options = SimOptions {
        seed,
        stances,
        heads,
        px_noise: 0.0,
        joint_noise: 0.0,
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
    let mut dataset = simulate(model, &options).expect("simulated");
    dataset.dir = dir.to_path_buf();
    dataset
}

/// Detects every image (model-guided, or with `chessboard` by OpenCV's chessboard finder
/// and the model's orientation) and compares each vertex with the truth (the simulated,
/// noise-free corners). Returns (RMS error, largest error, OpenCV's orders seen, summary).
fn detect_and_compare(dataset: &Dataset, chessboard: bool) -> (f64, f64, HashSet<Order>, Summary) {
    let options = DetectOptions {
        guided: !chessboard,
        ..DetectOptions::default()
    };
    let results = detect::detect_dataset(dataset, &options, &|_| {});
    let summary = Summary::of(&results);
    let truth = dataset.corners_by_capture();
    let (mut sum2, mut worst, mut n, mut orders) = (0.0, 0.0f64, 0, HashSet::new());
    for r in &results {
        let Outcome::Found { corners, order, .. } = &r.outcome else {
            continue;
        };
        assert_eq!(order.is_none(), !chessboard, "{r}");
        orders.extend(*order);
        let expected = &truth[&r.capture];
        assert_eq!(corners.len(), expected.len());
        for c in corners {
            let t = expected
                .iter()
                .find(|t| t.vertex == c.vertex)
                .expect("vertex in truth");
            let e2 = (c.pixel[0] - t.pixel[0]).powi(2) + (c.pixel[1] - t.pixel[1]).powi(2);
            assert!(
                e2.sqrt() < 1.0,
                "capture {} vertex {:?}: detected {:?}, true {:?} (wrong row/col?)",
                r.capture,
                c.vertex,
                c.pixel,
                t.pixel
            );
            sum2 += e2;
            worst = worst.max(e2.sqrt());
            n += 1;
        }
    }
    ((sum2 / n.max(1) as f64).sqrt(), worst, orders, summary)
}

#[test]
fn subpixel_accuracy_and_assignment_both_ways() {
    let tmp = tempfile::tempdir().unwrap();
    // The default board: OpenCV's order comes out turned against the board's.
    let model = Model::default();
    let dataset = rendered(&tmp.path().join("a"), &model, 7, 4, 2);
    let (rms, worst, _, summary) = detect_and_compare(&dataset, false);
    eprintln!("default board, model-guided: rms {rms:.4} px, worst {worst:.4} px, {summary}");
    assert_eq!(summary.found, dataset.captures.len(), "{summary}");
    assert!(rms < 0.05, "rms {rms} px");
    let (rms, worst, orders, summary) = detect_and_compare(&dataset, true);
    eprintln!("default board: rms {rms:.4} px, worst {worst:.4} px, {orders:?}, {summary}");
    assert_eq!(summary.found, dataset.captures.len(), "{summary}");
    assert!(rms < 0.05, "rms {rms} px");
    // The same pattern mounted turned by 180°: the images look alike, but the board's
    // numbering is reversed, so OpenCV's order now agrees with it.
    let mut turned = Model::default();
    turned.board.mount_rpy[2] = std::f64::consts::PI;
    let dataset = rendered(&tmp.path().join("b"), &turned, 8, 4, 2);
    let (rms_g, _, _, summary_g) = detect_and_compare(&dataset, false);
    eprintln!("turned board, model-guided: rms {rms_g:.4} px, {summary_g}");
    assert_eq!(summary_g.found, dataset.captures.len(), "{summary_g}");
    assert!(rms_g < 0.05, "rms {rms_g} px");
    let (rms_b, _, orders_b, summary_b) = detect_and_compare(&dataset, true);
    eprintln!("turned board: rms {rms_b:.4} px, {orders_b:?}, {summary_b}");
    assert_eq!(summary_b.found, dataset.captures.len(), "{summary_b}");
    assert!(rms_b < 0.05, "rms {rms_b} px");
    let all: HashSet<_> = orders.union(&orders_b).collect();
    assert!(
        all.len() >= 2,
        "several of OpenCV's orders must occur: {all:?}"
    );
    assert!(
        all.iter().any(|o| **o != Order::Same),
        "views where OpenCV's order is not the board's must occur"
    );
}

#[test]
fn vertex_truth_is_the_model_projection() {
    // With joint noise zero the simulated corners are the model's projections at the truth.
    let tmp = tempfile::tempdir().unwrap();
    let model = Model::default();
    let dataset = rendered(tmp.path(), &model, 3, 1, 1);
    let truth = &dataset.truth.as_ref().unwrap().values;
    for c in &dataset.captures {
        let chains = model.chains(c.side, &c.joints);
        let vertices: Vec<Vertex> = model.board.vertices().collect();
        let projected = model.project(&chains, &truth[..], &vertices);
        for (corner, p) in dataset.corners_of(c.id).zip(projected) {
            assert_eq!(corner.pixel, p.unwrap());
        }
        assert!(tmp.path().join(c.image.as_ref().unwrap()).exists());
    }
}

#[test]
fn end_to_end_recovers_the_truth() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let model = Model::default();
    // Paper-sized: 24 stances × 3 head postures × 2 legs = 144 images.
    let mut dataset = rendered(dir, &model, 11, 24, 3);
    let truth = dataset.truth.clone().unwrap();
    let results = detect::detect_dataset(&dataset, &DetectOptions::default(), &|_| {});
    let summary = Summary::of(&results);
    assert_eq!(summary.found, dataset.captures.len(), "{summary}");
    dataset.corners = detect::corners(&results);
    dataset.write(dir, true).unwrap();
    let dataset = Dataset::load(dir).unwrap();
    let problem = Problem::from_dataset(&dataset, FixedSet::default()).unwrap();
    let solver = backend(naocalib::solve::backend_names()[0], false).unwrap();
    let solution = solve(&problem, solver.as_ref()).unwrap();
    for p in Param::ALL.iter().take(21) {
        let est = p.unit().to_report(solution.values[p.index()]);
        let tru = truth.report_value(*p);
        // The targets.
        let tol = match p.unit() {
            naocalib::model::Unit::Deg => 0.03,
            _ => 0.15,
        };
        assert!(
            (est - tru).abs() < tol,
            "{}: estimated {est:.4}, true {tru:.4}",
            p.name()
        );
    }
}

#[test]
fn lens_distortion_is_rendered_and_handled() {
    let tmp = tempfile::tempdir().unwrap();
    let mut model = Model::default();
    model.camera.distortion = [-0.15, 0.05, 0.001, -0.001, 0.0];
    let dataset = rendered(tmp.path(), &model, 21, 3, 2);
    let (rms, worst, _, summary) = detect_and_compare(&dataset, false);
    eprintln!("distorted: rms {rms:.4} px, worst {worst:.4} px, {summary}");
    assert_eq!(summary.found, dataset.captures.len(), "{summary}");
    assert!(rms < 0.05, "rms {rms} px");
}
