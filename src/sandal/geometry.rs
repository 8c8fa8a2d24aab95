//! What a sandal is made of, in the sole frame `S` of its foot (docs/MODEL.md §1, §4): the
//! pattern's squares and vertices from the model's [`Board`], the pins at the FSRs, the
//! sole's outline, the plate and its strap slots.
//!
//! Every position is `(x, y)` in mm: origin at the ankle's projection on the sole, `x`
//! toward the toes, `y` to the robot's left, seen from the printed side (`+z_S`, the leg).

use crate::model::{Board, Side, Vertex};

use super::SandalError;

/// The FSRs under the **left** sole, `(name, [x, y])` in mm from the ankle's projection:
/// B-Human `Config/Robots/Default/robotDimensions.cfg` lines 54–59 (BHumanCodeRelease
/// d89d603f, `leftFsrPositions`), which its simulator places at `(x, y, −footHeight)` in the
/// foot frame, i.e. in the sole plane under the ankle (`Src/Libs/SimulatedNao/
/// SimulatedRobot3D.cpp` line 349). The right foot's are these mirrored
/// (`rightFsrPositions`, lines 60–65): see [`fsr_positions`].
pub const LEFT_FSR: [(&str, [f64; 2]); 4] = [
    ("fl", [70.25, 29.9]),
    ("fr", [70.25, -23.1]),
    ("bl", [-30.25, 29.9]),
    ("br", [-29.65, -19.1]),
];

/// The outline of the **left** sole (mm from the ankle's projection): B-Human
/// `Config/Robots/Default/robotDimensions.cfg` lines 13–37 (`soleShape`, BHumanCodeRelease
/// d89d603f); "the right one has mirrored y coordinates"
/// (`Src/Representations/Configuration/RobotDimensions.h` line 45).
pub const LEFT_SOLE: [[f64; 2]; 20] = [
    [8.97, -33.18],
    [57.7, -38.77],
    [73.95, -37.29],
    [87.65, -31.48],
    [96.87, -18.8],
    [99.42, -10.15],
    [98.99, 8.69],
    [94.0, 24.18],
    [84.54, 36.1],
    [65.68, 46.15],
    [49.91, 48.18],
    [9.56, 38.81],
    [-8.42, 39.54],
    [-21.99, 47.58],
    [-31.25, 50.02],
    [-49.05, 37.6],
    [-50.72, -21.38],
    [-42.62, -30.6],
    [-32.97, -34.35],
    [-9.01, -32.72],
];

/// The white border around the pattern, in squares: the quiet zone the vertex finder needs
/// (the width the simulator renders, `sim::render::RenderOptions::plate_margin`).
pub const BORDER_SQUARES: f64 = 0.8;

/// Where the strap slots are centred along the sole (mm ahead of the ankle's projection):
/// across the instep.
pub const SLOT_X: f64 = 20.0;
/// Clearance between the sole's outline and a strap slot (mm).
pub const SLOT_CLEARANCE: f64 = 5.0;

/// The plate's own dimensions: the named parameters of the OpenSCAD source, with their
/// defaults. The pin diameter and height are for the recesses at the FSRs; measure the
/// robot's soles and change them if they differ.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlateParams {
    /// Diameter of a pin (and of its hole in the plate) (mm).
    pub pin_diameter: f64,
    /// Height of a pin above the plate's top face (mm).
    pub pin_height: f64,
    /// Thickness of the plate (mm): it lies under the sole plane.
    pub plate_thickness: f64,
    /// Width of a strap slot, across the foot's axis (mm).
    pub slot_width: f64,
    /// Length of a strap slot, along the foot's axis (mm): the strap's width and some play.
    pub slot_length: f64,
    /// How far the plate reaches beyond a pin or a slot (mm).
    pub edge_margin: f64,
}

impl Default for PlateParams {
    /// Pins Ø 6 × 4 mm, a 3 mm plate, slots 27 × 4 mm for a 25 mm hook-and-loop strap,
    /// 12 mm of plate around pins and slots.
    fn default() -> Self {
        PlateParams {
            pin_diameter: 6.0,
            pin_height: 4.0,
            plate_thickness: 3.0,
            slot_width: 4.0,
            slot_length: 27.0,
            edge_margin: 12.0,
        }
    }
}

/// A pin at an FSR: its name (B-Human's `fl`, `fr`, `bl`, `br`: front/back, left/right in
/// the robot's frame) and position.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pin {
    /// `fl`, `fr`, `bl` or `br`.
    pub name: &'static str,
    /// Position in the sole frame (mm).
    pub at: [f64; 2],
}

/// A strap slot: a rectangle along the foot's axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Slot {
    /// `outer` or `inner` (the side of the foot).
    pub name: &'static str,
    /// Centre in the sole frame (mm).
    pub centre: [f64; 2],
}

/// The FSR positions of `side`'s foot: [`LEFT_FSR`], mirrored (`y → −y`, left ↔ right in
/// the name) for the right foot as B-Human's `rightFsrPositions` are.
pub fn fsr_positions(side: Side) -> [Pin; 4] {
    let mut pins = LEFT_FSR.map(|(name, [x, y])| Pin { name, at: [x, y] });
    if side == Side::Right {
        for pin in &mut pins {
            pin.at[1] = -pin.at[1];
            pin.name = match pin.name {
                "fl" => "fr",
                "fr" => "fl",
                "bl" => "br",
                _ => "bl",
            };
        }
        pins.sort_by_key(|p| LEFT_FSR.iter().position(|(n, _)| *n == p.name));
    }
    pins
}

/// One foot's sandal: the model's board mounted on that foot, and the plate around it.
#[derive(Debug, Clone, PartialEq)]
pub struct Sandal {
    /// The foot.
    pub side: Side,
    /// The board, exactly as the model has it (the same mount for both feet).
    pub board: Board,
    /// The plate's dimensions.
    pub plate: PlateParams,
}

impl Sandal {
    /// The sandal of `side`'s foot for `board`; an error for a board that cannot be made
    /// as a flat plate (mount roll, pitch or height not zero) or is no board at all.
    pub fn new(board: &Board, side: Side, plate: PlateParams) -> Result<Sandal, SandalError> {
        let bad = |field: &str, message: String| {
            Err(SandalError::Board {
                field: field.to_string(),
                message,
            })
        };
        for (field, n) in [
            ("board.squares_x", board.squares_x),
            ("board.squares_y", board.squares_y),
        ] {
            if !(2..=1000).contains(&n) {
                return bad(field, format!("must be 2 … 1000 squares, got {n}"));
            }
        }
        if !(board.square.is_finite() && board.square > 0.0) {
            return bad(
                "board.square_mm",
                format!("must be a positive length, got {}", board.square),
            );
        }
        for (i, x) in board.mount_origin.iter().enumerate() {
            if !x.is_finite() {
                return bad(
                    &format!("board.mount_origin_mm[{i}]"),
                    format!("{x} is not a finite number"),
                );
            }
        }
        if board.mount_origin[2] != 0.0 {
            return bad(
                "board.mount_origin_mm[2]",
                format!(
                    "is {} mm: a sandal plate is flat, with the pattern in the sole plane \
                     (height 0)",
                    board.mount_origin[2]
                ),
            );
        }
        for (i, name) in ["roll", "pitch", "yaw"].iter().enumerate() {
            let angle = board.mount_rpy[i];
            if !angle.is_finite() {
                return bad(
                    &format!("board.mount_rpy_deg[{i}]"),
                    format!("{angle} is not a finite number"),
                );
            }
            if i < 2 && angle != 0.0 {
                return bad(
                    &format!("board.mount_rpy_deg[{i}]"),
                    format!(
                        "the mount {name} is {}°: a sandal plate is flat, with the pattern \
                         in the sole plane (roll and pitch 0; yaw may be any)",
                        angle.to_degrees()
                    ),
                );
            }
        }
        for (field, n) in [
            ("board.squares_x", board.squares_x),
            ("board.squares_y", board.squares_y),
        ] {
            let side = f64::from(n) * board.square;
            if side > MAX_PATTERN_MM {
                // The key to change: the count when as many squares of the paper's size
                // would not fit either, else the square's size.
                let paper = Board::default().square;
                let field = if f64::from(n) * paper > MAX_PATTERN_MM {
                    field
                } else {
                    "board.square_mm"
                };
                return bad(
                    field,
                    format!(
                        "{n} squares of {} mm make a pattern {side} mm long: a sandal's pattern \
                         is at most {MAX_PATTERN_MM} mm on a side (a NAO's foot is 160 mm long)",
                        board.square
                    ),
                );
            }
        }
        let reach = board.mount_origin[0].hypot(board.mount_origin[1]);
        if reach > MAX_MOUNT_MM {
            return bad(
                "board.mount_origin_mm",
                format!(
                    "the pattern's centre is {reach:.0} mm from the ankle: a sandal's plate is \
                     strapped to the foot, its pattern within {MAX_MOUNT_MM} mm of the ankle"
                ),
            );
        }
        let sandal = Sandal {
            side,
            board: *board,
            plate,
        };
        let sole = sandal.sole_outline();
        if sandal
            .pattern_outline()
            .iter()
            .all(|&p| inside_polygon(p, &sole))
        {
            return bad(
                "board.mount_origin_mm",
                format!(
                    "the whole pattern lies under the {} sole (its centre at {} mm): the foot \
                     would hide it from the camera; the pattern goes beside the foot",
                    side.name(),
                    drawing_point(board.mount_origin)
                ),
            );
        }
        Ok(sandal)
    }

    /// A point `(x_B, y_B)` of the board plane in the sole frame (`T_SB`, docs/MODEL.md §4).
    pub fn board_to_sole(&self, p: [f64; 2]) -> [f64; 2] {
        let q = self.board.mount().apply(&[p[0], p[1], 0.0]);
        [q[0], q[1]]
    }

    /// A point of the sole frame in the board plane (the inverse of [`Sandal::board_to_sole`]).
    pub fn sole_to_board(&self, p: [f64; 2]) -> [f64; 2] {
        let m = self.board.mount();
        let d = [
            p[0] - m.translation[0],
            p[1] - m.translation[1],
            -m.translation[2],
        ];
        let r = m.rotation;
        [
            r[0][0] * d[0] + r[1][0] * d[1] + r[2][0] * d[2],
            r[0][1] * d[0] + r[1][1] * d[1] + r[2][1] * d[2],
        ]
    }

    /// Every inner vertex with its position in the sole frame, row by row: the model's
    /// [`Board::vertex_position`] mounted by [`Board::mount`].
    pub fn vertices(&self) -> Vec<(Vertex, [f64; 2])> {
        self.board
            .vertices()
            .map(|v| {
                let p = self.board.vertex_position(v);
                (v, self.board_to_sole([p[0], p[1]]))
            })
            .collect()
    }

    /// Half the pattern's extent along the board's x and y (mm).
    fn half_extent(&self) -> [f64; 2] {
        let b = &self.board;
        [
            b.squares_x as f64 * b.square / 2.0,
            b.squares_y as f64 * b.square / 2.0,
        ]
    }

    /// The black squares, each as its four corners in the sole frame: square `(ix, iy)`
    /// (from the board's `−x, −y` corner) is black when `ix + iy` is even, so the four
    /// corner squares are black and vertex `(row, col)` is where squares `col, col + 1`
    /// and `row, row + 1` meet (as the detector and the simulator have it).
    pub fn black_squares(&self) -> Vec<[[f64; 2]; 4]> {
        let [hx, hy] = self.half_extent();
        let s = self.board.square;
        let mut out = Vec::new();
        for iy in 0..self.board.squares_y {
            for ix in 0..self.board.squares_x {
                if (ix + iy) % 2 != 0 {
                    continue;
                }
                let (x0, y0) = (-hx + ix as f64 * s, -hy + iy as f64 * s);
                out.push(
                    [[x0, y0], [x0 + s, y0], [x0 + s, y0 + s], [x0, y0 + s]]
                        .map(|p| self.board_to_sole(p)),
                );
            }
        }
        out
    }

    /// The pattern's outer corners (the squares' area) in the sole frame.
    pub fn pattern_outline(&self) -> [[f64; 2]; 4] {
        self.rect_outline(0.0)
    }

    /// The white border's outer corners in the sole frame: the pattern grown by
    /// [`BORDER_SQUARES`] on every side.
    pub fn border_outline(&self) -> [[f64; 2]; 4] {
        self.rect_outline(BORDER_SQUARES * self.board.square)
    }

    fn rect_outline(&self, grow: f64) -> [[f64; 2]; 4] {
        let [hx, hy] = self.half_extent();
        let (hx, hy) = (hx + grow, hy + grow);
        [[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy]].map(|p| self.board_to_sole(p))
    }

    /// The pins at this foot's FSRs ([`fsr_positions`]).
    pub fn pins(&self) -> [Pin; 4] {
        fsr_positions(self.side)
    }

    /// The sole's outline ([`LEFT_SOLE`], mirrored for the right foot).
    pub fn sole_outline(&self) -> Vec<[f64; 2]> {
        let s = self.side.sign();
        LEFT_SOLE.iter().map(|&[x, y]| [x, s * y]).collect()
    }

    /// The two strap slots beside the foot at [`SLOT_X`], [`SLOT_CLEARANCE`] clear of the
    /// sole's widest extent.
    pub fn slots(&self) -> [Slot; 2] {
        let half = self.plate.slot_width / 2.0;
        let outer = LEFT_SOLE.iter().map(|p| p[1]).fold(f64::MIN, f64::max);
        let inner = LEFT_SOLE.iter().map(|p| p[1]).fold(f64::MAX, f64::min);
        let s = self.side.sign();
        [
            Slot {
                name: "outer",
                centre: [SLOT_X, s * (outer + SLOT_CLEARANCE + half)],
            },
            Slot {
                name: "inner",
                centre: [SLOT_X, s * (inner - SLOT_CLEARANCE - half)],
            },
        ]
    }

    /// A slot's four corners in the sole frame.
    pub fn slot_outline(&self, slot: &Slot) -> [[f64; 2]; 4] {
        let (hx, hy) = (self.plate.slot_length / 2.0, self.plate.slot_width / 2.0);
        let [cx, cy] = slot.centre;
        [
            [cx - hx, cy - hy],
            [cx + hx, cy - hy],
            [cx + hx, cy + hy],
            [cx - hx, cy + hy],
        ]
    }

    /// The plate's outline (counter-clockwise, seen from the printed side): the convex hull
    /// of the white border and of the pins and slots with [`PlateParams::edge_margin`]
    /// around them.
    pub fn plate_outline(&self) -> Vec<[f64; 2]> {
        let m = self.plate.edge_margin;
        let mut points: Vec<[f64; 2]> = self.border_outline().to_vec();
        let around = |c: [f64; 2], hx: f64, hy: f64| {
            [
                [c[0] - hx, c[1] - hy],
                [c[0] + hx, c[1] - hy],
                [c[0] + hx, c[1] + hy],
                [c[0] - hx, c[1] + hy],
            ]
        };
        for pin in self.pins() {
            let r = self.plate.pin_diameter / 2.0 + m;
            points.extend(around(pin.at, r, r));
        }
        for slot in self.slots() {
            points.extend(around(
                slot.centre,
                self.plate.slot_length / 2.0 + m,
                self.plate.slot_width / 2.0 + m,
            ));
        }
        convex_hull(points)
    }

    /// What a maker should know about this sandal's geometry: parts of the sole or a pin
    /// that lie on the pattern's squares (the foot then hides them from the camera).
    pub fn notes(&self) -> Vec<String> {
        let mut notes = Vec::new();
        let [hx, hy] = self.half_extent();
        let on_pattern = |p: [f64; 2]| {
            let q = self.sole_to_board(p);
            q[0].abs() < hx && q[1].abs() < hy
        };
        let sole = self.sole_outline();
        let covered: Vec<[f64; 2]> = sole.iter().copied().filter(|p| on_pattern(*p)).collect();
        if !covered.is_empty() {
            let reach = covered.iter().map(|p| p[0]).fold(f64::MIN, f64::max);
            notes.push(format!(
                "the {} sole reaches onto the pattern's squares (its outline to x = {reach:.1} \
                 mm; the squares begin at x = {:.1} mm): the toes stand on the print and hide \
                 part of the outer squares; a board turned by 90° and centred 200 mm ahead of \
                 the ankle clears them (docs/SANDALS.md)",
                self.side.name(),
                self.pattern_outline()
                    .iter()
                    .map(|p| p[0])
                    .fold(f64::MAX, f64::min)
            ));
        }
        for pin in self.pins() {
            if on_pattern(pin.at) {
                notes.push(format!(
                    "the {} pin {} at ({:.2}, {:.2}) mm lies on the pattern's squares",
                    self.side.name(),
                    pin.name,
                    pin.at[0],
                    pin.at[1]
                ));
            }
        }
        notes
    }
}

/// The longest side of a pattern a sandal may have (mm): twice an A3 sheet's width; the
/// drawing, its PDFs and their memory stay bounded (a few MB).
pub const MAX_PATTERN_MM: f64 = 600.0;

/// The farthest the pattern's centre may be from the ankle's projection (mm): a sandal is
/// strapped to the foot.
pub const MAX_MOUNT_MM: f64 = 400.0;

/// `(x, y)` of a 3-vector, for messages.
fn drawing_point(p: [f64; 3]) -> String {
    format!("({}, {})", p[0], p[1])
}

/// Whether `p` lies inside the closed polygon `polygon` (even–odd rule).
fn inside_polygon(p: [f64; 2], polygon: &[[f64; 2]]) -> bool {
    let mut inside = false;
    let n = polygon.len();
    for i in 0..n {
        let (a, b) = (polygon[i], polygon[(i + n - 1) % n]);
        if (a[1] > p[1]) != (b[1] > p[1])
            && p[0] < (b[0] - a[0]) * (p[1] - a[1]) / (b[1] - a[1]) + a[0]
        {
            inside = !inside;
        }
    }
    inside
}

/// The convex hull of `points`, counter-clockwise (Andrew's monotone chain).
fn convex_hull(mut points: Vec<[f64; 2]>) -> Vec<[f64; 2]> {
    points.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    points.dedup();
    if points.len() < 3 {
        return points;
    }
    let cross = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| {
        (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    };
    let mut hull: Vec<[f64; 2]> = Vec::with_capacity(2 * points.len());
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &[f64; 2]>> = if pass == 0 {
            Box::new(points.iter())
        } else {
            Box::new(points.iter().rev())
        };
        for &p in iter {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0
            {
                hull.pop();
            }
            hull.push(p);
        }
        hull.pop();
    }
    hull
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn right_pins_are_bhumans_right_fsr_positions() {
        // robotDimensions.cfg lines 60–65, written out here as the file has them.
        let expected = [
            ("fl", [70.25, 23.1]),
            ("fr", [70.25, -29.9]),
            ("bl", [-29.65, 19.1]),
            ("br", [-30.25, -29.9]),
        ];
        let pins = fsr_positions(Side::Right);
        for ((name, at), pin) in expected.iter().zip(pins) {
            assert_eq!((*name, *at), (pin.name, pin.at));
        }
    }

    #[test]
    fn hull_of_a_square_with_an_inner_point() {
        let hull = convex_hull(vec![
            [0.0, 0.0],
            [2.0, 0.0],
            [1.0, 1.0],
            [2.0, 2.0],
            [0.0, 2.0],
        ]);
        assert_eq!(hull, vec![[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]]);
    }

    #[test]
    fn sole_to_board_inverts_the_mount() {
        let board = Board {
            mount_origin: [160.0, 12.0, 0.0],
            mount_rpy: [0.0, 0.0, 0.3],
            ..Board::default()
        };
        let s = Sandal::new(&board, Side::Left, PlateParams::default()).unwrap();
        let p = [3.0, -7.5];
        let q = s.sole_to_board(s.board_to_sole(p));
        assert!((q[0] - p[0]).abs() < 1e-12 && (q[1] - p[1]).abs() < 1e-12);
    }

    /// The paper's board lies under the toes of both feet, and the note says so and names
    /// the board that clears them; that board, turned by 90° and centred 200 mm ahead of
    /// the ankle, gets no such note.
    #[test]
    fn the_toes_on_the_papers_board_are_noted_and_the_turned_board_clears_them() {
        for side in Side::BOTH {
            let paper = Sandal::new(&Board::default(), side, PlateParams::default()).unwrap();
            let notes = paper.notes();
            assert!(
                notes
                    .iter()
                    .any(|n| n.contains("the toes stand on the print")
                        && n.contains("turned by 90° and centred 200 mm")),
                "{notes:?}"
            );
            let turned = Board {
                mount_origin: [200.0, 0.0, 0.0],
                mount_rpy: [0.0, 0.0, 90f64.to_radians()],
                ..Board::default()
            };
            let turned = Sandal::new(&turned, side, PlateParams::default()).unwrap();
            assert!(
                !turned.notes().iter().any(|n| n.contains("toes")),
                "{:?}",
                turned.notes()
            );
        }
    }
}
