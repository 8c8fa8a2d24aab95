//! One report a person opens: a single self-contained HTML file (polyglot XHTML, so any
//! XML parser reads it too) that works offline — no scripts, no style sheets, no fonts or
//! images from elsewhere. It holds the parameter table with σ, the diagnosis
//! ([`super::diagnosis`]), the residual plots and the per-capture RMS as inline SVG, the
//! per-capture RMS as a table, and overlays of the worst captures (their image when the
//! dataset has one, else a blank frame; detected vertices as green crosses, the nominal
//! model red, the calibrated model blue) as embedded PNG.
//!
//! `naocalib solve DATASET --report FILE.html` writes [`solve_page`]; `naocalib batch
//! --report FILE.html` writes a page of the same parts, one section per run.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use plotters::prelude::*;

use super::plot::{self, PlotError};
use crate::dataset::Dataset;
use crate::model::{Side, Vertex};
use crate::output::{WriteError, WriteOptions, write_atomic};
use crate::run::{Change, Run};
use crate::solve::Solution;

/// How many of the worst captures get an overlay.
pub const OVERLAYS: usize = 3;

/// Why a report could not be made.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// A plot could not be drawn.
    #[error(transparent)]
    Plot(#[from] PlotError),
    /// An overlay could not be drawn.
    #[error("overlay of capture {capture}: {message}")]
    Overlay {
        /// The capture.
        capture: u64,
        /// What went wrong.
        message: String,
    },
    /// The file could not be written (or was refused).
    #[error(transparent)]
    Write(#[from] WriteError),
}

/// Text with `&`, `<`, `>`, `"` and `'` escaped for HTML and XML.
pub fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// Standard base64 (RFC 4648, with padding) of `bytes`, for `data:` URLs.
pub fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            chunk.get(1).copied().unwrap_or(0),
            chunk.get(2).copied().unwrap_or(0),
        ];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(ALPHABET[((n >> (18 - 6 * k)) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

const STYLE: &str = "body{font-family:sans-serif;margin:2em auto;max-width:1200px;\
color:#222;line-height:1.4}h1{font-size:1.6em}h2{font-size:1.3em;border-bottom:1px solid #ccc;\
margin-top:2em}table{border-collapse:collapse;margin:.5em 0}td,th{padding:.15em .7em;\
text-align:right;border-bottom:1px solid #eee}th{background:#f4f4f4}td.name,th.name{text-align:left}\
.bad{color:#b00;font-weight:bold}.diag{font-family:monospace;white-space:pre-wrap;\
background:#f8f8f8;padding:.7em;border:1px solid #ddd}figure{margin:1em 0}\
figcaption{color:#555;font-size:.9em}svg,img{max-width:100%;height:auto}\
.captures{max-height:24em;overflow:auto;display:inline-block}\
.overlays{display:flex;flex-wrap:wrap;gap:1em}.overlays figure{flex:1 1 30%;margin:0}";

/// One run's part of a page.
struct Section<'a> {
    /// Heading (the dataset).
    title: String,
    /// The run: its solution, calibration, change and truth.
    run: &'a Run,
    /// The dataset, for the cameras of the captures and the overlays.
    dataset: Option<&'a Dataset>,
    /// Whether to draw overlays of the worst captures (needs `dataset`).
    overlays: bool,
    /// Appended to the section's element ids, to keep them unique on a page of several.
    id_suffix: String,
}

/// The change since the robot's previous calibration as a table: previous, now, change
/// and `z = change/σ`, rows with |z| > 3 marked.
fn change_table(out: &mut String, changes: &[Change], id_suffix: &str) {
    let _ = writeln!(
        out,
        "<h3>Change since the previous calibration</h3>\n<table id=\"changes{id_suffix}\">\n\
         <tr><th class=\"name\">parameter</th><th>previous</th><th>now</th><th>change</th>\
         <th>z = change/σ</th><th class=\"name\">unit</th></tr>"
    );
    for c in changes {
        let z = if c.z.is_finite() {
            format!("{:+.2}", c.z)
        } else {
            "–".into()
        };
        let z = if c.z.abs() > 3.0 {
            format!("<span class=\"bad\">{z}</span>")
        } else {
            z
        };
        let _ = writeln!(
            out,
            "<tr><td class=\"name\">{}</td><td>{:.4}</td><td>{:.4}</td><td>{:+.4}</td>\
             <td>{z}</td><td class=\"name\">{}</td></tr>",
            c.param.name(),
            c.previous,
            c.value,
            c.change,
            escape(c.param.unit().name())
        );
    }
    out.push_str("</table>\n");
}

/// The calibrated cameras' intrinsics as the teams read them ([`super::intrinsics_rows`]),
/// one table per camera, with the previous calibration's values and the change when the
/// run started from one; nothing when the run calibrated no intrinsics.
fn intrinsics_tables(out: &mut String, cameras: &[crate::run::CameraIntrinsics], id_suffix: &str) {
    if cameras.is_empty() {
        return;
    }
    out.push_str("<h3>Camera intrinsics</h3>\n");
    for camera in cameras {
        let with_previous = camera.previous.is_some();
        let _ = writeln!(
            out,
            "<p>{}.</p>\n<table id=\"intrinsics-{}{id_suffix}\">\n<tr><th class=\"name\">quantity\
             </th><th>value</th><th>±1σ</th>{}<th class=\"name\">unit</th></tr>",
            escape(&super::intrinsics_heading(camera)),
            camera.now.camera,
            if with_previous {
                "<th>previous</th><th>change</th>"
            } else {
                ""
            }
        );
        for row in super::intrinsics_rows(camera) {
            let previous = match (row.previous, row.change()) {
                (Some(p), Some(c)) => format!("<td>{p:.4}</td><td>{c:+.4}</td>"),
                _ => String::new(),
            };
            let _ = writeln!(
                out,
                "<tr><td class=\"name\">{}</td><td>{:.4}</td><td>{}</td>{previous}\
                 <td class=\"name\">{}</td></tr>",
                row.quantity,
                row.value,
                escape(&row.sigma),
                row.unit
            );
        }
        out.push_str("</table>\n");
    }
}

/// Opens a report page titled `title`: the XHTML head, the style and the sign convention.
pub(crate) fn page_start(out: &mut String, title: &str) {
    let _ = write!(
        out,
        "<!DOCTYPE html>\n<html xmlns=\"http://www.w3.org/1999/xhtml\" lang=\"en\">\n<head>\n\
         <meta charset=\"utf-8\"/>\n<title>{}</title>\n<style>{STYLE}</style>\n</head>\n<body>\n\
         <h1>{}</h1>\n<p>Written by naocalib {}. A joint offset α means true angle = logged \
         angle + α; team frameworks compute true = sensor − stored and command request + \
         stored, so their files store −α. Camera offsets are rotation corrections of the \
         lower camera, after the head joints.</p>\n",
        escape(title),
        escape(title),
        env!("CARGO_PKG_VERSION")
    );
}

/// Closes a page [`page_start`] opened.
pub(crate) fn page_end(out: &mut String) {
    out.push_str("</body>\n</html>\n");
}

/// Inline SVG from plotters, without its XML prologue (if any).
pub(crate) fn inline_svg(svg: &str) -> &str {
    svg.find("<svg").map_or(svg, |i| &svg[i..])
}

fn parameter_table(out: &mut String, solution: &Solution, truth: Option<&[f64]>) {
    out.push_str(
        "<table>\n<tr><th class=\"name\">parameter</th><th>value</th><th>±1σ</th>\
                  <th class=\"name\">unit</th><th>sandwich σ</th>",
    );
    if truth.is_some() {
        out.push_str("<th>truth</th><th>error</th><th>err/σ</th>");
    }
    out.push_str("</tr>\n");
    for p in super::shown_parameters(solution) {
        let unit = p.unit();
        let fixed = solution.fixed.is_fixed(p);
        let determined = solution.is_determined(p);
        let sigma = |s: Option<f64>| -> String {
            if fixed {
                "fixed".into()
            } else if !determined {
                "<span class=\"bad\">NOT determined</span>".into()
            } else {
                s.map_or_else(|| "–".into(), |s| format!("{:.4}", unit.to_report(s)))
            }
        };
        let value = solution.report_value(p);
        let _ = write!(
            out,
            "<tr><td class=\"name\">{}</td><td>{value:.4}</td><td>{}</td><td class=\"name\">{}</td><td>{}</td>",
            p.name(),
            sigma(Some(solution.std[p.index()])),
            escape(unit.name()),
            sigma(solution.sandwich_std.map(|s| s[p.index()])),
        );
        if let Some(truth) = truth {
            let t = unit.to_report(truth[p.index()]);
            let z = if !fixed && determined && solution.std[p.index()] > 0.0 {
                format!("{:.2}", (value - t) / solution.report_std(p))
            } else {
                "–".into()
            };
            let _ = write!(out, "<td>{t:.4}</td><td>{:.4}</td><td>{z}</td>", value - t);
        }
        out.push_str("</tr>\n");
    }
    out.push_str("</table>\n");
}

/// ` (upper camera)` for a capture of `dataset` taken with the upper camera, else nothing.
fn camera_note(dataset: Option<&Dataset>, id: u64) -> &'static str {
    match dataset.and_then(|d| d.capture(id)).map(|c| c.camera) {
        Some(crate::model::CameraId::Upper) => " (upper camera)",
        _ => "",
    }
}

fn capture_table(
    out: &mut String,
    solution: &Solution,
    sides: Option<&BTreeMap<u64, Side>>,
    dataset: Option<&Dataset>,
) {
    let mut rms = plot::capture_rms_values(solution);
    rms.sort_by(|a, b| b.1.total_cmp(&a.1));
    out.push_str(
        "<div class=\"captures\"><table>\n<tr><th>capture</th><th class=\"name\">board</th>\
                  <th>RMS [px]</th></tr>\n",
    );
    for (id, r) in rms {
        let side = sides.and_then(|s| s.get(&id)).map_or("–", |s| s.name());
        let camera = camera_note(dataset, id);
        let _ = writeln!(
            out,
            "<tr><td>{id}</td><td class=\"name\">{side}{camera}</td><td>{r:.3}</td></tr>"
        );
    }
    out.push_str("</table></div>\n");
}

/// The worst captures by RMS residual after the solve, worst first (at most `n`).
pub fn worst_captures(solution: &Solution, n: usize) -> Vec<(u64, f64)> {
    let mut rms = plot::capture_rms_values(solution);
    rms.sort_by(|a, b| b.1.total_cmp(&a.1));
    rms.truncate(n);
    rms
}

/// The greyscale (or colour) image of a capture as RGB, when it can be read (PNG).
fn capture_image(dataset: &Dataset, capture: u64) -> Option<(u32, u32, Vec<u8>)> {
    let c = dataset.captures.iter().find(|c| c.id == capture)?;
    let bytes = std::fs::read(dataset.dir.join(c.image.as_ref()?)).ok()?;
    let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    decoder.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
    let mut reader = decoder.read_info().ok()?;
    let mut buf = vec![0; reader.output_buffer_size()?];
    let info = reader.next_frame(&mut buf).ok()?;
    let (w, h) = (info.width, info.height);
    let channels = match info.color_type {
        png::ColorType::Grayscale => 1,
        png::ColorType::GrayscaleAlpha => 2,
        png::ColorType::Rgb => 3,
        png::ColorType::Rgba => 4,
        png::ColorType::Indexed => return None,
    };
    let mut rgb = Vec::with_capacity((w * h * 3) as usize);
    for px in buf[..(w * h) as usize * channels].chunks(channels) {
        if channels < 3 {
            rgb.extend([px[0]; 3]);
        } else {
            rgb.extend(&px[..3]);
        }
    }
    Some((w, h, rgb))
}

/// The overlay of one capture as PNG bytes: its image (or a grey frame of the camera's
/// size), the detected vertices (green crosses), the nominal model's projection (red
/// circles) and the calibrated model's (blue circles).
pub fn overlay_png(
    solution: &Solution,
    dataset: &Dataset,
    capture: u64,
) -> Result<Vec<u8>, ReportError> {
    let fail = |message: String| ReportError::Overlay { capture, message };
    let detected: BTreeMap<Vertex, [f64; 2]> = dataset
        .corners
        .iter()
        .filter(|c| c.capture == capture)
        .map(|c| (c.vertex, c.pixel))
        .collect();
    let (w, h, mut buf) = capture_image(dataset, capture).unwrap_or_else(|| {
        let camera = dataset
            .capture(capture)
            .map_or(crate::model::CameraId::Lower, |c| c.camera);
        let intrinsics = dataset.model.intrinsics(camera);
        let (w, h) = (intrinsics.width, intrinsics.height);
        (w, h, vec![200; (w * h * 3) as usize])
    });
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        let at = |p: [f64; 2]| (p[0].round() as i32, p[1].round() as i32);
        let ok = |p: [f64; 2]| p.iter().all(|x| x.is_finite() && x.abs() < 1e5);
        for r in solution.residuals.iter().filter(|r| r.capture == capture) {
            let Some(&d) = detected.get(&r.vertex) else {
                continue;
            };
            // Residual = projection − detection.
            for (res, color) in [
                (r.initial, RGBColor(230, 0, 0)),
                (r.solved, RGBColor(0, 90, 255)),
            ] {
                let p = [d[0] + res[0], d[1] + res[1]];
                if ok(p) {
                    root.draw(&Circle::new(at(p), 5, color.stroke_width(2)))
                        .map_err(|e| fail(e.to_string()))?;
                }
            }
            if ok(d) {
                let (x, y) = at(d);
                for (dx, dy) in [(4, 4), (4, -4)] {
                    root.draw(&PathElement::new(
                        vec![(x - dx, y - dy), (x + dx, y + dy)],
                        RGBColor(0, 190, 0).stroke_width(2),
                    ))
                    .map_err(|e| fail(e.to_string()))?;
                }
            }
        }
        root.present().map_err(|e| fail(e.to_string()))?;
    }
    let mut out = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut out, w, h);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().map_err(|e| fail(e.to_string()))?;
        writer
            .write_image_data(&buf)
            .map_err(|e| fail(e.to_string()))?;
        writer.finish().map_err(|e| fail(e.to_string()))?;
    }
    Ok(out)
}

fn section(out: &mut String, s: &Section<'_>) -> Result<(), ReportError> {
    let run = s.run;
    let solution = &run.solution;
    let sides = Some(&run.sides);
    let _ = writeln!(out, "<h2>{}</h2>", escape(&s.title));
    out.push_str("<h3>Parameters</h3>\n");
    parameter_table(out, solution, run.truth());
    if let Some(changes) = &run.changes {
        change_table(out, changes, &s.id_suffix);
    }
    // With compliance or play estimated: the leg offsets the robot needs standing (what the
    // team files carry), beside the lying ones, with their one-sigma and caveats.
    let standing = super::standing_table(&run.calibration);
    if !standing.is_empty() {
        let _ = writeln!(
            out,
            "<h3>Standing leg offsets</h3>\n<pre>{}</pre>",
            escape(standing.trim())
        );
    }
    intrinsics_tables(out, &run.intrinsics, &s.id_suffix);
    out.push_str("<h3>Diagnosis</h3>\n<div class=\"diag\">");
    for line in super::diagnosis(solution) {
        let class = if line.contains("NOT") {
            " class=\"bad\""
        } else {
            ""
        };
        let _ = writeln!(out, "<span{class}>{}</span>", escape(&line));
    }
    out.push_str("</div>\n<h3>Residuals</h3>\n");
    let scatter = plot::residual_scatter_svg(solution, sides)?;
    let _ = writeln!(
        out,
        "<figure id=\"residuals{}\">{}<figcaption>Residual (projection − detection) of every \
         vertex before and after the solve, by board.</figcaption></figure>",
        s.id_suffix,
        inline_svg(&scatter)
    );
    out.push_str("<h3>RMS residual per capture</h3>\n");
    let captures = plot::capture_rms_svg(solution, sides)?;
    let _ = writeln!(
        out,
        "<figure id=\"captures{}\">{}<figcaption>RMS residual of each capture after the solve.\
         </figcaption></figure>",
        s.id_suffix,
        inline_svg(&captures)
    );
    capture_table(out, solution, sides, s.dataset);
    if let (true, Some(dataset)) = (s.overlays, s.dataset) {
        out.push_str("<h3>Worst captures</h3>\n<div class=\"overlays\">\n");
        for (id, rms) in worst_captures(solution, OVERLAYS) {
            let png = overlay_png(solution, dataset, id)?;
            let _ = writeln!(
                out,
                "<figure class=\"overlay\"><img alt=\"overlay of capture {id}\" \
                 src=\"data:image/png;base64,{}\"/><figcaption>Capture {id}{}, RMS {rms:.3} px: \
                 detected vertices (green crosses), nominal model (red), calibrated model \
                 (blue).</figcaption></figure>",
                base64(&png),
                camera_note(Some(dataset), id)
            );
        }
        out.push_str("</div>\n");
    }
    Ok(())
}

/// The report of one run: parameters, the change since the previous calibration
/// (`solve --start-from`), standing leg offsets, diagnosis, plots, per-capture RMS and
/// overlays of the [`OVERLAYS`] worst captures of `dataset`, the dataset it was fitted to.
pub fn solve_page(run: &Run, dataset: &Dataset) -> Result<String, ReportError> {
    let title = format!("naocalib calibration of {}", run.dataset().display());
    let mut out = String::new();
    page_start(&mut out, &title);
    section(
        &mut out,
        &Section {
            title: run.dataset().display().to_string(),
            run,
            dataset: Some(dataset),
            overlays: true,
            id_suffix: String::new(),
        },
    )?;
    page_end(&mut out);
    Ok(out)
}

/// One run's section of a page of many runs (a batch's): titled by its dataset, ids
/// suffixed with `id_suffix`, without overlays (which would need every dataset's images).
pub(crate) fn run_section(
    out: &mut String,
    run: &Run,
    id_suffix: String,
) -> Result<(), ReportError> {
    section(
        out,
        &Section {
            title: run.dataset().display().to_string(),
            run,
            dataset: None,
            overlays: false,
            id_suffix,
        },
    )
}

/// Writes [`solve_page`] to `path` (atomically; never over an input).
pub fn write_report(
    run: &Run,
    dataset: &Dataset,
    path: &Path,
    options: &WriteOptions,
) -> Result<(), ReportError> {
    let page = solve_page(run, dataset)?;
    Ok(write_atomic(path, page.as_bytes(), options)?)
}
