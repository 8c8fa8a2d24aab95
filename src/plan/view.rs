//! Whether the board stays in view: the whole board in the image (with a margin) and
//! facing the camera, for every offset within the bounds of [`Feasibility`] — the check
//! [`super::feasible`] applies to every planned capture.

use super::feasibility::Feasibility;
use crate::model::{
    CameraId, Joint, JointAngles, Model, PARAMETER_COUNT, Param, Pose, Side, StanceChains,
};

/// The offsets whose unknown values the view must tolerate for a capture of `side` by
/// `camera`, each with its bound.
fn uncertain(camera: CameraId, side: Side, f: &Feasibility) -> Vec<(Param, f64)> {
    let (angle, length) = match camera {
        CameraId::Lower => (f.offset_angle, f.offset_length),
        CameraId::Upper => (f.upper_offset, f.upper_offset.to_degrees()),
    };
    let mut out: Vec<(Param, f64)> = camera
        .rotation_params()
        .into_iter()
        .chain(side.leg_joints().map(Joint::offset))
        .map(|p| (p, angle))
        .collect();
    out.push((Param::HeadYaw, f.head_offset));
    out.push((Param::HeadPitch, f.head_offset));
    let [rot_z, trans_x, trans_y] = side.board_params();
    out.push((rot_z, angle));
    out.push((trans_x, length));
    out.push((trans_y, length));
    out
}

/// The camera's and the board's poses in `O` at the parameters a view starts from, and
/// which parameters each chain depends on: a view at parameters that differ in one
/// parameter evaluates again only the chain that depends on it (the same arithmetic as
/// evaluating both).
struct Posed<'a> {
    chains: &'a StanceChains,
    params: [f64; PARAMETER_COUNT],
    camera: Pose<f64>,
    board: Pose<f64>,
    in_camera: [bool; PARAMETER_COUNT],
    in_board: [bool; PARAMETER_COUNT],
}

impl<'a> Posed<'a> {
    fn new(chains: &'a StanceChains, params: [f64; PARAMETER_COUNT]) -> Self {
        let mask = |ps: Vec<Param>| {
            let mut m = [false; PARAMETER_COUNT];
            for p in ps {
                m[p.index()] = true;
            }
            m
        };
        Posed {
            chains,
            params,
            camera: chains.camera.eval(&params),
            board: chains.board.eval(&params),
            in_camera: mask(chains.camera.params()),
            in_board: mask(chains.board.params()),
        }
    }

    /// [`view`] at the start's parameters with parameter `p` moved by `by`.
    fn moved(&self, model: &Model, p: Param, by: f64) -> Option<(Vec<[f64; 2]>, f64)> {
        let mut params = self.params;
        params[p.index()] += by;
        let (camera_moved, board_moved);
        let camera = if self.in_camera[p.index()] {
            camera_moved = self.chains.camera.eval(&params);
            &camera_moved
        } else {
            &self.camera
        };
        let board = if self.in_board[p.index()] {
            board_moved = self.chains.board.eval(&params);
            &board_moved
        } else {
            &self.board
        };
        view_posed(model, self.chains, &camera.inverse_then(board), &params)
    }
}

/// The projected vertices and the angle between the board normal and the line of sight
/// for parameters `params`; `None` when a vertex is behind the camera.
fn view(model: &Model, chains: &StanceChains, params: &[f64]) -> Option<(Vec<[f64; 2]>, f64)> {
    view_posed(model, chains, &chains.camera_to_board(params), params)
}

/// [`view`] with the board's pose in the camera frame, `pose`, already found.
fn view_posed(
    model: &Model,
    chains: &StanceChains,
    pose: &Pose<f64>,
    params: &[f64],
) -> Option<(Vec<[f64; 2]>, f64)> {
    let to_camera = crate::sim::line_of_sight(pose);
    let dist = to_camera.iter().map(|x| x * x).sum::<f64>().sqrt();
    let angle = (to_camera[2] / dist).clamp(-1.0, 1.0).acos();
    let mut uv = Vec::with_capacity((model.board.rows() * model.board.cols()) as usize);
    for p in model.project_posed(chains, pose, params, model.board.vertices()) {
        uv.push(p?);
    }
    Some((uv, angle))
}

/// How far beyond a border (px) the spread summed so far must push a vertex for
/// [`board_in_view_of`] to stop early. The partial sum is a prefix of the whole, so it never
/// exceeds it; the allowance leaves every case within rounding of a border to the full test.
const ROUNDING_PX: f64 = 1e-6;
/// The same allowance for the view angle (rad).
const ROUNDING_RAD: f64 = 1e-9;

/// Whether the board on `side` stays fully in the image (with the margin) and facing the
/// camera for every combination of offsets within the bounds around
/// [`Feasibility::centre`], at the logged angles `joints`.
///
/// The pixel positions and the view angle are linear enough in the offsets over ±3° that
/// their extremes over the box of offsets lie at its corners given by the signs of their
/// derivatives; the test bounds each by the linear prediction and then evaluates the model
/// exactly at the worst corner of each image border and of the view angle.
pub fn board_in_view_for_all_offsets(
    model: &Model,
    side: Side,
    joints: &JointAngles,
    f: &Feasibility,
) -> bool {
    board_in_view_of(model, CameraId::Lower, side, joints, f)
}

/// [`board_in_view_for_all_offsets`] for the image of `camera`, with that camera's box of
/// offsets ([`Feasibility::upper_offset`] for the upper one).
pub fn board_in_view_of(
    model: &Model,
    camera: CameraId,
    side: Side,
    joints: &JointAngles,
    f: &Feasibility,
) -> bool {
    board_in_view_with(
        model,
        camera,
        side,
        &model.chains_for(camera, side, joints),
        f,
    )
}

/// [`board_in_view_of`] with the stance's chains ([`Model::chains_for`]) already built.
pub fn board_in_view_with(
    model: &Model,
    camera: CameraId,
    side: Side,
    chains: &StanceChains,
    f: &Feasibility,
) -> bool {
    let intrinsics = model.intrinsics(camera);
    let zero = f.centre;
    let posed = Posed::new(chains, zero);
    let at_centre = posed.camera.inverse_then(&posed.board);
    let Some((uv, angle)) = view_posed(model, chains, &at_centre, &zero) else {
        return false;
    };
    if angle > f.max_view_angle {
        return false;
    }
    let cols = model.board.cols() as usize;
    let min_edge = (0..uv.len())
        .filter(|k| (k + 1) % cols != 0)
        .map(|k| ((uv[k][0] - uv[k + 1][0]).powi(2) + (uv[k][1] - uv[k + 1][1]).powi(2)).sqrt())
        .fold(f64::INFINITY, f64::min);
    if min_edge < f.min_square_px {
        return false;
    }
    let bounds = uncertain(camera, side, f);
    let (w, hgt) = (intrinsics.width as f64, intrinsics.height as f64);
    let (lo, hi) = (
        [f.margin_px; 2],
        [w - 1.0 - f.margin_px, hgt - 1.0 - f.margin_px],
    );
    // Derivatives by central differences (the model is smooth; h of 1e-5 rad or mm). The
    // spread the offsets met so far already give only grows with the rest, so a board it
    // pushes out of the image (beyond rounding) is out without the others' derivatives.
    let h = 1e-5;
    let mut d_uv = vec![vec![[0.0; 2]; uv.len()]; bounds.len()];
    let mut d_angle = vec![0.0; bounds.len()];
    let mut spread_so_far = vec![[0.0; 2]; uv.len()];
    let mut angle_spread_so_far = 0.0;
    for (k, (p, b)) in bounds.iter().enumerate() {
        let (Some((up, ap)), Some((um, am))) =
            (posed.moved(model, *p, h), posed.moved(model, *p, -h))
        else {
            return false;
        };
        for v in 0..uv.len() {
            d_uv[k][v] = [
                (up[v][0] - um[v][0]) / (2.0 * h),
                (up[v][1] - um[v][1]) / (2.0 * h),
            ];
            for axis in 0..2 {
                spread_so_far[v][axis] += d_uv[k][v][axis].abs() * b;
                let s = spread_so_far[v][axis];
                if uv[v][axis] - s - lo[axis] < -ROUNDING_PX
                    || hi[axis] - (uv[v][axis] + s) < -ROUNDING_PX
                {
                    return false;
                }
            }
        }
        d_angle[k] = (ap - am) / (2.0 * h);
        angle_spread_so_far += d_angle[k].abs() * b;
        if angle + angle_spread_so_far > f.max_view_angle + ROUNDING_RAD {
            return false;
        }
    }
    // Linear bounds; remember the vertex closest to each border.
    let mut worst: [(f64, usize); 4] = [(f64::INFINITY, 0); 4];
    for v in 0..uv.len() {
        for axis in 0..2 {
            let spread: f64 = bounds
                .iter()
                .enumerate()
                .map(|(k, (_, b))| d_uv[k][v][axis].abs() * b)
                .sum();
            let low_room = uv[v][axis] - spread - lo[axis];
            let high_room = hi[axis] - (uv[v][axis] + spread);
            if low_room < 0.0 || high_room < 0.0 {
                return false;
            }
            for (slot, room) in [(2 * axis, low_room), (2 * axis + 1, high_room)] {
                if room < worst[slot].0 {
                    worst[slot] = (room, v);
                }
            }
        }
    }
    let angle_spread: f64 = bounds
        .iter()
        .enumerate()
        .map(|(k, (_, b))| d_angle[k].abs() * b)
        .sum();
    if angle + angle_spread > f.max_view_angle {
        return false;
    }
    // Exact checks at the worst corners.
    let corner = |sign: &dyn Fn(usize) -> f64| {
        let mut params = zero;
        for (k, (p, b)) in bounds.iter().enumerate() {
            params[p.index()] += sign(k) * b;
        }
        params
    };
    let inside = |params: &[f64; PARAMETER_COUNT]| match view(model, chains, params) {
        Some((uv, angle)) => {
            angle <= f.max_view_angle && uv.iter().all(|p| intrinsics.contains(*p, f.margin_px))
        }
        None => false,
    };
    for (slot, (_, v)) in worst.iter().enumerate() {
        let axis = slot / 2;
        // Towards the low border: against the derivative's sign; towards the high: with it.
        let towards = if slot % 2 == 0 { -1.0 } else { 1.0 };
        let params = corner(&|k| towards * d_uv[k][*v][axis].signum());
        if !inside(&params) {
            return false;
        }
    }
    inside(&corner(&|k| d_angle[k].signum()))
}
