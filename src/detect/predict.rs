//! Where the nominal model (all offsets zero) and the logged joints put the board in the
//! image: its vertices, and the region the chessboard finder searches.

use super::cv::Roi;

use crate::dataset::Capture;
use crate::model::{Model, PARAMETER_COUNT, Vertex};

/// Where the model with parameters `params` puts every vertex of the board in view of
/// `capture`, through the capture's camera (row-major), or `None` when a vertex is behind
/// the camera.
pub fn predict(model: &Model, capture: &Capture, params: &[f64]) -> Option<Vec<[f64; 2]>> {
    let vertices: Vec<Vertex> = model.board.vertices().collect();
    model
        .project(
            &model.chains_for(capture.camera, capture.side, &capture.joints),
            params,
            &vertices,
        )
        .into_iter()
        .collect()
}

/// The part of the image where the board (with a square's border and a margin for the
/// model's error) is predicted, or `None` when it cannot be predicted or fills most of the
/// image anyway.
pub(super) fn predicted_roi(
    model: &Model,
    capture: &Capture,
    params: &[f64; PARAMETER_COUNT],
) -> Option<Roi> {
    let b = &model.board;
    let (hx, hy) = (
        (b.squares_x as f64 / 2.0 + 1.0) * b.square,
        (b.squares_y as f64 / 2.0 + 1.0) * b.square,
    );
    let pose = model
        .chains_for(capture.camera, capture.side, &capture.joints)
        .camera_to_board(params);
    let camera = model.intrinsics_at(capture.camera, params);
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for (x, y) in [(-hx, -hy), (hx, -hy), (-hx, hy), (hx, hy)] {
        let p = camera.project(&pose.apply(&[x, y, 0.0]))?;
        for i in 0..2 {
            lo[i] = lo[i].min(p[i]);
            hi[i] = hi[i].max(p[i]);
        }
    }
    let (w, h) = (camera.width as f64, camera.height as f64);
    let margin = 40.0 + 0.15 * (hi[0] - lo[0]).max(hi[1] - lo[1]);
    let x0 = (lo[0] - margin).max(0.0).floor();
    let y0 = (lo[1] - margin).max(0.0).floor();
    let x1 = (hi[0] + margin).min(w).ceil();
    let y1 = (hi[1] + margin).min(h).ceil();
    if x1 - x0 < 32.0 || y1 - y0 < 32.0 || (x1 - x0) * (y1 - y0) > 0.8 * w * h {
        return None;
    }
    Some(Roi {
        x: x0 as i32,
        y: y0 as i32,
        width: (x1 - x0) as i32,
        height: (y1 - y0) as i32,
    })
}
