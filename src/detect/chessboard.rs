//! The fallback to OpenCV's chessboard finder: the board looked for in a region of the
//! image, refined with `cornerSubPix`, checked against one homography and numbered by the
//! model's orientation (or in OpenCV's order without the model).

use crate::sim::render::GreyImage;

use super::assign::{self, Grid};
use super::guided::{Board, MIN_VERTICES};
use super::predict::{predict, predicted_roi};
use super::saddle::Saddles;
use super::{DetectOptions, Outcome, board_grid, cv, find};
use crate::dataset::{Capture, Corner, Dataset};
use crate::model::{Camera, PARAMETER_COUNT, Vertex};

/// Where the chessboard finder looks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Search {
    /// In the whole image at full resolution: the model-guided search found part of the
    /// board and says where ([`worth_trying`]). OpenCV's finder misses boards in small
    /// regions (its adaptive threshold's block is a fraction of the region's size).
    Whole {
        /// At half resolution (refined at full): the board's squares are large enough,
        /// and the finder gives up four times sooner where it cannot get the board.
        half: bool,
    },
    /// Where the nominal model predicts the board, then in the whole image (at half
    /// resolution when the predicted squares are large enough; at full resolution without
    /// the model).
    Predicted,
}

/// Smallest side of a square (px) the chessboard finder is given: the whole image is
/// searched at half resolution only when the model predicts squares of twice this.
pub(super) const MIN_SQUARE: f64 = 8.0;

/// Whether OpenCV's chessboard finder may add to a board the model-guided search found in
/// part: only when the homography of the vertices found puts every vertex of the board in
/// the image (the finder needs all of them), and one it missed far enough inside for an
/// unbiased `cornerSubPix` window of `factor` squares (nearer the border, the guided
/// search leaves vertices out on purpose). The finder gives up slowly where no whole board
/// is, trying tens of thresholds, so this spares it most boards cut by the border.
pub(super) fn worth_trying(board: &Board, camera: &Camera, factor: f64) -> bool {
    let Some(square) = board.square() else {
        return false;
    };
    let half = (factor * square).round().clamp(2.0, 30.0);
    let (w, h) = (camera.width as f64 - 1.0, camera.height as f64 - 1.0);
    let mut missed_inside = false;
    for (vertex, p) in &board.fitted {
        let Some(p) = *p else {
            return false;
        };
        if !camera.contains(p, 0.0) {
            return false;
        }
        let room = p[0].min(p[1]).min(w - p[0]).min(h - p[1]);
        if room >= half + 2.0 && !board.vertices.iter().any(|(v, _)| v == vertex) {
            missed_inside = true;
        }
    }
    missed_inside
}

/// The median side of a square (px) where the nominal model puts the board, or `None`
/// when it cannot.
fn predicted_square(
    dataset: &Dataset,
    capture: &Capture,
    grid: Grid,
    params: &[f64; PARAMETER_COUNT],
) -> Option<f64> {
    let points = predict(&dataset.model, capture, params)?;
    let mut sides = find::local_square(&points, grid);
    sides.sort_by(f64::total_cmp);
    sides.get(sides.len() / 2).copied()
}

/// Whether the prediction puts every vertex of the board at least a square inside the
/// image (where a board a person can see is one the finder must get).
fn wholly_in_view(
    dataset: &Dataset,
    capture: &Capture,
    grid: Grid,
    options: &DetectOptions,
) -> bool {
    let Some(points) = predict(&dataset.model, capture, &options.prediction()) else {
        return false;
    };
    let mut sides = find::local_square(&points, grid);
    sides.sort_by(f64::total_cmp);
    let Some(&square) = sides.get(sides.len() / 2) else {
        return false;
    };
    square >= MIN_SQUARE
        && points.iter().all(|p| {
            dataset
                .model
                .intrinsics(capture.camera)
                .contains(*p, square)
        })
}

/// Points refined at full resolution that fit one homography, or why they do not.
type Checked = Result<Vec<[f64; 2]>, String>;

/// Refines the `points` OpenCV found (its order) with `cornerSubPix` and checks that one
/// homography explains them all (after removing the lens distortion): within a tenth of a
/// square with the model, a quarter without.
fn checked(
    grey: &GreyImage,
    mut points: Vec<[f64; 2]>,
    grid: Grid,
    options: &DetectOptions,
    cam: &Camera,
) -> cv::Result<Checked> {
    find::refine(grey, &mut points, grid, options.subpix_factor)?;
    let board_xy: Vec<[f64; 2]> = (0..grid.len())
        .map(|k| [(k as u32 % grid.cols) as f64, (k as u32 / grid.cols) as f64])
        .collect();
    let undistorted: Vec<[f64; 2]> = points
        .iter()
        .map(|p| {
            let [a, b] = cam.undistort(p[0], p[1]);
            [a * cam.fx + cam.cx, b * cam.fy + cam.cy]
        })
        .collect();
    let mut squares = find::local_square(&points, grid);
    squares.sort_by(f64::total_cmp);
    let square = squares[squares.len() / 2];
    let limit = if options.use_model {
        (0.1 * square).max(1.0)
    } else {
        (0.25 * square).max(1.0)
    };
    Ok(match assign::homography_residual(&board_xy, &undistorted) {
        None => Err("the points are degenerate (no homography fits them)".into()),
        Some(r) if r > limit => Err(format!(
            "the points do not fit one homography (a point is {r:.2} px off, more than \
             {limit:.2} px)"
        )),
        Some(_) => Ok(points),
    })
}

/// OpenCV's chessboard finder where `search` says; numbered by the model's orientation
/// (or OpenCV's order without the model).
pub(super) fn chessboard(
    dataset: &Dataset,
    capture: &Capture,
    grey: &GreyImage,
    grid: Grid,
    options: &DetectOptions,
    search: Search,
) -> cv::Result<Outcome> {
    let finder = Finder {
        dataset,
        capture,
        grey,
        grid,
        options,
    };
    let (found, whole_image) = finder.find(search)?;
    let points = match found {
        None => return Ok(Outcome::NotFound),
        Some(Err(reason)) => return Ok(Outcome::Rejected { reason }),
        Some(Ok(points)) => points,
    };
    let numbering = match finder.number(&points) {
        Ok(n) => n,
        Err(reason) => return Ok(Outcome::Rejected { reason }),
    };
    let mut corners: Vec<Corner> = numbering
        .vertices
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
    // The image test of a clean saddle, as for the guided search's vertices; with the
    // model only: another pattern's outer squares may be narrower than a square (as in
    // OpenCV's samples), and no robot stands in front of it.
    if !options.use_model {
        return Ok(Outcome::Found {
            corners,
            order: Some(numbering.order),
            whole_image,
            numbered: numbering.numbered,
            dropped: Vec::new(),
        });
    }
    let model = &dataset.model;
    let camera = model.intrinsics(capture.camera);
    let placed: Vec<(Vertex, [f64; 2])> = corners.iter().map(|c| (c.vertex, c.pixel)).collect();
    let (kept, dropped) = Saddles::new(grey, model, camera, options.subpix_factor).check(&placed);
    if kept.len() < MIN_VERTICES {
        return Ok(Outcome::Rejected {
            reason: format!(
                "{} of the {} vertices OpenCV found are dropped for an occluding edge",
                dropped.len(),
                placed.len()
            ),
        });
    }
    corners.retain(|c| kept.iter().any(|(v, _)| *v == c.vertex));
    Ok(Outcome::Found {
        corners,
        order: Some(numbering.order),
        whole_image,
        numbered: numbering.numbered,
        dropped,
    })
}

/// OpenCV's chessboard finder on one capture's image: what it searches and how.
struct Finder<'a> {
    /// The dataset (its model predicts the board).
    dataset: &'a Dataset,
    /// The capture whose image is searched.
    capture: &'a Capture,
    /// The image (8-bit grey).
    grey: &'a GreyImage,
    /// The pattern looked for.
    grid: Grid,
    /// How to detect.
    options: &'a DetectOptions,
}

/// The (row, col) OpenCV's points get.
struct Numbering {
    /// (row, col) of each point, in OpenCV's order.
    vertices: Vec<(u32, u32)>,
    /// How OpenCV's order relates to the board's.
    order: assign::Order,
    /// How the numbering was decided (for the log).
    numbered: String,
}

impl Finder<'_> {
    /// Refines and checks the points OpenCV found, if any ([`checked`]).
    fn check(&self, points: Option<Vec<[f64; 2]>>) -> cv::Result<Option<Checked>> {
        let intrinsics = self.dataset.model.intrinsics(self.capture.camera);
        match points {
            None => Ok(None),
            Some(points) => {
                checked(self.grey, points, self.grid, self.options, intrinsics).map(Some)
            }
        }
    }

    /// The points found where `search` says, refined and checked (`None` when nothing is
    /// found), and whether the whole image was searched after the predicted region.
    fn find(&self, search: Search) -> cv::Result<(Option<Checked>, bool)> {
        let (grey, grid, options) = (self.grey, self.grid, self.options);
        let (found, whole_image) = match search {
            Search::Whole { half: true } => match self.check(find::find_board_half(grey, grid)?)? {
                Some(Ok(points)) => (Some(Ok(points)), false),
                _ => (None, false),
            },
            Search::Whole { half: false } => {
                (self.check(find::find_board(grey, grid, None)?)?, false)
            }
            Search::Predicted => self.predicted()?,
        };
        // Nothing found quickly, but a calibrated prediction (the re-predict loop's, or
        // `--start-from`) puts the whole board well inside the image: the finder's full
        // search (without its fast check) finds oblique boards the quick one gives up on.
        // It is slow where there is no board, so not tried on the nominal model's word.
        let found = match found {
            None if options.use_model
                && options.is_calibrated()
                && search == Search::Predicted
                && wholly_in_view(self.dataset, self.capture, grid, options) =>
            {
                // The calibrated prediction is good to a few pixels: its region suffices.
                let roi = predicted_roi(&self.dataset.model, self.capture, &options.prediction());
                self.check(find::find_board_with(
                    grey,
                    grid,
                    roi,
                    cv::Search::Exhaustive,
                )?)?
            }
            found => found,
        };
        Ok((found, whole_image))
    }

    /// The points found where the model predicts the board, else in the whole image (at
    /// half resolution when the predicted squares are large enough), and whether the
    /// whole image was searched after a predicted region.
    fn predicted(&self) -> cv::Result<(Option<Checked>, bool)> {
        let (dataset, grey, grid, options) = (self.dataset, self.grey, self.grid, self.options);
        let model = &dataset.model;
        let roi = if options.use_model {
            predicted_roi(model, self.capture, &options.prediction())
        } else {
            None
        };
        if let Some(rect) = roi
            && let Some(found) = self.check(find::find_board(grey, grid, Some(rect))?)?
        {
            return Ok((Some(found), false));
        }
        let half = options.use_model
            && grid == board_grid(model)
            && predicted_square(dataset, self.capture, grid, &options.prediction())
                .is_some_and(|s| s >= 2.0 * MIN_SQUARE);
        let mut found = None;
        if half {
            found = self.check(find::find_board_half(grey, grid)?)?;
        }
        // At full resolution when not tried at half, or when what was found there does
        // not hold up at full resolution.
        if !half || found.as_ref().is_some_and(|f| f.is_err()) {
            found = self.check(find::find_board(grey, grid, None)?)?.or(found);
        }
        Ok((found, roi.is_some()))
    }

    /// The (row, col) of the `points` OpenCV found (its order): by the model's orientation
    /// (OpenCV's order without the model), or why the model cannot number them.
    fn number(&self, points: &[[f64; 2]]) -> Result<Numbering, String> {
        let (grid, options) = (self.grid, self.options);
        let model = &self.dataset.model;
        if !options.use_model {
            return Ok(Numbering {
                vertices: (0..grid.len() as u32)
                    .map(|k| (k / grid.cols, k % grid.cols))
                    .collect(),
                order: assign::Order::Same,
                numbered: "in OpenCV's order (no model)".to_string(),
            });
        }
        if grid != board_grid(model) {
            return Err(format!(
                "the pattern {}x{} is not the board's {}x{} (use --no-model)",
                grid.cols,
                grid.rows,
                model.board.cols(),
                model.board.rows()
            ));
        }
        let Some(predicted) = predict(model, self.capture, &options.prediction()) else {
            return Err("the model puts the board behind the camera".into());
        };
        let camera = model.intrinsics(self.capture.camera);
        let size = [camera.width as f64, camera.height as f64];
        let a = assign::assign(points, &predicted, grid, size)?;
        Ok(Numbering {
            numbered: format!(
                "numbered by OpenCV's whole {}×{} grid, as the prediction turns it ({:.0}° \
                 against it)",
                grid.cols, grid.rows, a.rotation_deg
            ),
            vertices: a.vertices,
            order: a.order,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Model;

    /// A 6 × 4 board of 30 px squares with its top-left vertex at `origin`, found except
    /// for the vertices in `missed`.
    fn board(origin: [f64; 2], missed: &[(u32, u32)]) -> Board {
        let fitted: Vec<(Vertex, Option<[f64; 2]>)> = (0..4)
            .flat_map(|row| (0..6).map(move |col| Vertex { row, col }))
            .map(|v| {
                let p = [
                    origin[0] + 30.0 * v.col as f64,
                    origin[1] + 30.0 * v.row as f64,
                ];
                (v, Some(p))
            })
            .collect();
        let vertices = fitted
            .iter()
            .filter(|(v, _)| !missed.contains(&(v.row, v.col)))
            .map(|(v, p)| (*v, p.unwrap()))
            .collect();
        Board {
            vertices,
            fitted,
            numbered: String::new(),
            dropped: Vec::new(),
        }
    }

    #[test]
    fn the_finder_is_tried_only_for_a_vertex_missed_well_inside_a_board_in_view() {
        let camera = Model::default().camera;
        // Wholly in view, a vertex missed in the middle: worth trying.
        assert!(worth_trying(
            &board([200.0, 200.0], &[(1, 2)]),
            &camera,
            0.3
        ));
        // Cut by the left border: OpenCV's finder cannot find the whole board.
        assert!(!worth_trying(
            &board([-10.0, 200.0], &[(0, 0)]),
            &camera,
            0.3
        ));
        // In view, but the only vertex missed is 3 px from the border, where the guided
        // search leaves it out on purpose (no unbiased 9 px window fits).
        assert!(!worth_trying(&board([3.0, 200.0], &[(2, 0)]), &camera, 0.3));
        // Nothing missed.
        assert!(!worth_trying(&board([200.0, 200.0], &[]), &camera, 0.3));
    }
}
