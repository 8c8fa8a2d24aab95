//! The 1:1 drawing of one sandal, once, in the sole frame; the SVG and the PDF both draw
//! this list of shapes (`svg.rs`, `pdf.rs`), so what they show cannot differ.
//!
//! On paper the sole frame is seen from the printed side with the toes up the page: page
//! `u` (mm, to the right) is `−y`, page `v` (mm, down) is `−x`, each plus an offset.

use super::geometry::Sandal;

/// What a shape is: it names the shape's group (SVG `id`, PDF marked-content tag), so that
/// a reader finds the pattern, the pins, the ankle mark and the scale bars.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    /// The black squares of the pattern.
    Squares,
    /// The white border's outline (where the print's quiet zone ends).
    Border,
    /// The plate's outline (cut along it).
    Plate,
    /// The strap slots (cut out).
    Slots,
    /// The sole's outline.
    Sole,
    /// The ankle's projection: a cross whose two lines meet at the origin of `S`.
    Ankle,
    /// A pin at an FSR: a circle of the pin's diameter and a cross at its centre.
    Pin(&'static str),
    /// The 100 mm scale bars.
    ScaleBar,
    /// Text.
    Labels,
    /// Tiling marks (PDF sheets only).
    Tiling,
}

impl Role {
    /// The group's name: `squares`, `pin-fl`, `scale-bar`, …
    pub fn name(self) -> String {
        match self {
            Role::Squares => "squares".into(),
            Role::Border => "border".into(),
            Role::Plate => "plate".into(),
            Role::Slots => "slots".into(),
            Role::Sole => "sole".into(),
            Role::Ankle => "ankle".into(),
            Role::Pin(name) => format!("pin-{name}"),
            Role::ScaleBar => "scale-bar".into(),
            Role::Labels => "labels".into(),
            Role::Tiling => "tiling".into(),
        }
    }
}

/// One shape, in page millimetres (`u` right, `v` down).
#[derive(Debug, Clone, PartialEq)]
pub enum Shape {
    /// A black filled polygon.
    Fill(Vec<[f64; 2]>),
    /// A stroked polyline (closed or not) of `width` mm, dashed or solid.
    Stroke {
        /// The points.
        points: Vec<[f64; 2]>,
        /// Whether the last point joins the first.
        closed: bool,
        /// Line width (mm).
        width: f64,
        /// Dashed (3 mm on, 2 mm off).
        dashed: bool,
    },
    /// A stroked circle.
    Circle {
        /// Centre.
        centre: [f64; 2],
        /// Radius (mm).
        radius: f64,
        /// Line width (mm).
        width: f64,
    },
    /// One line of text starting at `at` (its baseline's left end).
    Text {
        /// Baseline start.
        at: [f64; 2],
        /// Font size (mm, the em).
        size: f64,
        /// The text.
        text: String,
    },
}

impl Shape {
    /// The points that bound the shape (text approximately, by a mean glyph width).
    fn extent(&self) -> Vec<[f64; 2]> {
        match self {
            Shape::Fill(points) | Shape::Stroke { points, .. } => points.clone(),
            Shape::Circle { centre, radius, .. } => vec![
                [centre[0] - radius, centre[1] - radius],
                [centre[0] + radius, centre[1] + radius],
            ],
            Shape::Text { at, size, text } => vec![
                [at[0], at[1] - size],
                [
                    at[0] + 0.56 * size * text.chars().count() as f64,
                    at[1] + 0.25 * size,
                ],
            ],
        }
    }
}

/// A bounding box in page millimetres: `[u_min, v_min, u_max, v_max]`.
pub type BBox = [f64; 4];

fn bbox(points: impl IntoIterator<Item = [f64; 2]>) -> BBox {
    points.into_iter().fold(
        [f64::MAX, f64::MAX, f64::MIN, f64::MIN],
        |[a, b, c, d], [u, v]| [a.min(u), b.min(v), c.max(u), d.max(v)],
    )
}

/// The drawing of one sandal: its shapes by group, in page millimetres with the content's
/// top-left corner at `(0, 0)`.
#[derive(Debug, Clone, PartialEq)]
pub struct Drawing {
    /// The groups in drawing order, each with its shapes.
    pub groups: Vec<(Role, Vec<Shape>)>,
    /// Width and height of the content (mm).
    pub size: [f64; 2],
    /// Where the sole frame's origin (the ankle's projection) is on the page (mm).
    pub origin: [f64; 2],
    /// Bounding boxes (page mm) that a seam between sheets must not cut: the pattern with
    /// its border, each pin, each strap slot, the ankle mark, each scale bar and the
    /// instructions.
    pub keep_whole: Vec<BBox>,
    /// The squares' bounding box grown by 5 mm (page mm): kept off a seam where
    /// [`Drawing::keep_whole`] cannot be.
    pub keep_squares: BBox,
}

/// `x` with at most three decimals, without trailing zeros.
pub fn num(x: f64) -> String {
    let r = (x * 1000.0).round() / 1000.0;
    if r == 0.0 { "0".into() } else { format!("{r}") }
}

/// Line widths (mm).
const THIN: f64 = 0.2;
const LINE: f64 = 0.3;
/// Length of the scale bars (mm).
pub const SCALE_BAR_MM: f64 = 100.0;

impl Drawing {
    /// The drawing of `sandal`.
    pub fn of(sandal: &Sandal) -> Drawing {
        // Page coordinates before the offset: u = −y, v = −x.
        let page = |p: [f64; 2]| [-p[1], -p[0]];
        let pages = |ps: &[[f64; 2]]| ps.iter().map(|p| page(*p)).collect::<Vec<_>>();
        let mut groups: Vec<(Role, Vec<Shape>)> = vec![
            (
                Role::Plate,
                vec![Shape::Stroke {
                    points: pages(&sandal.plate_outline()),
                    closed: true,
                    width: LINE,
                    dashed: false,
                }],
            ),
            (
                Role::Slots,
                sandal
                    .slots()
                    .iter()
                    .map(|slot| Shape::Stroke {
                        points: pages(&sandal.slot_outline(slot)),
                        closed: true,
                        width: LINE,
                        dashed: false,
                    })
                    .collect(),
            ),
            (
                Role::Border,
                vec![Shape::Stroke {
                    points: pages(&sandal.border_outline()),
                    closed: true,
                    width: THIN,
                    dashed: true,
                }],
            ),
            (
                Role::Squares,
                sandal
                    .black_squares()
                    .iter()
                    .map(|q| Shape::Fill(pages(q)))
                    .collect(),
            ),
            (
                Role::Sole,
                vec![Shape::Stroke {
                    points: pages(&sandal.sole_outline()),
                    closed: true,
                    width: THIN,
                    dashed: true,
                }],
            ),
        ];
        let cross = |c: [f64; 2], arm: f64| {
            vec![
                Shape::Stroke {
                    points: vec![page([c[0] - arm, c[1]]), page([c[0] + arm, c[1]])],
                    closed: false,
                    width: THIN,
                    dashed: false,
                },
                Shape::Stroke {
                    points: vec![page([c[0], c[1] - arm]), page([c[0], c[1] + arm])],
                    closed: false,
                    width: THIN,
                    dashed: false,
                },
            ]
        };
        let mut ankle = cross([0.0, 0.0], 8.0);
        ankle.push(Shape::Circle {
            centre: page([0.0, 0.0]),
            radius: 2.5,
            width: THIN,
        });
        groups.push((Role::Ankle, ankle));
        let r = sandal.plate.pin_diameter / 2.0;
        for pin in sandal.pins() {
            let mut shapes = vec![Shape::Circle {
                centre: page(pin.at),
                radius: r,
                width: LINE,
            }];
            shapes.extend(cross(pin.at, r + 2.0));
            groups.push((Role::Pin(pin.name), shapes));
        }
        // Scale bars, 100 mm along both page axes, just outside the plate beside the
        // pattern: on the pattern's sheet, and cut away with the sheet's margin.
        let bar = |a: [f64; 2], b: [f64; 2]| {
            let (pa, pb) = (page(a), page(b));
            let along_u = (pa[1] - pb[1]).abs() < 1e-9;
            let tick = |p: [f64; 2]| {
                let d = if along_u { [0.0, 2.0] } else { [2.0, 0.0] };
                Shape::Stroke {
                    points: vec![[p[0] - d[0], p[1] - d[1]], [p[0] + d[0], p[1] + d[1]]],
                    closed: false,
                    width: THIN,
                    dashed: false,
                }
            };
            vec![
                Shape::Stroke {
                    points: vec![pa, pb],
                    closed: false,
                    width: THIN,
                    dashed: false,
                },
                tick(pa),
                tick(pb),
            ]
        };
        let outline = sandal.plate_outline();
        let x_far = outline.iter().map(|p| p[0]).fold(f64::MIN, f64::max);
        let y_right = outline.iter().map(|p| p[1]).fold(f64::MAX, f64::min);
        let [cx, cy] = [sandal.board.mount_origin[0], sandal.board.mount_origin[1]];
        let half = SCALE_BAR_MM / 2.0;
        let across_x = x_far + 8.0;
        let along_y = y_right - 8.0;
        let across = bar([across_x, cy + half], [across_x, cy - half]);
        let along = bar([cx - half, along_y], [cx + half, along_y]);
        // Kept whole on one sheet: each bar, the ankle mark, each pin.
        let mut keep: Vec<Vec<[f64; 2]>> = Vec::new();
        for shapes in [&across, &along] {
            keep.push(shapes.iter().flat_map(Shape::extent).collect());
        }
        keep.push(vec![page([-8.0, -8.0]), page([8.0, 8.0])]);
        for pin in sandal.pins() {
            let g = r + 3.0;
            keep.push(vec![
                page([pin.at[0] - g, pin.at[1] - g]),
                page([pin.at[0] + g, pin.at[1] + g]),
            ]);
        }
        keep.push(pages(&sandal.border_outline()));
        for slot in sandal.slots() {
            keep.push(pages(&sandal.slot_outline(&slot)));
        }
        groups.push((Role::ScaleBar, [across, along].concat()));

        let side = sandal.side.name().to_uppercase();
        let b = &sandal.board;
        let text = |at: [f64; 2], size: f64, text: String| Shape::Text {
            at: page(at),
            size,
            text,
        };
        // Text runs to the right on the page (toward −y) from y = 42 mm, on both feet;
        // lines go down the page (toward −x), between the ankle and the front pins.
        let start = 42.0;
        let mut labels = vec![
            text(
                [56.0, start],
                4.0,
                format!("{side} · this side toward the camera"),
            ),
            text(
                [50.0, start],
                2.8,
                format!(
                    "naocalib sandal · {} × {} squares of {} mm",
                    b.squares_x,
                    b.squares_y,
                    num(b.square)
                ),
            ),
            text(
                [46.0, start],
                2.8,
                format!(
                    "pattern centre ({}, {}) mm, yaw {}°",
                    num(b.mount_origin[0]),
                    num(b.mount_origin[1]),
                    num(b.mount_rpy[2].to_degrees())
                ),
            ),
            text(
                [41.0, start],
                2.8,
                "Print at 100 % (actual size): both bars".into(),
            ),
            text(
                [37.0, start],
                2.8,
                "must measure 100.0 mm before you glue".into(),
            ),
            text([33.0, start], 2.8, "the sheet flat on the plate.".into()),
        ];
        // The instructions stay together on one sheet.
        keep.push(labels.iter().flat_map(Shape::extent).collect());
        labels.extend([
            text([3.0, -5.0], 2.8, "ankle".into()),
            text([across_x + 3.0, cy + 8.0], 2.8, "100 mm".into()),
            text([cx - half - 6.0, along_y + 6.0], 2.8, "100 mm".into()),
        ]);
        for pin in sandal.pins() {
            labels.push(text(
                [pin.at[0] + r + 3.0, pin.at[1] + 2.0],
                2.8,
                format!("pin {}", pin.name),
            ));
        }
        groups.push((Role::Labels, labels));

        // Shift everything so that the content starts at (0, 0).
        let all = bbox(
            groups
                .iter()
                .flat_map(|(_, shapes)| shapes.iter().flat_map(Shape::extent)),
        );
        let shift = |p: [f64; 2]| [p[0] - all[0], p[1] - all[1]];
        for (_, shapes) in &mut groups {
            for shape in shapes {
                match shape {
                    Shape::Fill(points) | Shape::Stroke { points, .. } => {
                        for p in points {
                            *p = shift(*p);
                        }
                    }
                    Shape::Circle { centre, .. } => *centre = shift(*centre),
                    Shape::Text { at, .. } => *at = shift(*at),
                }
            }
        }
        let keep_whole = keep
            .into_iter()
            .map(|ps| bbox(ps.into_iter().map(shift)))
            .collect();
        let mut keep_squares = bbox(pages(&sandal.pattern_outline()).into_iter().map(shift));
        for (k, grow) in [(0, -5.0), (1, -5.0), (2, 5.0), (3, 5.0)] {
            keep_squares[k] += grow;
        }
        Drawing {
            keep_squares,
            groups,
            size: [all[2] - all[0], all[3] - all[1]],
            origin: shift(page([0.0, 0.0])),
            keep_whole,
        }
    }

    /// The page position (mm) of a sole-frame point.
    pub fn to_page(&self, p: [f64; 2]) -> [f64; 2] {
        [self.origin[0] - p[1], self.origin[1] - p[0]]
    }
}
