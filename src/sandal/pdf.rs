//! The drawing as a PDF at 1:1 on a paper size: one page when the whole drawing fits in
//! the printable area, else tiled onto sheets that overlap, with the seams placed clear of
//! the pattern and the pins and marked for cutting and aligning.
//!
//! Every page draws the whole drawing through one transform (page millimetres to points,
//! 72/25.4) clipped to its sheet's window, each group in a marked-content sequence tagged
//! with its name ([`Role::name`]).

use pdf_writer::{Content, Finish, Name, Pdf, Rect, Ref, Str};

use super::drawing::{BBox, Drawing, Role, Shape};

/// A paper size.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Paper {
    /// In file names: `a4`, `letter`.
    pub name: &'static str,
    /// For people: `A4`, `US Letter`.
    pub label: &'static str,
    /// Width and height (mm), portrait.
    pub size_mm: [f64; 2],
}

/// The paper sizes a PDF is written for (adding one here adds its files).
pub const PAPERS: [Paper; 2] = [
    Paper {
        name: "a4",
        label: "A4",
        size_mm: [210.0, 297.0],
    },
    Paper {
        name: "letter",
        label: "US Letter",
        size_mm: [215.9, 279.4],
    },
];

/// Points per millimetre.
pub const PT_PER_MM: f64 = 72.0 / 25.4;
/// The unprinted margin on every side of a sheet (mm): most printers print within it.
pub const PAGE_MARGIN: f64 = 10.0;
/// How far neighbouring sheets overlap (mm).
pub const OVERLAP: f64 = 10.0;
/// How far a seam stays from the pattern's border and the pins (mm).
const SEAM_CLEARANCE: f64 = 1.0;

/// One sheet of a tiled drawing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sheet {
    /// The part of the drawing on this sheet (drawing mm).
    pub window: BBox,
    /// Where the window's top-left corner is on the page (mm).
    pub offset: [f64; 2],
    /// Whether this sheet is cut at its right edge (a seam to the next column).
    pub cut_right: bool,
    /// Whether this sheet is cut at its bottom edge (a seam to the next row).
    pub cut_below: bool,
}

/// The windows along one axis: `[start, end]` pieces covering `0 … length`, each at most
/// `room` long, consecutive ones overlapping by [`OVERLAP`], every seam (a piece's end)
/// outside the `keep` intervals where that is possible, else outside the `fallback` ones. A
/// `length` that fits gives one piece of the full `room`, centred on the content.
fn pieces(length: f64, room: f64, keep: &[(f64, f64)], fallback: &[(f64, f64)]) -> Vec<(f64, f64)> {
    if length <= room {
        let pad = (room - length) / 2.0;
        return vec![(-pad, length + pad)];
    }
    let mut out = Vec::new();
    let mut start = 0.0;
    loop {
        if length - start <= room {
            out.push((start, start + room));
            return out;
        }
        let limit = start + room;
        let seam = |keep: &[(f64, f64)]| {
            let mut cut = limit;
            while let Some(&(a, _)) = keep.iter().find(|(a, b)| cut > *a && cut < *b) {
                cut = a;
            }
            (cut > start + 2.0 * OVERLAP).then_some(cut)
        };
        // Nothing may be kept whole within reach: cut at the limit.
        let cut = seam(keep).or_else(|| seam(fallback)).unwrap_or(limit);
        out.push((start, cut));
        start = cut - OVERLAP;
    }
}

/// The sheets of `drawing` on `paper`, row by row from the top.
pub fn sheets(drawing: &Drawing, paper: &Paper) -> Vec<Sheet> {
    let room = paper.size_mm.map(|s| s - 2.0 * PAGE_MARGIN);
    let keep = |axis: usize| {
        drawing
            .keep_whole
            .iter()
            .map(|b| (b[axis] - SEAM_CLEARANCE, b[axis + 2] + SEAM_CLEARANCE))
            .collect::<Vec<_>>()
    };
    let squares = |axis: usize| [(drawing.keep_squares[axis], drawing.keep_squares[axis + 2])];
    let cols = pieces(drawing.size[0], room[0], &keep(0), &squares(0));
    let rows = pieces(drawing.size[1], room[1], &keep(1), &squares(1));
    let mut out = Vec::new();
    for (j, &(v0, v1)) in rows.iter().enumerate() {
        for (i, &(u0, u1)) in cols.iter().enumerate() {
            out.push(Sheet {
                window: [u0, v0, u1, v1],
                offset: [PAGE_MARGIN, PAGE_MARGIN],
                cut_right: i + 1 < cols.len(),
                cut_below: j + 1 < rows.len(),
            });
        }
    }
    out
}

/// The tick marks across every seam (drawing mm): short lines perpendicular to the seam
/// at both ends of it, reaching [`OVERLAP`] to either side, so that on the sheet laid on
/// top they end at its cut edge and continue on the sheet below.
fn seam_ticks(sheets: &[Sheet]) -> Vec<Shape> {
    let mut out = Vec::new();
    let line = |a: [f64; 2], b: [f64; 2]| Shape::Stroke {
        points: vec![a, b],
        closed: false,
        width: 0.2,
        dashed: false,
    };
    for s in sheets {
        let [u0, v0, u1, v1] = s.window;
        if s.cut_below {
            for u in [u0 + 3.0, u1 - 3.0] {
                out.push(line([u, v1 - OVERLAP], [u, v1 + OVERLAP]));
            }
        }
        if s.cut_right {
            for v in [v0 + 3.0, v1 - 3.0] {
                out.push(line([u1 - OVERLAP, v], [u1 + OVERLAP, v]));
            }
        }
    }
    out
}

/// The PDF of `drawing` on `paper`; `title` names the foot. Returns the document and its
/// number of sheets.
pub fn pdf(drawing: &Drawing, paper: &Paper, title: &str) -> (Vec<u8>, usize) {
    let sheets = sheets(drawing, paper);
    let ticks = seam_ticks(&sheets);
    let mut pdf = Pdf::new();
    let catalog = Ref::new(1);
    let tree = Ref::new(2);
    let font = Ref::new(3);
    let font_name = Name(b"F1");
    let page_ids: Vec<Ref> = (0..sheets.len())
        .map(|i| Ref::new(4 + 2 * i as i32))
        .collect();
    pdf.catalog(catalog).pages(tree);
    pdf.pages(tree)
        .kids(page_ids.iter().copied())
        .count(sheets.len() as i32);
    pdf.type1_font(font)
        .base_font(Name(b"Helvetica"))
        .encoding_predefined(Name(b"WinAnsiEncoding"));
    let [pw, ph] = paper.size_mm.map(|s| s * PT_PER_MM);
    for (n, (sheet, id)) in sheets.iter().zip(&page_ids).enumerate() {
        let content_id = Ref::new(id.get() + 1);
        let mut page = pdf.page(*id);
        page.media_box(Rect::new(0.0, 0.0, pw as f32, ph as f32));
        page.parent(tree);
        page.contents(content_id);
        page.resources().fonts().pair(font_name, font);
        page.finish();

        let mut c = Content::new();
        let k = PT_PER_MM;
        let [u0, v0, u1, v1] = sheet.window;
        // Drawing mm → points: x = k·(u − u0 + offset_u), y = height − k·(v − v0 + offset_v).
        c.save_state();
        c.transform([
            k as f32,
            0.0,
            0.0,
            -k as f32,
            (k * (sheet.offset[0] - u0)) as f32,
            (ph - k * (sheet.offset[1] - v0)) as f32,
        ]);
        c.rect(u0 as f32, v0 as f32, (u1 - u0) as f32, (v1 - v0) as f32);
        c.clip_nonzero();
        c.end_path();
        for (role, shapes) in &drawing.groups {
            draw_group(&mut c, *role, shapes, font_name);
        }
        if !ticks.is_empty() {
            draw_group(&mut c, Role::Tiling, &ticks, font_name);
        }
        c.restore_state();

        // The sheet's own marks, in page millimetres (top-left origin), not clipped.
        c.save_state();
        c.transform([k as f32, 0.0, 0.0, -k as f32, 0.0, ph as f32]);
        let mut marks = Vec::new();
        let header = if sheets.len() == 1 {
            format!(
                "{title} · {} · print at 100 % (actual size), not \"fit to page\"",
                paper.label
            )
        } else {
            format!(
                "{title} · {} · sheet {} of {} · print at 100 % (actual size), not \"fit to page\"",
                paper.label,
                n + 1,
                sheets.len()
            )
        };
        marks.push(Shape::Text {
            at: [PAGE_MARGIN, PAGE_MARGIN - 4.0],
            size: 2.8,
            text: header,
        });
        let (ox, oy) = (sheet.offset[0], sheet.offset[1]);
        if sheet.cut_below {
            let y = oy + (v1 - v0);
            marks.push(Shape::Stroke {
                points: vec![[ox, y], [ox + (u1 - u0), y]],
                closed: false,
                width: 0.2,
                dashed: true,
            });
            marks.push(Shape::Text {
                at: [PAGE_MARGIN, y + 5.0],
                size: 2.8,
                text: format!(
                    "Cut along the dashed line and lay this sheet onto sheet {} so that the \
                     ticks and lines run on.",
                    n + 1 + cols_of(&sheets)
                ),
            });
        }
        if sheet.cut_right {
            let x = ox + (u1 - u0);
            marks.push(Shape::Stroke {
                points: vec![[x, oy], [x, oy + (v1 - v0)]],
                closed: false,
                width: 0.2,
                dashed: true,
            });
        }
        if sheet.cut_right || (sheets.len() > 1 && !sheet.cut_below) {
            marks.push(Shape::Text {
                at: [PAGE_MARGIN, paper.size_mm[1] - PAGE_MARGIN + 5.0],
                size: 2.8,
                text: "Sheets join at dashed lines: cut there and lay that sheet on its \
                       neighbour, ticks running on."
                    .into(),
            });
        }
        draw_group(&mut c, Role::Tiling, &marks, font_name);
        c.restore_state();
        pdf.stream(content_id, &c.finish());
    }
    (pdf.finish(), sheets.len())
}

/// Sheets per row.
fn cols_of(sheets: &[Sheet]) -> usize {
    sheets.iter().take_while(|s| s.cut_right).count() + 1
}

/// Draws one group (black on white) in a marked-content sequence tagged with its name.
fn draw_group(c: &mut Content, role: Role, shapes: &[Shape], font: Name) {
    let tag = role.name();
    c.begin_marked_content(Name(tag.as_bytes()));
    c.set_fill_gray(0.0);
    c.set_stroke_gray(0.0);
    for shape in shapes {
        match shape {
            Shape::Fill(points) => {
                path(c, points, true);
                c.fill_nonzero();
            }
            Shape::Stroke {
                points,
                closed,
                width,
                dashed,
            } => {
                c.set_line_width(*width as f32);
                if *dashed {
                    c.set_dash_pattern([3.0, 2.0], 0.0);
                } else {
                    c.set_dash_pattern([], 0.0);
                }
                path(c, points, *closed);
                c.stroke();
            }
            Shape::Circle {
                centre,
                radius,
                width,
            } => {
                c.set_line_width(*width as f32);
                c.set_dash_pattern([], 0.0);
                circle(c, *centre, *radius);
                c.stroke();
            }
            Shape::Text { at, size, text } => {
                c.begin_text();
                c.set_font(font, 1.0);
                // Upright glyphs in the flipped (y down) user space.
                c.set_text_matrix([
                    *size as f32,
                    0.0,
                    0.0,
                    -*size as f32,
                    at[0] as f32,
                    at[1] as f32,
                ]);
                c.show(Str(&win_ansi(text)));
                c.end_text();
            }
        }
    }
    c.end_marked_content();
}

fn path(c: &mut Content, points: &[[f64; 2]], closed: bool) {
    for (i, p) in points.iter().enumerate() {
        if i == 0 {
            c.move_to(p[0] as f32, p[1] as f32);
        } else {
            c.line_to(p[0] as f32, p[1] as f32);
        }
    }
    if closed {
        c.close_path();
    }
}

/// A circle as four cubic Bézier arcs (radial error 0.03 %), starting at its rightmost point.
fn circle(c: &mut Content, centre: [f64; 2], r: f64) {
    const KAPPA: f64 = 0.552_284_749_8;
    let [x, y] = centre;
    let k = KAPPA * r;
    let f = |v: f64| v as f32;
    c.move_to(f(x + r), f(y));
    c.cubic_to(f(x + r), f(y + k), f(x + k), f(y + r), f(x), f(y + r));
    c.cubic_to(f(x - k), f(y + r), f(x - r), f(y + k), f(x - r), f(y));
    c.cubic_to(f(x - r), f(y - k), f(x - k), f(y - r), f(x), f(y - r));
    c.cubic_to(f(x + k), f(y - r), f(x + r), f(y - k), f(x + r), f(y));
    c.close_path();
}

/// `text` in the WinAnsi encoding of the standard Helvetica font (characters it lacks
/// become `?`).
fn win_ansi(text: &str) -> Vec<u8> {
    text.chars()
        .map(|ch| match ch {
            ' '..='~' => ch as u8,
            '·' => 0xB7,
            '×' => 0xD7,
            '°' => 0xB0,
            '±' => 0xB1,
            'Ø' => 0xD8,
            '–' => 0x96,
            '−' => b'-',
            _ => b'?',
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seams_avoid_what_is_kept_whole() {
        // 330 mm on 277 mm sheets, the pattern at 0 … 220: the seam moves before it.
        let p = pieces(330.0, 277.0, &[(0.0, 220.0), (230.0, 240.0)], &[]);
        assert_eq!(p.len(), 2);
        // The seam goes as far as the sheet reaches when that is free (277 is).
        assert_eq!(p[0], (0.0, 277.0));
        let p = pieces(330.0, 277.0, &[(100.0, 300.0)], &[]);
        assert_eq!(p[0], (0.0, 100.0));
        assert_eq!(p[1], (90.0, 367.0));
        // A keep-out longer than a sheet is cut at the limit.
        let p = pieces(700.0, 277.0, &[(0.0, 600.0)], &[]);
        assert_eq!(p[0], (0.0, 277.0));
        // … unless the fallback can be kept off the seam.
        let p = pieces(700.0, 277.0, &[(0.0, 600.0)], &[(100.0, 290.0)]);
        assert_eq!(p[0], (0.0, 100.0));
    }

    #[test]
    fn winansi_has_the_signs_used() {
        assert_eq!(win_ansi("A·×°−"), vec![b'A', 0xB7, 0xD7, 0xB0, b'-']);
    }
}
