//! The OpenCV part: finding the chessboard and refining its vertices to sub-pixel accuracy.

use opencv::calib3d;
use opencv::core::{self, Mat, Point2f, Rect, Size, TermCriteria, Vector};
use opencv::imgproc;
use opencv::prelude::*;

use super::assign::Grid;

/// Flags for `findChessboardCorners`: adaptive thresholding on a normalised image, and a
/// fast check that gives up early on images without a board.
pub const FIND_FLAGS: i32 = calib3d::CALIB_CB_ADAPTIVE_THRESH
    | calib3d::CALIB_CB_NORMALIZE_IMAGE
    | calib3d::CALIB_CB_FAST_CHECK;

/// Flags for the exhaustive `findChessboardCorners`: as [`FIND_FLAGS`] without the fast
/// check, which gives up on some oblique boards that the full search finds.
pub const EXHAUSTIVE_FLAGS: i32 =
    calib3d::CALIB_CB_ADAPTIVE_THRESH | calib3d::CALIB_CB_NORMALIZE_IMAGE;

/// Runs `findChessboardCorners` on `image` (8-bit greyscale), or on the part `roi` of it;
/// the points are in full-image pixels, in OpenCV's order.
pub fn find_board(
    image: &Mat,
    grid: Grid,
    roi: Option<Rect>,
) -> opencv::Result<Option<Vec<[f64; 2]>>> {
    find_board_with(image, grid, roi, FIND_FLAGS)
}

/// [`find_board`] with the finder's `flags` (e.g. [`EXHAUSTIVE_FLAGS`]).
pub fn find_board_with(
    image: &Mat,
    grid: Grid,
    roi: Option<Rect>,
    flags: i32,
) -> opencv::Result<Option<Vec<[f64; 2]>>> {
    let size = Size::new(grid.cols as i32, grid.rows as i32);
    let mut corners = Vector::<Point2f>::new();
    let (found, offset) = match roi {
        Some(rect) => {
            let view = Mat::roi(image, rect)?;
            (
                calib3d::find_chessboard_corners(&view, size, &mut corners, flags)?,
                [rect.x as f64, rect.y as f64],
            )
        }
        None => (
            calib3d::find_chessboard_corners(image, size, &mut corners, flags)?,
            [0.0, 0.0],
        ),
    };
    if !found || corners.len() != grid.len() {
        return Ok(None);
    }
    Ok(Some(
        corners
            .iter()
            .map(|p| [p.x as f64 + offset[0], p.y as f64 + offset[1]])
            .collect(),
    ))
}

/// Runs `findChessboardCorners` on `image` (8-bit greyscale) shrunk to half its width and
/// height (each pixel the mean of four): a quarter of the pixels, and far quicker where no
/// whole board is (OpenCV then tries tens of thresholds). The points are in full-image
/// pixels, in OpenCV's order, to be refined at full resolution ([`refine`]).
pub fn find_board_half(image: &Mat, grid: Grid) -> opencv::Result<Option<Vec<[f64; 2]>>> {
    let mut half = Mat::default();
    imgproc::resize(
        image,
        &mut half,
        Size::new(image.cols() / 2, image.rows() / 2),
        0.0,
        0.0,
        imgproc::INTER_AREA,
    )?;
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
pub fn refine(image: &Mat, points: &mut [[f64; 2]], grid: Grid, factor: f64) -> opencv::Result<()> {
    let squares = local_square(points, grid);
    let half: Vec<i32> = squares
        .iter()
        .map(|s| ((factor * s).round() as i32).clamp(2, 30))
        .collect();
    let criteria = TermCriteria::new(
        core::TermCriteria_Type::COUNT as i32 | core::TermCriteria_Type::EPS as i32,
        50,
        1e-4,
    )?;
    let mut sizes = half.clone();
    sizes.sort_unstable();
    sizes.dedup();
    for w in sizes {
        let members: Vec<usize> = (0..points.len()).filter(|&k| half[k] == w).collect();
        let mut pts: Vector<Point2f> = members
            .iter()
            .map(|&k| Point2f::new(points[k][0] as f32, points[k][1] as f32))
            .collect();
        imgproc::corner_sub_pix(
            image,
            &mut pts,
            Size::new(w, w),
            Size::new(-1, -1),
            criteria,
        )?;
        for (k, p) in members.iter().zip(pts.iter()) {
            points[*k] = [p.x as f64, p.y as f64];
        }
    }
    Ok(())
}
