//! The predicted pattern of saddles: how every vertex of the board should look in the
//! image (where it is and which way its squares are coloured), and the image's grey levels
//! to compare that with.

use nalgebra::Matrix3;

use crate::detect::assign;
use crate::model::{Camera, Model, Pose, Vertex};
use crate::sim::render::GreyImage;

/// Where the colour samples lie: this fraction of a square along both board axes.
const SAMPLE: f64 = 0.3;
/// Where the inner colour samples lie (they show the saddle only near its centre).
const INNER: f64 = 0.12;
/// Saddle contrast (white minus black) that counts fully [grey levels].
const FULL_CONTRAST: f64 = 24.0;
/// Saddle score (of 1) a vertex needs to be taken.
pub(super) const MIN_SCORE: f64 = 0.5;

/// Grey-level sums over rectangles in O(1).
pub struct Integral {
    width: usize,
    height: usize,
    sums: Vec<u32>,
}

impl Integral {
    /// The integral image of an 8-bit greyscale `image`.
    pub fn new(image: &GreyImage) -> Integral {
        let (width, height) = (image.width as usize, image.height as usize);
        let bytes = &image.pixels;
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
        Integral {
            width,
            height,
            sums,
        }
    }

    /// The mean grey level of the square of half-size `h` ≥ 1 around pixel `(x, y)`
    /// (rounded), or `None` when it is not wholly in the image.
    pub(in crate::detect) fn mean(&self, x: f64, y: f64, h: i64) -> Option<f64> {
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

/// Two sample offsets (px or mm) from a vertex.
type Pair = [[f64; 2]; 2];

/// The predicted look of one vertex.
#[derive(Debug, Clone)]
pub(super) struct Predicted {
    /// Which vertex.
    pub(super) vertex: Vertex,
    /// Position on the board plane (mm) (x, y).
    pub(super) board: [f64; 2],
    /// Predicted pixel.
    pub(super) pixel: [f64; 2],
    /// Offsets of the two black and two white samples from the vertex (px): at
    /// [`SAMPLE`] of a square, and (`inner_*`) at [`INNER`].
    black: Pair,
    white: Pair,
    inner_black: Pair,
    inner_white: Pair,
    /// The same samples' offsets on the board plane (mm).
    board_black: Pair,
    board_white: Pair,
    board_inner_black: Pair,
    board_inner_white: Pair,
    /// Edge of a square on the board (mm).
    board_step: f64,
    /// Local size of a square (px).
    pub(super) square: f64,
}

impl Predicted {
    /// Patch half-size of the colour samples (px).
    fn patch(&self) -> i64 {
        ((0.1 * self.square).round() as i64).clamp(1, 6)
    }

    /// Saddle score at `p` (0 … 1): how much both white samples are brighter than both
    /// black ones, or `None` when a sample leaves the image.
    pub(super) fn score(&self, img: &Integral, p: [f64; 2]) -> Option<f64> {
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
    pub(super) fn centred(&self, img: &Integral, p: [f64; 2]) -> Option<f64> {
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
    pub(super) fn peak(&self, img: &Integral, start: [f64; 2]) -> Option<[f64; 2]> {
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

    /// This vertex's look redone with the homography `h` (board plane to undistorted
    /// pixels): where it is and how its squares lie in the image; `None` where `h` puts
    /// it or a sample behind the camera.
    fn reshaped(&self, h: &Matrix3<f64>, camera: &Camera) -> Option<Predicted> {
        let at = |x: f64, y: f64| distorted(camera, assign::apply(h, [x, y]));
        let [x, y] = self.board;
        let pixel = at(x, y)?;
        let to = |ring: &Pair| -> Option<Pair> {
            let mut out = [[0.0; 2]; 2];
            for (o, d) in out.iter_mut().zip(ring) {
                let q = at(x + d[0], y + d[1])?;
                *o = [q[0] - pixel[0], q[1] - pixel[1]];
            }
            Some(out)
        };
        let ax = at(x + self.board_step, y)?;
        let ay = at(x, y + self.board_step)?;
        let len = |q: [f64; 2]| (q[0] - pixel[0]).hypot(q[1] - pixel[1]);
        Some(Predicted {
            pixel,
            black: to(&self.board_black)?,
            white: to(&self.board_white)?,
            inner_black: to(&self.board_inner_black)?,
            inner_white: to(&self.board_inner_white)?,
            square: len(ax).min(len(ay)),
            ..self.clone()
        })
    }
}

/// Whether the square at board position `(x, y)` (mm) of `model`'s board is black, on the
/// checkerboard extended beyond the pattern (the four corner squares are black; squares
/// alternate).
pub(in crate::detect) fn is_black(model: &Model, x: f64, y: f64) -> bool {
    let b = &model.board;
    let ix = (x / b.square + b.squares_x as f64 / 2.0).floor() as i64;
    let iy = (y / b.square + b.squares_y as f64 / 2.0).floor() as i64;
    (ix + iy).rem_euclid(2) == 0
}

/// The look of every vertex of `model`'s board in pose `pose` (`T_CB`) for `camera`; a
/// vertex the camera cannot see (behind it) is left out.
pub(super) fn predict(model: &Model, camera: &Camera, pose: &Pose<f64>) -> Vec<Predicted> {
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

/// The prediction `predicted` redone with the homography `h` (board plane to undistorted
/// pixels) of the vertices found, or `None` when `h` puts a vertex behind the camera.
pub(super) fn reshape(
    predicted: &[Predicted],
    h: &Matrix3<f64>,
    camera: &Camera,
) -> Option<Vec<Predicted>> {
    predicted.iter().map(|p| p.reshaped(h, camera)).collect()
}

/// The median of the local square sizes (px) of `predicted` (not empty).
pub(super) fn median_square(predicted: &[Predicted]) -> f64 {
    let mut squares: Vec<f64> = predicted.iter().map(|p| p.square).collect();
    squares.sort_by(f64::total_cmp);
    squares[squares.len() / 2]
}

/// The undistorted pixel of `p` (the pinhole image of the same ray).
pub(in crate::detect) fn undistorted(camera: &Camera, p: [f64; 2]) -> [f64; 2] {
    let [a, b] = camera.undistort(p[0], p[1]);
    [camera.cx + camera.fx * a, camera.cy + camera.fy * b]
}

/// The (distorted) pixel of undistorted pixel `p`.
pub(in crate::detect) fn distorted(camera: &Camera, p: [f64; 2]) -> Option<[f64; 2]> {
    let a = (p[0] - camera.cx) / camera.fx;
    let b = (p[1] - camera.cy) / camera.fy;
    camera.project(&[1.0, -a, -b])
}
