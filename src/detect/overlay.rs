//! Overlays like the paper's Fig. 5: the image with the detected vertices and the model's
//! projection before (nominal, all offsets zero) and after calibration drawn on it.

use std::path::{Path, PathBuf};

use crate::dataset::{Corner, Dataset};
use crate::model::PARAMETER_COUNT;
use crate::output::{WriteOptions, write_atomic};

use super::cv::{self, Shape};
use super::{DetectError, ImageResult, Outcome};
use crate::sim::render::GreyImage;

/// Colour of the detected vertices (green crosses).
pub const DETECTED: [f64; 3] = [0.0, 200.0, 0.0];
/// Colour of the nominal model's projection (red circles).
pub const BEFORE: [f64; 3] = [0.0, 0.0, 255.0];
/// Colour of the calibrated model's projection (blue circles).
pub const AFTER: [f64; 3] = [255.0, 128.0, 0.0];

fn point(p: [f64; 2]) -> [i32; 2] {
    // Drawn with 4 fractional bits (shift 4) for sub-pixel placement.
    [(p[0] * 16.0).round() as i32, (p[1] * 16.0).round() as i32]
}

/// Draws on a colour copy of `grey`: the `before` and `after` projections as circles and the
/// `detected` vertices as crosses; returns it as PNG bytes.
pub fn draw(
    grey: &GreyImage,
    detected: &[[f64; 2]],
    before: Option<&[[f64; 2]]>,
    after: Option<&[[f64; 2]]>,
) -> cv::Result<Vec<u8>> {
    let mut shapes: Vec<Shape> = Vec::new();
    for (points, c) in [(before, BEFORE), (after, AFTER)] {
        for p in points.unwrap_or(&[]) {
            shapes.push(cv::circle(point(*p), 4 * 16, c));
        }
    }
    for p in detected {
        let q = point(*p);
        for (dx, dy) in [(3, 3), (3, -3)] {
            shapes.push(cv::line(
                [q[0] - dx * 16, q[1] - dy * 16],
                [q[0] + dx * 16, q[1] + dy * 16],
                DETECTED,
            ));
        }
    }
    let bgr = cv::draw(grey, &shapes)?;
    encode_png(&bgr, grey.width, grey.height).map_err(|e| cv::Error {
        message: e.to_string(),
    })
}

/// Encodes an 8-bit BGR image of `width × height` as RGB PNG bytes.
fn encode_png(bgr: &[u8], width: u32, height: u32) -> Result<Vec<u8>, png::EncodingError> {
    let rgb: Vec<u8> = bgr
        .chunks_exact(3)
        .flat_map(|p| [p[2], p[1], p[0]])
        .collect();
    let mut out = Vec::new();
    let mut encoder = png::Encoder::new(&mut out, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_compression(png::Compression::Fast);
    let mut writer = encoder.write_header()?;
    writer.write_image_data(&rgb)?;
    writer.finish()?;
    Ok(out)
}

/// The overlay file of capture `id` in `dir`: `capture_NNNN.png`.
pub fn path(dir: &Path, id: u64) -> PathBuf {
    dir.join(format!("capture_{id:04}.png"))
}

/// Writes the overlay of one result into `dir` as `capture_NNNN.png`, atomically and
/// as `options` allow (never an input, an existing file only with `force`), and returns
/// its path: detected vertices, the nominal model's projection and, with `after`, the
/// projection with those parameters. `None` for a capture without a readable image.
pub fn write(
    dataset: &Dataset,
    result: &ImageResult,
    dir: &Path,
    after: Option<&[f64; PARAMETER_COUNT]>,
    options: &WriteOptions,
) -> Option<Result<PathBuf, DetectError>> {
    let capture = dataset.capture(result.capture)?;
    let image = capture.image.as_ref()?;
    let image_path = super::resolve_image(&dataset.dir, image).ok()?;
    let grey = super::read_grey(&image_path).ok()?;
    let detected: Vec<[f64; 2]> = match &result.outcome {
        Outcome::Found { corners, .. } => corners.iter().map(|c: &Corner| c.pixel).collect(),
        _ => Vec::new(),
    };
    let model = &dataset.model;
    let before = super::predict(model, capture, &[0.0; PARAMETER_COUNT]);
    let after = after.and_then(|p| super::predict(model, capture, p));
    let out = path(dir, capture.id);
    let cv = |e: cv::Error| DetectError::OpenCv {
        path: out.clone(),
        message: e.message,
    };
    Some(
        draw(&grey, &detected, before.as_deref(), after.as_deref())
            .map_err(cv)
            .and_then(|png| write_atomic(&out, &png, options).map_err(DetectError::from))
            .map(|()| out.clone()),
    )
}
