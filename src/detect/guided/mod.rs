//! Model-guided detection: the logged joints and the model say where every vertex of the
//! board should appear and which way its squares are coloured; the image is searched for
//! that pattern of saddles, each vertex is refined where it is, checked, and numbered by
//! the image.
//!
//! 1. **Prediction.** Every vertex and four points around it (0.3 of a square along the
//!    board's diagonals, two on black squares and two on white ones) are projected with
//!    the model (`pattern.rs`).
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
//! 5. **Numbering.** The image decides each alignment's (row, col) ([`numbering`]); the
//!    prediction only rules out the pattern's 180° turn.
//!
//! One image's search is a `Search`: the image, the prediction and the settings every
//! step shares.
//!
//! Vertices too close to the image border for a window of [`MIN_HALF_WINDOW`] pixels are
//! left out rather than kept biased.

pub(in crate::detect) mod pattern;

use crate::detect::cv;
use crate::detect::find::{SUBPIX_EPS, SUBPIX_ITERATIONS};
use crate::sim::render::GreyImage;
use nalgebra::Matrix3;

use crate::model::{Camera, Model, Pose, Vertex};

use super::saddle::{Dropped, Saddles};
use super::{assign, numbering};
pub use pattern::Integral;
use pattern::{MIN_SCORE, Predicted, distorted, median_square, predict, reshape, undistorted};

/// Vertices by index into the prediction, with their pixels.
type Indexed = Vec<(usize, [f64; 2])>;
/// Vertices with their pixels.
type Placed = Vec<(Vertex, [f64; 2])>;

/// Smallest half-window of `cornerSubPix` (px); a vertex nearer the border than this
/// window (plus the pixel its gradients need) is not refined, but dropped.
pub const MIN_HALF_WINDOW: i32 = 2;
/// Fewest vertices of a board worth keeping.
pub const MIN_VERTICES: usize = 6;
/// Part of the best alignment's score another alignment a square away may reach.
const AMBIGUOUS: f64 = 0.75;
/// How much more support one alignment needs than another that numbers differently.
const CLEARLY: i64 = 4;

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
    /// The vertices refined but dropped by the image test ([`super::saddle`]): an
    /// occluding edge pulled them, or may have.
    pub dropped: Vec<Dropped>,
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
    image: &GreyImage,
    integral: &Integral,
    model: &Model,
    camera: &Camera,
    pose: &Pose<f64>,
    factor: f64,
    uncertainty_deg: f64,
) -> cv::Result<Result<Board, String>> {
    let prediction = predict(model, camera, pose);
    if prediction.len() < MIN_VERTICES {
        return Ok(Err("the model puts the board behind the camera".into()));
    }
    let square = median_square(&prediction);
    let search = Search {
        image,
        integral,
        model,
        camera,
        prediction,
        square,
        factor,
        tolerance: (0.04 * square).max(0.75),
    };
    search.run(uncertainty_deg)
}

/// One model-guided search of a board in one image: the image, where the model predicts
/// the board, and the settings every step of the search shares.
struct Search<'a> {
    /// The image (8-bit grey).
    image: &'a GreyImage,
    /// Its integral image, for the saddle scores.
    integral: &'a Integral,
    /// The model (its board's geometry).
    model: &'a Model,
    /// The camera that took the image.
    camera: &'a Camera,
    /// The predicted look of every vertex in front of the camera (at least
    /// [`MIN_VERTICES`]).
    prediction: Vec<Predicted>,
    /// The median local size of a square in the prediction (px).
    square: f64,
    /// Half-window of `cornerSubPix` in squares.
    factor: f64,
    /// Farthest (px) a vertex may lie from the homography of the others.
    tolerance: f64,
}

/// The vertices one alignment leads to.
struct Found {
    /// Index into the prediction and pixel of each vertex found.
    kept: Indexed,
    /// Vertices the final homography puts well inside the image where no saddle of their
    /// colours is.
    missing: usize,
    /// That homography: board plane (mm) to undistorted pixels.
    homography: Matrix3<f64>,
    /// How the numbering was decided, once it is.
    numbered: Option<String>,
}

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

    /// Whether a vertex of both lies at the same pixel: both are on one lattice.
    fn shares_a_pixel(&self, other: &Found) -> bool {
        self.kept.iter().any(|(_, q)| {
            other
                .kept
                .iter()
                .any(|(_, r)| (q[0] - r[0]).hypot(q[1] - r[1]) < 1.0)
        })
    }
}

impl Search<'_> {
    /// The whole search: the alignments of the prediction with the image, the vertices
    /// each leads to, numbered by the image; the board when one numbering is clearly
    /// best supported.
    fn run(&self, uncertainty_deg: f64) -> cv::Result<Result<Board, String>> {
        let candidates = match self.alignments(uncertainty_deg) {
            Ok(c) => c,
            Err(reason) => return Ok(Err(reason)),
        };
        let mut outcomes = Vec::new();
        for shift in &candidates {
            if let Some(found) = self.search(&self.prediction, *shift)? {
                outcomes.push(found);
            }
        }
        if outcomes.is_empty() {
            return Ok(Err(
                "too few vertices found where the model predicts the board".into(),
            ));
        }
        let settled = match self.settle_all(outcomes)? {
            Ok(settled) => settled,
            Err(reason) => return Ok(Err(reason)),
        };
        Ok(best(&settled).and_then(|found| self.checked(self.board(found))))
    }

    /// `board` with only the vertices that pass the image test ([`Saddles::check`]), the
    /// others named as dropped; `Err` when fewer than [`MIN_VERTICES`] pass.
    fn checked(&self, mut board: Board) -> Result<Board, String> {
        let saddles = Saddles::new(self.image, self.model, self.camera, self.factor);
        let (kept, dropped) = saddles.check(&board.vertices);
        if kept.len() < MIN_VERTICES {
            return Err(format!(
                "{} of {} vertices found are dropped for an occluding edge, too few are left",
                dropped.len(),
                board.vertices.len()
            ));
        }
        board.vertices = kept;
        board.dropped = dropped;
        Ok(board)
    }

    /// The shifts of the prediction worth searching from. A small error of the prediction
    /// moves the board by up to about a square; the search reaches a little further first,
    /// then as far as the prediction's uncertainty (`uncertainty_deg` of camera angle) can
    /// move it. Alignments off by whole squares are numbered right by the image
    /// ([`Search::settle`]).
    fn alignments(&self, uncertainty_deg: f64) -> Result<Vec<[f64; 2]>, String> {
        let reach = (1.25 * self.square).max(24.0);
        let wide = uncertainty_deg.to_radians() * self.camera.fx.max(self.camera.fy);
        match self.align(reach) {
            Err(_) if wide > reach => self.align(wide),
            aligned => aligned,
        }
    }

    /// How well the prediction shifted by `t` matches the image: every vertex in the image
    /// adds its saddle score less one half, so that a vertex predicted in the image where
    /// there is no saddle of its colours counts against the shift (a vertex predicted
    /// outside the image counts for nothing).
    fn total(&self, t: [f64; 2]) -> f64 {
        self.prediction
            .iter()
            .filter_map(|p| p.score(self.integral, [p.pixel[0] + t[0], p.pixel[1] + t[1]]))
            .map(|s| s - 0.5)
            .sum()
    }

    /// The shifts of the prediction that match the image best, searched within `reach`
    /// pixels: the best, and any other a square or more away that matches nearly as well
    /// (see [`AMBIGUOUS`]); `Err` when nothing matches.
    fn align(&self, reach: f64) -> Result<Vec<[f64; 2]>, String> {
        let r = reach.ceil() as i64;
        let square = self.square;
        let score = |dx: i64, dy: i64| self.total([dx as f64, dy as f64]);
        // Coarse to fine: first every sixth of a square (a sample 0.3 squares from its
        // vertex then stays on its square), then every 2 px around every coarse shift that
        // scores at least half the best: where the best alignment and any rival of it can
        // lie.
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
                "no board pattern near where the model predicts it (best match {best:.1} \
                 vertices)"
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

    /// Finds the vertices of `seen` (the prediction, or the prediction redone with a
    /// homography) moved by `shift`: each where its saddle peaks, refined and checked,
    /// those fitting one homography kept; then the vertices that homography predicts,
    /// likewise ([`Search::grow`]). `None` when too few are found.
    fn search(&self, seen: &[Predicted], shift: [f64; 2]) -> cv::Result<Option<Found>> {
        let mut found: Indexed = Vec::new();
        for (k, p) in seen.iter().enumerate() {
            let guess = [p.pixel[0] + shift[0], p.pixel[1] + shift[1]];
            if let Some(q) = self.locate(p, guess)? {
                found.push((k, q));
            }
        }
        self.grow(&found)
    }

    /// The vertices of `found` that fit one homography, and those that homography predicts
    /// (twice over); `None` when too few are left.
    fn grow(&self, found: &[(usize, [f64; 2])]) -> cv::Result<Option<Found>> {
        let Some((mut h, mut kept)) = self.consistent(found) else {
            return Ok(None);
        };
        // The homography of the vertices found predicts the others, and how each looks (the
        // model's prediction may be turned against the image).
        let mut missing = 0;
        for round in 0..2 {
            let Some(seen) = reshape(&self.prediction, &h, self.camera) else {
                return Ok(None);
            };
            missing = 0;
            let before = kept.len();
            for (k, p) in seen.iter().enumerate() {
                if kept.iter().any(|(j, _)| *j == k) {
                    continue;
                }
                if let Some(q) = self.locate(p, p.pixel)? {
                    kept.push((k, q));
                } else if p.score(self.integral, p.pixel).is_some_and(|s| s == 0.0) {
                    missing += 1;
                }
            }
            match self.consistent(&kept) {
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

    /// Finds the vertex `p` near `guess`: where its saddle peaks, refined with
    /// `cornerSubPix`, and still a saddle there.
    fn locate(&self, p: &Predicted, guess: [f64; 2]) -> cv::Result<Option<[f64; 2]>> {
        let Some(start) = p.peak(self.integral, guess) else {
            return Ok(None);
        };
        let r = self.refine(p, start)?;
        Ok(r.filter(|q| p.centred(self.integral, *q).unwrap_or(0.0) >= MIN_SCORE))
    }

    /// Refines the vertex `p` started at `start` (the pixel where its saddle peaks) with
    /// `cornerSubPix` in a half-window of about [`Search::factor`] squares that stays
    /// inside the image; `None` when it is too near the border, or leaves its start by a
    /// quarter of a square (at least 3 px) or more.
    fn refine(&self, p: &Predicted, start: [f64; 2]) -> cv::Result<Option<[f64; 2]>> {
        let image = self.image;
        let (w, h) = (image.width as f64, image.height as f64);
        let room = start[0]
            .min(start[1])
            .min(w - 1.0 - start[0])
            .min(h - 1.0 - start[1]);
        let half = ((self.factor * p.square).round() as i32)
            .clamp(MIN_HALF_WINDOW, 30)
            .min((room - 2.0).floor() as i32);
        if half < MIN_HALF_WINDOW {
            return Ok(None);
        }
        let mut pts = [[start[0] as f32, start[1] as f32]];
        cv::corner_sub_pix(image, &mut pts, half, SUBPIX_ITERATIONS, SUBPIX_EPS)?;
        let q = pts[0];
        if q[0] == start[0] as f32 && q[1] == start[1] as f32 {
            // cornerSubPix leaves a point where its window holds no usable gradients.
            return Ok(None);
        }
        let q = [q[0] as f64, q[1] as f64];
        let moved = ((q[0] - start[0]).powi(2) + (q[1] - start[1]).powi(2)).sqrt();
        let inside = q[0] - half as f64 - 1.0 >= 0.0
            && q[1] - half as f64 - 1.0 >= 0.0
            && q[0] + half as f64 + 1.0 <= w - 1.0
            && q[1] + half as f64 + 1.0 <= h - 1.0;
        Ok((moved < (p.square / 4.0).max(3.0) && inside).then_some(q))
    }

    /// A homography from the board plane to undistorted pixels fitted to `found` (indices
    /// into the prediction), dropping the worst vertex while one is more than
    /// [`Search::tolerance`] px off; returns it with the vertices kept.
    fn consistent(&self, found: &[(usize, [f64; 2])]) -> Option<(Matrix3<f64>, Indexed)> {
        let mut kept: Indexed = found.to_vec();
        loop {
            if kept.len() < MIN_VERTICES {
                return None;
            }
            let src: Vec<[f64; 2]> = kept
                .iter()
                .map(|(k, _)| self.prediction[*k].board)
                .collect();
            let dst: Vec<[f64; 2]> = kept
                .iter()
                .map(|(_, q)| undistorted(self.camera, *q))
                .collect();
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
            if err <= self.tolerance {
                return Some((h, kept));
            }
            kept.remove(worst);
        }
    }

    /// Lets the image number every alignment's vertices ([`Search::settle`]), best
    /// supported first: the alignments numbered (best supported first), or why none is.
    /// An alignment sharing a vertex's pixel with one already settled is on the same
    /// lattice, which the image numbers the same way: not settled again.
    fn settle_all(&self, mut outcomes: Vec<Found>) -> cv::Result<Result<Vec<Found>, String>> {
        outcomes.sort_by_key(|f| std::cmp::Reverse(f.support()));
        let mut settled: Vec<Found> = Vec::new();
        let mut undecided = None;
        for found in outcomes {
            if settled.iter().any(|s| s.shares_a_pixel(&found)) {
                continue;
            }
            match self.settle(found)? {
                Ok(f) => settled.push(f),
                Err(reason) => undecided = undecided.or(Some(reason)),
            }
        }
        if settled.is_empty() {
            return Ok(Err(format!(
                "numbering not decided: {}",
                undecided.unwrap_or_default()
            )));
        }
        settled.sort_by_key(|f| std::cmp::Reverse(f.support()));
        Ok(Ok(settled))
    }

    /// Lets the image decide the numbering of `found` ([`numbering::decide`]); when it is
    /// off by whole squares, searches again where the corrected numbering puts the
    /// vertices. Then the prediction must rule out the 180° turn
    /// ([`numbering::turn_check`]). `Err` with the reason when the numbering cannot be
    /// decided.
    fn settle(&self, mut found: Found) -> cv::Result<Result<Found, String>> {
        let mut total_shift = (0, 0);
        for _ in 0..3 {
            let decided = match self.decide(&found) {
                Ok(d) => d,
                Err(reason) => return Ok(Err(reason)),
            };
            if decided.shift == (0, 0) {
                let turn = match self.turn(&found) {
                    Ok(t) => t,
                    Err(reason) => return Ok(Err(reason)),
                };
                let decided = numbering::Decided {
                    shift: total_shift,
                    ..decided
                };
                found.numbered = Some(format!(
                    "{}; numbered as the prediction turns it ({turn:.0}° against it)",
                    decided.describe()
                ));
                return Ok(Ok(found));
            }
            total_shift = (
                total_shift.0 + decided.shift.0,
                total_shift.1 + decided.shift.1,
            );
            let h = numbering::shifted(self.model, &found.homography, decided.shift);
            let again = match reshape(&self.prediction, &h, self.camera) {
                Some(seen) => self.search(&seen, [0.0, 0.0])?,
                None => None,
            };
            match again {
                Some(f) => found = f,
                None => {
                    return Ok(Err(format!(
                        "the image puts the board {} column(s), {} row(s) from the \
                         prediction's alignment, but too few vertices are found there",
                        decided.shift.0, decided.shift.1
                    )));
                }
            }
        }
        Ok(Err("the numbering does not settle".into()))
    }

    /// The image's numbering of the vertices `found` ([`numbering::decide`]).
    fn decide(&self, found: &Found) -> Result<numbering::Decided, String> {
        let lattice: Vec<(i32, i32)> = found
            .kept
            .iter()
            .map(|(k, _)| {
                let v = self.prediction[*k].vertex;
                (v.col as i32, v.row as i32)
            })
            .collect();
        numbering::decide(
            self.integral,
            self.camera,
            self.model,
            &found.homography,
            &lattice,
        )
    }

    /// How far (deg) the vertices `found` appear turned against the prediction, or why
    /// that cannot rule out the pattern's 180° turn ([`numbering::turn_check`]).
    fn turn(&self, found: &Found) -> Result<f64, String> {
        let pixels: Vec<[f64; 2]> = found.kept.iter().map(|(_, q)| *q).collect();
        let expected: Vec<[f64; 2]> = found
            .kept
            .iter()
            .map(|(k, _)| self.prediction[*k].pixel)
            .collect();
        numbering::turn_check(&pixels, &expected)
    }

    /// The board the vertices `found` make: in row-major order, with where their
    /// homography puts every vertex of the board.
    fn board(&self, found: &Found) -> Board {
        let mut kept = found.kept.clone();
        kept.sort_by_key(|(k, _)| self.prediction[*k].vertex);
        let fitted = self
            .model
            .board
            .vertices()
            .map(|v| {
                let [x, y, _] = self.model.board.vertex_position(v);
                let pixel = distorted(self.camera, assign::apply(&found.homography, [x, y]));
                (v, pixel.filter(|p| p[0].is_finite() && p[1].is_finite()))
            })
            .collect();
        Board {
            numbered: found.numbered.clone().unwrap_or_default(),
            dropped: Vec::new(),
            vertices: kept
                .into_iter()
                .map(|(k, q)| (self.prediction[k].vertex, q))
                .collect(),
            fitted,
        }
    }
}

/// The best supported of the numbered alignments `settled` (best supported first; not
/// empty). Alignments that end in the same vertices at the same pixels are one; of
/// different numberings, one must be clearly better supported, else nothing is numbered.
fn best(settled: &[Found]) -> Result<&Found, String> {
    let best = &settled[0];
    for other in &settled[1..] {
        if !best.agrees(other) && other.support() + CLEARLY > best.support() {
            return Err(format!(
                "ambiguous: the pattern fits {} vertices (and misses {}) in one place and {} \
                 (missing {}) a square or more away",
                best.kept.len(),
                best.missing,
                other.kept.len(),
                other.missing
            ));
        }
    }
    Ok(best)
}
