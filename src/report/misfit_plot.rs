//! Pictures of the misfit: every vertex's residual after the solve against what an effect
//! the model lacks would follow — the gravity torque of each leg joint (compliance, play),
//! the position in the image (intrinsics, distortion), the head angles (head offsets) — and
//! per capture. A residual that is noise shows no structure in any of them.
//!
//! Two figures, each as PNG and SVG: `<stem>_torques` (residual against each leg joint's
//! gravity torque, 2 × 3 panels) and `<stem>_image_head` (residual against u, v, HeadYaw,
//! HeadPitch, and the mean residual of each capture).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::prelude::*;

use super::plot::{DrawResult, FONT, Figure, PlotError, err, save};
use crate::dataset::Dataset;
use crate::model::gravity::leg_torques;
use crate::model::{Joint, Vertex};
use crate::output::WriteOptions;
use crate::solve::Solution;

const U_COLOUR: RGBColor = RGBColor(31, 119, 180);
const V_COLOUR: RGBColor = RGBColor(255, 127, 14);

/// One panel: residual u and v (px) against a quantity.
struct Panel {
    title: String,
    x_label: String,
    u: Vec<(f64, f64)>,
    v: Vec<(f64, f64)>,
}

/// Panels in a grid.
struct Grid {
    panels: Vec<Panel>,
    cols: usize,
}

impl Figure for Grid {
    fn size(&self) -> (u32, u32) {
        let rows = self.panels.len().div_ceil(self.cols);
        (420 * self.cols as u32, 320 * rows as u32)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult {
        root.fill(&WHITE).map_err(err)?;
        let rows = self.panels.len().div_ceil(self.cols);
        let areas = root.split_evenly((rows, self.cols));
        for (panel, area) in self.panels.iter().zip(areas.iter()) {
            let finite = |p: &&(f64, f64)| p.0.is_finite() && p.1.is_finite();
            let all: Vec<&(f64, f64)> = panel.u.iter().chain(&panel.v).filter(finite).collect();
            if all.is_empty() {
                continue;
            }
            let (mut x0, mut x1) = all
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
                    (a.min(p.0), b.max(p.0))
                });
            let ymax = all.iter().map(|p| p.1.abs()).fold(0.0, f64::max).max(1e-6) * 1.1;
            if x1 - x0 < 1e-9 {
                x0 -= 1.0;
                x1 += 1.0;
            }
            let pad = 0.05 * (x1 - x0);
            let mut chart = ChartBuilder::on(area)
                .caption(&panel.title, (FONT, 16))
                .margin(8)
                .x_label_area_size(32)
                .y_label_area_size(48)
                .build_cartesian_2d(x0 - pad..x1 + pad, -ymax..ymax)
                .map_err(err)?;
            chart
                .configure_mesh()
                .x_desc(panel.x_label.as_str())
                .y_desc("residual [px]")
                .label_style((FONT, 12))
                .draw()
                .map_err(err)?;
            for (points, colour, name) in [(&panel.u, U_COLOUR, "u"), (&panel.v, V_COLOUR, "v")] {
                chart
                    .draw_series(
                        points
                            .iter()
                            .filter(|p| p.0.is_finite() && p.1.is_finite())
                            .map(|p| Circle::new(*p, 2, colour.mix(0.5).filled())),
                    )
                    .map_err(err)?
                    .label(name)
                    .legend(move |(x, y)| Circle::new((x, y), 3, colour.filled()));
            }
            chart
                .configure_series_labels()
                .label_font((FONT, 12))
                .background_style(WHITE.mix(0.8))
                .draw()
                .map_err(err)?;
        }
        Ok(())
    }
}

/// Writes the misfit figures of `solution` on `dataset` into `dir` as `<stem>_torques` and
/// `<stem>_image_head` (PNG and SVG); returns the files written.
pub fn misfit_plots(
    solution: &Solution,
    dataset: &Dataset,
    dir: &Path,
    stem: &str,
    options: &WriteOptions,
) -> Result<Vec<PathBuf>, PlotError> {
    if solution.residuals.is_empty() {
        return Err(PlotError::Empty("the solution has no residuals"));
    }
    let model = &dataset.model;
    let captures: BTreeMap<u64, &crate::dataset::Capture> =
        dataset.captures.iter().map(|c| (c.id, c)).collect();
    let pixels: BTreeMap<(u64, Vertex), [f64; 2]> = dataset
        .corners
        .iter()
        .map(|c| ((c.capture, c.vertex), c.pixel))
        .collect();
    let torques: BTreeMap<u64, [f64; 6]> = dataset
        .captures
        .iter()
        .map(|c| {
            (
                c.id,
                leg_torques(&model.robot, &model.board, c.side, &c.joints),
            )
        })
        .collect();
    let names = [
        "HipYawPitch",
        "HipRoll",
        "HipPitch",
        "KneePitch",
        "AnklePitch",
        "AnkleRoll",
    ];
    let mut joint_panels: Vec<Panel> = names
        .iter()
        .map(|n| Panel {
            title: format!("{n} (leg in view)"),
            x_label: "gravity torque [N·m]".into(),
            u: Vec::new(),
            v: Vec::new(),
        })
        .collect();
    let panel = |title: &str, x: &str| Panel {
        title: title.into(),
        x_label: x.into(),
        u: Vec::new(),
        v: Vec::new(),
    };
    let mut image = [
        panel("image position u", "u [px]"),
        panel("image position v", "v [px]"),
        panel("HeadYaw", "HeadYaw [deg]"),
        panel("HeadPitch", "HeadPitch [deg]"),
    ];
    let mut per_capture: BTreeMap<u64, (f64, f64, usize)> = BTreeMap::new();
    for r in &solution.residuals {
        let [du, dv] = r.solved;
        if let Some(t) = torques.get(&r.capture) {
            for (k, p) in joint_panels.iter_mut().enumerate() {
                p.u.push((t[k], du));
                p.v.push((t[k], dv));
            }
        }
        if let Some(px) = pixels.get(&(r.capture, r.vertex)) {
            image[0].u.push((px[0], du));
            image[1].v.push((px[1], dv));
        }
        if let Some(c) = captures.get(&r.capture) {
            let yaw = c.joints.get(Joint::HeadYaw).to_degrees();
            let pitch = c.joints.get(Joint::HeadPitch).to_degrees();
            image[2].u.push((yaw, du));
            image[2].v.push((yaw, dv));
            image[3].u.push((pitch, du));
            image[3].v.push((pitch, dv));
        }
        let e = per_capture.entry(r.capture).or_insert((0.0, 0.0, 0));
        e.0 += du;
        e.1 += dv;
        e.2 += 1;
    }
    let mut means = panel("mean residual per capture", "capture");
    for (id, (su, sv, n)) in &per_capture {
        means.u.push((*id as f64, su / *n as f64));
        means.v.push((*id as f64, sv / *n as f64));
    }
    let mut files = save(
        &Grid {
            panels: joint_panels,
            cols: 3,
        },
        &dir.join(format!("{stem}_torques")),
        options,
    )?;
    let mut panels: Vec<Panel> = image.into_iter().collect();
    panels.push(means);
    files.extend(save(
        &Grid { panels, cols: 3 },
        &dir.join(format!("{stem}_image_head")),
        options,
    )?);
    Ok(files)
}
