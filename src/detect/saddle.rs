//! The image test every refined vertex passes before it is reported: its four squares
//! look like a clean saddle, and it lies where the lines through its neighbours put it.
//!
//! `cornerSubPix` takes every grey-level gradient in its window for part of an edge
//! through the vertex. Where an edge that is not the board's crosses the window (a toe
//! standing on the board, a leg or an arm in front of it), it pulls the vertex by pixels,
//! and neither the saddle score before refinement nor the board's homography (which
//! allows for the lens model's error) sees a pull of a few pixels on a large square. So
//! after refinement, each vertex's four squares are sampled along the board's two
//! directions (from the homography of the vertex and its neighbours), from just off the
//! lines through the vertex to just beyond the refinement window:
//!
//! * each square must be plain: a plane fitted to its samples (which takes up smooth
//!   shading, vignetting or an uneven light) leaves a spread of the grey-level noise, not
//!   the step of an edge;
//! * diagonal squares must be alike, adjacent ones contrasting;
//! * the vertex must lie where a homography of its neighbours (those that passed) puts it.
//!
//! A vertex that fails is dropped and named ([`Dropped`]), never reported off. The
//! thresholds are in units of the image's grey-level noise (estimated from the image,
//! [`noise_sigma`]) and of the saddle's own contrast, and in pixels.

use std::fmt;

use nalgebra::{Matrix3, Vector3};

use super::assign;
use super::guided::pattern::{distorted, is_black, undistorted};
use crate::model::{Camera, Model, Vertex};
use crate::sim::render::GreyImage;

/// How far beyond the refinement window's rim (px) each square is sampled: the pixel the
/// window's gradients need and three blur σ of 0.8 px, so that an edge whose blur reaches
/// into the window is seen. An edge farther out cannot move the vertex, and sampling
/// farther would drop vertices beside marks printed on the plate (the sandal's sole
/// outline crosses its last row of squares) and beside parts of the body that do not
/// reach the window.
const RIM_PX: f64 = 3.0;
/// Farthest reach (squares): the next lines' blur stays out of the samples.
const MAX_REACH: f64 = 0.8;
/// How far off the lines through the vertex (px) the samples start: a blur of σ 0.8 px
/// leaves less than half a grey level of a 180-level step 2.5 σ away, plus the pixel the
/// sample is rounded to.
const LINE_MARGIN_PX: f64 = 2.5;
/// And in squares: where the lens model is off, the lines bend by a little of a square.
const LINE_MARGIN_SQ: f64 = 0.06;
/// Least span of the sampled part of a square (px); a smaller square is not judged by its
/// look (its window is a few pixels, and a pull there is too).
const MIN_SPAN_PX: f64 = 2.0;
/// Most samples per axis in a square.
const MAX_SAMPLES: usize = 8;

/// Largest RMS (in noise σ) of a square's samples about their plane: with at least 9
/// samples (6 degrees of freedom) plain noise exceeds 2.5 σ once in 10⁵ squares.
const SPREAD_NOISE: f64 = 2.5;
/// Largest RMS as a part of the saddle's contrast: an edge of a tenth of the contrast
/// through a square (a pull of hundredths of a pixel) leaves about a fortieth.
const SPREAD_CONTRAST: f64 = 0.03;
/// Largest single sample's distance from its plane (noise σ): 6 σ happens once in 5 · 10⁸
/// samples, however many vertices are judged.
const PEAK_NOISE: f64 = 6.0;
/// The same as a part of the contrast: a sliver of an edge at a square's far corner.
const PEAK_CONTRAST: f64 = 0.12;
/// Largest difference of diagonal squares as a part of the contrast: shading (vignetting,
/// light) changes a level by far less across one square.
const DIAGONAL: f64 = 0.25;
/// Least contrast of adjacent squares as a part of the saddle's contrast.
const ADJACENT: f64 = 0.5;
/// Least contrast of the saddle (noise σ).
const MIN_CONTRAST_NOISE: f64 = 6.0;
/// Least grey-level noise σ assumed: 8-bit quantisation alone gives 0.3, and a camera's
/// noise is spatially correlated, which the estimate underrates.
const NOISE_FLOOR: f64 = 1.0;
/// Farthest (px) a vertex may lie from where its neighbours' homography puts it, when
/// they surround it: 5 σ of the refinement's error (0.05 px on a clean board), under the
/// accuracy asked of detection (0.3 px). Where the neighbours lie to one side (the board's
/// edge and corners) the prediction is an extrapolation, and the limit grows as its error
/// does (`leverage`).
pub const OFF_LINES_PX: f64 = 0.25;
/// Fewest neighbours to judge a vertex by its neighbours' lines: within one square all
/// eight, else those within two squares, at least this many.
const MIN_NEIGHBOURS: usize = 8;
/// How many times the board's typical distance from the neighbours' lines a vertex may
/// lie off them where the lens model leaves the lines bent: a pull stands out against
/// the bend, which changes slowly across the board.
const BEND: f64 = 3.0;

/// Why a vertex is not reported.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Why {
    /// An edge crosses one of its squares: the samples' spread about their plane (RMS or
    /// single sample, grey levels) exceeds the limit.
    Edge {
        /// The spread.
        spread: f64,
        /// The limit.
        limit: f64,
    },
    /// Its squares' levels are not a saddle's: diagonal squares unlike, or adjacent ones
    /// not contrasting (grey levels).
    Levels {
        /// The contrast of white and black squares.
        contrast: f64,
        /// The larger difference of diagonal squares.
        diagonal: f64,
        /// The smallest contrast of adjacent squares.
        adjacent: f64,
    },
    /// Off where the homography of its neighbours puts it (px).
    OffLines {
        /// The distance.
        px: f64,
        /// The limit there.
        limit: f64,
    },
    /// The body model puts a part of the robot in front of its refinement window
    /// ([`super::behind`]).
    Behind {
        /// The part.
        kind: crate::body::Kind,
        /// Its side, for a part of a leg or an arm.
        side: Option<crate::model::Side>,
    },
}

/// A vertex refined but dropped: an occluding edge pulled it, or may have.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dropped {
    /// Which vertex.
    pub vertex: Vertex,
    /// Where refinement put it.
    pub pixel: [f64; 2],
    /// Why it is dropped.
    pub why: Why,
}

impl fmt::Display for Dropped {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let v = self.vertex;
        write!(f, "(row {}, col {}) ", v.row, v.col)?;
        match self.why {
            Why::Edge { spread, limit } => write!(
                f,
                "an edge crosses a square (spread {spread:.1} > {limit:.1} grey levels)"
            ),
            Why::Levels {
                contrast,
                diagonal,
                adjacent,
            } => write!(
                f,
                "not a clean saddle (contrast {contrast:.0}, diagonal squares {diagonal:.0} \
                 apart, adjacent ones {adjacent:.0})"
            ),
            Why::OffLines { px, limit } => write!(
                f,
                "{px:.2} px off its neighbours' lines (more than {limit:.2} px)"
            ),
            Why::Behind { kind, side } => {
                let side = side.map_or(String::new(), |s| format!("{} ", s.name()));
                write!(
                    f,
                    "the {side}{} stands in front of its window (body model)",
                    kind.name()
                )
            }
        }
    }
}

/// Vertices with their pixels.
pub type Placed = Vec<(Vertex, [f64; 2])>;

/// The grey-level noise σ of `image`, from the median absolute response to the
/// Laplacian difference that cancels planes and is 6 σ for white noise (Immerkær's
/// operator, robust to the edges the median leaves out), at least `NOISE_FLOOR`.
pub fn noise_sigma(image: &GreyImage) -> f64 {
    let (w, h) = (image.width as usize, image.height as usize);
    if w < 3 || h < 3 {
        return NOISE_FLOOR;
    }
    let px = |u: usize, v: usize| image.pixels[v * w + u] as i32;
    let mut histogram = vec![0usize; 16 * 255 + 1];
    let mut n = 0;
    for v in 1..h - 1 {
        for u in 1..w - 1 {
            let r = px(u - 1, v - 1) + px(u + 1, v - 1) + px(u - 1, v + 1) + px(u + 1, v + 1)
                - 2 * (px(u, v - 1) + px(u, v + 1) + px(u - 1, v) + px(u + 1, v))
                + 4 * px(u, v);
            histogram[r.unsigned_abs() as usize] += 1;
            n += 1;
        }
    }
    let (mut seen, mut median) = (0, 0);
    for (value, count) in histogram.iter().enumerate() {
        seen += count;
        if 2 * seen >= n {
            median = value;
            break;
        }
    }
    // For Gaussian noise the median of |6σ z| is 0.6745 · 6σ.
    (median as f64 / (0.6745 * 6.0)).max(NOISE_FLOOR)
}

/// The image test of one image's vertices.
pub struct Saddles<'a> {
    /// The image (8-bit grey).
    image: &'a GreyImage,
    /// Its grey-level noise σ ([`noise_sigma`]).
    noise: f64,
    /// The model (its board).
    model: &'a Model,
    /// The camera that took the image (its lens model undistorts).
    camera: &'a Camera,
    /// Half-window of `cornerSubPix` in squares.
    factor: f64,
}

/// What the samples of one square show.
#[derive(Debug, Clone, Copy)]
struct Square {
    /// Whether the board's square there is black.
    black: bool,
    /// The plane's level at the samples' centre.
    level: f64,
    /// RMS of the samples about the plane.
    rms: f64,
    /// Largest distance of a sample from the plane.
    peak: f64,
}

impl<'a> Saddles<'a> {
    /// The test of the vertices in `image` of `model`'s board seen by `camera`, refined
    /// with a half-window of `factor` squares.
    pub fn new(image: &'a GreyImage, model: &'a Model, camera: &'a Camera, factor: f64) -> Self {
        Saddles {
            image,
            noise: noise_sigma(image),
            model,
            camera,
            factor,
        }
    }

    /// The grey-level noise σ the thresholds are in units of.
    pub fn noise(&self) -> f64 {
        self.noise
    }

    /// The vertices of `vertices` that pass (in their order), and those dropped.
    pub fn check(&self, vertices: &[(Vertex, [f64; 2])]) -> (Placed, Vec<Dropped>) {
        let mut kept = Vec::new();
        let mut dropped = Vec::new();
        let (src, dst): (Vec<[f64; 2]>, Vec<[f64; 2]>) = vertices
            .iter()
            .map(|&(v, q)| {
                let [x, y, _] = self.model.board.vertex_position(v);
                ([x, y], undistorted(self.camera, q))
            })
            .unzip();
        let whole = assign::homography(&src, &dst);
        for &(vertex, pixel) in vertices {
            // The board's directions at the vertex: from the homography of it and its
            // neighbours (local, so that a lens model that is off bends them little), else
            // of the whole board.
            let h = self.near(vertices, vertex, true).map(|(h, _)| h).or(whole);
            let why = h.and_then(|h| self.look(&h, vertex, pixel));
            match why {
                Some(why) => dropped.push(Dropped { vertex, pixel, why }),
                None => kept.push((vertex, pixel)),
            }
        }
        // Then the lines through the neighbours, the worst first.
        let bend = self.bend(&kept);
        while let Some((k, px, limit)) = self.worst_off_lines(&kept, bend) {
            let (vertex, pixel) = kept.remove(k);
            dropped.push(Dropped {
                vertex,
                pixel,
                why: Why::OffLines { px, limit },
            });
        }
        dropped.sort_by_key(|d| d.vertex);
        (kept, dropped)
    }

    /// The homography (board plane, mm, to undistorted pixels) of the neighbours of
    /// `vertex` among `placed` (and of `vertex` itself with `itself`): within one square
    /// when all eight are there, else within two (at least [`MIN_NEIGHBOURS`]); with the
    /// neighbours' offsets (squares) from `vertex`. `None` when too few are placed.
    fn near(
        &self,
        placed: &[(Vertex, [f64; 2])],
        vertex: Vertex,
        itself: bool,
    ) -> Option<(Matrix3<f64>, Vec<[f64; 2]>)> {
        let within = |reach: u32| -> Vec<&(Vertex, [f64; 2])> {
            placed
                .iter()
                .filter(|(v, _)| {
                    (itself || *v != vertex)
                        && v.row.abs_diff(vertex.row) <= reach
                        && v.col.abs_diff(vertex.col) <= reach
                })
                .collect()
        };
        let others = |n: &[&(Vertex, [f64; 2])]| n.iter().filter(|(v, _)| *v != vertex).count();
        let mut neighbours = within(1);
        if others(&neighbours) < MIN_NEIGHBOURS {
            neighbours = within(2);
        }
        if others(&neighbours) < MIN_NEIGHBOURS {
            return None;
        }
        let src: Vec<[f64; 2]> = neighbours
            .iter()
            .map(|(v, _)| {
                let [x, y, _] = self.model.board.vertex_position(*v);
                [x, y]
            })
            .collect();
        let dst: Vec<[f64; 2]> = neighbours
            .iter()
            .map(|(_, q)| undistorted(self.camera, *q))
            .collect();
        let offsets = neighbours
            .iter()
            .filter(|(v, _)| *v != vertex)
            .map(|(v, _)| {
                [
                    v.col as f64 - vertex.col as f64,
                    v.row as f64 - vertex.row as f64,
                ]
            })
            .collect();
        Some((assign::homography(&src, &dst)?, offsets))
    }

    /// How far (px) `vertex` at `pixel` lies from where the homography of its neighbours
    /// among `placed` puts it, with the prediction's [`leverage`] there; `None` when too
    /// few neighbours are placed.
    fn off_lines(
        &self,
        placed: &[(Vertex, [f64; 2])],
        vertex: Vertex,
        pixel: [f64; 2],
    ) -> Option<(f64, f64)> {
        let (h, offsets) = self.near(placed, vertex, false)?;
        let [x, y, _] = self.model.board.vertex_position(vertex);
        let p = distorted(self.camera, assign::apply(&h, [x, y]))?;
        Some(((p[0] - pixel[0]).hypot(p[1] - pixel[1]), leverage(&offsets)))
    }

    /// How far the vertices `placed` typically lie from their neighbours' lines (px): the
    /// median, scaled to a vertex amid eight neighbours. Where the lens model is right it
    /// is the refinement's error; where it is off (a camera whose distortion the dataset
    /// does not give), the lines bend and every vertex lies off by about as much.
    fn bend(&self, placed: &[(Vertex, [f64; 2])]) -> f64 {
        let mut off: Vec<f64> = placed
            .iter()
            .filter_map(|&(v, q)| self.off_lines(placed, v, q))
            .map(|(px, lev)| px / ((1.0 + lev) / (1.0 + 1.0 / 8.0)).sqrt())
            .collect();
        off.sort_by(f64::total_cmp);
        off.get(off.len() / 2).copied().unwrap_or(0.0)
    }

    /// Why the vertex `vertex` refined to `pixel` does not look like a clean saddle, or
    /// `None` when it does (or its squares are too small to judge). `h` maps the board
    /// plane (mm) to undistorted pixels.
    fn look(&self, h: &Matrix3<f64>, vertex: Vertex, pixel: [f64; 2]) -> Option<Why> {
        let inverse = h.try_inverse()?;
        let at = assign::apply(&inverse, undistorted(self.camera, pixel));
        let s = self.model.board.square;
        let map = |a: f64, b: f64| {
            distorted(
                self.camera,
                assign::apply(h, [at[0] + a * s, at[1] + b * s]),
            )
            .filter(|p| p[0].is_finite() && p[1].is_finite())
        };
        let (ax, bx) = (map(0.5, 0.0)?, map(-0.5, 0.0)?);
        let (ay, by) = (map(0.0, 0.5)?, map(0.0, -0.5)?);
        let square = (ax[0] - bx[0])
            .hypot(ax[1] - bx[1])
            .min((ay[0] - by[0]).hypot(ay[1] - by[1]));
        let half = (self.factor * square).round().clamp(2.0, 30.0);
        let start = LINE_MARGIN_PX / square + LINE_MARGIN_SQ;
        let end = ((half + RIM_PX) / square).min(MAX_REACH);
        if (end - start) * square < MIN_SPAN_PX {
            return None;
        }
        let n = (((end - start) * square).floor() as usize + 1).clamp(3, MAX_SAMPLES);
        let [x, y, _] = self.model.board.vertex_position(vertex);
        let mut squares = Vec::with_capacity(4);
        for (sx, sy) in [(1.0, 1.0), (-1.0, 1.0), (1.0, -1.0), (-1.0, -1.0)] {
            let black = is_black(self.model, x + 0.5 * sx * s, y + 0.5 * sy * s);
            // A square leaving the image is not judged (the window stays inside it).
            if let Some(q) = self.square(&map, [sx, sy], start, end, n, black) {
                squares.push(q);
            }
        }
        self.judge(&squares)
    }

    /// The samples of the square on side `sign` of the vertex, from `start` to `end`
    /// squares along both directions, `n` per axis, fitted with a plane; `None` when a
    /// sample leaves the image.
    fn square(
        &self,
        map: &dyn Fn(f64, f64) -> Option<[f64; 2]>,
        sign: [f64; 2],
        start: f64,
        end: f64,
        n: usize,
        black: bool,
    ) -> Option<Square> {
        let (w, h) = (self.image.width as i64, self.image.height as i64);
        let mut samples = Vec::with_capacity(n * n);
        for i in 0..n {
            for j in 0..n {
                let a = start + (end - start) * i as f64 / (n - 1) as f64;
                let b = start + (end - start) * j as f64 / (n - 1) as f64;
                let p = map(sign[0] * a, sign[1] * b)?;
                let (u, v) = (p[0].round() as i64, p[1].round() as i64);
                if u < 0 || v < 0 || u >= w || v >= h {
                    return None;
                }
                let g = self.image.pixels[(v * w + u) as usize] as f64;
                samples.push((a, b, g));
            }
        }
        // Least squares plane g = c0 + c1 a + c2 b.
        let mut m = Matrix3::zeros();
        let mut r = Vector3::zeros();
        for &(a, b, g) in &samples {
            let x = Vector3::new(1.0, a, b);
            m += x * x.transpose();
            r += x * g;
        }
        let c = m.try_inverse()? * r;
        let (mut sum2, mut peak) = (0.0, 0.0f64);
        for &(a, b, g) in &samples {
            let e = g - (c[0] + c[1] * a + c[2] * b);
            sum2 += e * e;
            peak = peak.max(e.abs());
        }
        let mid = 0.5 * (start + end);
        Some(Square {
            black,
            level: c[0] + (c[1] + c[2]) * mid,
            rms: (sum2 / (samples.len() - 3) as f64).sqrt(),
            peak,
        })
    }

    /// Why the `squares` around a vertex are not a clean saddle, or `None`. Without a
    /// square of each colour nothing is judged.
    fn judge(&self, squares: &[Square]) -> Option<Why> {
        let levels = |black: bool| -> Vec<f64> {
            squares
                .iter()
                .filter(|q| q.black == black)
                .map(|q| q.level)
                .collect()
        };
        let (mut black, mut white) = (levels(true), levels(false));
        if black.is_empty() || white.is_empty() {
            return None;
        }
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
        // Numbered in OpenCV's order (without the model), the colours may be the other
        // way round: a saddle either way.
        if mean(&white) < mean(&black) {
            std::mem::swap(&mut black, &mut white);
        }
        let contrast = mean(&white) - mean(&black);
        let spread = |v: &[f64]| {
            v.iter().copied().fold(f64::NEG_INFINITY, f64::max)
                - v.iter().copied().fold(f64::INFINITY, f64::min)
        };
        let diagonal = spread(&black).max(spread(&white));
        let adjacent = white.iter().copied().fold(f64::INFINITY, f64::min)
            - black.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let sigma = self.noise;
        // An edge first: the squares' levels tell of it only when it covers a square.
        let rms_limit = (SPREAD_NOISE * sigma).max(SPREAD_CONTRAST * contrast);
        let peak_limit = (PEAK_NOISE * sigma).max(PEAK_CONTRAST * contrast);
        for q in squares {
            if q.rms > rms_limit {
                return Some(Why::Edge {
                    spread: q.rms,
                    limit: rms_limit,
                });
            }
            if q.peak > peak_limit {
                return Some(Why::Edge {
                    spread: q.peak,
                    limit: peak_limit,
                });
            }
        }
        let saddle = contrast >= MIN_CONTRAST_NOISE * sigma
            && diagonal <= DIAGONAL * contrast + 4.0 * sigma
            && adjacent >= ADJACENT * contrast;
        (!saddle).then_some(Why::Levels {
            contrast,
            diagonal,
            adjacent,
        })
    }

    /// The vertex of `kept` farthest (relative to its limit) from where the homography of
    /// its neighbours puts it, when that is more than its limit: [`OFF_LINES_PX`], or
    /// [`BEND`] times the board's typical distance `bend` when that is more, grown by the
    /// prediction's [`leverage`]. Its index, distance and limit (px).
    fn worst_off_lines(&self, kept: &[(Vertex, [f64; 2])], bend: f64) -> Option<(usize, f64, f64)> {
        let mut worst: Option<(usize, f64, f64, f64)> = None;
        for (k, &(vertex, pixel)) in kept.iter().enumerate() {
            let Some((px, lev)) = self.off_lines(kept, vertex, pixel) else {
                continue;
            };
            let limit = OFF_LINES_PX.max(BEND * bend) * ((1.0 + lev) / (1.0 + 1.0 / 8.0)).sqrt();
            let excess = px / limit;
            if excess > 1.0 && worst.is_none_or(|(_, w, _, _)| excess > w) {
                worst = Some((k, excess, px, limit));
            }
        }
        worst.map(|(k, _, px, limit)| (k, px, limit))
    }
}

/// The leverage of a point at the origin on a plane (of an affine map) fitted to points at
/// `offsets` (in squares): the variance of the fitted value there in units of one point's.
/// 1/8 amid a full ring of eight neighbours, 0.8 at a corner of the board, and at most 8
/// where the fit is nearly degenerate.
fn leverage(offsets: &[[f64; 2]]) -> f64 {
    let mut m = Matrix3::zeros();
    for o in offsets {
        let x = Vector3::new(1.0, o[0], o[1]);
        m += x * x.transpose();
    }
    m.try_inverse()
        .map_or(8.0, |inv| inv[(0, 0)].clamp(0.0, 8.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Pose;
    use crate::sim::render::{RenderOptions, render};

    /// The default board 400 mm ahead of the camera, facing it (squares of about 35 px),
    /// rendered without lens distortion, and the true pixel of every vertex.
    fn scene(options: &RenderOptions) -> (Model, GreyImage, Placed) {
        let model = Model::default();
        let mut pose = Pose::translation(400.0, 0.0, 0.0);
        pose.rotation = [[0.0, 0.0, -1.0], [1.0, 0.0, 0.0], [0.0, -1.0, 0.0]];
        let image = render(&model, &pose, options, 5).unwrap();
        let truth = model
            .board
            .vertices()
            .map(|v| {
                let p = model.board.vertex_position(v);
                (v, model.camera.project(&pose.apply(&p)).unwrap())
            })
            .collect();
        (model, image, truth)
    }

    /// Paints the pixels of `image` with `x · n ≥ d` (and within `width` px of that line,
    /// and `half` px of `centre` along it) a plain grey `grey`.
    fn paint(image: &mut GreyImage, centre: [f64; 2], n: [f64; 2], d: f64, grey: u8) {
        for v in 0..image.height {
            for u in 0..image.width {
                let (x, y) = (u as f64 - centre[0], v as f64 - centre[1]);
                let across = x * n[0] + y * n[1];
                let along = -x * n[1] + y * n[0];
                if across >= d && across < d + 40.0 && along.abs() < 60.0 {
                    image.pixels[(v * image.width + u) as usize] = grey;
                }
            }
        }
    }

    #[test]
    fn the_noise_is_estimated_from_the_image() {
        for sigma in [2.0, 5.0] {
            let options = RenderOptions {
                noise: sigma,
                ..RenderOptions::default()
            };
            let (_, image, _) = scene(&options);
            let estimate = noise_sigma(&image);
            assert!(
                (estimate - sigma).abs() < 0.2 * sigma,
                "σ {sigma}: estimated {estimate}"
            );
        }
    }

    #[test]
    fn a_clean_board_passes_also_under_strong_shading() {
        for vignetting in [0.0, 0.3, 0.9] {
            let options = RenderOptions {
                vignetting,
                ..RenderOptions::default()
            };
            let (model, mut image, truth) = scene(&options);
            // And a light falling off across the image by half.
            let width = image.width as f64;
            for (k, p) in image.pixels.iter_mut().enumerate() {
                let u = (k % image.width as usize) as f64;
                *p = (*p as f64 * (1.0 - 0.5 * u / width)).round() as u8;
            }
            let saddles = Saddles::new(&image, &model, &model.camera, 0.3);
            let (kept, dropped) = saddles.check(&truth);
            assert!(dropped.is_empty(), "vignetting {vignetting}: {dropped:?}");
            assert_eq!(kept.len(), truth.len());
        }
    }

    #[test]
    fn an_edge_across_a_square_drops_its_vertex() {
        let (model, mut image, truth) = scene(&RenderOptions::default());
        let target = Vertex { row: 1, col: 2 };
        let p = truth.iter().find(|(v, _)| *v == target).unwrap().1;
        // An edge 0.2 squares (7 px) from the vertex, turned 30° from the grid, plastic
        // grey over the squares beyond it.
        let n = [30f64.to_radians().cos(), 30f64.to_radians().sin()];
        paint(&mut image, p, n, 7.0, 160);
        let saddles = Saddles::new(&image, &model, &model.camera, 0.3);
        let (kept, dropped) = saddles.check(&truth);
        assert!(
            dropped
                .iter()
                .any(|d| d.vertex == target && matches!(d.why, Why::Edge { .. })),
            "{dropped:?}"
        );
        assert!(!kept.iter().any(|(v, _)| *v == target));
        // The vertices more than 0.8 squares (28 px) clear of the occluder pass.
        let clear = |q: [f64; 2]| {
            let (x, y) = (q[0] - p[0], q[1] - p[1]);
            let (across, along) = (x * n[0] + y * n[1], -x * n[1] + y * n[0]);
            let out = [
                (7.0 - across).max(across - 47.0).max(0.0),
                (along.abs() - 60.0).max(0.0),
            ];
            out[0].hypot(out[1]) > 28.0
        };
        for (v, q) in &truth {
            if clear(*q) {
                assert!(kept.iter().any(|(w, _)| w == v), "{v:?}: {dropped:?}");
            }
        }
        let message = dropped
            .iter()
            .find(|d| d.vertex == target)
            .unwrap()
            .to_string();
        assert!(message.contains("an edge crosses a square"), "{message}");
    }

    #[test]
    fn a_vertex_off_its_neighbours_lines_is_dropped() {
        let (model, image, mut truth) = scene(&RenderOptions::default());
        // Pulled by 0.5 px along a diagonal: its squares still look clean.
        let k = truth
            .iter()
            .position(|(v, _)| *v == Vertex { row: 2, col: 3 })
            .unwrap();
        truth[k].1[0] += 0.35;
        truth[k].1[1] += 0.35;
        let saddles = Saddles::new(&image, &model, &model.camera, 0.3);
        let (kept, dropped) = saddles.check(&truth);
        assert_eq!(kept.len(), truth.len() - 1, "{dropped:?}");
        assert_eq!(dropped.len(), 1);
        assert_eq!(dropped[0].vertex, Vertex { row: 2, col: 3 });
        assert!(matches!(dropped[0].why, Why::OffLines { px, .. } if px > 0.4));
    }
}
