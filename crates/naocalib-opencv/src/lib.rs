//! naocalib's OpenCV plugin. The commands that detect load this shared library at their
//! first image (naocalib's `detect::cv`); every other command starts without OpenCV and the
//! some 40 shared libraries it brings (GLX, X11, ATLAS, TBB, …).
//!
//! Each function takes its image as a [`abi::Grey`] view of the caller's pixels, reports an
//! OpenCV error (or a panic) in its [`abi::Message`] with a non-zero return, and never
//! unwinds into the caller.

pub mod abi;

use std::panic::{AssertUnwindSafe, catch_unwind};

use abi::{Grey, Message, Roi, Search, Shape};
use opencv::calib3d;
use opencv::core::{self, Mat, Point, Point2f, Rect, Scalar, Size, TermCriteria, Vector};
use opencv::imgproc;
use opencv::prelude::*;

/// Runs `body`, turning an OpenCV error or a panic into `message` and a return of 1.
fn guarded(message: *mut Message, body: impl FnOnce() -> opencv::Result<()>) -> i32 {
    let text = match catch_unwind(AssertUnwindSafe(body)) {
        Ok(Ok(())) => return 0,
        Ok(Err(e)) => e.message,
        Err(panic) => panic
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "the plugin panicked".into()),
    };
    // SAFETY: the caller passes a valid, exclusive `Message` (abi.rs).
    if let Some(m) = unsafe { message.as_mut() } {
        m.set(&text);
    }
    1
}

/// The caller's pixels as a `Mat` (no copy).
///
/// # Safety
/// `grey.data` points at `width × height` readable bytes that outlive the `Mat`.
unsafe fn mat(grey: &Grey) -> opencv::Result<opencv::boxed_ref::BoxedRef<'_, Mat>> {
    if grey.data.is_null() || grey.width <= 0 || grey.height <= 0 {
        return Err(opencv::Error::new(
            core::StsBadArg,
            "an empty image".to_string(),
        ));
    }
    let n = grey.width as usize * grey.height as usize;
    // SAFETY: the caller's promise above.
    let pixels = unsafe { std::slice::from_raw_parts(grey.data, n) };
    Mat::new_rows_cols_with_data(grey.height, grey.width, pixels)
}

/// [`abi::VERSION`].
#[unsafe(no_mangle)]
pub extern "C" fn naocalib_opencv_version() -> u32 {
    abi::VERSION
}

/// `findChessboardCorners` on `grey` (or on its part `roi`) for a pattern of `cols × rows`
/// inner corners; on success `*count` is how many corners it gave (0 when it found no
/// board), the first `cols × rows` of them written to `out` as x, y pairs in the part's
/// pixels.
///
/// # Safety
/// `grey` as [`abi::Grey`] says; `out` has room for `2 × cols × rows` floats; `count` and
/// `message` are valid.
#[unsafe(no_mangle)]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn naocalib_opencv_find_chessboard(
    grey: Grey,
    roi: Roi,
    cols: i32,
    rows: i32,
    search: Search,
    out: *mut f32,
    count: *mut i32,
    message: *mut Message,
) -> i32 {
    guarded(message, || {
        // SAFETY: the caller's promise.
        let image = unsafe { mat(&grey)? };
        let flags = calib3d::CALIB_CB_ADAPTIVE_THRESH
            | calib3d::CALIB_CB_NORMALIZE_IMAGE
            | match search {
                Search::Fast => calib3d::CALIB_CB_FAST_CHECK,
                Search::Exhaustive => 0,
            };
        let size = Size::new(cols, rows);
        let mut corners = Vector::<Point2f>::new();
        let found = if roi.width == 0 {
            calib3d::find_chessboard_corners(&image, size, &mut corners, flags)?
        } else {
            let rect = Rect::new(roi.x, roi.y, roi.width, roi.height);
            let view = Mat::roi(&image, rect)?;
            calib3d::find_chessboard_corners(&view, size, &mut corners, flags)?
        };
        let room = (cols.max(0) * rows.max(0)) as usize;
        let given = if found { corners.len() } else { 0 };
        let n = given.min(room);
        // SAFETY: `out` has room for `room` pairs and `count` is valid.
        unsafe {
            let out = std::slice::from_raw_parts_mut(out, 2 * n);
            for (k, p) in corners.iter().take(n).enumerate() {
                out[2 * k] = p.x;
                out[2 * k + 1] = p.y;
            }
            *count = given as i32;
        }
        Ok(())
    })
}

/// `resize` of `grey` to `width / 2 × height / 2` with `INTER_AREA` (each pixel the mean of
/// four), into `out`.
///
/// # Safety
/// `grey` as [`abi::Grey`] says; `out` has room for `(width / 2) × (height / 2)` bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn naocalib_opencv_resize_half(
    grey: Grey,
    out: *mut u8,
    message: *mut Message,
) -> i32 {
    guarded(message, || {
        // SAFETY: the caller's promise.
        let image = unsafe { mat(&grey)? };
        let (w, h) = (grey.width / 2, grey.height / 2);
        let mut half = Mat::default();
        imgproc::resize(
            &image,
            &mut half,
            Size::new(w, h),
            0.0,
            0.0,
            imgproc::INTER_AREA,
        )?;
        let bytes = half.data_bytes()?;
        // SAFETY: `out` has room for `w × h` bytes.
        unsafe { std::slice::from_raw_parts_mut(out, bytes.len()) }.copy_from_slice(bytes);
        Ok(())
    })
}

/// `cornerSubPix` of the `n` points at `points` (x, y pairs, refined in place) with the
/// half-window `half`, no zero zone, and at most `max_count` iterations or a step below `eps`.
///
/// # Safety
/// `grey` as [`abi::Grey`] says; `points` holds `2 × n` floats.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn naocalib_opencv_corner_sub_pix(
    grey: Grey,
    points: *mut f32,
    n: i32,
    half: i32,
    max_count: i32,
    eps: f64,
    message: *mut Message,
) -> i32 {
    guarded(message, || {
        // SAFETY: the caller's promise.
        let image = unsafe { mat(&grey)? };
        // SAFETY: `points` holds `2 × n` floats.
        let points = unsafe { std::slice::from_raw_parts_mut(points, 2 * n.max(0) as usize) };
        let mut pts: Vector<Point2f> = points
            .chunks_exact(2)
            .map(|p| Point2f::new(p[0], p[1]))
            .collect();
        let criteria = TermCriteria::new(
            core::TermCriteria_Type::COUNT as i32 | core::TermCriteria_Type::EPS as i32,
            max_count,
            eps,
        )?;
        imgproc::corner_sub_pix(
            &image,
            &mut pts,
            Size::new(half, half),
            Size::new(-1, -1),
            criteria,
        )?;
        for (p, q) in points.chunks_exact_mut(2).zip(pts.iter()) {
            p[0] = q.x;
            p[1] = q.y;
        }
        Ok(())
    })
}

/// `grey` in colour (`cvtColor`, grey to BGR) with the `n` shapes drawn on it in order,
/// anti-aliased, 1 px wide, with 4 fractional bits, into `out` (BGR, row-major).
///
/// # Safety
/// `grey` as [`abi::Grey`] says; `shapes` holds `n` shapes; `out` has room for
/// `3 × width × height` bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn naocalib_opencv_draw(
    grey: Grey,
    shapes: *const Shape,
    n: usize,
    out: *mut u8,
    message: *mut Message,
) -> i32 {
    guarded(message, || {
        // SAFETY: the caller's promise.
        let image = unsafe { mat(&grey)? };
        let shapes = if n == 0 {
            &[][..]
        } else {
            // SAFETY: `shapes` holds `n` shapes.
            unsafe { std::slice::from_raw_parts(shapes, n) }
        };
        let mut img = Mat::default();
        imgproc::cvt_color(&image, &mut img, imgproc::COLOR_GRAY2BGR, 0)?;
        for s in shapes {
            let colour = Scalar::new(s.colour[0], s.colour[1], s.colour[2], 0.0);
            let a = Point::new(s.a[0], s.a[1]);
            match s.kind {
                abi::CIRCLE => {
                    imgproc::circle(&mut img, a, s.radius, colour, 1, imgproc::LINE_AA, 4)?
                }
                _ => {
                    let b = Point::new(s.b[0], s.b[1]);
                    imgproc::line(&mut img, a, b, colour, 1, imgproc::LINE_AA, 4)?
                }
            }
        }
        let bytes = img.data_bytes()?;
        // SAFETY: `out` has room for the image's `3 × width × height` bytes.
        unsafe { std::slice::from_raw_parts_mut(out, bytes.len()) }.copy_from_slice(bytes);
        Ok(())
    })
}

/// `setNumThreads(n)`: how many worker threads OpenCV's own loops use.
#[unsafe(no_mangle)]
pub extern "C" fn naocalib_opencv_set_num_threads(n: i32) {
    let _ = catch_unwind(|| core::set_num_threads(n));
}
