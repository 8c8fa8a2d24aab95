//! The fallback to OpenCV's chessboard finder: the board looked for in a region of the
//! image, refined with `cornerSubPix`, checked against one homography and numbered by the
//! model's orientation (or in OpenCV's order without the model).

use opencv::core::Mat;

use super::assign::{self, Grid};
use super::predict::{predict, predicted_roi};
use super::{DetectOptions, Outcome, board_grid, find};
use crate::dataset::{Capture, Corner, Dataset};
use crate::model::{PARAMETER_COUNT, Vertex};

/// OpenCV's chessboard finder in the predicted region, then the whole image; numbered by
/// the model's orientation (or OpenCV's order without the model).
pub(super) fn chessboard(
    dataset: &Dataset,
    capture: &Capture,
    grey: &Mat,
    grid: Grid,
    options: &DetectOptions,
) -> opencv::Result<Outcome> {
    let model = &dataset.model;
    let camera = [model.camera.width, model.camera.height];
    let cv = |e: opencv::Error| e;
    let roi = if options.use_model {
        predicted_roi(model, capture)
    } else {
        None
    };
    let mut whole_image = false;
    let mut points = match roi {
        Some(rect) => find::find_board(grey, grid, Some(rect)).map_err(cv)?,
        None => None,
    };
    if points.is_none() {
        whole_image = roi.is_some();
        points = find::find_board(grey, grid, None).map_err(cv)?;
    }
    let Some(mut points) = points else {
        return Ok(Outcome::NotFound);
    };
    find::refine(grey, &mut points, grid, options.subpix_factor).map_err(cv)?;

    // One homography must explain every point (after removing the lens distortion).
    let board_xy: Vec<[f64; 2]> = (0..grid.len())
        .map(|k| [(k as u32 % grid.cols) as f64, (k as u32 / grid.cols) as f64])
        .collect();
    let cam = &model.camera;
    let undistorted: Vec<[f64; 2]> = points
        .iter()
        .map(|p| {
            let [a, b] = cam.undistort(p[0], p[1]);
            [a * cam.fx + cam.cx, b * cam.fy + cam.cy]
        })
        .collect();
    let squares = find::local_square(&points, grid);
    let mut sorted = squares.clone();
    sorted.sort_by(f64::total_cmp);
    let square = sorted[sorted.len() / 2];
    let limit = if options.use_model {
        (0.1 * square).max(1.0)
    } else {
        (0.25 * square).max(1.0)
    };
    match assign::homography_residual(&board_xy, &undistorted) {
        None => {
            return Ok(Outcome::Rejected {
                reason: "the points are degenerate (no homography fits them)".into(),
            });
        }
        Some(r) if r > limit => {
            return Ok(Outcome::Rejected {
                reason: format!(
                    "the points do not fit one homography (a point is {r:.2} px off, more \
                     than {limit:.2} px)"
                ),
            });
        }
        Some(_) => {}
    }

    let (vertices, order) = if options.use_model {
        if grid != board_grid(model) {
            return Ok(Outcome::Rejected {
                reason: format!(
                    "the pattern {}x{} is not the board's {}x{} (use --no-model)",
                    grid.cols,
                    grid.rows,
                    model.board.cols(),
                    model.board.rows()
                ),
            });
        }
        let Some(predicted) = predict(model, capture, &[0.0; PARAMETER_COUNT]) else {
            return Ok(Outcome::Rejected {
                reason: "the model puts the board behind the camera".into(),
            });
        };
        match assign::assign(
            &points,
            &predicted,
            grid,
            [camera[0] as f64, camera[1] as f64],
        ) {
            Ok(a) => (a.vertices, a.order),
            Err(reason) => return Ok(Outcome::Rejected { reason }),
        }
    } else {
        let order = (0..grid.len() as u32)
            .map(|k| (k / grid.cols, k % grid.cols))
            .collect();
        (order, assign::Order::Same)
    };
    let order = Some(order);
    let mut corners: Vec<Corner> = vertices
        .iter()
        .zip(&points)
        .map(|(&(row, col), p)| Corner {
            capture: capture.id,
            vertex: Vertex { row, col },
            pixel: *p,
            line: 0,
        })
        .collect();
    corners.sort_by_key(|c| c.vertex);
    Ok(Outcome::Found {
        corners,
        order,
        whole_image,
    })
}
