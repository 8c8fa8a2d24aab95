//! Model-guided detection: the logged joints and the model say where every vertex of the
//! board should appear and which way its squares are coloured; the image is searched for
//! that pattern of saddles, each vertex is refined where it is, checked, and numbered by
//! the prediction.
//!
//! 1. **Prediction.** Every vertex and four points around it (0.3 of a square along the
//!    board's diagonals, two on black squares and two on white ones) are projected with
//!    the model.
//! 2. **Alignment.** The model's error moves the whole board by up to about a square.
//!    The shift of the predicted pattern that best matches the image is searched (a
//!    saddle with the predicted colours scores up to ½, a vertex predicted in the image
//!    without one costs ½). A shift by one square turns every saddle's colours round, and
//!    one by two squares puts a row or column of the pattern on the plain plate or the
//!    background, so the true alignment stands out, also for a board cut by the image
//!    border; when another alignment a square or more away scores nearly as well, the
//!    image is given up (nothing is numbered by guesswork).
//! 3. **Refinement and checks.** Each vertex with a clear saddle is refined with
//!    `cornerSubPix` in a window that stays inside the image; it must stay near its
//!    start, still show its saddle, and fit one homography with the others (after the
//!    lens distortion is removed).
//! 4. **The rest.** The homography predicts the vertices not yet found (also those the
//!    first alignment missed); each is refined and checked the same way.
//!
//! Vertices too close to the image border for a window of [`MIN_HALF_WINDOW`] pixels are
//! left out rather than kept biased.

use nalgebra::Matrix3;
use opencv::core::{self, Mat, Point2f, Size, TermCriteria, Vector};
use opencv::imgproc;
use opencv::prelude::*;

use crate::model::{Camera, Model, Pose, Vertex};

use super::{assign, numbering};

/// Vertices by index, with their pixels.
type Indexed = Vec<(usize, [f64; 2])>;
/// Vertices with their pixels.
type Placed = Vec<(Vertex, [f64; 2])>;

/// Smallest half-window of `cornerSubPix` (px); a vertex nearer the border than this
/// window (plus the pixel its gradients need) is not refined, but dropped.
pub const MIN_HALF_WINDOW: i32 = 2;
/// Fewest vertices of a board worth keeping.
pub const MIN_VERTICES: usize = 6;
/// Where the colour samples lie: this fraction of a square along both board axes.
const SAMPLE: f64 = 0.3;
/// Where the inner colour samples lie (they show the saddle only near its centre).
const INNER: f64 = 0.12;
/// Saddle contrast (white minus black) that counts fully [grey levels].
const FULL_CONTRAST: f64 = 24.0;
/// Saddle score (of 1) a vertex needs to be taken.
const MIN_SCORE: f64 = 0.5;
/// Part of the best alignment's score another alignment a square away may reach.
const AMBIGUOUS: f64 = 0.75;

/// Grey-level sums over rectangles in O(1).
pub struct Integral {
    width: usize,
    height: usize,
    sums: Vec<u32>,
}

impl Integral {
    /// The integral image of an 8-bit greyscale `image`.
    pub fn new(image: &Mat) -> opencv::Result<Integral> {
        let (width, height) = (image.cols() as usize, image.rows() as usize);
        let bytes = image.data_bytes()?;
        let w1 = width + 1;
        let mut sums = vec![0u32; w1 * (height + 1)];
        for v in 0..height {
            let mut row = 0u32;
            let src = &bytes[v * width..(v + 1) * width];
            for u in 0..width {
                row += src[u] as u32;
                sums[(v + 1) * w1 + u + 1] = sums[v * w1 + u + 1] + row;
            }
        }
        Ok(Integral {
            width,
            height,
            sums,
        })
    }

    /// The mean grey level of the square of half-size `h` ≥ 1 around pixel `(x, y)`
    /// (rounded), or `None` when it is not wholly in the image.
    pub(super) fn mean(&self, x: f64, y: f64, h: i64) -> Option<f64> {
        // Rounded as `round` does for x, y ≥ -0.5 (below, a square of half-size h ≥ 1
        // leaves the image either way), without a call into libm.
        let (x, y) = ((x + 0.5) as i64, (y + 0.5) as i64);
        if x - h < 0 || y - h < 0 || x + h >= self.width as i64 || y + h >= self.height as i64 {
            return None;
        }
        let w1 = self.width + 1;
        let (x0, y0) = ((x - h) as usize, (y - h) as usize);
        let (x1, y1) = ((x + h + 1) as usize, (y + h + 1) as usize);
        let s = self.sums[y1 * w1 + x1] + self.sums[y0 * w1 + x0]
            - self.sums[y0 * w1 + x1]
            - self.sums[y1 * w1 + x0];
        let n = (2 * h + 1) * (2 * h + 1);
        Some(s as f64 / n as f64)
    }
}

/// The predicted look of one vertex.
#[derive(Debug, Clone)]
struct Predicted {
    vertex: Vertex,
    /// Position on the board plane (mm) (x, y).
    board: [f64; 2],
    /// Predicted pixel.
    pixel: [f64; 2],
    /// Offsets of the two black and two white samples from the vertex (px): at
    /// [`SAMPLE`] of a square, and (`inner_*`) at [`INNER`].
    black: [[f64; 2]; 2],
    white: [[f64; 2]; 2],
    inner_black: [[f64; 2]; 2],
    inner_white: [[f64; 2]; 2],
    /// The same samples' offsets on the board plane (mm).
    board_black: [[f64; 2]; 2],
    board_white: [[f64; 2]; 2],
    board_inner_black: [[f64; 2]; 2],
    board_inner_white: [[f64; 2]; 2],
    /// Edge of a square on the board (mm).
    board_step: f64,
    /// Local size of a square (px).
    square: f64,
}

impl Predicted {
    /// Patch half-size of the colour samples (px).
    fn patch(&self) -> i64 {
        ((0.1 * self.square).round() as i64).clamp(1, 6)
    }

    /// Saddle score at `p` (0 … 1): how much both white samples are brighter than both
    /// black ones, or `None` when a sample leaves the image.
    fn score(&self, img: &Integral, p: [f64; 2]) -> Option<f64> {
        Some((self.contrast(img, p, false)? / FULL_CONTRAST).clamp(0.0, 1.0))
    }

    /// White minus black of the samples around `p` (the inner ones with `inner`)
    /// [grey levels].
    fn contrast(&self, img: &Integral, p: [f64; 2], inner: bool) -> Option<f64> {
        let (black, white, h) = if inner {
            (&self.inner_black, &self.inner_white, 1)
        } else {
            (&self.black, &self.white, self.patch())
        };
        let at = |d: [f64; 2]| img.mean(p[0] + d[0], p[1] + d[1], h);
        let b = at(black[0])?.max(at(black[1])?);
        let w = at(white[0])?.min(at(white[1])?);
        Some(w - b)
    }

    /// Score of a vertex exactly at `p` (0 … 1): both rings of samples must show the
    /// saddle; the inner one only does within a few pixels of its centre.
    fn centred(&self, img: &Integral, p: [f64; 2]) -> Option<f64> {
        Some((self.both(img, p)? / FULL_CONTRAST).clamp(0.0, 1.0))
    }

    /// The smaller contrast of the two rings at `p`; the inner ring's alone near the image
    /// border, where the outer ring leaves the image.
    fn both(&self, img: &Integral, p: [f64; 2]) -> Option<f64> {
        let inner = self.contrast(img, p, true)?;
        Some(match self.contrast(img, p, false) {
            Some(outer) => outer.min(inner),
            None => inner,
        })
    }

    /// The pixel within a third of a square of `start` where both rings show the saddle
    /// most strongly, or `None` when none shows it.
    fn peak(&self, img: &Integral, start: [f64; 2]) -> Option<[f64; 2]> {
        let r = (self.square / 3.0).round() as i64;
        let centre = [start[0].round(), start[1].round()];
        // Both rings' contrast and the inner ring's at `centre` moved by (dx, dy).
        let at = |dx: i64, dy: i64| {
            let p = [centre[0] + dx as f64, centre[1] + dy as f64];
            Some((self.both(img, p)?, self.contrast(img, p, true)?, p))
        };
        // Coarse to fine: every twelfth of a square (the inner ring, 0.12 squares out, still
        // shows the saddle half a step away), then every pixel around the coarse best.
        let step = ((self.square / 12.0).floor() as i64).max(1);
        let (cx, cy) = if step == 1 {
            (0, 0)
        } else {
            let mut best: Option<(f64, i64, i64)> = None;
            for dy in (-r..=r).step_by(step as usize) {
                for dx in (-r..=r).step_by(step as usize) {
                    if let Some((c, inner, _)) = at(dx, dy)
                        && best.is_none_or(|(b, _, _)| c + inner > b)
                    {
                        best = Some((c + inner, dx, dy));
                    }
                }
            }
            let (_, cx, cy) = best?;
            (cx, cy)
        };
        let reach = if step == 1 { r } else { step };
        let mut best: Option<(f64, [f64; 2])> = None;
        for dy in (cy - reach).max(-r)..=(cy + reach).min(r) {
            for dx in (cx - reach).max(-r)..=(cx + reach).min(r) {
                let Some((c, inner, p)) = at(dx, dy) else {
                    continue;
                };
                if c >= MIN_SCORE * FULL_CONTRAST && best.is_none_or(|(b, _)| c + inner > b) {
                    best = Some((c + inner, p));
                }
            }
        }
        best.map(|(_, p)| p)
    }
}

/// Whether the square at board position `(x, y)` (mm) is black (the four corner squares
/// are; squares alternate).
fn is_black(model: &Model, x: f64, y: f64) -> bool {
    let b = &model.board;
    let ix = (x / b.square + b.squares_x as f64 / 2.0).floor() as i64;
    let iy = (y / b.square + b.squares_y as f64 / 2.0).floor() as i64;
    (ix + iy).rem_euclid(2) == 0
}

fn predict(model: &Model, camera: &Camera, pose: &Pose<f64>) -> Vec<Predicted> {
    let sq = model.board.square;
    let project = |x: f64, y: f64| camera.project(&pose.apply(&[x, y, 0.0]));
    model
        .board
        .vertices()
        .filter_map(|vertex| {
            let [x, y, _] = model.board.vertex_position(vertex);
            let pixel = project(x, y)?;
            let mut black = Vec::new();
            let mut white = Vec::new();
            let mut inner_black = Vec::new();
            let mut inner_white = Vec::new();
            let mut board = [Vec::new(), Vec::new(), Vec::new(), Vec::new()];
            for (sx, sy) in [(1.0, 1.0), (-1.0, 1.0), (1.0, -1.0), (-1.0, -1.0)] {
                for (ring, at, b, w) in [
                    (0, SAMPLE, &mut black, &mut white),
                    (2, INNER, &mut inner_black, &mut inner_white),
                ] {
                    let (dx, dy) = (sx * at * sq, sy * at * sq);
                    let q = project(x + dx, y + dy)?;
                    let d = [q[0] - pixel[0], q[1] - pixel[1]];
                    if is_black(model, x + dx, y + dy) {
                        b.push(d);
                        board[ring].push([dx, dy]);
                    } else {
                        w.push(d);
                        board[ring + 1].push([dx, dy]);
                    }
                }
            }
            let ax = project(x + sq, y)?;
            let ay = project(x, y + sq)?;
            let len = |q: [f64; 2]| ((q[0] - pixel[0]).powi(2) + (q[1] - pixel[1]).powi(2)).sqrt();
            Some(Predicted {
                vertex,
                board: [x, y],
                pixel,
                black: [black[0], black[1]],
                white: [white[0], white[1]],
                inner_black: [inner_black[0], inner_black[1]],
                inner_white: [inner_white[0], inner_white[1]],
                board_black: [board[0][0], board[0][1]],
                board_white: [board[1][0], board[1][1]],
                board_inner_black: [board[2][0], board[2][1]],
                board_inner_white: [board[3][0], board[3][1]],
                board_step: sq,
                square: len(ax).min(len(ay)),
            })
        })
        .collect()
}

/// How well the prediction shifted by `t` matches the image: every vertex in the image
/// adds its saddle score less one half, so that a vertex predicted in the image where
/// there is no saddle of its colours counts against the shift (a vertex predicted outside
/// the image counts for nothing).
fn total(img: &Integral, predicted: &[Predicted], t: [f64; 2]) -> f64 {
    predicted
        .iter()
        .filter_map(|p| p.score(img, [p.pixel[0] + t[0], p.pixel[1] + t[1]]))
        .map(|s| s - 0.5)
        .sum()
}

/// The shifts of the prediction that match the image best, searched within `reach`
/// pixels: the best, and any other a square or more away that matches nearly as well
/// (see [`AMBIGUOUS`]); `Err` when nothing matches.
fn align(img: &Integral, predicted: &[Predicted], reach: f64) -> Result<Vec<[f64; 2]>, String> {
    let r = reach.ceil() as i64;
    let mut squares: Vec<f64> = predicted.iter().map(|p| p.square).collect();
    squares.sort_by(f64::total_cmp);
    let square = squares[squares.len() / 2];
    let score = |dx: i64, dy: i64| total(img, predicted, [dx as f64, dy as f64]);
    // Coarse to fine: first every sixth of a square (a sample 0.3 squares from its vertex
    // then stays on its square), then every 2 px around every coarse shift that scores at
    // least half the best: where the best alignment and any rival of it can lie.
    let coarse = ((square / 6.0).floor() as i64).max(2) / 2 * 2;
    let steps: Vec<i64> = (-r..=r).step_by(coarse as usize).collect();
    let grid: Vec<Vec<f64>> = steps
        .iter()
        .map(|&dy| steps.iter().map(|&dx| score(dx, dy)).collect())
        .collect();
    let top = grid
        .iter()
        .flatten()
        .copied()
        .fold(f64::NEG_INFINITY, f64::max);
    let mut seeds: Vec<(f64, i64, i64)> = Vec::new();
    for (row, &dy) in grid.iter().zip(&steps) {
        for (&v, &dx) in row.iter().zip(&steps) {
            if v == top || v >= 0.5 * top {
                seeds.push((v, dx, dy));
            }
        }
    }
    let mut fine = std::collections::BTreeMap::new();
    for &(_, sx, sy) in &seeds {
        let (lo_x, lo_y) = ((sx - coarse).max(-r), (sy - coarse).max(-r));
        for dy in (lo_y..=(sy + coarse).min(r)).filter(|d| (d + r) % 2 == 0) {
            for dx in (lo_x..=(sx + coarse).min(r)).filter(|d| (d + r) % 2 == 0) {
                fine.entry((dy, dx)).or_insert_with(|| score(dx, dy));
            }
        }
    }
    let scores: Vec<(f64, [f64; 2])> = fine
        .into_iter()
        .map(|((dy, dx), v)| (v, [dx as f64, dy as f64]))
        .collect();
    let (best, at) = scores
        .iter()
        .copied()
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .unwrap_or((0.0, [0.0, 0.0]));
    if best < MIN_VERTICES as f64 * 0.5 {
        return Err(format!(
            "no board pattern near where the model predicts it (best match {best:.1} vertices)"
        ));
    }
    let far = |t: &[f64; 2], u: &[f64; 2]| (t[0] - u[0]).hypot(t[1] - u[1]) > 0.7 * square;
    let mut candidates = vec![at];
    let mut rivals: Vec<(f64, [f64; 2])> = scores
        .iter()
        .copied()
        .filter(|(s, t)| *s > AMBIGUOUS * best && far(t, &at))
        .collect();
    rivals.sort_by(|a, b| b.0.total_cmp(&a.0));
    for (_, t) in rivals {
        if candidates.len() < 4 && candidates.iter().all(|c| far(c, &t)) {
            candidates.push(t);
        }
    }
    Ok(candidates)
}

/// Refines the vertex started at `start` (the pixel where its saddle peaks) with
/// `cornerSubPix` in a half-window of about `factor` squares that stays inside the image;
/// `None` when it is too near the border, or leaves its start by a quarter of a square
/// (at least 3 px) or more.
fn refine(
    image: &Mat,
    p: &Predicted,
    start: [f64; 2],
    factor: f64,
) -> opencv::Result<Option<[f64; 2]>> {
    let (w, h) = (image.cols() as f64, image.rows() as f64);
    let room = start[0]
        .min(start[1])
        .min(w - 1.0 - start[0])
        .min(h - 1.0 - start[1]);
    let half = ((factor * p.square).round() as i32)
        .clamp(MIN_HALF_WINDOW, 30)
        .min((room - 2.0).floor() as i32);
    if half < MIN_HALF_WINDOW {
        return Ok(None);
    }
    let mut pts = Vector::<Point2f>::from_iter([Point2f::new(start[0] as f32, start[1] as f32)]);
    let criteria = TermCriteria::new(
        core::TermCriteria_Type::COUNT as i32 | core::TermCriteria_Type::EPS as i32,
        50,
        1e-4,
    )?;
    imgproc::corner_sub_pix(
        image,
        &mut pts,
        Size::new(half, half),
        Size::new(-1, -1),
        criteria,
    )?;
    let q = pts.get(0)?;
    if q.x == start[0] as f32 && q.y == start[1] as f32 {
        // cornerSubPix leaves a point where its window holds no usable gradients.
        return Ok(None);
    }
    let q = [q.x as f64, q.y as f64];
    let moved = ((q[0] - start[0]).powi(2) + (q[1] - start[1]).powi(2)).sqrt();
    let inside = q[0] - half as f64 - 1.0 >= 0.0
        && q[1] - half as f64 - 1.0 >= 0.0
        && q[0] + half as f64 + 1.0 <= w - 1.0
        && q[1] + half as f64 + 1.0 <= h - 1.0;
    Ok((moved < (p.square / 4.0).max(3.0) && inside).then_some(q))
}

/// Finds the vertex `p` near `guess`: where its saddle peaks, refined with
/// `cornerSubPix`, and still a saddle there.
fn locate(
    image: &Mat,
    integral: &Integral,
    p: &Predicted,
    guess: [f64; 2],
    factor: f64,
) -> opencv::Result<Option<[f64; 2]>> {
    let Some(start) = p.peak(integral, guess) else {
        return Ok(None);
    };
    let r = refine(image, p, start, factor)?;
    Ok(r.filter(|q| p.centred(integral, *q).unwrap_or(0.0) >= MIN_SCORE))
}

/// The undistorted pixel of `p` (the pinhole image of the same ray).
fn undistorted(camera: &Camera, p: [f64; 2]) -> [f64; 2] {
    let [a, b] = camera.undistort(p[0], p[1]);
    [camera.cx + camera.fx * a, camera.cy + camera.fy * b]
}

/// The (distorted) pixel of undistorted pixel `p`.
fn distorted(camera: &Camera, p: [f64; 2]) -> Option<[f64; 2]> {
    let a = (p[0] - camera.cx) / camera.fx;
    let b = (p[1] - camera.cy) / camera.fy;
    camera.project(&[1.0, -a, -b])
}

/// A homography from the board plane to undistorted pixels fitted to `found` (indices
/// into `predicted`), dropping the worst vertex while one is more than `tolerance` px
/// off; returns it with the vertices kept.
fn consistent(
    camera: &Camera,
    predicted: &[Predicted],
    found: &[(usize, [f64; 2])],
    tolerance: f64,
) -> Option<(Matrix3<f64>, Indexed)> {
    let mut kept: Vec<(usize, [f64; 2])> = found.to_vec();
    loop {
        if kept.len() < MIN_VERTICES {
            return None;
        }
        let src: Vec<[f64; 2]> = kept.iter().map(|(k, _)| predicted[*k].board).collect();
        let dst: Vec<[f64; 2]> = kept.iter().map(|(_, q)| undistorted(camera, *q)).collect();
        let h = assign::homography(&src, &dst)?;
        let (worst, err) = src
            .iter()
            .zip(&dst)
            .map(|(s, d)| {
                let q = assign::apply(&h, *s);
                ((q[0] - d[0]).powi(2) + (q[1] - d[1]).powi(2)).sqrt()
            })
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(&b.1))?;
        if err <= tolerance {
            return Some((h, kept));
        }
        kept.remove(worst);
    }
}

/// What the model-guided search found of one board.
#[derive(Debug, Clone)]
pub struct Board {
    /// The vertices found, in row-major order, with their pixels.
    pub vertices: Placed,
    /// Where the homography of the vertices found puts every vertex of the board (row-major;
    /// `None` for one it cannot place in the image plane): which of them are in view.
    pub fitted: Vec<(Vertex, Option<[f64; 2]>)>,
    /// How the numbering was decided (for the log).
    pub numbered: String,
}

impl Board {
    /// The board's side in pixels, from neighbouring vertices where the homography puts
    /// them (the median over the board), or `None` when no two neighbours are placed.
    pub fn square(&self) -> Option<f64> {
        let at = |v: Vertex| {
            self.fitted
                .iter()
                .find(|(w, _)| *w == v)
                .and_then(|(_, p)| *p)
        };
        let mut sides: Vec<f64> = self
            .fitted
            .iter()
            .filter_map(|(v, p)| {
                let p = (*p)?;
                let q = at(Vertex {
                    row: v.row,
                    col: v.col + 1,
                })?;
                Some((p[0] - q[0]).hypot(p[1] - q[1]))
            })
            .collect();
        sides.sort_by(f64::total_cmp);
        sides.get(sides.len() / 2).copied()
    }
}

/// The vertices of the board found by the model-guided search in `image` (8-bit grey),
/// with the board predicted in pose `pose` (`T_CB`) for camera `camera`; `Err` with the
/// reason when fewer than [`MIN_VERTICES`] are found or the alignment is ambiguous.
/// `factor` is the half-window of `cornerSubPix` in squares; `uncertainty_deg` how far
/// (as an angle of view) the prediction may be off.
pub fn detect(
    image: &Mat,
    integral: &Integral,
    model: &Model,
    camera: &Camera,
    pose: &Pose<f64>,
    factor: f64,
    uncertainty_deg: f64,
) -> opencv::Result<Result<Board, String>> {
    let predicted = predict(model, camera, pose);
    if predicted.len() < MIN_VERTICES {
        return Ok(Err("the model puts the board behind the camera".into()));
    }
    let mut squares: Vec<f64> = predicted.iter().map(|p| p.square).collect();
    squares.sort_by(f64::total_cmp);
    let square = squares[squares.len() / 2];
    // A small error of the prediction moves the board by up to about a square; the search
    // reaches a little further first, then as far as the prediction's uncertainty
    // (`uncertainty_deg` of camera angle) can move it. Alignments off by whole squares are
    // numbered right by the image ([`settle`]).
    let reach = (1.25 * square).max(24.0);
    let wide = uncertainty_deg.to_radians() * camera.fx.max(camera.fy);
    let candidates = match align(integral, &predicted, reach) {
        Ok(c) => c,
        Err(_) if wide > reach => match align(integral, &predicted, wide) {
            Ok(c) => c,
            Err(reason) => return Ok(Err(reason)),
        },
        Err(reason) => return Ok(Err(reason)),
    };
    let tolerance = (0.04 * square).max(0.75);
    let mut outcomes = Vec::new();
    for shift in &candidates {
        if let Some(found) = search(
            image, integral, camera, &predicted, *shift, factor, tolerance,
        )? {
            outcomes.push(found);
        }
    }
    if outcomes.is_empty() {
        return Ok(Err(
            "too few vertices found where the model predicts the board".into(),
        ));
    }
    // The image decides each alignment's numbering; one it cannot decide is dropped. An
    // alignment sharing a vertex's pixel with one already settled is on the same lattice,
    // which the image numbers the same way: not settled again.
    outcomes.sort_by_key(|f| std::cmp::Reverse(f.support()));
    let mut settled: Vec<Found> = Vec::new();
    let mut undecided = None;
    for found in outcomes {
        let same_lattice = settled.iter().any(|s| {
            s.kept.iter().any(|(_, q)| {
                found
                    .kept
                    .iter()
                    .any(|(_, r)| (q[0] - r[0]).hypot(q[1] - r[1]) < 1.0)
            })
        });
        if same_lattice {
            continue;
        }
        match settle(
            image, integral, model, camera, &predicted, found, factor, tolerance,
        )? {
            Ok(f) => settled.push(f),
            Err(reason) => undecided = undecided.or(Some(reason)),
        }
    }
    let mut outcomes = settled;
    // Alignments that end in the same vertices at the same pixels are one; of different
    // numberings, one must be clearly better supported, else nothing is numbered.
    outcomes.sort_by_key(|f| std::cmp::Reverse(f.support()));
    let Some(best) = outcomes.first() else {
        return Ok(Err(format!(
            "numbering not decided: {}",
            undecided.unwrap_or_default()
        )));
    };
    for other in &outcomes[1..] {
        if !best.agrees(other) && other.support() + CLEARLY > best.support() {
            return Ok(Err(format!(
                "ambiguous: the pattern fits {} vertices (and misses {}) in one place and {} \
                 (missing {}) a square or more away",
                best.kept.len(),
                best.missing,
                other.kept.len(),
                other.missing
            )));
        }
    }
    let mut kept = best.kept.clone();
    kept.sort_by_key(|(k, _)| predicted[*k].vertex);
    let fitted = model
        .board
        .vertices()
        .map(|v| {
            let [x, y, _] = model.board.vertex_position(v);
            let pixel = distorted(camera, assign::apply(&best.homography, [x, y]));
            (v, pixel.filter(|p| p[0].is_finite() && p[1].is_finite()))
        })
        .collect();
    Ok(Ok(Board {
        numbered: best.numbered.clone().unwrap_or_default(),
        vertices: kept
            .into_iter()
            .map(|(k, q)| (predicted[k].vertex, q))
            .collect(),
        fitted,
    }))
}

/// The vertices one alignment leads to.
struct Found {
    /// Index into the prediction and pixel of each vertex found.
    kept: Vec<(usize, [f64; 2])>,
    /// Vertices the final homography puts well inside the image where no saddle of their
    /// colours is.
    missing: usize,
    /// That homography: board plane (mm) to undistorted pixels.
    homography: Matrix3<f64>,
    /// How the numbering was decided, once it is.
    numbered: Option<String>,
}

/// How much more support one alignment needs than another that numbers differently.
const CLEARLY: i64 = 4;

impl Found {
    /// Vertices found less twice the vertices missing.
    fn support(&self) -> i64 {
        self.kept.len() as i64 - 2 * self.missing as i64
    }

    /// Whether both give the same vertex at the same pixel wherever they share a pixel.
    fn agrees(&self, other: &Found) -> bool {
        self.kept.iter().all(|(k, q)| {
            other.kept.iter().all(|(j, r)| {
                let same_place = (q[0] - r[0]).hypot(q[1] - r[1]) < 1.0;
                same_place == (k == j)
            })
        })
    }
}

/// Finds the vertices starting from the prediction shifted by `shift`: each where its
/// saddle peaks, refined and checked, those fitting one homography kept; then the
/// vertices that homography predicts, likewise. `None` when too few are found.
fn search(
    image: &Mat,
    integral: &Integral,
    camera: &Camera,
    predicted: &[Predicted],
    shift: [f64; 2],
    factor: f64,
    tolerance: f64,
) -> opencv::Result<Option<Found>> {
    let mut found: Vec<(usize, [f64; 2])> = Vec::new();
    for (k, p) in predicted.iter().enumerate() {
        let guess = [p.pixel[0] + shift[0], p.pixel[1] + shift[1]];
        if let Some(q) = locate(image, integral, p, guess, factor)? {
            found.push((k, q));
        }
    }
    grow(
        image, integral, camera, predicted, &found, factor, tolerance,
    )
}

/// Finds the vertices where the homography `h` (board plane to undistorted pixels) puts
/// them, as [`search`] does from a shifted prediction.
fn search_from(
    image: &Mat,
    integral: &Integral,
    camera: &Camera,
    predicted: &[Predicted],
    h: &Matrix3<f64>,
    factor: f64,
    tolerance: f64,
) -> opencv::Result<Option<Found>> {
    let Some(seen) = reshape(predicted, h, camera) else {
        return Ok(None);
    };
    let mut found: Vec<(usize, [f64; 2])> = Vec::new();
    for (k, p) in seen.iter().enumerate() {
        if let Some(q) = locate(image, integral, p, p.pixel, factor)? {
            found.push((k, q));
        }
    }
    grow(
        image, integral, camera, predicted, &found, factor, tolerance,
    )
}

/// The vertices of `found` that fit one homography, and those that homography predicts
/// (twice over); `None` when too few are left.
fn grow(
    image: &Mat,
    integral: &Integral,
    camera: &Camera,
    predicted: &[Predicted],
    found: &[(usize, [f64; 2])],
    factor: f64,
    tolerance: f64,
) -> opencv::Result<Option<Found>> {
    let Some((mut h, mut kept)) = consistent(camera, predicted, found, tolerance) else {
        return Ok(None);
    };
    // The homography of the vertices found predicts the others, and how each looks (the
    // model's prediction may be turned against the image).
    let mut missing = 0;
    for round in 0..2 {
        let Some(seen) = reshape(predicted, &h, camera) else {
            return Ok(None);
        };
        missing = 0;
        let before = kept.len();
        for (k, p) in seen.iter().enumerate() {
            if kept.iter().any(|(j, _)| *j == k) {
                continue;
            }
            if let Some(q) = locate(image, integral, p, p.pixel, factor)? {
                kept.push((k, q));
            } else if p.score(integral, p.pixel).is_some_and(|s| s == 0.0) {
                missing += 1;
            }
        }
        match consistent(camera, predicted, &kept, tolerance) {
            Some((h2, k2)) => (h, kept) = (h2, k2),
            None => return Ok(None),
        }
        if round == 1 || kept.len() == before {
            break;
        }
    }
    Ok(Some(Found {
        kept,
        missing,
        homography: h,
        numbered: None,
    }))
}

/// Lets the image decide the numbering of `found` ([`numbering::decide`]); when it is off
/// by whole squares, searches again where the corrected numbering puts the vertices.
/// Then the prediction must rule out the 180° turn ([`numbering::turn_check`]). `Err`
/// with the reason when the numbering cannot be decided.
#[allow(clippy::too_many_arguments)]
fn settle(
    image: &Mat,
    integral: &Integral,
    model: &Model,
    camera: &Camera,
    predicted: &[Predicted],
    mut found: Found,
    factor: f64,
    tolerance: f64,
) -> opencv::Result<Result<Found, String>> {
    let mut total_shift = (0, 0);
    for _ in 0..3 {
        let lattice: Vec<(i32, i32)> = found
            .kept
            .iter()
            .map(|(k, _)| {
                let v = predicted[*k].vertex;
                (v.col as i32, v.row as i32)
            })
            .collect();
        let decided = match numbering::decide(integral, camera, model, &found.homography, &lattice)
        {
            Ok(d) => d,
            Err(reason) => return Ok(Err(reason)),
        };
        if decided.shift == (0, 0) {
            let pixels: Vec<[f64; 2]> = found.kept.iter().map(|(_, q)| *q).collect();
            let expected: Vec<[f64; 2]> = found
                .kept
                .iter()
                .map(|(k, _)| predicted[*k].pixel)
                .collect();
            let turn = match numbering::turn_check(&pixels, &expected) {
                Ok(t) => t,
                Err(reason) => return Ok(Err(reason)),
            };
            let decided = numbering::Decided {
                shift: total_shift,
                ..decided
            };
            found.numbered = Some(format!(
                "{}; 180° turn ruled out by the prediction (turned {turn:.0}° against it)",
                decided.describe()
            ));
            return Ok(Ok(found));
        }
        total_shift = (
            total_shift.0 + decided.shift.0,
            total_shift.1 + decided.shift.1,
        );
        let h = numbering::shifted(model, &found.homography, decided.shift);
        match search_from(image, integral, camera, predicted, &h, factor, tolerance)? {
            Some(f) => found = f,
            None => {
                return Ok(Err(format!(
                    "the image puts the board {} column(s), {} row(s) from the prediction's \
                     alignment, but too few vertices are found there",
                    decided.shift.0, decided.shift.1
                )));
            }
        }
    }
    Ok(Err("the numbering does not settle".into()))
}

/// The prediction redone with the homography `h` (board plane to undistorted pixels) of
/// the vertices found: where each vertex is and how its squares lie in the image.
fn reshape(predicted: &[Predicted], h: &Matrix3<f64>, camera: &Camera) -> Option<Vec<Predicted>> {
    let at = |x: f64, y: f64| distorted(camera, assign::apply(h, [x, y]));
    predicted
        .iter()
        .map(|p| {
            let [x, y] = p.board;
            let pixel = at(x, y)?;
            let to = |ring: &[[f64; 2]; 2]| -> Option<[[f64; 2]; 2]> {
                let mut out = [[0.0; 2]; 2];
                for (o, d) in out.iter_mut().zip(ring) {
                    let q = at(x + d[0], y + d[1])?;
                    *o = [q[0] - pixel[0], q[1] - pixel[1]];
                }
                Some(out)
            };
            let ax = at(x + p.board_step, y)?;
            let ay = at(x, y + p.board_step)?;
            let len = |q: [f64; 2]| (q[0] - pixel[0]).hypot(q[1] - pixel[1]);
            Some(Predicted {
                pixel,
                black: to(&p.board_black)?,
                white: to(&p.board_white)?,
                inner_black: to(&p.board_inner_black)?,
                inner_white: to(&p.board_inner_white)?,
                square: len(ax).min(len(ay)),
                ..p.clone()
            })
        })
        .collect()
}
