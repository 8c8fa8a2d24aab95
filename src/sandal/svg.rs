//! The drawing as plain SVG at 1:1: one user unit is one millimetre, presentation
//! attributes only (no CSS, no `<pattern>`), each group an `id` ([`Role::name`]).

use std::fmt::Write as _;

use super::drawing::{Drawing, Role, Shape};

/// Margin around the content (mm).
const MARGIN: f64 = 5.0;

/// The SVG document of `drawing`, with `title` (the foot and what it is).
pub fn svg(drawing: &Drawing, title: &str) -> String {
    let [w, h] = drawing.size.map(|s| s + 2.0 * MARGIN);
    let mut out = String::new();
    let _ = writeln!(out, r#"<?xml version="1.0" encoding="UTF-8"?>"#);
    let _ = writeln!(
        out,
        r#"<svg xmlns="http://www.w3.org/2000/svg" version="1.1" width="{}mm" height="{}mm" viewBox="0 0 {} {}">"#,
        f(w),
        f(h),
        f(w),
        f(h)
    );
    let _ = writeln!(out, "<title>{}</title>", escape(title));
    let [ou, ov] = [drawing.origin[0] + MARGIN, drawing.origin[1] + MARGIN];
    let _ = writeln!(
        out,
        "<desc>1 unit = 1 mm. Sole frame: origin (the ankle's projection) at ({}, {}), x \
         toward the toes = up the page, y to the robot's left = to the left.</desc>",
        f(ou),
        f(ov)
    );
    let at = |p: [f64; 2]| [p[0] + MARGIN, p[1] + MARGIN];
    let points = |ps: &[[f64; 2]]| {
        ps.iter()
            .map(|p| {
                let [u, v] = at(*p);
                format!("{},{}", f(u), f(v))
            })
            .collect::<Vec<_>>()
            .join(" ")
    };
    for (role, shapes) in &drawing.groups {
        if *role == Role::Labels {
            let _ = writeln!(
                out,
                r##"<g id="{}" font-family="Helvetica, Arial, sans-serif" fill="#000000" stroke="none">"##,
                role.name()
            );
        } else {
            let _ = writeln!(
                out,
                r##"<g id="{}" fill="none" stroke="#000000" stroke-linecap="butt">"##,
                role.name()
            );
        }
        for shape in shapes {
            match shape {
                Shape::Fill(ps) => {
                    let _ = writeln!(
                        out,
                        r##"<polygon points="{}" fill="#000000" stroke="none"/>"##,
                        points(ps)
                    );
                }
                Shape::Stroke {
                    points: ps,
                    closed,
                    width,
                    dashed,
                } => {
                    let dash = if *dashed {
                        r#" stroke-dasharray="3 2""#
                    } else {
                        ""
                    };
                    let tag = if *closed { "polygon" } else { "polyline" };
                    let _ = writeln!(
                        out,
                        r#"<{tag} points="{}" stroke-width="{}"{dash}/>"#,
                        points(ps),
                        f(*width)
                    );
                }
                Shape::Circle {
                    centre,
                    radius,
                    width,
                } => {
                    let [u, v] = at(*centre);
                    let _ = writeln!(
                        out,
                        r#"<circle cx="{}" cy="{}" r="{}" stroke-width="{}"/>"#,
                        f(u),
                        f(v),
                        f(*radius),
                        f(*width)
                    );
                }
                Shape::Text { at: p, size, text } => {
                    let [u, v] = at(*p);
                    let _ = writeln!(
                        out,
                        r#"<text x="{}" y="{}" font-size="{}">{}</text>"#,
                        f(u),
                        f(v),
                        f(*size),
                        escape(text)
                    );
                }
            }
        }
        let _ = writeln!(out, "</g>");
    }
    let _ = writeln!(out, "</svg>");
    out
}

/// A coordinate with 4 decimals (0.1 µm), trailing zeros dropped.
fn f(x: f64) -> String {
    let s = format!("{x:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".into() } else { s.into() }
}

fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}
