//! The OpenCV part: finding the chessboard and refining its vertices to sub-pixel accuracy.

use super::assign::Grid;
use super::cv::{self, Roi, Search};
use crate::sim::render::GreyImage;

/// Runs `findChessboardCorners` on `image` (8-bit greyscale), or on the part `roi` of it,
/// with the fast check that gives up early on images without a board; the points are in
/// full-image pixels, in OpenCV's order.
pub fn find_board(
    image: &GreyImage,
    grid: Grid,
    roi: Option<Roi>,
) -> cv::Result<Option<Vec<[f64; 2]>>> {
    find_board_with(image, grid, roi, Search::Fast)
}

/// [`find_board`] with the finder's `search` (e.g. [`Search::Exhaustive`], without the
/// fast check, which gives up on some oblique boards that the full search finds).
pub fn find_board_with(
    image: &GreyImage,
    grid: Grid,
    roi: Option<Roi>,
    search: Search,
) -> cv::Result<Option<Vec<[f64; 2]>>> {
    let Some(corners) =
        cv::find_chessboard(image, roi, grid.cols as usize, grid.rows as usize, search)?
    else {
        return Ok(None);
    };
    let offset = roi.map_or([0.0, 0.0], |r| [r.x as f64, r.y as f64]);
    Ok(Some(
        corners
            .iter()
            .map(|p| [p[0] as f64 + offset[0], p[1] as f64 + offset[1]])
            .collect(),
    ))
}

/// Runs `findChessboardCorners` on `image` (8-bit greyscale) shrunk to half its width and
/// height (each pixel the mean of four): a quarter of the pixels, and far quicker where no
/// whole board is (OpenCV then tries tens of thresholds). The points are in full-image
/// pixels, in OpenCV's order, to be refined at full resolution ([`refine`]).
pub fn find_board_half(image: &GreyImage, grid: Grid) -> cv::Result<Option<Vec<[f64; 2]>>> {
    let half = cv::resize_half(image)?;
    // Pixel x of the half image covers full pixels 2x and 2x + 1: its centre is 2x + 0.5.
    Ok(find_board(&half, grid, None)?.map(|points| {
        points
            .into_iter()
            .map(|p| [2.0 * p[0] + 0.5, 2.0 * p[1] + 0.5])
            .collect()
    }))
}

/// The distance from each point to its nearest neighbour in the grid (px): the local
/// size of a square.
pub fn local_square(points: &[[f64; 2]], grid: Grid) -> Vec<f64> {
    let (rows, cols) = (grid.rows as i64, grid.cols as i64);
    (0..points.len())
        .map(|k| {
            let (r, c) = (k as i64 / cols, k as i64 % cols);
            [(0, 1), (0, -1), (1, 0), (-1, 0)]
                .iter()
                .filter_map(|(dr, dc)| {
                    let (rr, cc) = (r + dr, c + dc);
                    (rr >= 0 && rr < rows && cc >= 0 && cc < cols).then(|| {
                        let q = points[(rr * cols + cc) as usize];
                        let p = points[k];
                        ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt()
                    })
                })
                .fold(f64::INFINITY, f64::min)
        })
        .collect()
}

/// Refines `points` in place with `cornerSubPix`, each with a half-window of `factor` times
/// its local square size (at least 2 px), so that the window never reaches the next vertex.
pub fn refine(
    image: &GreyImage,
    points: &mut [[f64; 2]],
    grid: Grid,
    factor: f64,
) -> cv::Result<()> {
    let squares = local_square(points, grid);
    let half: Vec<i32> = squares
        .iter()
        .map(|s| ((factor * s).round() as i32).clamp(2, 30))
        .collect();
    let mut sizes = half.clone();
    sizes.sort_unstable();
    sizes.dedup();
    for w in sizes {
        let members: Vec<usize> = (0..points.len()).filter(|&k| half[k] == w).collect();
        let mut pts: Vec<[f32; 2]> = members
            .iter()
            .map(|&k| [points[k][0] as f32, points[k][1] as f32])
            .collect();
        cv::corner_sub_pix(image, &mut pts, w, SUBPIX_ITERATIONS, SUBPIX_EPS)?;
        for (k, p) in members.iter().zip(pts.iter()) {
            points[*k] = [p[0] as f64, p[1] as f64];
        }
    }
    Ok(())
}

/// `cornerSubPix` stops after this many iterations …
pub const SUBPIX_ITERATIONS: i32 = 50;
/// … or when a step is shorter than this (px).
pub const SUBPIX_EPS: f64 = 1e-4;
