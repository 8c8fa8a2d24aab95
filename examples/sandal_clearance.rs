//! How far the feet stay from the camera's view of each sandal's squares over a plan: for
//! every capture of the default plan (144 captures, planned past the body), every inner
//! vertex's refinement window (the vertex and the 8 points half a square from it) and each
//! line of sight from the camera to those points, the distance by which the body model's
//! foot and toe of the board's own leg miss it (the solids are already 5 mm larger than
//! the real foot: docs/BODY.md). Per sandal: the smallest such clearance over the plan, the
//! capture and vertex where it falls, how many of the plan's vertex windows the foot or toe
//! covers and how many it misses by less than 10 mm. naocalib's sandal (`Board::turned`)
//! against the paper's board, each with its own plan, at zero offsets.
//!
//!     cargo run --release --example sandal_clearance

use naocalib::body::{BodyModel, Kind};
use naocalib::model::{Board, Model, PARAMETER_COUNT, Vertex};
use naocalib::plan::{PlanOptions, plan};

/// The grow (mm) at which `blocks` first holds, to 0.01 mm (at most 200 mm).
fn clearance(blocks: impl Fn(f64) -> bool) -> f64 {
    if blocks(0.0) {
        return 0.0;
    }
    let (mut lo, mut hi) = (0.0, 200.0);
    if !blocks(hi) {
        return hi;
    }
    while hi - lo > 0.01 {
        let mid = (lo + hi) / 2.0;
        if blocks(mid) { hi = mid } else { lo = mid }
    }
    lo
}

fn main() {
    let body = BodyModel::default();
    let zero = [0.0; PARAMETER_COUNT];
    println!(
        "| sandal | captures | vertex windows | covered by the foot or toe | clear by less than 10 mm | smallest clearance | where |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- |");
    for (name, board) in [
        ("naocalib's (turned)", Board::turned()),
        ("the paper's", Board::default()),
    ] {
        let model = Model {
            board,
            ..Model::unconfigured()
        };
        let mut options = PlanOptions::default();
        options.feasibility.sight = Some(body);
        let planned = plan(&model, &options).expect("a plan");
        let (mut windows, mut covered, mut near) = (0usize, 0usize, 0usize);
        let mut smallest = (f64::INFINITY, String::new());
        for (k, c) in planned.captures.iter().enumerate() {
            let chains = model.chains_for(c.camera, c.side, &c.joints);
            let eye = chains.camera.eval(&zero).translation;
            let on_board = chains.board.eval(&zero);
            let posed = body.pose(&model.robot, &model.board, &c.joints);
            let feet: Vec<_> = posed
                .parts
                .iter()
                .filter(|p| p.side == Some(c.side) && matches!(p.kind, Kind::Foot | Kind::Toe))
                .collect();
            let h = model.board.square / 2.0;
            for v in model.board.vertices() {
                let [x, y, _] = model.board.vertex_position(v);
                let window: Vec<[f64; 3]> = (-1..=1)
                    .flat_map(|i| (-1..=1).map(move |j| (i, j)))
                    .map(|(i, j)| on_board.apply(&[x + i as f64 * h, y + j as f64 * h, 0.0]))
                    .collect();
                let d = feet
                    .iter()
                    .map(|p| clearance(|g| window.iter().any(|t| p.shape.blocks(eye, *t, g))))
                    .fold(f64::INFINITY, f64::min);
                windows += 1;
                if d == 0.0 {
                    covered += 1;
                } else if d < 10.0 {
                    near += 1;
                }
                if d < smallest.0 {
                    let Vertex { row, col } = v;
                    smallest = (
                        d,
                        format!(
                            "capture {k} ({} leg), vertex row {row} col {col}",
                            c.side.name()
                        ),
                    );
                }
            }
        }
        println!(
            "| {name} | {} | {windows} | {covered} | {near} | {:.1} mm | {} |",
            planned.captures.len(),
            smallest.0,
            smallest.1
        );
    }
}
