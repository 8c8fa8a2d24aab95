//! Rendering camera images of the sandal with known truth.
//!
//! The renderer is an exact backward map: every pixel is traced back through the camera
//! model (docs/MODEL.md §3, lens distortion inverted numerically) onto the board plane in its
//! true pose `T_CB`, and shaded from the pattern there. Pixels whose footprint crosses an
//! edge of the pattern or of the plate are supersampled on an `n × n` grid, so the
//! projective mapping (and with it every vertex position) is rendered without bias; the
//! vertices' true positions are the model's projections ([`crate::model::Model::project`]).
//!
//! The board is a white plate around the `squares_x × squares_y` pattern, with black
//! squares in the four corners (square `(ix, iy)` is black when `ix + iy` is even). The
//! rest of the image is a cluttered, uneven background. Then come vignetting, a Gaussian
//! blur, grey-level noise and quantisation to 8 bits.

use std::path::{Path, PathBuf};

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

use super::scene::{self, BodyView};
use crate::body::BodyModel;
use crate::model::{CameraId, JointAngles, Model, Pose, Side};

/// How to render images.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderOptions {
    /// Gaussian blur σ (px) (0 for none).
    pub blur: f64,
    /// Grey-level noise σ [grey levels of 255] (0 for none).
    pub noise: f64,
    /// Relative loss of brightness in the image corners (0 for none, at most 0.9).
    pub vignetting: f64,
    /// Samples per axis in pixels that cross an edge of the pattern or plate (1 … 32).
    pub supersampling: u32,
    /// Width of the white plate around the pattern, in squares.
    pub plate_margin: f64,
    /// Grey level of the black squares.
    pub black: f64,
    /// Grey level of the white squares and plate.
    pub white: f64,
    /// Seed of the background and noise (each image mixes in its capture id).
    pub seed: u64,
    /// The robot's body drawn in front of the boards (`None`: the boards alone, in front
    /// of the background). [`render_all`] and the simulated robot's pictures pose it.
    pub body: Option<BodyModel>,
}

impl Default for RenderOptions {
    /// Blur σ 0.8 px, noise σ 2, 30 % vignetting, 8 × 8 supersampling at edges, the NAO
    /// V6's body drawn with the arms where capture holds them.
    fn default() -> Self {
        RenderOptions {
            blur: 0.8,
            noise: 2.0,
            vignetting: 0.3,
            supersampling: 8,
            plate_margin: 0.8,
            black: 35.0,
            white: 215.0,
            seed: 1,
            body: Some(BodyModel::default()),
        }
    }
}

/// Why an image could not be rendered or written.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// An option is out of range.
    #[error("render options: {0}")]
    Options(String),
    /// The file could not be written.
    #[error("{}: cannot write: {source}", path.display())]
    Io {
        /// The image file.
        path: PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// The image could not be encoded.
    #[error("{}: cannot encode the PNG: {message}", path.display())]
    Encode {
        /// The image file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// The image could not be written.
    #[error(transparent)]
    Write(#[from] crate::output::WriteError),
    /// An image exists and `force` was not given.
    #[error("{}: already exists; use --force to overwrite", path.display())]
    Exists {
        /// The existing image.
        path: PathBuf,
    },
}

/// An 8-bit greyscale image, row by row.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct GreyImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width × height` grey levels, row-major.
    pub pixels: Vec<u8>,
}

impl GreyImage {
    /// The grey level at pixel `(u, v)`.
    pub fn get(&self, u: u32, v: u32) -> u8 {
        self.pixels[(v * self.width + u) as usize]
    }

    /// Turns the image by 180° (as a sensor mounted upside down gives it).
    pub fn turn_half(&mut self) {
        self.pixels.reverse();
    }

    /// Scales every grey level by `factor` (an exposure other than the one rendered),
    /// rounded and clamped to 0 … 255; a factor of 1 changes nothing.
    pub fn expose(&mut self, factor: f64) {
        if factor == 1.0 {
            return;
        }
        for p in &mut self.pixels {
            *p = (f64::from(*p) * factor).round().clamp(0.0, 255.0) as u8;
        }
    }

    /// The image as an 8-bit greyscale PNG.
    pub fn to_png(&self) -> Result<Vec<u8>, String> {
        let mut out = Vec::new();
        {
            let mut encoder = png::Encoder::new(&mut out, self.width, self.height);
            encoder.set_color(png::ColorType::Grayscale);
            encoder.set_depth(png::BitDepth::Eight);
            encoder.set_compression(png::Compression::Fast);
            let mut writer = encoder.write_header().map_err(|e| e.to_string())?;
            writer
                .write_image_data(&self.pixels)
                .map_err(|e| e.to_string())?;
            writer.finish().map_err(|e| e.to_string())?;
        }
        Ok(out)
    }

    /// Writes the image as PNG to `path` with [`crate::output::write_atomic`], replacing an
    /// existing file (callers check for existing images first).
    pub fn write_png(&self, path: &Path) -> Result<(), RenderError> {
        let bytes = self.to_png().map_err(|message| RenderError::Encode {
            path: path.to_path_buf(),
            message,
        })?;
        let options = crate::output::WriteOptions::new(true);
        Ok(crate::output::write_atomic(path, &bytes, &options)?)
    }
}

impl RenderOptions {
    /// Checks that every option is in range.
    pub fn validate(&self) -> Result<(), RenderError> {
        let bad = |what: &str| Err(RenderError::Options(what.to_string()));
        let nonneg = |x: f64| x.is_finite() && x >= 0.0;
        if !nonneg(self.blur) || self.blur > 10.0 {
            return bad("blur σ must be in 0 … 10 px");
        }
        if !nonneg(self.noise) || self.noise > 100.0 {
            return bad("noise σ must be in 0 … 100 grey levels");
        }
        if !nonneg(self.vignetting) || self.vignetting > 0.9 {
            return bad("vignetting must be in 0 … 0.9");
        }
        if !(1..=32).contains(&self.supersampling) {
            return bad("supersampling must be 1 … 32 samples per axis");
        }
        if !nonneg(self.plate_margin) || self.plate_margin > 10.0 {
            return bad("the plate margin must be in 0 … 10 squares");
        }
        let grey = |x: f64| x.is_finite() && (0.0..=255.0).contains(&x);
        if !grey(self.black) || !grey(self.white) || self.white - self.black < 20.0 {
            return bad("grey levels must be in 0 … 255, white at least 20 above black");
        }
        Ok(())
    }
}

/// The plane of the board seen from the camera: maps a normalised image point to board
/// coordinates (the inverse of the homography `[r1 r2 t]`).
struct BoardPlane {
    inv: [[f64; 3]; 3],
    /// The board's normal and origin in the camera frame.
    normal: [f64; 3],
    origin: [f64; 3],
}

impl BoardPlane {
    fn new(pose: &Pose<f64>) -> Option<BoardPlane> {
        let r = &pose.rotation;
        let t = &pose.translation;
        let h = [
            [r[0][0], r[0][1], t[0]],
            [r[1][0], r[1][1], t[1]],
            [r[2][0], r[2][1], t[2]],
        ];
        let det = h[0][0] * (h[1][1] * h[2][2] - h[1][2] * h[2][1])
            - h[0][1] * (h[1][0] * h[2][2] - h[1][2] * h[2][0])
            + h[0][2] * (h[1][0] * h[2][1] - h[1][1] * h[2][0]);
        if det.abs() < 1e-12 {
            return None;
        }
        let mut inv = [[0.0; 3]; 3];
        for (i, row) in inv.iter_mut().enumerate() {
            for (j, x) in row.iter_mut().enumerate() {
                let (a, b) = ((j + 1) % 3, (j + 2) % 3);
                let (c, d) = ((i + 1) % 3, (i + 2) % 3);
                *x = (h[a][c] * h[b][d] - h[a][d] * h[b][c]) / det;
            }
        }
        Some(BoardPlane {
            inv,
            normal: [r[0][2], r[1][2], r[2][2]],
            origin: *t,
        })
    }

    /// Distance (mm) from the camera along the ray through normalised point `(a, b)` to the
    /// board's plane, or infinity when the plane is not in front along it.
    fn depth(&self, a: f64, b: f64) -> f64 {
        let d = [1.0, -a, -b];
        let n = &self.normal;
        let along = n[0] * d[0] + n[1] * d[1] + n[2] * d[2];
        let s = (n[0] * self.origin[0] + n[1] * self.origin[1] + n[2] * self.origin[2]) / along;
        if along.abs() < 1e-15 || s <= 0.0 {
            return f64::INFINITY;
        }
        s * (1.0 + a * a + b * b).sqrt()
    }

    /// Board coordinates `(x_B, y_B)` hit by the ray through normalised point `(a, b)`, or
    /// `None` when the plane is not in front of the camera along that ray.
    fn hit(&self, a: f64, b: f64) -> Option<[f64; 2]> {
        let d = [1.0, -a, -b];
        let m = &self.inv;
        let w = m[2][0] * d[0] + m[2][1] * d[1] + m[2][2] * d[2];
        if w <= 1e-12 {
            return None;
        }
        let x = m[0][0] * d[0] + m[0][1] * d[1] + m[0][2] * d[2];
        let y = m[1][0] * d[0] + m[1][1] * d[1] + m[1][2] * d[2];
        Some([x / w, y / w])
    }
}

/// The pattern and its plate in board coordinates: regions bounded by the lines of the
/// pattern and the plate edges. Each region is a rectangle (convex), so a pixel whose four
/// corners fall in the same region lies wholly in it.
struct Pattern {
    square: f64,
    squares: [i64; 2],
    margin: f64,
    black: f64,
    white: f64,
}

/// Region of a point off the board plane (behind the camera or beyond the horizon).
const NO_PLANE: u32 = u32::MAX;
/// Regions from this one on are the body's parts (`BODY + part`).
const BODY: u32 = 0x4000_0000;

impl Pattern {
    /// Index of the band along one axis: 0 outside the plate, 1 in the plate margin, then
    /// `2 + i` in square `i`, then the far margin and beyond.
    fn band(&self, coord: f64, axis: usize) -> u32 {
        let n = self.squares[axis];
        let t = coord / self.square + n as f64 / 2.0;
        if t < -self.margin {
            0
        } else if t < 0.0 {
            1
        } else if t < n as f64 {
            2 + t as u32
        } else if t < n as f64 + self.margin {
            2 + n as u32
        } else {
            3 + n as u32
        }
    }

    fn region(&self, p: Option<[f64; 2]>) -> u32 {
        match p {
            None => NO_PLANE,
            Some([x, y]) => self.band(x, 0) * 1024 + self.band(y, 1),
        }
    }

    /// The grey level of a region, or `None` for the background.
    fn shade(&self, region: u32) -> Option<f64> {
        if region >= BODY {
            return None;
        }
        let (bx, by) = (region / 1024, region % 1024);
        let outside = |b: u32, n: i64| b == 0 || b == 3 + n as u32;
        if outside(bx, self.squares[0]) || outside(by, self.squares[1]) {
            return None;
        }
        let inner = |b: u32, n: i64| b >= 2 && b < 2 + n as u32;
        if inner(bx, self.squares[0]) && inner(by, self.squares[1]) && (bx + by) % 2 == 0 {
            Some(self.black)
        } else {
            Some(self.white)
        }
    }
}

/// A cluttered, uneven background at pixel resolution: a brightness gradient, smooth
/// blotches and random rectangles, ellipses and bars of many grey levels.
fn background(width: usize, height: usize, rng: &mut impl Rng) -> Vec<f32> {
    let (w, h) = (width as f64, height as f64);
    let base = rng.random_range(70.0..140.0);
    let gx = rng.random_range(-60.0..60.0);
    let gy = rng.random_range(-60.0..60.0);
    let blotches: Vec<[f64; 4]> = (0..6)
        .map(|_| {
            [
                rng.random_range(0.0..w),
                rng.random_range(0.0..h),
                rng.random_range(40.0..200.0),
                rng.random_range(-40.0..40.0),
            ]
        })
        .collect();
    let mut img = vec![0f32; width * height];
    for v in 0..height {
        for u in 0..width {
            let (x, y) = (u as f64, v as f64);
            let mut g = base + gx * (x / w - 0.5) + gy * (y / h - 0.5);
            for [cx, cy, r, amp] in &blotches {
                let d2 = ((x - cx).powi(2) + (y - cy).powi(2)) / (r * r);
                g += amp * (-d2).exp();
            }
            img[v * width + u] = g as f32;
        }
    }
    let shapes = rng.random_range(12..30);
    for _ in 0..shapes {
        let grey = rng.random_range(10.0..240.0f32);
        let (cx, cy) = (rng.random_range(0.0..w), rng.random_range(0.0..h));
        let (rx, ry): (f64, f64) = (rng.random_range(5.0..80.0), rng.random_range(5.0..80.0));
        let angle: f64 = rng.random_range(0.0..std::f64::consts::PI);
        let kind = rng.random_range(0..3);
        let (s, c) = angle.sin_cos();
        let reach = rx.max(ry) * if kind == 2 { 3.0 } else { 1.5 };
        let u0 = (cx - reach).max(0.0) as usize;
        let u1 = ((cx + reach) as usize).min(width - 1);
        let v0 = (cy - reach).max(0.0) as usize;
        let v1 = ((cy + reach) as usize).min(height - 1);
        for v in v0..=v1 {
            for u in u0..=u1 {
                let (dx, dy) = (u as f64 - cx, v as f64 - cy);
                let (p, q) = (c * dx + s * dy, -s * dx + c * dy);
                let inside = match kind {
                    0 => (p / rx).powi(2) + (q / ry).powi(2) <= 1.0,
                    1 => p.abs() <= rx && q.abs() <= ry,
                    _ => p.abs() <= 3.0 * rx && q.abs() <= 2.0 + ry / 20.0,
                };
                if inside {
                    img[v * width + u] = grey;
                }
            }
        }
    }
    img
}

/// Separable Gaussian blur with σ `sigma` (border pixels repeated).
fn blur(img: &mut [f32], width: usize, height: usize, sigma: f64) {
    if sigma <= 0.0 {
        return;
    }
    let radius = (3.5 * sigma).ceil() as isize;
    let mut kernel: Vec<f32> = (-radius..=radius)
        .map(|i| (-(i * i) as f64 / (2.0 * sigma * sigma)).exp() as f32)
        .collect();
    let sum: f32 = kernel.iter().sum();
    kernel.iter_mut().for_each(|k| *k /= sum);
    let mut tmp = vec![0f32; img.len()];
    let clamp = |i: isize, n: usize| i.clamp(0, n as isize - 1) as usize;
    for v in 0..height {
        let row = &img[v * width..(v + 1) * width];
        for u in 0..width {
            let mut acc = 0.0;
            for (k, w) in kernel.iter().enumerate() {
                acc += w * row[clamp(u as isize + k as isize - radius, width)];
            }
            tmp[v * width + u] = acc;
        }
    }
    for v in 0..height {
        for u in 0..width {
            let mut acc = 0.0;
            for (k, w) in kernel.iter().enumerate() {
                acc += w * tmp[clamp(v as isize + k as isize - radius, height) * width + u];
            }
            img[v * width + u] = acc;
        }
    }
}

/// Renders the view of the camera `model.camera` onto a board in pose `pose` (`T_CB`, the
/// board in the camera frame), with the background and noise drawn from `seed`.
pub fn render(
    model: &Model,
    pose: &Pose<f64>,
    options: &RenderOptions,
    seed: u64,
) -> Result<GreyImage, RenderError> {
    render_with(model, pose, None, options, seed)
}

/// What one line of sight meets: a part of the body nearer than the board's plate, else
/// the board's region.
fn region_of(
    pattern: &Pattern,
    plane: &BoardPlane,
    body: Option<&BodyView>,
    a: f64,
    b: f64,
) -> u32 {
    let board = pattern.region(plane.hit(a, b));
    let Some(body) = body else {
        return board;
    };
    let limit = if pattern.shade(board).is_some() {
        plane.depth(a, b)
    } else {
        f64::INFINITY
    };
    match body.hit(a, b, limit) {
        Some((k, _)) => BODY + k as u32,
        None => board,
    }
}

/// The grey level seen along the line of sight through `(a, b)`: the body where it stands
/// in front of the plate, else the board, else the background `bg`.
fn grey_of(
    pattern: &Pattern,
    plane: &BoardPlane,
    body: Option<&BodyView>,
    a: f64,
    b: f64,
    bg: f64,
) -> f64 {
    let board = pattern.region(plane.hit(a, b));
    let shade = pattern.shade(board);
    if let Some(body) = body {
        let limit = if shade.is_some() {
            plane.depth(a, b)
        } else {
            f64::INFINITY
        };
        if let Some((_, grey)) = body.hit(a, b, limit) {
            return grey;
        }
    }
    shade.unwrap_or(bg)
}

/// [`render`] with the robot's body in front of the board (`body`, as
/// [`scene::body_view`] poses it), drawn shaded, its silhouettes supersampled like the
/// pattern's edges.
pub fn render_with(
    model: &Model,
    pose: &Pose<f64>,
    body: Option<&BodyView>,
    options: &RenderOptions,
    seed: u64,
) -> Result<GreyImage, RenderError> {
    options.validate()?;
    let body = body.filter(|b| !b.is_empty());
    let camera = &model.camera;
    let (width, height) = (camera.width as usize, camera.height as usize);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut img = background(width, height, &mut rng);
    let pattern = Pattern {
        square: model.board.square,
        squares: [model.board.squares_x as i64, model.board.squares_y as i64],
        margin: options.plate_margin,
        black: options.black,
        white: options.white,
    };
    if let Some(plane) = BoardPlane::new(pose) {
        // Normalised coordinates and regions at the pixel corners (u ± 0.5, v ± 0.5).
        let gw = width + 1;
        let mut norm = vec![[0.0f64; 2]; gw * (height + 1)];
        let mut region = vec![0u32; gw * (height + 1)];
        for j in 0..=height {
            for i in 0..=width {
                let n = camera.undistort(i as f64 - 0.5, j as f64 - 0.5);
                norm[j * gw + i] = n;
                region[j * gw + i] = region_of(&pattern, &plane, body, n[0], n[1]);
            }
        }
        let n = options.supersampling as usize;
        for v in 0..height {
            for u in 0..width {
                let k = v * gw + u;
                let corners = [k, k + 1, k + gw, k + gw + 1];
                let r = region[k];
                let bg = img[v * width + u] as f64;
                let [a00, a10, a01, a11] = corners.map(|c| norm[c]);
                if corners.iter().all(|&c| region[c] == r) {
                    if r >= BODY {
                        // Shaded at the pixel's centre.
                        let (a, b) = (
                            (a00[0] + a10[0] + a01[0] + a11[0]) / 4.0,
                            (a00[1] + a10[1] + a01[1] + a11[1]) / 4.0,
                        );
                        img[v * width + u] = grey_of(&pattern, &plane, body, a, b, bg) as f32;
                    } else if let Some(g) = pattern.shade(r) {
                        img[v * width + u] = g as f32;
                    }
                    continue;
                }
                let mut acc = 0.0;
                for sj in 0..n {
                    let t = (sj as f64 + 0.5) / n as f64;
                    for si in 0..n {
                        let s = (si as f64 + 0.5) / n as f64;
                        let lerp = |d: usize| {
                            (1.0 - t) * ((1.0 - s) * a00[d] + s * a10[d])
                                + t * ((1.0 - s) * a01[d] + s * a11[d])
                        };
                        acc += grey_of(&pattern, &plane, body, lerp(0), lerp(1), bg);
                    }
                }
                img[v * width + u] = (acc / (n * n) as f64) as f32;
            }
        }
    }
    // Vignetting and an uneven illumination.
    let tilt_u = rng.random_range(-0.1..0.1);
    let tilt_v = rng.random_range(-0.1..0.1);
    let (w, h) = (width as f64, height as f64);
    let rmax2 = (w * w + h * h) / 4.0;
    for v in 0..height {
        for u in 0..width {
            let (du, dv) = (u as f64 - w / 2.0, v as f64 - h / 2.0);
            let factor = (1.0 - options.vignetting * (du * du + dv * dv) / rmax2)
                * (1.0 + tilt_u * du / w + tilt_v * dv / h);
            img[v * width + u] *= factor as f32;
        }
    }
    blur(&mut img, width, height, options.blur);
    let noise = Normal::new(0.0, options.noise).map_err(|e| RenderError::Options(e.to_string()))?;
    let pixels = img
        .iter()
        .map(|&g| {
            (g as f64 + noise.sample(&mut rng))
                .round()
                .clamp(0.0, 255.0) as u8
        })
        .collect();
    Ok(GreyImage {
        width: camera.width,
        height: camera.height,
        pixels,
    })
}

/// Where and how [`crate::sim::simulate`] renders the images of a simulated dataset.
#[derive(Debug, Clone, PartialEq)]
pub struct ImageOutput {
    /// The dataset directory; images go to `dir/images/NNNN.png`.
    pub dir: PathBuf,
    /// How to render.
    pub options: RenderOptions,
    /// Replace existing images.
    pub force: bool,
}

/// One image to render: the capture id, the camera, the board in view and the actual joint
/// angles.
#[derive(Debug, Clone, PartialEq)]
pub struct ImageJob {
    /// Capture id (names the file `images/NNNN.png` and seeds the image).
    pub id: u64,
    /// The camera that takes it.
    pub camera: CameraId,
    /// The leg whose board is in view.
    pub side: Side,
    /// The actual (not the logged) joint angles.
    pub joints: JointAngles,
}

/// The image path of capture `id`, relative to the dataset directory: `images/NNNN.png`.
pub fn image_name(id: u64) -> PathBuf {
    PathBuf::from(format!("images/{id:04}.png"))
}

/// Renders every job with the true parameters `params` and writes it to
/// `dir/images/NNNN.png`, on all cores. Refuses to replace an existing image unless
/// `force` (checked for all images before any is written).
pub fn render_all(
    model: &Model,
    params: &[f64],
    jobs: &[ImageJob],
    options: &RenderOptions,
    dir: &Path,
    force: bool,
) -> Result<(), RenderError> {
    options.validate()?;
    let images = dir.join("images");
    if !force {
        for job in jobs {
            let path = dir.join(image_name(job.id));
            if path.symlink_metadata().is_ok() {
                return Err(RenderError::Exists { path });
            }
        }
    }
    std::fs::create_dir_all(&images).map_err(|source| RenderError::Io {
        path: images.clone(),
        source,
    })?;
    let threads = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1)
        .min(jobs.len().max(1));
    // The true cameras: the a-priori intrinsics with the true intrinsics errors added.
    let models = CameraId::ALL.map(|camera| crate::model::Model {
        camera: model.intrinsics_at(camera, params),
        ..*model
    });
    let next = std::sync::atomic::AtomicUsize::new(0);
    std::thread::scope(|scope| {
        let workers: Vec<_> = (0..threads)
            .map(|_| {
                scope.spawn(|| -> Result<(), RenderError> {
                    loop {
                        let k = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        let Some(job) = jobs.get(k) else {
                            return Ok(());
                        };
                        let model = &models[job.camera as usize];
                        let pose = model
                            .chains_for(job.camera, job.side, &job.joints)
                            .camera_to_board(params);
                        let seed = options.seed ^ job.id.wrapping_mul(0x9E37_79B9_7F4A_7C15);
                        let view = options.body.as_ref().map(|body| {
                            scene::body_view(model, body, job.camera, job.side, &job.joints, params)
                        });
                        let image = render_with(model, &pose, view.as_ref(), options, seed)?;
                        image.write_png(&dir.join(image_name(job.id)))?;
                    }
                })
            })
            .collect();
        workers
            .into_iter()
            .try_for_each(|w| w.join().expect("render thread panicked"))
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{Camera, Pose};

    #[test]
    fn undistort_inverts_the_camera() {
        let camera = Camera {
            distortion: [-0.2, 0.05, 0.001, -0.002, 0.01],
            ..Camera::default()
        };
        for (u, v) in [(0.0, 0.0), (320.0, 240.0), (639.0, 479.0), (100.0, 400.0)] {
            let [a, b] = camera.undistort(u, v);
            let p = camera.project(&[1.0, -a, -b]).unwrap();
            assert!((p[0] - u).abs() < 1e-9 && (p[1] - v).abs() < 1e-9, "{p:?}");
        }
    }

    #[test]
    fn board_plane_hits_the_projected_vertex() {
        let model = Model::default();
        // Board 400 mm ahead, facing the camera (+z_B toward the camera).
        let mut pose = Pose::translation(400.0, 0.0, 0.0);
        pose.rotation = [[0.0, 0.0, -1.0], [1.0, 0.0, 0.0], [0.0, -1.0, 0.0]];
        let plane = BoardPlane::new(&pose).unwrap();
        for v in model.board.vertices() {
            let p = model.board.vertex_position(v);
            let uv = model.camera.project(&pose.apply(&p)).unwrap();
            let n = model.camera.undistort(uv[0], uv[1]);
            let hit = plane.hit(n[0], n[1]).unwrap();
            assert!((hit[0] - p[0]).abs() < 1e-9 && (hit[1] - p[1]).abs() < 1e-9);
        }
        let image = render(&model, &pose, &RenderOptions::default(), 3).unwrap();
        assert_eq!(image.pixels.len(), 640 * 480);
        // The centre vertex (row 1, col 2 → 3 squares) is at a junction: black square (2, 1)
        // (ix + iy odd is white) lies up-left in the image … just check contrast nearby.
        let uv = model
            .camera
            .project(
                &pose.apply(
                    &model
                        .board
                        .vertex_position(crate::model::Vertex { row: 0, col: 0 }),
                ),
            )
            .unwrap();
        let (u, v) = (uv[0].round() as u32, uv[1].round() as u32);
        let around: Vec<u8> = [(-6i32, -6i32), (6, -6), (-6, 6), (6, 6)]
            .iter()
            .map(|(du, dv)| image.get((u as i32 + du) as u32, (v as i32 + dv) as u32))
            .collect();
        let (lo, hi) = (around.iter().min().unwrap(), around.iter().max().unwrap());
        assert!(hi - lo > 100, "{around:?}");
        let png = image.to_png().unwrap();
        assert_eq!(&png[1..4], b"PNG");
    }

    #[test]
    fn options_are_checked() {
        let bad = RenderOptions {
            supersampling: 0,
            ..RenderOptions::default()
        };
        assert!(bad.validate().is_err());
        let bad = RenderOptions {
            noise: f64::NAN,
            ..RenderOptions::default()
        };
        assert!(bad.validate().is_err());
    }
}
