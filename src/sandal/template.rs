//! The drilling and cutting template: every dimension of the plate in mm in the sole frame,
//! as plain text to work from and to check the finished sandal against.

use std::fmt::Write as _;

use super::drawing::num;
use super::geometry::{BORDER_SQUARES, Sandal};

/// The template of `sandal`.
pub fn template(sandal: &Sandal) -> String {
    let mut out = String::new();
    let side = sandal.side.name();
    let b = &sandal.board;
    let p = &sandal.plate;
    let xy = |q: [f64; 2]| format!("x {:>8.2}  y {:>8.2}", q[0], q[1]);
    let _ = writeln!(
        out,
        "naocalib sandal: drilling and cutting template, {} foot\n",
        side.to_uppercase()
    );
    let _ = writeln!(
        out,
        "All dimensions in mm in the sole frame of the {side} foot: origin at the ankle's \
         projection on\nthe sole, x toward the toes, y to the robot's left, seen from the \
         printed side (the side\ntoward the leg and the camera). The printed sheet \
         (sandal-{side}-*.pdf) shows the same at 1:1.\n"
    );
    let _ = writeln!(
        out,
        "Board (dataset.toml [board]): {} x {} squares of {} mm, pattern centre ({}, {}), \
         yaw {} deg.\n",
        b.squares_x,
        b.squares_y,
        num(b.square),
        num(b.mount_origin[0]),
        num(b.mount_origin[1]),
        num(b.mount_rpy[2].to_degrees())
    );
    let _ = writeln!(
        out,
        "DRILL: pin holes, diameter {} mm, for pins {} mm high (at the FSRs: B-Human \
         robotDimensions.cfg)",
        num(p.pin_diameter),
        num(p.pin_height)
    );
    for pin in sandal.pins() {
        let _ = writeln!(out, "  pin {}   {}", pin.name, xy(pin.at));
    }
    let _ = writeln!(
        out,
        "\nCUT: the plate's outline ({} mm plate; corners in order, counter-clockwise)",
        num(p.plate_thickness)
    );
    for (i, q) in sandal.plate_outline().iter().enumerate() {
        let _ = writeln!(out, "  {:>2}       {}", i + 1, xy(*q));
    }
    let _ = writeln!(
        out,
        "\nCUT: strap slots, {} mm along x by {} mm across (for the hook-and-loop strap)",
        num(p.slot_length),
        num(p.slot_width)
    );
    for slot in sandal.slots() {
        let _ = writeln!(out, "  {:<7}  centre {}", slot.name, xy(slot.centre));
    }
    let _ = writeln!(out, "\nPATTERN: the squares' outer corners");
    for q in sandal.pattern_outline() {
        let _ = writeln!(out, "           {}", xy(q));
    }
    let _ = writeln!(
        out,
        "  with a white border of {} squares ({} mm) all round: keep it free of marks.",
        num(BORDER_SQUARES),
        num(BORDER_SQUARES * b.square)
    );
    let _ = writeln!(
        out,
        "\nVERTICES: where the solver puts them (row, col: the numbering of corners.csv)"
    );
    for (v, q) in sandal.vertices() {
        let _ = writeln!(out, "  ({}, {})   {}", v.row, v.col, xy(q));
    }
    let _ = writeln!(
        out,
        "\nCHECK the finished sandal: measure from the pin centres to the vertices above; the \
         board\nmounting parameters (BoardRotZ, BoardTransX, BoardTransY) absorb small \
         errors, but the\nsquares must be {} mm and the sheet flat.",
        num(b.square)
    );
    for note in sandal.notes() {
        let _ = writeln!(out, "\nNOTE: {note}.");
    }
    out
}
