//! The C interface between naocalib and its OpenCV plugin: the plugin's exported symbols, the
//! types they pass and the interface's version. naocalib reads this same file (through a
//! `#[path]` module), so the two sides cannot drift apart within one build; the version
//! catches a plugin left over from another one.

/// The interface's version: [`VERSION_SYMBOL`] returns it.
pub const VERSION: u32 = 1;

/// `extern "C" fn() -> u32`: [`VERSION`].
pub const VERSION_SYMBOL: &[u8] = b"naocalib_opencv_version\0";
/// `extern "C" fn(Grey, Roi, i32, i32, Search, *mut f32, *mut i32, *mut Message) -> i32`:
/// `findChessboardCorners`.
pub const FIND_SYMBOL: &[u8] = b"naocalib_opencv_find_chessboard\0";
/// `extern "C" fn(Grey, *mut u8, *mut Message) -> i32`: `resize` to half width and height
/// with `INTER_AREA`.
pub const HALF_SYMBOL: &[u8] = b"naocalib_opencv_resize_half\0";
/// `extern "C" fn(Grey, *mut f32, i32, i32, i32, f64, *mut Message) -> i32`: `cornerSubPix`.
pub const SUBPIX_SYMBOL: &[u8] = b"naocalib_opencv_corner_sub_pix\0";
/// `extern "C" fn(Grey, *const Shape, usize, *mut u8, *mut Message) -> i32`: the grey image
/// in colour with anti-aliased shapes drawn on it.
pub const DRAW_SYMBOL: &[u8] = b"naocalib_opencv_draw\0";
/// `extern "C" fn(i32)`: `setNumThreads`.
pub const THREADS_SYMBOL: &[u8] = b"naocalib_opencv_set_num_threads\0";

/// The signature behind [`VERSION_SYMBOL`].
pub type VersionFn = unsafe extern "C" fn() -> u32;
/// The signature behind [`FIND_SYMBOL`].
pub type FindFn =
    unsafe extern "C" fn(Grey, Roi, i32, i32, Search, *mut f32, *mut i32, *mut Message) -> i32;
/// The signature behind [`HALF_SYMBOL`].
pub type HalfFn = unsafe extern "C" fn(Grey, *mut u8, *mut Message) -> i32;
/// The signature behind [`SUBPIX_SYMBOL`].
pub type SubPixFn = unsafe extern "C" fn(Grey, *mut f32, i32, i32, i32, f64, *mut Message) -> i32;
/// The signature behind [`DRAW_SYMBOL`].
pub type DrawFn = unsafe extern "C" fn(Grey, *const Shape, usize, *mut u8, *mut Message) -> i32;
/// The signature behind [`THREADS_SYMBOL`].
pub type ThreadsFn = unsafe extern "C" fn(i32);

/// An 8-bit greyscale image lent to the plugin: `width × height` bytes, row-major.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct Grey {
    /// The first pixel.
    pub data: *const u8,
    /// Width in pixels.
    pub width: i32,
    /// Height in pixels.
    pub height: i32,
}

/// A rectangle of the image (pixels); `width == 0` means the whole image.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Roi {
    /// Left column.
    pub x: i32,
    /// Top row.
    pub y: i32,
    /// Width.
    pub width: i32,
    /// Height.
    pub height: i32,
}

/// How `findChessboardCorners` searches.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Search {
    /// Adaptive thresholds on a normalised image, and the fast check that gives up early on
    /// images without a board.
    Fast = 0,
    /// The same without the fast check, which gives up on some oblique boards.
    Exhaustive = 1,
}

/// One anti-aliased shape to draw, its coordinates with 4 fractional bits (×16).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shape {
    /// 0: a circle around `a` of radius `radius`; 1: a line from `a` to `b`.
    pub kind: i32,
    /// The centre, or the line's start.
    pub a: [i32; 2],
    /// The line's end.
    pub b: [i32; 2],
    /// The circle's radius.
    pub radius: i32,
    /// Blue, green, red.
    pub colour: [f64; 3],
}

/// [`Shape::kind`] of a circle.
pub const CIRCLE: i32 = 0;
/// [`Shape::kind`] of a line.
pub const LINE: i32 = 1;

/// What went wrong, written by the plugin when a call returns non-zero: UTF-8, `len` bytes.
#[repr(C)]
pub struct Message {
    /// How many bytes of `text` are used.
    pub len: usize,
    /// The text.
    pub text: [u8; 512],
}

impl Message {
    /// An empty message.
    pub const fn new() -> Message {
        Message {
            len: 0,
            text: [0; 512],
        }
    }

    /// The text (cut at a character boundary where it was too long).
    pub fn as_str(&self) -> &str {
        let bytes = &self.text[..self.len.min(self.text.len())];
        match std::str::from_utf8(bytes) {
            Ok(s) => s,
            Err(e) => std::str::from_utf8(&bytes[..e.valid_up_to()]).unwrap_or_default(),
        }
    }

    /// Sets the text to `s`, cut to fit.
    pub fn set(&mut self, s: &str) {
        let mut n = s.len().min(self.text.len());
        while !s.is_char_boundary(n) {
            n -= 1;
        }
        self.text[..n].copy_from_slice(&s.as_bytes()[..n]);
        self.len = n;
    }
}

impl Default for Message {
    fn default() -> Message {
        Message::new()
    }
}
