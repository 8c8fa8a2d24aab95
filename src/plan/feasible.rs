//! What a planned capture must satisfy on a real, not yet calibrated robot: joint angles
//! inside the limits with a margin, no self-collision, the whole board in view, facing
//! the camera, for every offset within the stated bounds, and a straight collision-free
//! move from the rest posture. And the pool of random captures
//! that satisfy it, from which the design picks. The bounds are [`Feasibility`]
//! ([`super::feasibility`]); the view check itself is in [`super::view`].

use rand::Rng;

pub use super::feasibility::{Feasibility, MIN_IN_SIGHT};
pub use super::view::{board_in_view_for_all_offsets, board_in_view_of, board_in_view_with};

use super::collision;
use crate::model::{
    CameraId, Joint, JointAngles, Model, PARAMETER_COUNT, Side, gravity, head_pitch_limits,
};

/// Why a capture is not feasible.
#[derive(Debug, Clone, PartialEq)]
pub enum Infeasible {
    /// A joint angle lies outside its limits less the margin.
    Limits(Joint),
    /// LHipYawPitch and RHipYawPitch differ (they are one motor).
    HipYawPitch,
    /// Two parts collide (named).
    Collision(String),
    /// The board leaves the image, turns away or is too small for some offsets in the box.
    View,
    /// The resting leg stands between the camera and the board (named).
    Occluded(String),
    /// Planning past the body: it leaves fewer than [`MIN_IN_SIGHT`] of the vertices in
    /// plain sight.
    Hidden {
        /// The vertices that must be in plain sight.
        need: usize,
        /// The board's vertices.
        of: usize,
    },
    /// The straight move between the rest posture and the capture collides.
    Unreachable,
}

impl std::fmt::Display for Infeasible {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Infeasible::Limits(j) => write!(f, "{} outside its limits less the margin", j.name()),
            Infeasible::HipYawPitch => f.write_str("LHipYawPitch and RHipYawPitch differ"),
            Infeasible::Collision(what) => write!(f, "collision: {what}"),
            Infeasible::Occluded(what) => write!(f, "the {what} hides the board"),
            Infeasible::Hidden { need, of } => {
                write!(
                    f,
                    "the body leaves fewer than {need} of the board's {of} vertices in plain \
                     sight"
                )
            }
            Infeasible::Unreachable => {
                f.write_str("the straight move between the rest posture and it collides")
            }
            Infeasible::View => f.write_str(
                "the board does not stay fully in view, facing the camera, for every offset \
                 within the bounds",
            ),
        }
    }
}

/// Why the capture of `side` at `joints` cannot be executed safely, or `Ok` when it can.
pub fn check(
    model: &Model,
    side: Side,
    joints: &JointAngles,
    f: &Feasibility,
) -> Result<(), Infeasible> {
    check_for(model, CameraId::Lower, side, joints, f)
}

/// [`check`] for a capture by `camera`.
pub fn check_for(
    model: &Model,
    camera: CameraId,
    side: Side,
    joints: &JointAngles,
    f: &Feasibility,
) -> Result<(), Infeasible> {
    within_margins(camera, joints, f)?;
    if let Some(what) = collision(model, f, joints) {
        return Err(Infeasible::Collision(what));
    }
    in_view_and_reach(model, camera, side, joints, f)
}

/// The first collision of the posture `joints`, named: in the collision model, and when
/// planning past the body ([`Feasibility::sight`]) any contact of the whole body model
/// (two parts, a leg and the floor, the head and a leg).
fn collision(model: &Model, f: &Feasibility, joints: &JointAngles) -> Option<String> {
    collision::collision(&model.robot, &f.body, joints).or_else(|| {
        let body = f.sight.as_ref()?;
        let posed = body.pose(&model.robot, &model.board, joints);
        crate::body::any_contact(&posed, body.floor_x)
    })
}

/// [`check_for`] of a posture whose legs are known to be free of collision (the head
/// moves no part of the collision model, and only the head itself in the whole body
/// model).
fn check_legs_free(
    model: &Model,
    camera: CameraId,
    side: Side,
    joints: &JointAngles,
    f: &Feasibility,
) -> Result<(), Infeasible> {
    within_margins(camera, joints, f)?;
    if let Some(body) = &f.sight
        && let Some(what) =
            crate::body::head_contact(&body.pose(&model.robot, &model.board, joints))
    {
        return Err(Infeasible::Collision(what));
    }
    in_view_and_reach(model, camera, side, joints, f)
}

/// The joint limits less the margins, the head's yaw-dependent pitch range, one
/// HipYawPitch.
fn within_margins(
    camera: CameraId,
    joints: &JointAngles,
    f: &Feasibility,
) -> Result<(), Infeasible> {
    for j in Joint::ALL {
        let (lo, hi) = j.limits();
        let q = joints.get(j);
        let margin = f.margin(camera, j);
        if !(lo + margin..=hi - margin).contains(&q) {
            return Err(Infeasible::Limits(j));
        }
    }
    let (lo, hi) = head_pitch_limits(joints.get(Joint::HeadYaw));
    let margin = f.margin(camera, Joint::HeadPitch);
    if !(lo + margin..=hi - margin).contains(&joints.get(Joint::HeadPitch)) {
        return Err(Infeasible::Limits(Joint::HeadPitch));
    }
    if joints.get(Joint::LHipYawPitch) != joints.get(Joint::RHipYawPitch) {
        return Err(Infeasible::HipYawPitch);
    }
    Ok(())
}

/// The board in view for every offset, in plain sight, and the posture reachable straight
/// from rest.
fn in_view_and_reach(
    model: &Model,
    camera: CameraId,
    side: Side,
    joints: &JointAngles,
    f: &Feasibility,
) -> Result<(), Infeasible> {
    let chains = model.chains_for(camera, side, joints);
    if !board_in_view_with(model, camera, side, &chains, f) {
        return Err(Infeasible::View);
    }
    // Every vertex in plain sight of the camera past the resting leg (at the centre).
    let zero = f.centre;
    let eye = chains.camera.eval(&zero).translation;
    let board = chains.board.eval(&zero);
    let vertices: Vec<[f64; 3]> = model
        .board
        .vertices()
        .map(|v| board.apply(&model.board.vertex_position(v)))
        .collect();
    let resting = match side {
        Side::Left => Side::Right,
        Side::Right => Side::Left,
    };
    if let Some(what) =
        collision::sight_blocked(&model.robot, &f.body, joints, resting, eye, &vertices)
    {
        return Err(Infeasible::Occluded(what));
    }
    if let Some(past) = f.past_body() {
        let of = model.board.vertices().count();
        let need = (MIN_IN_SIGHT * of as f64).ceil() as usize;
        if !past.at_least_in_sight(model, side, joints, &chains, need) {
            return Err(Infeasible::Hidden { need, of });
        }
    }
    // Reachable straight from rest and back: then every order of the captures has a way
    // for every move (through rest, if nothing shorter), and any capture can end the phase.
    // Past the body, the move is walked in the body model too, as the plan's moves are.
    let rest = super::route::rest_posture();
    let reach = match f.sight {
        Some(_) => super::route::move_is_clear,
        None => super::route::move_is_free,
    };
    if !reach(model, &f.body, &rest, joints) {
        return Err(Infeasible::Unreachable);
    }
    Ok(())
}

/// Turns the head so that the board centre appears at pixel `target` for the parameters
/// `centre` (the nominal model at zero; Gauss–Newton on HeadYaw and HeadPitch); `None` when it does not get there within the
/// head's limits less the margin.
pub fn aim_head(
    model: &Model,
    side: Side,
    joints: &JointAngles,
    target: [f64; 2],
    joint_margin: f64,
    centre: &[f64; PARAMETER_COUNT],
) -> Option<JointAngles> {
    aim_head_for(
        model,
        CameraId::Lower,
        side,
        joints,
        target,
        joint_margin,
        centre,
    )
}

/// [`aim_head`] for the image of `camera`.
pub fn aim_head_for(
    model: &Model,
    camera: CameraId,
    side: Side,
    joints: &JointAngles,
    target: [f64; 2],
    joint_margin: f64,
    centre: &[f64; PARAMETER_COUNT],
) -> Option<JointAngles> {
    Aim::new(model, camera, side, joints, centre).at(target, joint_margin)
}

/// The aiming of the head at the board of one leg stance ([`aim_head_for`]): the board's
/// pose, which the head does not move, and the start of the search, found once for every
/// image point aimed at.
struct Aim<'a> {
    model: &'a Model,
    camera: CameraId,
    params: [f64; PARAMETER_COUNT],
    /// `T_OB` at `params`.
    board: crate::model::Pose<f64>,
    /// The stance with the head turned towards the sole.
    start: JointAngles,
}

impl<'a> Aim<'a> {
    fn new(
        model: &'a Model,
        camera: CameraId,
        side: Side,
        joints: &JointAngles,
        centre: &[f64; PARAMETER_COUNT],
    ) -> Self {
        let board = model.chains_for(camera, side, joints).board.eval(centre);
        let sole = model
            .robot
            .sole_chain(side, joints, &[0.0; 6])
            .eval(centre)
            .translation;
        let mut start = *joints;
        start.set(Joint::HeadYaw, sole[1].atan2(sole[0]));
        start.set(Joint::HeadPitch, 0.2);
        Aim {
            model,
            camera,
            params: *centre,
            board,
            start,
        }
    }

    /// The head posture that puts the board centre at pixel `target`, if within the
    /// head's limits less `joint_margin`.
    fn at(&self, target: [f64; 2], joint_margin: f64) -> Option<JointAngles> {
        let intrinsics = self.model.intrinsics(self.camera);
        let centre = |j: &JointAngles| -> Option<[f64; 2]> {
            let pose = self
                .model
                .robot
                .camera_chain_of(self.camera, j)
                .eval(&self.params)
                .inverse_then(&self.board);
            intrinsics.project(&pose.translation)
        };
        let (j, reached) = crate::sim::steer_head(centre, self.start, target, 0.5, 15)?;
        let within = |joint: Joint| {
            let (lo, hi) = joint.limits();
            (lo + joint_margin..=hi - joint_margin).contains(&j.get(joint))
        };
        (reached && within(Joint::HeadYaw) && within(Joint::HeadPitch)).then_some(j)
    }
}

/// One feasible capture of the pool: a leg stance (shared by its head postures) and the
/// head posture.
#[derive(Debug, Clone, PartialEq)]
pub struct Candidate {
    /// The camera that takes the picture.
    pub camera: CameraId,
    /// The leg whose board is in view.
    pub side: Side,
    /// The logged angles to command.
    pub joints: JointAngles,
    /// Index of its leg stance in the pool (captures of one stance differ in the head).
    pub stance: usize,
    /// The image point the head aimed the board centre at (px).
    pub target: [f64; 2],
}

/// The resting leg's postures, tried in turn: `(HipRoll outward, HipPitch, KneePitch,
/// AnklePitch)` (rad). Straight and slightly spread first; flexed (thigh raised, knee bent)
/// when the straight leg would hit the floor, as it does whenever the shared HipYawPitch
/// is positive, the stances that load a HipRoll the other way.
const RESTING: [(f64, f64, f64, f64); 3] = [
    (0.15, 0.0, 0.1, 0.0),
    (0.15, -0.5, 1.0, -0.5),
    (0.3, -0.9, 1.6, -0.7),
];

/// Puts the resting leg `side` into its `k`-th posture of [`RESTING`], its HipYawPitch
/// equal to the measured leg's (one motor).
fn park(side: Side, joints: &mut JointAngles, k: usize) {
    let [hyp, roll, pitch, knee, ankle_pitch, ankle_roll] = side.leg_joints();
    let shared = match side {
        Side::Left => Joint::RHipYawPitch,
        Side::Right => Joint::LHipYawPitch,
    };
    let (r, p, q, a) = RESTING[k];
    joints.set(hyp, joints.get(shared));
    joints.set(roll, side.sign() * r);
    joints.set(pitch, p);
    joints.set(knee, q);
    joints.set(ankle_pitch, a);
    joints.set(ankle_roll, 0.0);
}

/// The image points the head aims the board centre at, in order of preference: for the
/// lower camera the centre, then points around it; for the upper camera points below the
/// centre (lying on its back, the NAO cannot pitch its head far enough to bring a sandal to
/// the upper image's centre).
fn aim_targets(model: &Model, camera: CameraId) -> Vec<[f64; 2]> {
    let intrinsics = model.intrinsics(camera);
    let (w, h) = (intrinsics.width as f64, intrinsics.height as f64);
    let offsets: &[(f64, f64)] = match camera {
        CameraId::Lower => &[
            (0.0, 0.0),
            (-0.12, -0.1),
            (0.12, 0.1),
            (0.12, -0.1),
            (-0.12, 0.1),
            (0.0, -0.15),
            (0.0, 0.15),
            (-0.18, 0.0),
            (0.18, 0.0),
        ],
        CameraId::Upper => &[
            (0.0, 0.1),
            (-0.2, 0.1),
            (0.2, 0.1),
            (0.0, 0.05),
            (0.0, 0.15),
            (-0.2, 0.15),
            (0.2, 0.15),
            (0.0, 0.2),
        ],
    };
    offsets
        .iter()
        .map(|(du, dv)| [w * (0.5 + du), h * (0.5 + dv)])
        .collect()
}

/// The directions a camera's image is swept in when its intrinsics are free: the four
/// corners, then the four edges, as offsets (fractions of the image's width and height)
/// from the camera's first `aim_targets` point.
pub const SWEEP: [(f64, f64); 8] = [
    (-0.34, -0.3),
    (0.34, 0.3),
    (0.34, -0.3),
    (-0.34, 0.3),
    (0.0, -0.36),
    (0.42, 0.0),
    (0.0, 0.36),
    (-0.42, 0.0),
];

/// The image points a stance's swept head posture aims the board centre at, in order of
/// preference: out along direction `k` of [`SWEEP`] from the camera's first aim point,
/// the farthest first, then nearer (the board must stay in view for every offset).
fn sweep_targets(model: &Model, camera: CameraId, k: usize) -> Vec<[f64; 2]> {
    let intrinsics = model.intrinsics(camera);
    let (w, h) = (intrinsics.width as f64, intrinsics.height as f64);
    let [u, v] = aim_targets(model, camera)[0];
    let (du, dv) = SWEEP[k % SWEEP.len()];
    [1.0, 0.85, 0.7, 0.6, 0.5, 0.4, 0.3]
        .iter()
        .map(|s| [u + s * du * w, v + s * dv * h])
        .collect()
}

/// Up to `heads` feasible captures of the stance `joints` of the measured leg `side` (the
/// other leg put into the first of its [`RESTING`] postures that collides with nothing,
/// the head aimed at the [`aim_targets`] in turn, each posture passing [`check`]); empty
/// when every resting posture collides or no head posture keeps the board in view.
fn postures(
    model: &Model,
    camera: CameraId,
    side: Side,
    joints: &JointAngles,
    heads: usize,
    targets: &[[f64; 2]],
    f: &Feasibility,
) -> Vec<(JointAngles, [f64; 2])> {
    aimed_postures(model, camera, side, joints, &[(targets, heads)], f)
}

/// [`postures`] for several lists of image points: for each `(targets, count)` of `aims`
/// up to `count` postures aimed at `targets` in turn, each with the point it aims at.
fn aimed_postures(
    model: &Model,
    camera: CameraId,
    side: Side,
    joints: &JointAngles,
    aims: &[(&[[f64; 2]], usize)],
    f: &Feasibility,
) -> Vec<(JointAngles, [f64; 2])> {
    let other = match side {
        Side::Left => Side::Right,
        Side::Right => Side::Left,
    };
    let Some(joints) = (0..RESTING.len())
        .map(|k| {
            let mut parked = *joints;
            park(other, &mut parked, k);
            parked
        })
        .find(|parked| collision(model, f, parked).is_none())
    else {
        return Vec::new();
    };
    let mut out = Vec::new();
    let aim = Aim::new(model, camera, side, &joints, &f.centre);
    for (targets, count) in aims {
        let mut found = 0;
        for target in targets.iter() {
            if found == *count {
                break;
            }
            let Some(aimed) = aim.at(*target, f.margin(camera, Joint::HeadPitch)) else {
                continue;
            };
            // The legs are those found free of collision above (the head moves none of the
            // collision model's parts).
            if check_legs_free(model, camera, side, &aimed, f).is_ok() {
                out.push((aimed, *target));
                found += 1;
            }
        }
    }
    out
}

/// The range a leg angle of the pool is drawn from: the joint's limits less the margin;
/// for the upper camera the hip's HipYawPitch and HipPitch only where it can see a sandal
/// lying on its back (HipYawPitch −65…+12°, HipPitch −87…−32°).
fn leg_range(camera: CameraId, j: Joint, margin: f64) -> (f64, f64) {
    let (lo, hi) = j.limits();
    let (lo, hi) = (lo + margin, hi - margin);
    let window = match (camera, j) {
        (CameraId::Upper, Joint::LHipYawPitch | Joint::RHipYawPitch) => Some((-65.0, 12.0)),
        (CameraId::Upper, Joint::LHipPitch | Joint::RHipPitch) => Some((-87.0, -32.0)),
        _ => None,
    };
    match window {
        Some((a, b)) => (lo.max(f64::to_radians(a)), hi.min(f64::to_radians(b))),
        None => (lo, hi),
    }
}

/// A leg angle drawn within `[lo, hi]` from the arcsine distribution (density
/// `1/(π·sqrt((x − lo)(hi − x)))`, applied twice): most draws lie near the limits, where the
/// stances are most informative (the design picks from a pool drawn so about twice as
/// well as from a uniform one), while every angle in between stays possible.
fn towards_limits(lo: f64, hi: f64, rng: &mut impl Rng) -> f64 {
    let arcsine = |x: f64| 0.5 - 0.5 * (std::f64::consts::PI * x).cos();
    lo + (hi - lo) * arcsine(arcsine(rng.random_range(0.0..1.0)))
}

/// Draws up to `stances` feasible leg stances for `side` (each leg angle within the limits
/// less the margin, drawn mostly near the limits), each with up to `heads` head postures (the board
/// aimed at the image centre and at points around it), all passing [`check`], within
/// `tries` random leg postures; then up to `tries` more draws look only for stances that
/// load a joint with a sign of gravity torque the pool lacks. With `sweep` (the camera's
/// intrinsics are free) each stance gets one head posture more, aimed out towards a corner
/// or an edge of the image, the stances taking the directions of [`SWEEP`] in turn.
#[allow(clippy::too_many_arguments)] // each is one plain setting of the pool
pub fn candidates(
    model: &Model,
    camera: CameraId,
    side: Side,
    stances: usize,
    heads: usize,
    sweep: bool,
    tries: usize,
    f: &Feasibility,
    first_stance: usize,
    rng: &mut impl Rng,
) -> Vec<Candidate> {
    let targets = aim_targets(model, camera);
    let swept: Vec<Vec<[f64; 2]>> = (0..SWEEP.len())
        .map(|k| sweep_targets(model, camera, k))
        .collect();
    let mut out = Vec::new();
    let mut found = 0;
    // Which signs of each joint's gravity torque the pool has: compliance and play can only
    // be told from the offset by stances that load a joint both ways.
    let mut signs = [[false; 2]; 6];
    let torque_signs = |joints: &JointAngles| {
        gravity::leg_torques(&model.robot, &model.board, side, joints).map(|t| [t > 0.0, t < 0.0])
    };
    for attempt in 0..2 * tries {
        if found >= stances && signs.iter().all(|s| s[0] && s[1]) {
            break;
        }
        // A search that cannot succeed says so in seconds: nothing feasible in the first
        // FUTILE_TRIES draws (a feasible region is met within a few hundred) ends it.
        if found == 0 && attempt == FUTILE_TRIES {
            break;
        }
        let mut joints = JointAngles::default();
        for j in side.leg_joints() {
            let (lo, hi) = leg_range(camera, j, f.joint_margin);
            joints.set(j, towards_limits(lo, hi, rng));
        }
        let these = torque_signs(&joints);
        // Once the pool is full, only stances that load a joint in a way it lacks.
        let new_sign = (0..6).any(|k| (0..2).any(|s| these[k][s] && !signs[k][s]));
        if found >= stances && !new_sign {
            continue;
        }
        let postures = if sweep {
            let out = &swept[found % SWEEP.len()];
            aimed_postures(
                model,
                camera,
                side,
                &joints,
                &[(&targets, heads), (out, 1)],
                f,
            )
        } else {
            postures(model, camera, side, &joints, heads, &targets, f)
        };
        if postures.is_empty() {
            continue;
        }
        let stance = first_stance + found;
        found += 1;
        for k in 0..6 {
            for s in 0..2 {
                signs[k][s] |= these[k][s];
            }
        }
        out.extend(postures.into_iter().map(|(joints, target)| Candidate {
            camera,
            side,
            joints,
            stance,
            target,
        }));
    }
    out
}

/// Draws after which a pool search that found nothing gives up (a camera, board or box of
/// offsets that admit captures yield the first within a few hundred draws; every draw
/// costs up to a millisecond).
pub const FUTILE_TRIES: usize = 4000;

/// Up to `count` feasible variants of the capture `base` (one head posture each): its
/// measured leg's angles moved by up to ± `spread` (rad) each, kept within the limits less
/// the margin, the other leg parked with the same HipYawPitch, the head aimed as for a
/// pool stance, or with `sweep` at the image point the base aimed at. Numbered as stances
/// from `first_stance`. Used to refine a design around the stances it picked.
#[allow(clippy::too_many_arguments)] // each is one plain setting of the refinement
pub fn variants(
    model: &Model,
    base: &Candidate,
    count: usize,
    tries: usize,
    spread: f64,
    sweep: bool,
    f: &Feasibility,
    first_stance: usize,
    rng: &mut impl Rng,
) -> Vec<Candidate> {
    let side = base.side;
    let camera = base.camera;
    let targets = if sweep {
        vec![base.target]
    } else {
        aim_targets(model, camera)
    };
    let mut out = Vec::new();
    for _ in 0..tries {
        if out.len() == count {
            break;
        }
        let mut joints = base.joints;
        for j in side.leg_joints() {
            let (lo, hi) = j.limits();
            let q = joints.get(j) + rng.random_range(-spread..=spread);
            joints.set(j, q.clamp(lo + f.joint_margin, hi - f.joint_margin));
        }
        if let Some((aimed, target)) = postures(model, camera, side, &joints, 1, &targets, f).pop()
        {
            out.push(Candidate {
                camera,
                side,
                joints: aimed,
                stance: first_stance + out.len(),
                target,
            });
        }
    }
    out
}
