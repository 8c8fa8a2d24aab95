//! Reading image files: the path kept inside the dataset, the header checked before any
//! pixel is decoded, PNG decoded with the `png` crate and JPEG, BMP and PGM with `image`,
//! all as 8-bit grey levels.

use std::path::{Component, Path, PathBuf};

use super::DetectError;
use crate::model::CameraId;
use crate::sim::render::GreyImage;

/// The full path of `image` in `dir`, checked to stay inside `dir` (also through symbolic
/// links).
pub fn resolve_image(dir: &Path, image: &Path) -> Result<PathBuf, DetectError> {
    let path = dir.join(image);
    let outside = || DetectError::OutsideDataset {
        path: path.clone(),
        dir: dir.to_path_buf(),
    };
    if image
        .components()
        .any(|c| !matches!(c, Component::Normal(_) | Component::CurDir))
    {
        return Err(outside());
    }
    match (path.canonicalize(), dir.canonicalize()) {
        (Ok(real), Ok(real_dir)) if !real.starts_with(&real_dir) => Err(outside()),
        _ => Ok(path),
    }
}

/// Reads an image file as 8-bit greyscale.
pub fn read_grey(path: &Path) -> Result<GreyImage, DetectError> {
    decode_grey(path, &read_bytes(path)?)
}

/// Reads an image file as 8-bit greyscale, refusing one whose size is not `size` (the
/// resolution of `camera`, the camera that took it): from the header, before any pixel
/// is decoded, and again after decoding.
pub(super) fn read_sized(
    path: &Path,
    size: [u32; 2],
    camera_id: CameraId,
) -> Result<GreyImage, DetectError> {
    let camera = size;
    let bytes = read_bytes(path)?;
    if !bytes.is_empty() {
        let size = check_header(path, &bytes)?;
        if size != camera {
            return Err(DetectError::Size {
                path: path.to_path_buf(),
                size,
                camera,
                camera_id,
            });
        }
    }
    let grey = decode_grey(path, &bytes)?;
    drop(bytes);
    let size = [grey.width, grey.height];
    if size != camera {
        return Err(DetectError::Size {
            path: path.to_path_buf(),
            size,
            camera,
            camera_id,
        });
    }
    Ok(grey)
}

/// Reads an image file's bytes.
fn read_bytes(path: &Path) -> Result<Vec<u8>, DetectError> {
    match std::fs::read(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Err(DetectError::Missing {
            path: path.to_path_buf(),
        }),
        Err(source) => Err(DetectError::Io {
            path: path.to_path_buf(),
            source,
        }),
        Ok(b) => Ok(b),
    }
}

/// Largest image side detection reads (px).
pub const MAX_SIDE: u32 = 16_384;
/// Largest image detection reads (pixels): 64 megapixels (64 MB of grey levels).
pub const MAX_PIXELS: u64 = 64_000_000;

/// The width and height an image file's header claims (PNG, JPEG, BMP or PGM), read
/// without decoding the pixels.
pub fn header_size(path: &Path, bytes: &[u8]) -> Result<[u32; 2], DetectError> {
    let decode = |message: String| DetectError::Decode {
        path: path.to_path_buf(),
        message,
    };
    if bytes.starts_with(b"\x89PNG") {
        let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
        let reader = decoder.read_info().map_err(|e| decode(e.to_string()))?;
        let info = reader.info();
        return Ok([info.width, info.height]);
    }
    let reader = image::io::Reader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| decode(e.to_string()))?;
    let (w, h) = reader
        .into_dimensions()
        .map_err(|e| decode(e.to_string()))?;
    Ok([w, h])
}

/// Refuses an image whose header claims more than [`MAX_SIDE`] or [`MAX_PIXELS`] (and one
/// that is no PNG, JPEG, BMP or PGM).
fn check_header(path: &Path, bytes: &[u8]) -> Result<[u32; 2], DetectError> {
    const KNOWN: [&[u8]; 5] = [b"\x89PNG", b"\xff\xd8\xff", b"BM", b"P5", b"P2"];
    if !KNOWN.iter().any(|m| bytes.starts_with(m)) {
        return Err(DetectError::Decode {
            path: path.to_path_buf(),
            message: "not a PNG, JPEG, BMP or PGM file (unknown signature)".into(),
        });
    }
    let size = header_size(path, bytes)?;
    if size[0] > MAX_SIDE || size[1] > MAX_SIDE || size[0] as u64 * size[1] as u64 > MAX_PIXELS {
        return Err(DetectError::TooLarge {
            path: path.to_path_buf(),
            size,
        });
    }
    Ok(size)
}

/// Decodes image bytes (PNG, JPEG, BMP or PGM) as 8-bit greyscale. The size in the header
/// is checked against [`MAX_SIDE`] and [`MAX_PIXELS`] before anything is decoded.
pub fn decode_grey(path: &Path, bytes: &[u8]) -> Result<GreyImage, DetectError> {
    let decode = |message: String| DetectError::Decode {
        path: path.to_path_buf(),
        message,
    };
    if bytes.is_empty() {
        return Err(DetectError::Empty {
            path: path.to_path_buf(),
        });
    }
    check_header(path, bytes)?;
    if bytes.starts_with(b"\x89PNG") {
        let (pixels, width, height) = decode_png(bytes).map_err(decode)?;
        return Ok(GreyImage {
            width,
            height,
            pixels,
        });
    }
    let (pixels, width, height) = decode_other(bytes).map_err(decode)?;
    Ok(GreyImage {
        width,
        height,
        pixels,
    })
}

/// Decodes a JPEG, BMP or PGM into 8-bit grey levels (colour as in [`decode_png`]).
fn decode_other(bytes: &[u8]) -> Result<(Vec<u8>, u32, u32), String> {
    let img = image::load_from_memory(bytes).map_err(|e| e.to_string())?;
    let (width, height) = (img.width(), img.height());
    let grey = match img {
        image::DynamicImage::ImageLuma8(g) => g.into_raw(),
        other => other
            .to_rgb8()
            .pixels()
            .map(|p| bt601(p.0[0], p.0[1], p.0[2]))
            .collect(),
    };
    Ok((grey, width, height))
}

/// ITU-R BT.601 luma, as OpenCV's colour-to-grey conversion.
fn bt601(r: u8, g: u8, b: u8) -> u8 {
    (0.299 * r as f64 + 0.587 * g as f64 + 0.114 * b as f64).round() as u8
}

/// Decodes a PNG into 8-bit grey levels (colour converted with ITU-R BT.601 weights).
fn decode_png(bytes: &[u8]) -> Result<(Vec<u8>, u32, u32), String> {
    let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    decoder.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
    let mut reader = decoder.read_info().map_err(|e| e.to_string())?;
    let size = reader
        .output_buffer_size()
        .ok_or_else(|| "the image is too large".to_string())?;
    let mut buf = vec![0; size];
    let info = reader.next_frame(&mut buf).map_err(|e| e.to_string())?;
    buf.truncate(info.buffer_size());
    let channels = info.color_type.samples();
    let grey = match channels {
        1 => buf,
        2 => buf.chunks_exact(2).map(|p| p[0]).collect(),
        _ => buf
            .chunks_exact(channels)
            .map(|p| bt601(p[0], p[1], p[2]))
            .collect(),
    };
    Ok((grey, info.width, info.height))
}
