//! Which (row, col) the vertices of a found board get: decided by the image, not by the
//! prediction.
//!
//! The vertices found lie on a lattice of the board plane, given by a homography from
//! their tentative numbering. The pattern's 6 × 4 inner vertices are saddles; the ring of
//! lattice points just outside them (on the pattern's edge, where the outer squares meet
//! the white plate) are not. Every numbering that keeps all vertices found inside the
//! pattern (the tentative one shifted by whole squares) is scored against what the image
//! shows at each lattice point: a saddle of the expected colours, the pattern's edge (a
//! white plate on one side, squares of both colours on the other), something else, or
//! unknown (out of view, too small). Only saddles and the pattern's edge are evidence: a
//! point that shows neither may be covered (a toe standing on the board, a leg in front of
//! it), which says nothing of the numbering. A numbering is accepted only when it agrees
//! with the image and every other disagrees clearly more; a board whose visible part fits
//! several is rejected with the reason (nothing is numbered by guesswork).
//!
//! The 7 × 5 pattern (odd by odd, black corners) looks the same turned by 180°: that turn
//! alone is resolved by the prediction, and only when the board appears turned against
//! the prediction by far less than 90° (the two candidates are 180° apart), see
//! [`turn_check`].

use nalgebra::Matrix3;

use super::assign;
use super::guided::pattern::{self, Integral, is_black};
use crate::model::{Camera, Model};

/// What the image shows at one lattice point.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Seen {
    /// A saddle with the colours of the tentative numbering (`true`) or the opposite.
    Saddle(bool),
    /// The pattern's edge: on one side a plain area as bright as the white squares (the
    /// plate), on the other two squares of both colours.
    Edge,
    /// No saddle and not the pattern's edge: a plain area (the plate, the background, a
    /// part of the robot covering the board) or another edge.
    Plain,
    /// Out of view, too small or unclear.
    Unknown,
}

/// Smallest local square (px) at which a lattice point is judged.
const MIN_SQUARE_PX: f64 = 5.0;
/// Smallest saddle contrast (grey levels) that counts as a saddle.
const MIN_CONTRAST: f64 = 12.0;
/// How many more disagreements every other numbering must have than the accepted one.
pub const MARGIN: usize = 3;
/// Most disagreements the accepted numbering may have (a vertex blurred or occluded)…
const MAX_DISAGREE: usize = 1;
/// … or this part of its agreements: a column of the pattern covered by a toe whose edge
/// looks like the pattern's (4 points against the 30 or more a board's visible part
/// agrees at), and one more. A numbering whose lattice is wrong disagrees far more.
const MAX_DISAGREE_PART: f64 = 1.0 / 6.0;
/// Largest in-image turn (deg) of a board against the prediction for the prediction to
/// decide between a numbering and its 180° turn.
pub const MAX_TURN_DEG: f64 = 45.0;

/// How a board's numbering was decided.
#[derive(Debug, Clone, PartialEq)]
pub struct Decided {
    /// The shift (columns, rows) of the lattice from the tentative numbering to the
    /// accepted one: the accepted vertex (row, col) is tentative (row − rows, col − cols).
    pub shift: (i32, i32),
    /// Lattice points whose look agrees with the accepted numbering.
    pub agree: usize,
    /// Lattice points whose look contradicts it.
    pub disagree: usize,
    /// Numberings considered (all keeping the vertices found inside the pattern).
    pub candidates: usize,
    /// The fewest disagreements of any other numbering (`None` when there was none).
    pub runner_up: Option<usize>,
    /// Pattern edges (left, right, top, bottom) seen as edges (no saddle on the ring).
    pub edges: [bool; 4],
}

impl Decided {
    /// One line for the log.
    pub fn describe(&self) -> String {
        let names = ["left", "right", "top", "bottom"];
        let edges: Vec<&str> = names
            .iter()
            .zip(self.edges)
            .filter_map(|(n, e)| e.then_some(*n))
            .collect();
        let mut s = format!(
            "numbered by the image: {} lattice points agree, {} disagree",
            self.agree, self.disagree
        );
        if !edges.is_empty() {
            s += &format!(", pattern edge seen {}", edges.join("/"));
        }
        match self.runner_up {
            Some(r) => {
                s += &format!(
                    "; every other of {} numberings disagrees at ≥ {r}",
                    self.candidates
                )
            }
            None => s += "; no other numbering possible",
        }
        if self.shift != (0, 0) {
            s += &format!(
                "; the prediction's alignment was {} column(s), {} row(s) off",
                self.shift.0, self.shift.1
            );
        }
        s
    }
}

/// Board-plane position (mm) of lattice point (col `i`, row `j`) of `model`'s board (the
/// inner vertices are `0 ≤ i < cols`, `0 ≤ j < rows`).
fn lattice(model: &Model, i: i32, j: i32) -> [f64; 2] {
    let b = &model.board;
    [
        (i as f64 - (b.squares_x as f64 - 2.0) / 2.0) * b.square,
        (j as f64 - (b.squares_y as f64 - 2.0) / 2.0) * b.square,
    ]
}

/// The (distorted) pixel of undistorted pixel `p`, or `None` when it is not finite.
fn distorted(camera: &Camera, p: [f64; 2]) -> Option<[f64; 2]> {
    pattern::distorted(camera, p).filter(|q| q[0].is_finite() && q[1].is_finite())
}

/// What the image shows at lattice point `(i, j)` of the board mapped by `h` (board plane
/// to undistorted pixels), with the colours of that numbering.
fn look(img: &Integral, camera: &Camera, model: &Model, h: &Matrix3<f64>, i: i32, j: i32) -> Seen {
    let sq = model.board.square;
    let [x, y] = lattice(model, i, j);
    let at = |dx: f64, dy: f64| distorted(camera, assign::apply(h, [x + dx, y + dy]));
    let Some(p) = at(0.0, 0.0) else {
        return Seen::Unknown;
    };
    let side = |q: Option<[f64; 2]>| q.map(|q| (q[0] - p[0]).hypot(q[1] - p[1]));
    let (Some(ax), Some(ay)) = (side(at(sq, 0.0)), side(at(0.0, sq))) else {
        return Seen::Unknown;
    };
    let square = ax.min(ay);
    if square.is_nan() || square < MIN_SQUARE_PX {
        return Seen::Unknown;
    }
    let patch = ((0.1 * square).round() as i64).clamp(1, 6);
    let (mut black, mut white) = (Vec::with_capacity(2), Vec::with_capacity(2));
    // The samples by side: (x > 0, y > 0), (x < 0, y > 0), (x > 0, y < 0), (x < 0, y < 0).
    let mut around = [0.0; 4];
    for (k, (sx, sy)) in [(1.0, 1.0), (-1.0, 1.0), (1.0, -1.0), (-1.0, -1.0)]
        .into_iter()
        .enumerate()
    {
        let (dx, dy) = (0.3 * sq * sx, 0.3 * sq * sy);
        let Some(q) = at(dx, dy) else {
            return Seen::Unknown;
        };
        let Some(m) = img.mean(q[0], q[1], patch) else {
            return Seen::Unknown;
        };
        around[k] = m;
        if is_black(model, x + dx, y + dy) {
            black.push(m);
        } else {
            white.push(m);
        }
    }
    if black.len() != 2 || white.len() != 2 {
        return Seen::Unknown;
    }
    let max = |v: &[f64]| v[0].max(v[1]);
    let min = |v: &[f64]| v[0].min(v[1]);
    let range = max(&black).max(max(&white)) - min(&black).min(min(&white));
    let same = min(&white) - max(&black);
    let opposite = min(&black) - max(&white);
    let strong = MIN_CONTRAST.max(0.4 * range);
    if same >= strong {
        Seen::Saddle(true)
    } else if opposite >= strong {
        Seen::Saddle(false)
    } else if is_edge(&around, strong, range) {
        Seen::Edge
    } else if range < 0.5 * MIN_CONTRAST || same.max(opposite) <= 0.15 * range {
        Seen::Plain
    } else {
        Seen::Unknown
    }
}

/// Whether the four samples `around` a lattice point (see [`look`]) show the pattern's
/// edge along either board axis: one side's two alike (within 15 % of the samples'
/// `range`) and as bright as the other side's brighter one, the other side's two apart by
/// at least `strong`.
fn is_edge(around: &[f64; 4], strong: f64, range: f64) -> bool {
    // The pairs on each side: x > 0 and x < 0, then y > 0 and y < 0.
    let sides = [[0, 2], [1, 3], [0, 1], [2, 3]];
    (0..4).any(|k| {
        let plate = sides[k];
        let squares = sides[k ^ 1];
        let (p0, p1) = (around[plate[0]], around[plate[1]]);
        let (q0, q1) = (around[squares[0]], around[squares[1]]);
        (p0 - p1).abs() <= 0.15 * range
            && (q0 - q1).abs() >= strong
            && p0.min(p1) >= q0.max(q1) - 0.15 * range
    })
}

/// How one numbering (the tentative one shifted by whole squares) fares against the image.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Score {
    /// The shift (columns, rows) from the tentative numbering (see [`Decided::shift`]).
    shift: (i32, i32),
    /// Lattice points whose look agrees with this numbering.
    agree: usize,
    /// Lattice points whose look contradicts it.
    disagree: usize,
    /// Pattern edges (left, right, top, bottom) seen as edges (no saddle on the ring).
    edges: [bool; 4],
}

/// What the image shows on a rectangle of lattice points, each looked at once.
struct Looks {
    /// Lattice point (col, row) of the rectangle's first entry.
    origin: (i32, i32),
    /// Columns of the rectangle.
    width: usize,
    /// Row by row.
    seen: Vec<Seen>,
}

impl Looks {
    /// What the image shows at every lattice point `(i, j)` with `i` in `cols`, `j` in
    /// `rows`, of the board mapped by `h` ([`look`]).
    fn new(
        img: &Integral,
        camera: &Camera,
        model: &Model,
        h: &Matrix3<f64>,
        cols: std::ops::Range<i32>,
        rows: std::ops::Range<i32>,
    ) -> Looks {
        let seen = rows
            .clone()
            .flat_map(|j| cols.clone().map(move |i| (i, j)))
            .map(|(i, j)| look(img, camera, model, h, i, j))
            .collect();
        Looks {
            origin: (cols.start, rows.start),
            width: cols.len(),
            seen,
        }
    }

    /// What the image shows at lattice point `(i, j)` (inside the rectangle).
    fn at(&self, i: i32, j: i32) -> Seen {
        let (i0, j0) = self.origin;
        self.seen[(j - j0) as usize * self.width + (i - i0) as usize]
    }

    /// How the numbering shifted by `(a, b)` fares: its `cols` × `rows` inner vertices
    /// must show saddles of its colours, the ring just outside them none.
    fn score(&self, (a, b): (i32, i32), cols: i32, rows: i32) -> Score {
        let parity = (a + b).rem_euclid(2) == 0;
        let mut score = Score {
            shift: (a, b),
            agree: 0,
            disagree: 0,
            edges: [false; 4],
        };
        for j in b - 1..=b + rows {
            for i in a - 1..=a + cols {
                let inner = i >= a && i < a + cols && j >= b && j < b + rows;
                let ring = !inner;
                // The ring's corners touch a single square: not looked at.
                if ring && (i == a - 1 || i == a + cols) && (j == b - 1 || j == b + rows) {
                    continue;
                }
                // A plain look may be the robot's body covering the board: no evidence.
                let ok = match (inner, self.at(i, j)) {
                    (_, Seen::Unknown | Seen::Plain) => None,
                    (true, Seen::Saddle(p)) => Some(p == parity),
                    (true, Seen::Edge) => Some(false),
                    (false, Seen::Edge) => Some(true),
                    (false, Seen::Saddle(_)) => Some(false),
                };
                match ok {
                    Some(true) => score.agree += 1,
                    Some(false) => score.disagree += 1,
                    None => {}
                }
                if ring && ok == Some(true) {
                    let side = if i == a - 1 {
                        0
                    } else if i == a + cols {
                        1
                    } else if j == b - 1 {
                        2
                    } else {
                        3
                    };
                    score.edges[side] = true;
                }
            }
        }
        score
    }
}

/// Decides the numbering of a board whose vertices were found at lattice points `found`
/// (col, row of the tentative numbering) with homography `h` (board plane of the
/// tentative numbering, mm, to undistorted pixels): the shift to the numbering the image
/// supports, or why it cannot be decided.
pub fn decide(
    img: &Integral,
    camera: &Camera,
    model: &Model,
    h: &Matrix3<f64>,
    found: &[(i32, i32)],
) -> Result<Decided, String> {
    let (cols, rows) = (model.board.cols() as i32, model.board.rows() as i32);
    if found.is_empty() {
        return Err("no vertex found".into());
    }
    let (min_i, max_i) = found
        .iter()
        .fold((i32::MAX, i32::MIN), |(a, b), v| (a.min(v.0), b.max(v.0)));
    let (min_j, max_j) = found
        .iter()
        .fold((i32::MAX, i32::MIN), |(a, b), v| (a.min(v.1), b.max(v.1)));
    // Shifts (a, b): the accepted vertex (row r, col c) is at tentative lattice point
    // (c + a, r + b); every vertex found must stay an inner vertex.
    let (a_lo, a_hi) = (max_i - (cols - 1), min_i);
    let (b_lo, b_hi) = (max_j - (rows - 1), min_j);
    if a_lo > a_hi || b_lo > b_hi {
        return Err(format!(
            "the vertices found span {} columns and {} rows, more than the pattern's {cols} × {rows}",
            max_i - min_i + 1,
            max_j - min_j + 1
        ));
    }
    // What the image shows on every lattice point any candidate looks at.
    let looks = Looks::new(
        img,
        camera,
        model,
        h,
        a_lo - 1..a_hi + cols + 1,
        b_lo - 1..b_hi + rows + 1,
    );
    let mut scored: Vec<Score> = (b_lo..=b_hi)
        .flat_map(|b| (a_lo..=a_hi).map(move |a| (a, b)))
        .map(|shift| looks.score(shift, cols, rows))
        .collect();
    scored.sort_by_key(|s| (s.disagree, std::cmp::Reverse(s.agree)));
    let best = scored[0];
    let runner_up = scored.get(1).map(|s| s.disagree);
    let allowed = MAX_DISAGREE.max((MAX_DISAGREE_PART * best.agree as f64).floor() as usize);
    if best.disagree > allowed {
        return Err(format!(
            "no numbering fits the image: the best disagrees at {} lattice points",
            best.disagree
        ));
    }
    if let Some(r) = runner_up
        && r < best.disagree + MARGIN
    {
        let close = scored
            .iter()
            .filter(|s| s.disagree < best.disagree + MARGIN)
            .count();
        return Err(format!(
            "the visible part fits {close} numberings (shifted by whole squares): the \
             pattern's edges are not seen on enough sides"
        ));
    }
    Ok(Decided {
        shift: best.shift,
        agree: best.agree,
        disagree: best.disagree,
        candidates: scored.len(),
        runner_up,
        edges: best.edges,
    })
}

/// The homography of the numbering shifted by `shift` (see [`Decided::shift`]) from that of
/// the tentative one, `h`.
pub fn shifted(model: &Model, h: &Matrix3<f64>, shift: (i32, i32)) -> Matrix3<f64> {
    let sq = model.board.square;
    let t = Matrix3::new(
        1.0,
        0.0,
        shift.0 as f64 * sq,
        0.0,
        1.0,
        shift.1 as f64 * sq,
        0.0,
        0.0,
        1.0,
    );
    h * t
}

/// The in-image turn (deg) of the `found` pixels against the `predicted` ones of the same
/// vertices (least squares about their centroids), or `None` for fewer than two.
pub fn turn_deg(found: &[[f64; 2]], predicted: &[[f64; 2]]) -> Option<f64> {
    let n = found.len();
    if n < 2 || predicted.len() != n {
        return None;
    }
    let mean = |v: &[[f64; 2]]| {
        let s = v.iter().fold([0.0, 0.0], |a, p| [a[0] + p[0], a[1] + p[1]]);
        [s[0] / n as f64, s[1] / n as f64]
    };
    let (mf, mp) = (mean(found), mean(predicted));
    let (mut cross, mut dot) = (0.0, 0.0);
    for (f, p) in found.iter().zip(predicted) {
        let (d, q) = ([f[0] - mf[0], f[1] - mf[1]], [p[0] - mp[0], p[1] - mp[1]]);
        cross += q[0] * d[1] - q[1] * d[0];
        dot += q[0] * d[0] + q[1] * d[1];
    }
    Some(cross.atan2(dot).to_degrees())
}

/// Whether the prediction decides between a numbering and its 180° turn: the board must
/// appear turned by at most [`MAX_TURN_DEG`] against it (the turned numbering then by at
/// least 180° − that). Returns the turn, or why it cannot decide.
pub fn turn_check(found: &[[f64; 2]], predicted: &[[f64; 2]]) -> Result<f64, String> {
    match turn_deg(found, predicted) {
        None => Err("too few vertices to compare with the prediction".into()),
        Some(t) if t.abs() <= MAX_TURN_DEG => Ok(t),
        Some(t) => Err(format!(
            "the board appears turned by {t:.0}° against the prediction: its 180° symmetry \
             cannot be resolved"
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::render::GreyImage;

    /// A board seen face-on: board plane (mm) to pixels, `sx` and `sy` px per mm, the
    /// board's centre at (320, 240).
    fn face_on(sx: f64, sy: f64) -> Matrix3<f64> {
        Matrix3::new(sx, 0.0, 320.0, 0.0, sy, 240.0, 0.0, 0.0, 1.0)
    }

    /// The 640 × 480 image of `model`'s pattern on a white plate through `h` (no lens
    /// distortion), as an integral image.
    fn render(model: &Model, h: &Matrix3<f64>) -> Integral {
        let b = &model.board;
        let (half_x, half_y) = (
            b.squares_x as f64 * b.square / 2.0,
            b.squares_y as f64 * b.square / 2.0,
        );
        let (sx, sy) = (h[(0, 0)], h[(1, 1)]);
        let mut grey: Vec<u8> = Vec::with_capacity(640 * 480);
        for v in 0..480 {
            for u in 0..640 {
                let (x, y) = ((u as f64 - 320.0) / sx, (v as f64 - 240.0) / sy);
                let pattern = x.abs() < half_x && y.abs() < half_y;
                grey.push(if pattern && is_black(model, x, y) {
                    30
                } else {
                    220
                });
            }
        }
        Integral::new(&GreyImage {
            width: 640,
            height: 480,
            pixels: grey,
        })
    }

    /// The middle 2 × 2 inner vertices (col, row) of `model`'s board.
    fn middle() -> Vec<(i32, i32)> {
        vec![(2, 1), (3, 1), (2, 2), (3, 2)]
    }

    #[test]
    fn the_image_corrects_a_numbering_off_by_whole_squares() {
        let model = Model::default();
        let camera = Camera::default();
        let truth = face_on(2.0, 2.0);
        let img = render(&model, &truth);
        for (a, b) in [(0, 0), (1, 0), (0, -1), (2, 1), (-1, -1)] {
            // A tentative numbering whose lattice point (i, j) is the board's (i + a, j + b).
            let h = shifted(&model, &truth, (a, b));
            let found: Vec<(i32, i32)> = middle().iter().map(|&(c, r)| (c - a, r - b)).collect();
            let d = decide(&img, &camera, &model, &h, &found).unwrap();
            assert_eq!(d.shift, (-a, -b), "tentative shift ({a}, {b})");
            assert_eq!(d.disagree, 0);
            // The 24 inner vertices and the 20 ring points off its corners.
            assert_eq!(d.agree, 44);
            assert_eq!(d.edges, [true; 4]);
            // Columns 2 and 3 fit 5 placements, rows 1 and 2 fit 3.
            assert_eq!(d.candidates, 15);
            assert!(d.runner_up.is_some_and(|r| r >= MARGIN), "{d:?}");
            // Corrected, the homography is the board's.
            let back = shifted(&model, &h, d.shift);
            assert!((back - truth).abs().max() < 1e-9);
        }
    }

    #[test]
    fn a_board_seen_only_in_its_middle_is_not_numbered() {
        let model = Model::default();
        let camera = Camera::default();
        // 8 px per mm across: columns 2 and 3 in view, the pattern's left and right edges
        // far outside the image; its top and bottom in view.
        let truth = face_on(8.0, 2.0);
        let img = render(&model, &truth);
        let e = decide(&img, &camera, &model, &truth, &middle()).unwrap_err();
        // Shifts by 0 or ±2 columns keep the saddles' colours and see no edge to tell them
        // apart; an odd shift turns every colour round.
        assert!(e.contains("fits 3 numberings"), "{e}");
        // Seen whole (2 px per mm), the same vertices are numbered.
        let whole = face_on(2.0, 2.0);
        let img = render(&model, &whole);
        let d = decide(&img, &camera, &model, &whole, &middle()).unwrap();
        assert_eq!((d.shift, d.disagree), ((0, 0), 0));
    }

    #[test]
    fn turn_is_measured_about_the_centroid() {
        let pred: Vec<[f64; 2]> = (0..6)
            .map(|k| [k as f64 * 20.0, (k % 2) as f64 * 10.0])
            .collect();
        let (s, c) = 30f64.to_radians().sin_cos();
        let found: Vec<[f64; 2]> = pred
            .iter()
            .map(|p| [100.0 + c * p[0] - s * p[1], 50.0 + s * p[0] + c * p[1]])
            .collect();
        assert!((turn_deg(&found, &pred).unwrap() - 30.0).abs() < 1e-9);
        let turned: Vec<[f64; 2]> = found.iter().rev().copied().collect();
        assert!(turn_check(&turned, &pred).is_err());
        assert!(turn_check(&found, &pred).is_ok());
    }
}
