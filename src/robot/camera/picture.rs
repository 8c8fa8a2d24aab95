//! A picture's bytes: its kind (PNG or JPEG, from its first bytes), the size its header
//! claims, checked against the camera's before anything is allocated for its pixels, and
//! its grey levels.

/// The extension of an encoded PNG or JPEG image, from its first bytes.
pub fn image_kind(bytes: &[u8]) -> Option<&'static str> {
    if bytes.starts_with(b"\x89PNG\r\n\x1a\n") {
        Some("png")
    } else if bytes.starts_with(&[0xff, 0xd8, 0xff]) {
        Some("jpg")
    } else {
        None
    }
}

/// The size (width, height) a PNG or JPEG image's header claims, and its extension: read
/// from the header alone (PNG's `IHDR`, JPEG's frame header), nothing allocated for its
/// pixels.
pub fn header_size(bytes: &[u8]) -> Result<(&'static str, (u32, u32)), String> {
    match image_kind(bytes) {
        Some("png") => {
            let reader = png::Decoder::new(std::io::Cursor::new(bytes))
                .read_info()
                .map_err(|e| format!("is not a readable PNG: {e}"))?;
            let info = reader.info();
            Ok(("png", (info.width, info.height)))
        }
        Some(_) => {
            let mut decoder = jpeg_decoder::Decoder::new(std::io::Cursor::new(bytes));
            decoder
                .read_info()
                .map_err(|e| format!("is not a readable JPEG: {e}"))?;
            let info = decoder.info().ok_or("is not a readable JPEG: no frame")?;
            Ok(("jpg", (info.width.into(), info.height.into())))
        }
        None => Err("is neither a PNG nor a JPEG".into()),
    }
}

/// Checks the size an image's header claims ([`header_size`]) against the camera's
/// (`width`×`height`, from the dataset's intrinsics) before anything is allocated for its
/// pixels: a picture that is not what the camera delivers is refused unread.
fn check_header(bytes: &[u8], (width, height): (u32, u32)) -> Result<&'static str, String> {
    let (extension, size) = header_size(bytes)?;
    if size != (width, height) {
        return Err(format!(
            "is {}×{} pixels; the camera's intrinsics are for {width}×{height}",
            size.0, size.1
        ));
    }
    Ok(extension)
}

/// Decodes a PNG or JPEG image of the camera's `size` in full (its header checked first,
/// [`check_header`]); its extension and size (width, height).
fn decode_size(bytes: &[u8], size: (u32, u32)) -> Result<(&'static str, (u32, u32)), String> {
    match check_header(bytes, size)? {
        "png" => {
            let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
            let mut reader = decoder
                .read_info()
                .map_err(|e| format!("is not a readable PNG: {e}"))?;
            let size = reader
                .output_buffer_size()
                .ok_or("is not a readable PNG: too large")?;
            let mut buf = vec![0; size];
            let info = reader
                .next_frame(&mut buf)
                .map_err(|e| format!("is not a readable PNG: {e}"))?;
            Ok(("png", (info.width, info.height)))
        }
        _ => {
            let mut decoder = jpeg_decoder::Decoder::new(std::io::Cursor::new(bytes));
            let pixels = decoder
                .decode()
                .map_err(|e| format!("is not a readable JPEG: {e}"))?;
            let info = decoder.info().ok_or("is not a readable JPEG: no frame")?;
            let (w, h) = (info.width as usize, info.height as usize);
            if pixels.len() < w * h {
                return Err("is not a readable JPEG: its image data is short".into());
            }
            Ok(("jpg", (info.width.into(), info.height.into())))
        }
    }
}

/// Decodes a PNG or JPEG image of the camera's `size` to grey levels (8 bits, the mean of
/// its colour channels): its size (width, height) and pixels. A picture whose header
/// claims another size is refused before anything is allocated for it (`check_header`).
pub fn decode_grey(bytes: &[u8], size: (u32, u32)) -> Result<((u32, u32), Vec<u8>), String> {
    match check_header(bytes, size)? {
        "png" => {
            let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
            decoder
                .set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
            let mut reader = decoder
                .read_info()
                .map_err(|e| format!("is not a readable PNG: {e}"))?;
            let size = reader
                .output_buffer_size()
                .ok_or("is not a readable PNG: too large")?;
            let mut buf = vec![0; size];
            let info = reader
                .next_frame(&mut buf)
                .map_err(|e| format!("is not a readable PNG: {e}"))?;
            buf.truncate(info.buffer_size());
            let colours = match info.color_type {
                png::ColorType::Grayscale | png::ColorType::GrayscaleAlpha => 1,
                _ => 3,
            };
            let channels = info.color_type.samples();
            Ok(((info.width, info.height), grey_of(&buf, channels, colours)))
        }
        _ => {
            let mut decoder = jpeg_decoder::Decoder::new(std::io::Cursor::new(bytes));
            let pixels = decoder
                .decode()
                .map_err(|e| format!("is not a readable JPEG: {e}"))?;
            let info = decoder.info().ok_or("is not a readable JPEG: no frame")?;
            let channels = match info.pixel_format {
                jpeg_decoder::PixelFormat::L8 => 1,
                jpeg_decoder::PixelFormat::L16 => {
                    return Err("is a 16-bit JPEG; 8-bit pictures are expected".into());
                }
                jpeg_decoder::PixelFormat::RGB24 => 3,
                jpeg_decoder::PixelFormat::CMYK32 => 4,
            };
            let grey = grey_of(&pixels, channels, channels.min(3));
            Ok(((info.width.into(), info.height.into()), grey))
        }
    }
}

/// The grey level of each pixel of `samples` (`channels` per pixel): the mean of its
/// first `colours` channels.
fn grey_of(samples: &[u8], channels: usize, colours: usize) -> Vec<u8> {
    samples
        .chunks_exact(channels)
        .map(|p| (p[..colours].iter().map(|&c| u32::from(c)).sum::<u32>() / colours as u32) as u8)
        .collect()
}

/// Checks that a picture has the camera's size (`width`×`height` from the dataset's camera
/// intrinsics) — by its header, before anything is allocated for its pixels — and decodes
/// in full at that size: what `detect` will need of it.
pub fn check_picture(bytes: &[u8], width: u32, height: u32) -> Result<&'static str, String> {
    let (extension, size) = decode_size(bytes, (width, height))?;
    if size != (width, height) {
        return Err(format!(
            "is {}×{} pixels; the camera's intrinsics are for {width}×{height}",
            size.0, size.1
        ));
    }
    Ok(extension)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grey_levels_of_colour_and_grey_pictures() {
        assert_eq!(grey_of(&[30, 60, 90, 255, 0, 0, 0, 255], 4, 3), vec![60, 0]);
        assert_eq!(grey_of(&[7, 9], 1, 1), vec![7, 9]);
    }

    /// A PNG whose header claims 1 000 000 × 1 000 000 pixels is refused by its header,
    /// before anything is allocated for its pixels; its claimed size is read.
    #[test]
    fn a_header_claiming_another_size_is_refused_unread() {
        let mut bytes = Vec::new();
        {
            let mut encoder = png::Encoder::new(&mut bytes, 1_000_000, 1_000_000);
            encoder.set_color(png::ColorType::Grayscale);
            let mut writer = encoder.write_header().unwrap();
            writer
                .write_chunk(
                    png::chunk::IDAT,
                    &[0x78, 0x9c, 0x03, 0x00, 0x00, 0x00, 0x00, 0x01],
                )
                .unwrap();
        }
        assert_eq!(header_size(&bytes), Ok(("png", (1_000_000, 1_000_000))));
        let e = check_picture(&bytes, 640, 480).unwrap_err();
        assert_eq!(
            e,
            "is 1000000×1000000 pixels; the camera's intrinsics are for 640×480"
        );
        assert!(decode_grey(&bytes, (640, 480)).is_err());
        let mut jpeg = vec![0xff, 0xd8, 0xff, 0xc0, 0x00, 0x0b, 0x08];
        jpeg.extend(65_000u16.to_be_bytes());
        jpeg.extend(65_000u16.to_be_bytes());
        jpeg.extend([0x01, 0x01, 0x11, 0x00]);
        jpeg.resize(4096, 0);
        let e = check_picture(&jpeg, 640, 480).unwrap_err();
        assert!(e.starts_with("is 65000×65000 pixels"), "{e}");
    }
}
