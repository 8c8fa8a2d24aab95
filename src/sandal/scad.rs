//! A parametric OpenSCAD source of the plate with its pins, for teams that 3D-print it:
//! the dimensions a maker may change are named parameters at the top with their defaults
//! ([`PlateParams`](super::geometry::PlateParams)); the positions that must match the
//! model (pins, outline, pattern) follow as data.

use std::fmt::Write as _;

use super::geometry::Sandal;

fn point(p: [f64; 2]) -> String {
    format!("[{:.4}, {:.4}]", p[0], p[1])
}

fn list(points: &[[f64; 2]]) -> String {
    points
        .iter()
        .map(|p| point(*p))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The OpenSCAD source of `sandal`'s plate.
pub fn scad(sandal: &Sandal) -> String {
    let p = &sandal.plate;
    let side = sandal.side.name();
    let mut out = String::new();
    let _ = writeln!(
        out,
        "// naocalib sandal: the {} plate with its pins, for 3D printing. Units: mm.\n\
         // Sole frame: origin at the ankle's projection on the sole, x toward the toes, y to\n\
         // the robot's left, z toward the leg. The plate's top face is the sole plane (z = 0):\n\
         // the pins stand up from it into the recesses at the FSRs, the printed pattern is\n\
         // glued onto it. Print the pattern with `naocalib sandal` (sandal-{side}-*.pdf).\n",
        side.to_uppercase()
    );
    let _ = writeln!(out, "// Parameters (defaults from naocalib).");
    let _ = writeln!(
        out,
        "pin_diameter = {};     // pins that fit the recesses at the FSRs: measure your robot",
        p.pin_diameter
    );
    let _ = writeln!(
        out,
        "pin_height = {};       // above the plate's top face",
        p.pin_height
    );
    let _ = writeln!(
        out,
        "plate_thickness = {};  // below the sole plane",
        p.plate_thickness
    );
    let _ = writeln!(
        out,
        "slot_width = {};       // strap slots, across the foot",
        p.slot_width
    );
    let _ = writeln!(
        out,
        "slot_length = {};     // strap slots, along the foot: the strap's width and some play",
        p.slot_length
    );
    let _ = writeln!(
        out,
        "show_pattern = true;  // preview the pattern's squares on the top face (not printed)\n"
    );
    let _ = writeln!(
        out,
        "// Geometry from the model's board (dataset.toml [board]); regenerate rather than edit."
    );
    let pins: Vec<[f64; 2]> = sandal.pins().iter().map(|pin| pin.at).collect();
    let _ = writeln!(
        out,
        "pins = [{}];  // {}",
        list(&pins),
        sandal
            .pins()
            .iter()
            .map(|pin| pin.name)
            .collect::<Vec<_>>()
            .join(", ")
    );
    let slots: Vec<[f64; 2]> = sandal.slots().iter().map(|s| s.centre).collect();
    let _ = writeln!(out, "slots = [{}];  // outer, inner", list(&slots));
    let _ = writeln!(out, "outline = [{}];", list(&sandal.plate_outline()));
    let squares: Vec<String> = sandal
        .black_squares()
        .iter()
        .map(|q| format!("[{}]", list(q)))
        .collect();
    let _ = writeln!(out, "squares = [\n  {}\n];\n", squares.join(",\n  "));
    let _ = writeln!(
        out,
        "module plate() {{\n\
         \x20 difference() {{\n\
         \x20   translate([0, 0, -plate_thickness]) linear_extrude(plate_thickness) polygon(outline);\n\
         \x20   for (s = slots)\n\
         \x20     translate([s[0] - slot_length / 2, s[1] - slot_width / 2, -plate_thickness - 1])\n\
         \x20       cube([slot_length, slot_width, plate_thickness + 2]);\n\
         \x20 }}\n\
         \x20 for (q = pins)\n\
         \x20   translate([q[0], q[1], -plate_thickness / 2])\n\
         \x20     cylinder(d = pin_diameter, h = pin_height + plate_thickness / 2, $fn = 48);\n\
         }}\n\n\
         plate();\n\
         if (show_pattern)\n\
         \x20 %color(\"black\") for (q = squares) linear_extrude(0.05) polygon(q);"
    );
    out
}
