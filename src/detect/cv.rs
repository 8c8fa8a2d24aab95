//! OpenCV, loaded by the commands that detect and by no other: naocalib's plugin
//! (`crates/naocalib-opencv`, the shared library `libnaocalib_opencv.so`) holds the
//! chessboard finder, `cornerSubPix` and the overlay's drawing behind a C interface, and is
//! opened with `dlopen` at the first call. A command that never looks at an image thus
//! starts without OpenCV's some 40 shared libraries.
//!
//! The plugin is looked for at `$NAOCALIB_OPENCV_PLUGIN` when that is set, else next to the
//! executable, in its `deps/` (cargo's `target/<profile>/`) and in `../deps/` (cargo's
//! examples); cargo builds it with naocalib.

use std::path::PathBuf;
use std::sync::OnceLock;

use crate::sim::render::GreyImage;

#[path = "../../crates/naocalib-opencv/src/abi.rs"]
#[allow(dead_code)] // the plugin's half of the interface is not called from here
mod abi;

pub use abi::{Roi, Search, Shape};

/// The environment variable that names the plugin's file.
pub const PLUGIN_VARIABLE: &str = "NAOCALIB_OPENCV_PLUGIN";

/// What OpenCV, or loading it, reported.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{message}")]
pub struct Error {
    /// The message.
    pub message: String,
}

/// A result of an OpenCV call.
pub type Result<T> = std::result::Result<T, Error>;

/// The plugin's functions, resolved once.
struct Plugin {
    find: abi::FindFn,
    half: abi::HalfFn,
    subpix: abi::SubPixFn,
    draw: abi::DrawFn,
    threads: abi::ThreadsFn,
    /// Kept open for as long as the process runs.
    _library: libloading::Library,
}

/// The file name of the plugin.
fn file_name() -> String {
    format!(
        "{}naocalib_opencv{}",
        std::env::consts::DLL_PREFIX,
        std::env::consts::DLL_SUFFIX
    )
}

/// Where the plugin is looked for when [`PLUGIN_VARIABLE`] is not set, in order.
fn candidates() -> Vec<PathBuf> {
    let name = file_name();
    let Some(dir) = std::env::current_exe()
        .ok()
        .and_then(|exe| exe.parent().map(|d| d.to_path_buf()))
    else {
        return Vec::new();
    };
    vec![
        dir.join(&name),
        dir.join("deps").join(&name),
        dir.join("..").join("deps").join(&name),
    ]
}

/// Opens the plugin at `path` and resolves its functions, checking its interface version.
fn open(path: &std::path::Path) -> std::result::Result<Plugin, String> {
    // SAFETY: the plugin is naocalib's own library (crates/naocalib-opencv); its
    // initialisers are OpenCV's. The symbols' types are abi.rs's, the same file it was
    // built from, and its version is checked before any other is used.
    unsafe {
        let library = libloading::Library::new(path).map_err(|e| e.to_string())?;
        let version = *library
            .get::<abi::VersionFn>(abi::VERSION_SYMBOL)
            .map_err(|e| e.to_string())?;
        if version() != abi::VERSION {
            return Err(format!(
                "its interface is version {}, this naocalib needs {}; rebuild it with naocalib",
                version(),
                abi::VERSION
            ));
        }
        let symbol = |name: &[u8]| String::from_utf8_lossy(&name[..name.len() - 1]).into_owned();
        macro_rules! get {
            ($name:expr, $ty:ty) => {
                *library
                    .get::<$ty>($name)
                    .map_err(|e| format!("{}: {e}", symbol($name)))?
            };
        }
        Ok(Plugin {
            find: get!(abi::FIND_SYMBOL, abi::FindFn),
            half: get!(abi::HALF_SYMBOL, abi::HalfFn),
            subpix: get!(abi::SUBPIX_SYMBOL, abi::SubPixFn),
            draw: get!(abi::DRAW_SYMBOL, abi::DrawFn),
            threads: get!(abi::THREADS_SYMBOL, abi::ThreadsFn),
            _library: library,
        })
    }
}

/// The plugin, opened at the first call; the same error at every call when it cannot be.
fn plugin() -> Result<&'static Plugin> {
    static PLUGIN: OnceLock<std::result::Result<Plugin, String>> = OnceLock::new();
    PLUGIN
        .get_or_init(|| {
            let opened = |path: &std::path::Path| {
                open(path).map_err(|e| {
                    format!(
                        "naocalib's OpenCV plugin {} did not load: {e}",
                        path.display()
                    )
                })
            };
            if let Some(path) = std::env::var_os(PLUGIN_VARIABLE) {
                return opened(std::path::Path::new(&path));
            }
            let candidates = candidates();
            match candidates.iter().find(|p| p.exists()) {
                Some(path) => opened(path),
                None => Err(format!(
                    "naocalib's OpenCV plugin {} is not in {}; it is built with naocalib \
                     (cargo build --release) and belongs next to the naocalib executable, or \
                     set {PLUGIN_VARIABLE} to its path",
                    file_name(),
                    if candidates.is_empty() {
                        "the executable's directory (which cannot be found)".into()
                    } else {
                        candidates
                            .iter()
                            .map(|p| p.display().to_string())
                            .collect::<Vec<_>>()
                            .join(", ")
                    }
                )),
            }
        })
        .as_ref()
        .map_err(|message| Error {
            message: message.clone(),
        })
}

/// Loads OpenCV now: an error here is the one every detection would give.
pub fn load() -> Result<()> {
    plugin().map(|_| ())
}

/// The image as the plugin's view of it.
fn view(image: &GreyImage) -> Result<abi::Grey> {
    let (width, height) = (image.width as i32, image.height as i32);
    if width <= 0
        || height <= 0
        || image.pixels.len() != image.width as usize * image.height as usize
    {
        return Err(Error {
            message: format!("an image of {}×{} pixels", image.width, image.height),
        });
    }
    Ok(abi::Grey {
        data: image.pixels.as_ptr(),
        width,
        height,
    })
}

/// The result of a plugin call that returned `status`.
fn status(status: i32, message: &abi::Message) -> Result<()> {
    match status {
        0 => Ok(()),
        _ => Err(Error {
            message: message.as_str().to_string(),
        }),
    }
}

/// `findChessboardCorners` for a pattern of `cols × rows` inner corners in `image`, or in
/// its part `roi`: the corners in the part's pixels, in OpenCV's order; `None` when it found
/// no board, or other than `cols × rows` corners.
pub fn find_chessboard(
    image: &GreyImage,
    roi: Option<Roi>,
    cols: usize,
    rows: usize,
    search: Search,
) -> Result<Option<Vec<[f32; 2]>>> {
    let plugin = plugin()?;
    let grey = view(image)?;
    let mut out = vec![0f32; 2 * cols * rows];
    let mut count = 0i32;
    let mut message = abi::Message::new();
    // SAFETY: `grey` views `image`'s pixels, `out` has room for `cols × rows` pairs.
    let s = unsafe {
        (plugin.find)(
            grey,
            roi.unwrap_or_default(),
            cols as i32,
            rows as i32,
            search,
            out.as_mut_ptr(),
            &mut count,
            &mut message,
        )
    };
    status(s, &message)?;
    Ok((count > 0 && count as usize == cols * rows)
        .then(|| out.chunks_exact(2).map(|p| [p[0], p[1]]).collect()))
}

/// `image` shrunk to half its width and height with `INTER_AREA` (each pixel the mean of
/// four).
pub fn resize_half(image: &GreyImage) -> Result<GreyImage> {
    let plugin = plugin()?;
    let grey = view(image)?;
    let (width, height) = (image.width / 2, image.height / 2);
    let mut pixels = vec![0u8; width as usize * height as usize];
    let mut message = abi::Message::new();
    // SAFETY: `grey` views `image`'s pixels, `pixels` has room for the half image.
    let s = unsafe { (plugin.half)(grey, pixels.as_mut_ptr(), &mut message) };
    status(s, &message)?;
    Ok(GreyImage {
        width,
        height,
        pixels,
    })
}

/// `cornerSubPix` of `points` (refined in place) in `image`, with the half-window `half` px,
/// no zero zone, and at most `max_count` iterations or a step below `eps` px.
pub fn corner_sub_pix(
    image: &GreyImage,
    points: &mut [[f32; 2]],
    half: i32,
    max_count: i32,
    eps: f64,
) -> Result<()> {
    let plugin = plugin()?;
    let grey = view(image)?;
    let mut message = abi::Message::new();
    // SAFETY: `grey` views `image`'s pixels; `points` is `points.len()` pairs of floats.
    let s = unsafe {
        (plugin.subpix)(
            grey,
            points.as_mut_ptr().cast::<f32>(),
            points.len() as i32,
            half,
            max_count,
            eps,
            &mut message,
        )
    };
    status(s, &message)
}

/// A circle of `radius` around `centre`, as [`draw`] draws it (coordinates ×16).
pub fn circle(centre: [i32; 2], radius: i32, colour: [f64; 3]) -> Shape {
    Shape {
        kind: abi::CIRCLE,
        a: centre,
        b: centre,
        radius,
        colour,
    }
}

/// A line from `a` to `b`, as [`draw`] draws it (coordinates ×16).
pub fn line(a: [i32; 2], b: [i32; 2], colour: [f64; 3]) -> Shape {
    Shape {
        kind: abi::LINE,
        a,
        b,
        radius: 0,
        colour,
    }
}

/// `image` in colour with `shapes` drawn on it in order (anti-aliased, 1 px wide, with 4
/// fractional bits): `3 × width × height` bytes, blue, green, red, row by row.
pub fn draw(image: &GreyImage, shapes: &[Shape]) -> Result<Vec<u8>> {
    let plugin = plugin()?;
    let grey = view(image)?;
    let mut bgr = vec![0u8; 3 * image.pixels.len()];
    let mut message = abi::Message::new();
    // SAFETY: `grey` views `image`'s pixels, `shapes` is `shapes.len()` shapes, `bgr` has
    // room for the colour image.
    let s = unsafe {
        (plugin.draw)(
            grey,
            shapes.as_ptr(),
            shapes.len(),
            bgr.as_mut_ptr(),
            &mut message,
        )
    };
    status(s, &message)?;
    Ok(bgr)
}

/// How many worker threads OpenCV's own loops use (`setNumThreads`).
pub fn set_num_threads(n: i32) -> Result<()> {
    let plugin = plugin()?;
    // SAFETY: no arguments to get wrong.
    unsafe { (plugin.threads)(n) };
    Ok(())
}
