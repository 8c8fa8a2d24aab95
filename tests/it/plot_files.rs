//! Plots are produced as valid, non-empty PNG and SVG files that show the data.

use std::path::Path;

use crate::util::solve;
use naocalib::export::WriteOptions;
use naocalib::model::{FixedSet, Model};
use naocalib::report::plot;
use naocalib::sim::{SimOptions, simulate};
use naocalib::solve::{Problem, backend};

fn check_png(path: &Path, min: (u32, u32)) {
    let bytes = std::fs::read(path).unwrap();
    assert!(
        bytes.len() > 10_000,
        "{}: {} bytes",
        path.display(),
        bytes.len()
    );
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "{}", path.display());
    assert_eq!(&bytes[12..16], b"IHDR");
    let w = u32::from_be_bytes(bytes[16..20].try_into().unwrap());
    let h = u32::from_be_bytes(bytes[20..24].try_into().unwrap());
    assert!(w >= min.0 && h >= min.1, "{w}×{h}");
}

fn check_svg(path: &Path, needles: &[&str]) {
    let text = std::fs::read_to_string(path).unwrap();
    assert!(text.trim_start().starts_with("<svg"), "{}", path.display());
    assert!(text.trim_end().ends_with("</svg>"));
    for n in needles {
        assert!(text.contains(n), "{} lacks {n}", path.display());
    }
}

#[test]
fn solution_and_batch_plots() {
    let mut solutions = Vec::new();
    let mut sides = None;
    for seed in [1, 2] {
        let options = SimOptions {
            seed,
            stances: 6,
            heads: 2,
            ..SimOptions::default()
        };
        let dataset = simulate(&Model::default(), &options).unwrap();
        let problem = Problem::from_dataset(&dataset, FixedSet::default()).unwrap();
        solutions.push(solve(&problem, backend("lm", false).unwrap().as_ref()).unwrap());
        sides.get_or_insert_with(|| plot::capture_sides(&dataset));
    }
    let dir = tempfile::tempdir().unwrap();
    let opts = WriteOptions::default();
    let files =
        plot::solution_plots(&solutions[0], sides.as_ref(), dir.path(), "run", &opts).unwrap();
    assert_eq!(files.len(), 4);
    check_png(&dir.path().join("run_residuals.png"), (1000, 500));
    check_svg(
        &dir.path().join("run_residuals.svg"),
        &[
            "<circle",
            "left board (",
            "before the solve",
            "after the solve",
        ],
    );
    // One circle per vertex and panel, at least.
    let svg = std::fs::read_to_string(dir.path().join("run_residuals.svg")).unwrap();
    assert!(svg.matches("<circle").count() >= 2 * solutions[0].residuals.len());
    check_png(&dir.path().join("run_captures.png"), (1000, 400));
    check_svg(
        &dir.path().join("run_captures.svg"),
        &["capture id", "<circle"],
    );

    let refs: Vec<_> = solutions.iter().collect();
    let files = plot::parameter_estimates(&refs, &dir.path().join("parameters"), &opts).unwrap();
    assert_eq!(files.len(), 2);
    check_png(&files[0], (1000, 1000));
    check_svg(&files[1], &["CamYaw [deg]", "RBoardTransY [mm]"]);

    // Existing files are not replaced without force.
    assert!(plot::solution_plots(&solutions[0], None, dir.path(), "run", &opts).is_err());
    let force = WriteOptions {
        force: true,
        ..WriteOptions::default()
    };
    plot::solution_plots(&solutions[0], None, dir.path(), "run", &force).unwrap();
    assert!(plot::capture_rms_values(&solutions[0]).len() == solutions[0].captures);
}
