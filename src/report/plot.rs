//! Plots of a calibration, each as PNG and SVG (with `plotters`; text in the embedded
//! DejaVu Sans, so no system fonts are needed):
//!
//! - [`residual_scatter`]: every vertex's residual `(Δu, Δv)` before and after the solve,
//!   left and right board in two colours (the paper's Fig. 4).
//! - [`capture_rms`]: the RMS residual of each capture after the solve, so that bad
//!   captures (a misdetected board, a wrong joint reading) stand out.
//! - [`parameter_estimates`]: per parameter the estimate of each run with its ±1σ error
//!   bar and the mean across runs (for a batch).
//!
//! Files are written atomically and never replace an existing file unless `force`.
//!
//! ```
//! use naocalib::{export::WriteOptions, report::plot};
//! # use naocalib::model::{FixedSet, Model};
//! # use naocalib::sim::{SimOptions, simulate};
//! # use naocalib::solve::{Problem, UncertaintyOptions, backend, calibrate};
//! # let options = SimOptions { stances: 4, heads: 2, ..SimOptions::default() };
//! # let dataset = simulate(&Model::default(), &options).unwrap();
//! # let problem = Problem::from_dataset(&dataset, FixedSet::default()).unwrap();
//! # let solution = calibrate(&problem, backend("lm", false).unwrap().as_ref(), &UncertaintyOptions::plain()).unwrap();
//! let dir = tempfile::tempdir().unwrap();
//! let sides = plot::capture_sides(&dataset);
//! let files = plot::solution_plots(&solution, Some(&sides), dir.path(), "run", &WriteOptions::default()).unwrap();
//! assert_eq!(files.len(), 4); // residuals and captures, PNG and SVG
//! ```

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Once;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::dataset::Dataset;
use crate::model::{Param, Side};
use crate::output::{WriteError, WriteOptions, write_atomic, write_atomic_with};
use crate::solve::{Solution, VertexResidual};

/// Why a plot could not be made.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// Drawing failed.
    #[error("{}: cannot draw the plot: {message}", path.display())]
    Draw {
        /// The file being drawn.
        path: PathBuf,
        /// The backend's message.
        message: String,
    },
    /// Writing the file failed (or was refused).
    #[error(transparent)]
    Write(#[from] WriteError),
    /// Nothing to plot.
    #[error("nothing to plot: {0}")]
    Empty(&'static str),
}

const LEFT: RGBColor = RGBColor(31, 119, 180);
const RIGHT: RGBColor = RGBColor(214, 39, 40);
const GREY: RGBColor = RGBColor(120, 120, 120);
pub(super) const FONT: &str = "sans-serif";

fn register_fonts() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        let _ = plotters::style::register_font(FONT, FontStyle::Normal, dejavu::sans::regular());
        let _ = plotters::style::register_font(FONT, FontStyle::Bold, dejavu::sans::bold());
    });
}

/// Which board each capture shows, for colouring residuals by leg.
pub fn capture_sides(dataset: &Dataset) -> BTreeMap<u64, Side> {
    dataset.captures.iter().map(|c| (c.id, c.side)).collect()
}

pub(super) type DrawResult = Result<(), String>;

/// A figure that can be drawn on any backend.
pub(super) trait Figure {
    fn size(&self) -> (u32, u32);
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult;
}

pub(super) fn err<E: std::fmt::Display>(e: E) -> String {
    e.to_string()
}

/// Draws `fig` as SVG text.
fn svg_text(fig: &impl Figure) -> Result<String, String> {
    register_fonts();
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, fig.size()).into_drawing_area();
        fig.draw(&root).and_then(|()| root.present().map_err(err))?;
    }
    Ok(text)
}

/// The residual scatter of [`residual_scatter`] as SVG text (for embedding in a page).
pub fn residual_scatter_svg(
    solution: &Solution,
    sides: Option<&BTreeMap<u64, Side>>,
) -> Result<String, PlotError> {
    if solution.residuals.is_empty() {
        return Err(PlotError::Empty("the solution has no residuals"));
    }
    svg_text(&Scatter {
        residuals: &solution.residuals,
        sides,
        rms: [solution.initial_rms_px, solution.rms_px],
    })
    .map_err(|message| PlotError::Draw {
        path: PathBuf::from("residuals.svg"),
        message,
    })
}

/// The per-capture RMS plot of [`capture_rms`] as SVG text (for embedding in a page).
pub fn capture_rms_svg(
    solution: &Solution,
    sides: Option<&BTreeMap<u64, Side>>,
) -> Result<String, PlotError> {
    let rms = capture_rms_values(solution);
    if rms.is_empty() {
        return Err(PlotError::Empty("the solution has no residuals"));
    }
    svg_text(&Captures { rms, sides }).map_err(|message| PlotError::Draw {
        path: PathBuf::from("captures.svg"),
        message,
    })
}

/// Draws `fig` into `<stem>.png` and `<stem>.svg`.
pub(super) fn save(
    fig: &impl Figure,
    stem: &Path,
    options: &WriteOptions,
) -> Result<Vec<PathBuf>, PlotError> {
    register_fonts();
    let png = stem.with_extension("png");
    let svg = stem.with_extension("svg");
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, fig.size()).into_drawing_area();
        fig.draw(&root)
            .and_then(|()| root.present().map_err(err))
            .map_err(|message| PlotError::Draw {
                path: svg.clone(),
                message,
            })?;
    }
    let mut failure = None;
    let written = write_atomic_with(&png, options, |tmp| {
        let root = BitMapBackend::new(tmp, fig.size()).into_drawing_area();
        let result = fig.draw(&root).and_then(|()| root.present().map_err(err));
        result.map_err(|message| {
            failure = Some(message.clone());
            std::io::Error::other(message)
        })
    });
    if let Some(message) = failure {
        return Err(PlotError::Draw { path: png, message });
    }
    written?;
    write_atomic(&svg, text.as_bytes(), options)?;
    Ok(vec![png, svg])
}

/// A tick label without a spurious minus sign on zero.
fn tick(x: &f64) -> String {
    let s = format!("{x}");
    let s = if s.len() > 8 { format!("{x:.4}") } else { s };
    if s.trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        "0".into()
    } else {
        s
    }
}

/// Values beyond this magnitude are not plotted: the plotting library's tick search does
/// not end for ranges near the limits of `f64` (nor for non-finite ones).
pub const PLOT_LIMIT: f64 = 1e12;

/// Whether `x` can be plotted (finite, within [`PLOT_LIMIT`]).
fn plottable(x: f64) -> bool {
    x.is_finite() && x.abs() <= PLOT_LIMIT
}

/// A range `[lo, hi]` around the values with a margin, never empty, always plottable.
fn padded(lo: f64, hi: f64) -> (f64, f64) {
    let (lo, hi) = if plottable(lo) && plottable(hi) && lo <= hi {
        (lo, hi)
    } else {
        (-1.0, 1.0)
    };
    let span = (hi - lo).abs().max(1e-9 * (1.0 + hi.abs()));
    (lo - 0.08 * span, hi + 0.08 * span)
}

struct Scatter<'a> {
    residuals: &'a [VertexResidual],
    sides: Option<&'a BTreeMap<u64, Side>>,
    rms: [[f64; 2]; 2],
}

impl Figure for Scatter<'_> {
    fn size(&self) -> (u32, u32) {
        (1400, 680)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult {
        root.fill(&WHITE).map_err(err)?;
        let (title, body) = root.split_vertically(50);
        title
            .draw_text(
                "Residuals (projection − observation) of every vertex",
                &(FONT, 26).into_font().style(FontStyle::Bold).color(&BLACK),
                (20, 12),
            )
            .map_err(err)?;
        let panels = body.split_evenly((1, 2));
        for (k, panel) in panels.iter().enumerate() {
            let pick = |r: &VertexResidual| if k == 0 { r.initial } else { r.solved };
            let points: Vec<([f64; 2], Option<Side>)> = self
                .residuals
                .iter()
                .map(|r| (pick(r), self.sides.and_then(|s| s.get(&r.capture).copied())))
                .filter(|(p, _)| plottable(p[0]) && plottable(p[1]))
                .collect();
            let extent = points
                .iter()
                .map(|(p, _)| p[0].abs().max(p[1].abs()))
                .fold(0.0f64, f64::max)
                .max(1e-6)
                * 1.08;
            let left_out = self.residuals.len() - points.len();
            let caption = format!(
                "{} the solve: rms x {:.3} px, y {:.3} px{}",
                if k == 0 { "before" } else { "after" },
                self.rms[k][0],
                self.rms[k][1],
                if left_out > 0 {
                    format!(" ({left_out} non-finite left out)")
                } else {
                    String::new()
                }
            );
            let mut chart = ChartBuilder::on(panel)
                .caption(caption, (FONT, 22))
                .margin(18)
                .x_label_area_size(50)
                .y_label_area_size(80)
                .build_cartesian_2d(-extent..extent, -extent..extent)
                .map_err(err)?;
            chart
                .configure_mesh()
                .x_desc("Δu [px]")
                .y_desc("Δv [px]")
                .x_label_formatter(&tick)
                .y_label_formatter(&tick)
                .label_style((FONT, 16))
                .axis_desc_style((FONT, 18))
                .light_line_style(RGBColor(235, 235, 235))
                .draw()
                .map_err(err)?;
            for (side, color, label) in [
                (Some(Side::Left), LEFT, "left board"),
                (Some(Side::Right), RIGHT, "right board"),
                (None, GREY, "vertex"),
            ] {
                let pts: Vec<(f64, f64)> = points
                    .iter()
                    .filter(|(_, s)| *s == side)
                    .map(|(p, _)| (p[0], p[1]))
                    .collect();
                if pts.is_empty() {
                    continue;
                }
                chart
                    .draw_series(
                        pts.iter()
                            .map(|&(x, y)| Circle::new((x, y), 2, color.mix(0.55).filled())),
                    )
                    .map_err(err)?
                    .label(format!("{label} ({})", pts.len()))
                    .legend(move |(x, y)| Circle::new((x, y), 5, color.filled()));
            }
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::UpperRight)
                .label_font((FONT, 16))
                .background_style(WHITE.mix(0.85))
                .border_style(GREY)
                .draw()
                .map_err(err)?;
        }
        Ok(())
    }
}

/// Writes the residual scatter before and after the solve (the paper's Fig. 4) to
/// `<stem>.png` and `<stem>.svg`; `sides` (see [`capture_sides`]) colours the vertices by
/// board. Returns the files written.
pub fn residual_scatter(
    solution: &Solution,
    sides: Option<&BTreeMap<u64, Side>>,
    stem: &Path,
    options: &WriteOptions,
) -> Result<Vec<PathBuf>, PlotError> {
    if solution.residuals.is_empty() {
        return Err(PlotError::Empty("the solution has no residuals"));
    }
    save(
        &Scatter {
            residuals: &solution.residuals,
            sides,
            rms: [solution.initial_rms_px, solution.rms_px],
        },
        stem,
        options,
    )
}

/// The RMS residual `√(mean(Δu² + Δv²))` of each capture at the solution (px), by capture
/// id, with its board.
pub fn capture_rms_values(solution: &Solution) -> Vec<(u64, f64)> {
    let mut sums: BTreeMap<u64, (f64, usize)> = BTreeMap::new();
    for r in &solution.residuals {
        let e = sums.entry(r.capture).or_default();
        e.0 += r.solved[0].powi(2) + r.solved[1].powi(2);
        e.1 += 1;
    }
    sums.into_iter()
        .map(|(id, (s, n))| (id, (s / n as f64).sqrt()))
        .collect()
}

/// A capture stands out when its RMS exceeds this many times the median capture RMS.
pub const OUTLIER_FACTOR: f64 = 3.0;

struct Captures<'a> {
    rms: Vec<(u64, f64)>,
    sides: Option<&'a BTreeMap<u64, Side>>,
}

impl Figure for Captures<'_> {
    fn size(&self) -> (u32, u32) {
        (1400, 620)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult {
        root.fill(&WHITE).map_err(err)?;
        let all = &self.rms;
        let rms: Vec<(u64, f64)> = all.iter().copied().filter(|r| plottable(r.1)).collect();
        let left_out = all.len() - rms.len();
        let mut sorted: Vec<f64> = rms.iter().map(|r| r.1).collect();
        sorted.sort_by(f64::total_cmp);
        let median = sorted.get(sorted.len() / 2).copied().unwrap_or(0.0);
        let threshold = OUTLIER_FACTOR * median;
        let max_y = (sorted.last().copied().unwrap_or(1.0).max(threshold) * 1.12).max(1e-9);
        let first = all.first().map_or(0, |r| r.0) as f64;
        let last = all.last().map_or(1, |r| r.0) as f64;
        let (x0, x1) = padded(first, last);
        let outliers = rms.iter().filter(|r| r.1 > threshold).count();
        let caption = format!(
            "RMS residual per capture after the solve (median {median:.3} px; {outliers} above {OUTLIER_FACTOR}× median{})",
            if left_out > 0 {
                format!("; {left_out} non-finite left out")
            } else {
                String::new()
            }
        );
        let mut chart = ChartBuilder::on(root)
            .caption(caption, (FONT, 22))
            .margin(20)
            .x_label_area_size(50)
            .y_label_area_size(80)
            .build_cartesian_2d(x0..x1, 0.0..max_y)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc("capture id")
            .y_desc("RMS residual [px]")
            .label_style((FONT, 16))
            .axis_desc_style((FONT, 18))
            .light_line_style(RGBColor(235, 235, 235))
            .draw()
            .map_err(err)?;
        for (side, color, label) in [
            (Some(Side::Left), LEFT, "left board"),
            (Some(Side::Right), RIGHT, "right board"),
            (None, GREY, "capture"),
        ] {
            let pts: Vec<(f64, f64)> = rms
                .iter()
                .filter(|(id, _)| self.sides.and_then(|s| s.get(id).copied()) == side)
                .map(|&(id, r)| (id as f64, r))
                .collect();
            if pts.is_empty() {
                continue;
            }
            chart
                .draw_series(
                    pts.iter()
                        .map(|&(x, y)| PathElement::new(vec![(x, 0.0), (x, y)], color.mix(0.5))),
                )
                .map_err(err)?;
            chart
                .draw_series(
                    pts.iter()
                        .map(|&(x, y)| Circle::new((x, y), 4, color.filled())),
                )
                .map_err(err)?
                .label(label)
                .legend(move |(x, y)| Circle::new((x, y), 5, color.filled()));
        }
        chart
            .draw_series(LineSeries::new(
                [(x0, threshold), (x1, threshold)],
                BLACK.stroke_width(1),
            ))
            .map_err(err)?
            .label(format!("{OUTLIER_FACTOR}× median"))
            .legend(|(x, y)| PathElement::new(vec![(x - 8, y), (x + 8, y)], BLACK));
        // Name the captures that stand out.
        chart
            .draw_series(rms.iter().filter(|r| r.1 > threshold).map(|&(id, r)| {
                Text::new(
                    format!("{id}"),
                    (id as f64, r + max_y * 0.02),
                    (FONT, 15).into_font().color(&BLACK),
                )
            }))
            .map_err(err)?;
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .label_font((FONT, 16))
            .background_style(WHITE.mix(0.85))
            .border_style(GREY)
            .draw()
            .map_err(err)?;
        Ok(())
    }
}

/// Writes the RMS residual of each capture after the solve ([`capture_rms_values`]) to
/// `<stem>.png` and `<stem>.svg`, with a line at [`OUTLIER_FACTOR`] × the median and the
/// ids of the captures above it.
pub fn capture_rms(
    solution: &Solution,
    sides: Option<&BTreeMap<u64, Side>>,
    stem: &Path,
    options: &WriteOptions,
) -> Result<Vec<PathBuf>, PlotError> {
    let rms = capture_rms_values(solution);
    if rms.is_empty() {
        return Err(PlotError::Empty("the solution has no residuals"));
    }
    save(&Captures { rms, sides }, stem, options)
}

/// Both plots of one solution into `dir`: `<prefix>_residuals` and `<prefix>_captures`,
/// PNG and SVG each.
pub fn solution_plots(
    solution: &Solution,
    sides: Option<&BTreeMap<u64, Side>>,
    dir: &Path,
    prefix: &str,
    options: &WriteOptions,
) -> Result<Vec<PathBuf>, PlotError> {
    let mut files = residual_scatter(
        solution,
        sides,
        &dir.join(format!("{prefix}_residuals")),
        options,
    )?;
    files.extend(capture_rms(
        solution,
        sides,
        &dir.join(format!("{prefix}_captures")),
        options,
    )?);
    Ok(files)
}

struct Estimates<'a> {
    runs: &'a [&'a Solution],
    params: Vec<Param>,
}

const PANEL_COLUMNS: usize = 3;

impl Figure for Estimates<'_> {
    fn size(&self) -> (u32, u32) {
        let rows = self.params.len().div_ceil(PANEL_COLUMNS) as u32;
        (1500, 60 + 250 * rows)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult {
        root.fill(&WHITE).map_err(err)?;
        let (title, body) = root.split_vertically(60);
        title
            .draw_text(
                &format!(
                    "Estimates of {} runs with ±1σ error bars; dashed: mean across runs",
                    self.runs.len()
                ),
                &(FONT, 26).into_font().style(FontStyle::Bold).color(&BLACK),
                (20, 16),
            )
            .map_err(err)?;
        let rows = self.params.len().div_ceil(PANEL_COLUMNS);
        let panels = body.split_evenly((rows, PANEL_COLUMNS));
        let n = self.runs.len();
        for (panel, &p) in panels.iter().zip(&self.params) {
            let pts: Vec<(f64, f64, f64)> = self
                .runs
                .iter()
                .enumerate()
                .filter(|(_, s)| !s.fixed.is_fixed(p))
                .map(|(i, s)| ((i + 1) as f64, s.report_value(p), s.report_std(p)))
                .filter(|&(_, v, s)| plottable(v) && plottable(s))
                .collect();
            let lo = pts
                .iter()
                .map(|&(_, v, s)| v - s)
                .fold(f64::INFINITY, f64::min);
            let hi = pts
                .iter()
                .map(|&(_, v, s)| v + s)
                .fold(f64::NEG_INFINITY, f64::max);
            let (y0, y1) = padded(lo, hi);
            let mut chart = ChartBuilder::on(panel)
                .caption(format!("{} [{}]", p.name(), p.unit().name()), (FONT, 20))
                .margin(10)
                .x_label_area_size(30)
                .y_label_area_size(70)
                .build_cartesian_2d(0.5..(n as f64 + 0.5), y0..y1)
                .map_err(err)?;
            chart
                .configure_mesh()
                .x_labels(n.min(12))
                .x_label_formatter(&|x| format!("{x:.0}"))
                .y_labels(5)
                .label_style((FONT, 14))
                .light_line_style(RGBColor(238, 238, 238))
                .draw()
                .map_err(err)?;
            if pts.is_empty() {
                continue;
            }
            let mean = pts.iter().map(|p| p.1).sum::<f64>() / pts.len() as f64;
            chart
                .draw_series(DashedLineSeries::new(
                    [(0.5, mean), (n as f64 + 0.5, mean)],
                    6,
                    4,
                    GREY.stroke_width(1),
                ))
                .map_err(err)?;
            chart
                .draw_series(pts.iter().map(|&(x, v, s)| {
                    ErrorBar::new_vertical(x, v - s, v, v + s, LEFT.stroke_width(2), 10)
                }))
                .map_err(err)?;
            chart
                .draw_series(
                    pts.iter()
                        .map(|&(x, v, _)| Circle::new((x, v), 4, LEFT.filled())),
                )
                .map_err(err)?;
        }
        Ok(())
    }
}

/// The per-parameter estimates plot of [`parameter_estimates`] as SVG text.
pub fn parameter_estimates_svg(runs: &[&Solution]) -> Result<String, PlotError> {
    if runs.is_empty() {
        return Err(PlotError::Empty("no runs"));
    }
    svg_text(&Estimates {
        runs,
        params: estimated_params(runs),
    })
    .map_err(|message| PlotError::Draw {
        path: PathBuf::from("parameters.svg"),
        message,
    })
}

/// The paper's 21, the upper camera's when some run has upper-camera captures, and any
/// further parameter some run estimated.
fn estimated_params(runs: &[&Solution]) -> Vec<Param> {
    Param::ALL
        .iter()
        .copied()
        .filter(|p| runs.iter().any(|s| s.fixed.is_shown(*p)))
        .collect()
}

/// Writes the per-parameter estimates of several runs with ±1σ error bars and the mean
/// across runs (one panel per parameter: the paper's 21 and any further one estimated) to
/// `<stem>.png` and `<stem>.svg`.
pub fn parameter_estimates(
    runs: &[&Solution],
    stem: &Path,
    options: &WriteOptions,
) -> Result<Vec<PathBuf>, PlotError> {
    if runs.is_empty() {
        return Err(PlotError::Empty("no runs"));
    }
    let params = estimated_params(runs);
    save(&Estimates { runs, params }, stem, options)
}
