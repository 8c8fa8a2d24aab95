//! The simulator: realistic true offsets, stances in which a sandal is fully in view, and
//! the vertices the camera would see, with pixel and joint-angle noise.
//!
//! As in the paper's measurement phase, each leg takes `stances` stances, and each stance is
//! photographed with `heads` head postures (24 × 3 × 2 = 144 captures by default). On
//! request, each leg also takes `upper_stances` stances photographed with the upper camera,
//! found by search among random stances (few let the upper camera see a whole sandal).

pub mod camera;
pub mod render;
pub mod request;
pub mod scene;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

use crate::dataset::{Capture, Corner, Dataset, Truth};
use crate::model::{
    CameraId, Family, Joint, JointAngles, Model, PARAMETER_COUNT, Param, Pose, Side, StanceChains,
};

/// What to simulate.
#[derive(Debug, Clone, PartialEq)]
pub struct SimOptions {
    /// Seed of the random generator; the same seed gives the same dataset.
    pub seed: u64,
    /// Stances per leg (lower camera).
    pub stances: usize,
    /// Head postures per stance.
    pub heads: usize,
    /// Stances per leg photographed with the upper camera (each with `heads` postures),
    /// after the lower camera's.
    pub upper_stances: usize,
    /// Pixel noise σ per coordinate (px).
    pub px_noise: f64,
    /// Joint-angle noise σ per joint and capture (rad).
    pub joint_noise: f64,
    /// True parameters (internal units); drawn at random when `None`.
    pub truth: Option<[f64; PARAMETER_COUNT]>,
    /// Families beyond the paper's whose effects the drawn truth has (see
    /// [`draw_effects`]); ignored when `truth` is given.
    pub effects: Vec<Family>,
    /// Seed for the noise alone, when it should differ from the stance seed (repeated
    /// simulations of the same stances and truth with new noise).
    pub noise_seed: Option<u64>,
    /// Render one image per capture (true pose, actual joints) and name it in the capture.
    pub images: Option<render::ImageOutput>,
    /// Stances to photograph instead of drawing them (a plan's schedule); `stances`,
    /// `upper_stances` and `heads` are then ignored.
    pub schedule: Option<Vec<Stance>>,
    /// The camera of each stance of `schedule`, in its order (a plan's `camera` column);
    /// stances beyond its end are the lower camera's.
    pub schedule_cameras: Vec<CameraId>,
    /// Draw the true offsets as the teams' robot files show them ([`draw_team_truth`])
    /// instead of [`draw_truth`]; ignored when `truth` is given.
    pub team_offsets: bool,
    /// Let boards come near and across the image border (to test detection): head
    /// postures after a stance's first aim the board centre anywhere in the image, and a
    /// board partly outside is kept when [`MIN_VISIBLE`] vertices are in view. Only
    /// vertices in the image become corners.
    pub near_border: bool,
    /// The robot's own body between the cameras and the boards: a vertex whose refinement
    /// window a part of it covers, at the true offsets and the actual angles, gives no
    /// corner, as a camera would not see it whole (images draw it with their own
    /// [`render::RenderOptions::body`]).
    pub body: Option<crate::body::BodyModel>,
}

impl Default for SimOptions {
    fn default() -> Self {
        SimOptions {
            seed: 1,
            stances: 24,
            heads: 3,
            upper_stances: 0,
            px_noise: 0.1,
            joint_noise: 0.0,
            truth: None,
            effects: Vec::new(),
            noise_seed: None,
            images: None,
            schedule: None,
            schedule_cameras: Vec::new(),
            team_offsets: false,
            near_border: false,
            body: None,
        }
    }
}

/// Why a simulation could not be made.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// No stance with the board fully in view was found in many tries.
    #[error(
        "found only {found} of {wanted} stances for the {side} leg with the whole board in view \
         of the {camera} camera; check the camera intrinsics and board geometry"
    )]
    NoStances {
        /// The camera.
        camera: &'static str,
        /// The leg.
        side: &'static str,
        /// Stances found.
        found: usize,
        /// Stances wanted.
        wanted: usize,
    },
    /// An option is out of range.
    #[error("{0}")]
    Options(String),
    /// An image could not be rendered or written.
    #[error(transparent)]
    Render(#[from] render::RenderError),
    /// The dataset the images belong to could not be written (checked before any image is).
    #[error(transparent)]
    Dataset(#[from] crate::dataset::DatasetError),
}

/// Draws plausible true offsets: camera ±3°, joints σ 1° (at most 2.5°), board rotation
/// σ 0.5°, board translation σ 1.5 mm. Head offsets stay zero (held fixed by default).
pub fn draw_truth(rng: &mut impl Rng) -> [f64; PARAMETER_COUNT] {
    let mut truth = [0.0; PARAMETER_COUNT];
    let joint = Normal::new(0.0, 1.0f64.to_radians()).expect("valid σ");
    let board_rot = Normal::new(0.0, 0.5f64.to_radians()).expect("valid σ");
    let board_trans = Normal::new(0.0, 1.5).expect("valid σ");
    let limit = 2.5f64.to_radians();
    for p in Param::ALL {
        use Param::*;
        truth[p.index()] = match p {
            CamYaw | CamPitch | CamRoll => rng.random_range(-3.0f64..3.0).to_radians(),
            LBoardRotZ | RBoardRotZ => board_rot.sample(rng),
            LBoardTransX | LBoardTransY | RBoardTransX | RBoardTransY => board_trans.sample(rng),
            _ if p.family() != crate::model::Family::Paper => 0.0,
            _ => joint.sample(rng).clamp(-limit, limit),
        };
    }
    truth
}

/// Draws the upper camera's rotation offsets into `truth` as [`draw_truth`] draws the
/// lower camera's: ±3° each.
pub fn draw_upper_camera(rng: &mut impl Rng, truth: &mut [f64; PARAMETER_COUNT]) {
    for p in CameraId::Upper.rotation_params() {
        truth[p.index()] = rng.random_range(-3.0f64..3.0).to_radians();
    }
}

/// Draws true offsets of the sizes SPL teams' per-robot files show (SPQR's 2024 files in
/// the B-Human framework, converted to naocalib's `q = θ + α`): lower-camera pitch
/// −3.1…−7.8°, its yaw and roll within ±2°; upper-camera pitch −2.2…−10.2° with median
/// −8.5°, its roll within ±2.7° and yaw within ±2°; head offsets within ±6.8° (yaw) and
/// ±4.7° (pitch); leg joint offsets within ±2°; sandal mounting as [`draw_truth`]. Every
/// value uniform in its range (the upper pitch uniform on each side of its median).
pub fn draw_team_truth(rng: &mut impl Rng) -> [f64; PARAMETER_COUNT] {
    let mut truth = [0.0; PARAMETER_COUNT];
    let board_rot = Normal::new(0.0, 0.5f64.to_radians()).expect("valid σ");
    let board_trans = Normal::new(0.0, 1.5).expect("valid σ");
    for p in Param::ALL {
        use Param::*;
        truth[p.index()] = match p {
            CamPitch => deg(rng, -7.8, -3.1),
            CamYaw | CamRoll | UpperCamYaw => deg(rng, -2.0, 2.0),
            UpperCamPitch => {
                if rng.random_bool(0.5) {
                    deg(rng, -10.2, -8.5)
                } else {
                    deg(rng, -8.5, -2.2)
                }
            }
            UpperCamRoll => deg(rng, -2.7, 2.7),
            HeadYaw => deg(rng, -6.8, 6.8),
            HeadPitch => deg(rng, -4.7, 4.7),
            LBoardRotZ | RBoardRotZ | LBoardTransX | LBoardTransY | RBoardTransX | RBoardTransY => {
                continue;
            }
            _ if p.group() == crate::model::ParamGroup::LeftLeg
                || p.group() == crate::model::ParamGroup::RightLeg =>
            {
                deg(rng, -2.0, 2.0)
            }
            _ => 0.0,
        };
    }
    for p in [
        Param::LBoardRotZ,
        Param::LBoardTransX,
        Param::LBoardTransY,
        Param::RBoardRotZ,
        Param::RBoardTransX,
        Param::RBoardTransY,
    ] {
        truth[p.index()] = if p.unit() == crate::model::Unit::Deg {
            board_rot.sample(rng)
        } else {
            board_trans.sample(rng)
        };
    }
    truth
}

/// A robot as [`draw_team_truth`] draws it, its head offsets at zero (the fit holds them
/// there), with both cameras' focal lengths 1–3 % off the a-priori values of `model` (fx
/// and fy together, within 0.2 % of each other) and their optical centres up to 10 px off
/// (internal units): the teams' one set of intrinsics on a robot whose cameras differ.
pub fn draw_team_truth_with_intrinsics(
    model: &Model,
    rng: &mut impl Rng,
) -> [f64; PARAMETER_COUNT] {
    let mut truth = draw_team_truth(rng);
    truth[Param::HeadYaw.index()] = 0.0;
    truth[Param::HeadPitch.index()] = 0.0;
    for camera in CameraId::ALL {
        let apriori = model.intrinsics(camera);
        let [fx, fy, cx, cy, _, _] = camera.projection_params();
        let sign = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
        let scale = sign * rng.random_range(0.01..=0.03);
        let aspect = rng.random_range(-0.002..=0.002);
        truth[fx.index()] = scale * apriori.fx;
        truth[fy.index()] = (scale + aspect) * apriori.fy;
        truth[cx.index()] = rng.random_range(-10.0..=10.0);
        truth[cy.index()] = rng.random_range(-10.0..=10.0);
    }
    truth
}

/// An angle drawn uniformly from `lo…hi` degrees, in radians.
fn deg(rng: &mut impl Rng, lo: f64, hi: f64) -> f64 {
    rng.random_range(lo..hi).to_radians()
}

/// Adds to `truth` effects of realistic size for each of `families` (the paper's family is
/// drawn by [`draw_truth`]), each with a random sign where the sign is physical: head
/// offsets 0.5°, focal lengths 1 % (5.6 px) and principal point 3 px, distortion k1, k2
/// 0.01, link lengths 0.5 mm, compliance 0.3 deg/(N·m) (bending with the load), play 0.5°
/// full width. The upper camera's intrinsics are not drawn here (a simulation gives them
/// in its truth).
pub fn draw_effects(rng: &mut impl Rng, families: &[Family], truth: &mut [f64; PARAMETER_COUNT]) {
    for p in Param::ALL {
        if !families.contains(&p.family()) || p.is_upper_projection() {
            continue;
        }
        let sign = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
        truth[p.index()] = match p.family() {
            Family::Paper | Family::UpperCamera => continue,
            Family::Head => sign * 0.5f64.to_radians(),
            Family::Intrinsics => match p {
                Param::Fx | Param::Fy => sign * 5.625,
                _ => sign * 3.0,
            },
            Family::Distortion => sign * 0.01,
            Family::Links => sign * 0.5,
            Family::Compliance => 0.3f64.to_radians(),
            Family::Play => 0.5f64.to_radians(),
        };
    }
}

/// One stance with the head postures it is photographed in.
#[derive(Debug, Clone, PartialEq)]
pub struct Stance {
    /// The leg whose board is in view.
    pub side: Side,
    /// Logged joint angles of every capture of this stance (legs equal, head differs).
    pub postures: Vec<JointAngles>,
}

/// A schedule of captures `(camera, side, joints)` as the simulator's stances (one
/// posture each, in order) and the camera of each (`SimOptions::schedule` and
/// `schedule_cameras`).
pub fn schedule(
    captures: impl IntoIterator<Item = (CameraId, Side, JointAngles)>,
) -> (Vec<Stance>, Vec<CameraId>) {
    captures
        .into_iter()
        .map(|(camera, side, joints)| {
            (
                Stance {
                    side,
                    postures: vec![joints],
                },
                camera,
            )
        })
        .unzip()
}

/// Smallest distance of a vertex from the image border (px).
const MARGIN: f64 = 12.0;
/// Smallest projected square edge (px), so that detection is realistic.
const MIN_SQUARE_PX: f64 = 14.0;
/// Largest angle between the board normal and the line of sight.
const MAX_VIEW_ANGLE_DEG: f64 = 60.0;

/// Fewest vertices in view (3 px inside the image) of a board partly outside the image
/// ([`SimOptions::near_border`]).
pub const MIN_VISIBLE: usize = 8;

/// The line of sight from the board centre to the camera in the board frame (`−Rᵀ·t` of the
/// camera-to-board pose `pose`); its z component over its length is the cosine of the angle
/// between the board normal and the line of sight.
pub(crate) fn line_of_sight(pose: &Pose<f64>) -> [f64; 3] {
    std::array::from_fn(|j| {
        -(0..3)
            .map(|i| pose.rotation[i][j] * pose.translation[i])
            .sum::<f64>()
    })
}

/// The projected vertices of the board on `side`, if the whole board is in view of
/// `camera` (with `partial`, at least [`MIN_VISIBLE`] vertices), facing it, and not too
/// small.
fn board_in_view(
    model: &Model,
    camera: CameraId,
    chains: &StanceChains,
    params: &[f64],
    partial: bool,
) -> Option<Vec<[f64; 2]>> {
    let intrinsics = model.intrinsics(camera);
    let to_camera = line_of_sight(&chains.camera_to_board(params));
    let dist = to_camera.iter().map(|x| x * x).sum::<f64>().sqrt();
    if to_camera[2] < dist * MAX_VIEW_ANGLE_DEG.to_radians().cos() {
        return None;
    }
    let vertices: Vec<_> = model.board.vertices().collect();
    let uv: Vec<[f64; 2]> = model
        .project(chains, params, &vertices)
        .into_iter()
        .collect::<Option<_>>()?;
    if partial {
        if uv.iter().filter(|p| intrinsics.contains(**p, 3.0)).count() < MIN_VISIBLE {
            return None;
        }
    } else if !uv.iter().all(|p| intrinsics.contains(*p, MARGIN)) {
        return None;
    }
    let cols = model.board.cols() as usize;
    let min_edge = (0..uv.len())
        .filter(|k| (k + 1) % cols != 0)
        .map(|k| ((uv[k][0] - uv[k + 1][0]).powi(2) + (uv[k][1] - uv[k + 1][1]).powi(2)).sqrt())
        .fold(f64::INFINITY, f64::min);
    (min_edge >= MIN_SQUARE_PX).then_some(uv)
}

/// Gauss–Newton on (HeadYaw, HeadPitch) with a numerical Jacobian from `start`, so that
/// `centre` (where the board centre appears for given joint angles) comes within
/// `tolerance` pixels of `target`, in at most `iterations` steps of at most 0.3 rad each.
/// Returns the angles and whether the target was reached; `None` when a projection fails or
/// the Jacobian is singular. Shared by the simulator and the stance planner.
pub fn steer_head(
    centre: impl Fn(&JointAngles) -> Option<[f64; 2]>,
    start: JointAngles,
    target: [f64; 2],
    tolerance: f64,
    iterations: usize,
) -> Option<(JointAngles, bool)> {
    let mut j = start;
    for _ in 0..iterations {
        let c = centre(&j)?;
        let e = [c[0] - target[0], c[1] - target[1]];
        if e[0].abs() < tolerance && e[1].abs() < tolerance {
            return Some((j, true));
        }
        let h = 1e-6;
        let mut jac = [[0.0; 2]; 2];
        for (k, joint) in [Joint::HeadYaw, Joint::HeadPitch].into_iter().enumerate() {
            let mut jp = j;
            jp.set(joint, j.get(joint) + h);
            let cp = centre(&jp)?;
            jac[0][k] = (cp[0] - c[0]) / h;
            jac[1][k] = (cp[1] - c[1]) / h;
        }
        let det = jac[0][0] * jac[1][1] - jac[0][1] * jac[1][0];
        if det.abs() < 1e-9 {
            return None;
        }
        let d_yaw = (jac[1][1] * e[0] - jac[0][1] * e[1]) / det;
        let d_pitch = (-jac[1][0] * e[0] + jac[0][0] * e[1]) / det;
        j.set(
            Joint::HeadYaw,
            j.get(Joint::HeadYaw) - d_yaw.clamp(-0.3, 0.3),
        );
        j.set(
            Joint::HeadPitch,
            j.get(Joint::HeadPitch) - d_pitch.clamp(-0.3, 0.3),
        );
    }
    Some((j, false))
}

/// Turns the head so that the board centre appears at `target` (pixels) of `camera` with
/// [`steer_head`]; `None` if it leaves the joint limits.
fn aim_head(
    model: &Model,
    camera: CameraId,
    side: Side,
    joints: &JointAngles,
    params: &[f64],
    target: [f64; 2],
) -> Option<JointAngles> {
    let intrinsics = model.intrinsics(camera);
    let centre = |j: &JointAngles| -> Option<[f64; 2]> {
        let chains = model.chains_for(camera, side, j);
        let pose = chains.camera_to_board(params);
        intrinsics.project(&pose.translation)
    };
    let mut start = *joints;
    let sole = model.chains(side, joints).board.eval(params).translation;
    start.set(Joint::HeadYaw, sole[1].atan2(sole[0]));
    start.set(Joint::HeadPitch, 0.3);
    let (j, _) = steer_head(centre, start, target, 0.01, 20)?;
    let within = |joint: Joint| {
        let (lo, hi) = joint.limits();
        (lo..=hi).contains(&j.get(joint))
    };
    (within(Joint::HeadYaw) && within(Joint::HeadPitch)).then_some(j)
}

/// Draws a leg posture uniformly within (slightly inset) joint limits.
fn random_leg(rng: &mut impl Rng, side: Side, joints: &mut JointAngles) {
    for joint in side.leg_joints() {
        let (lo, hi) = joint.limits();
        let inset = 0.05 * (hi - lo);
        joints.set(joint, rng.random_range(lo + inset..hi - inset));
    }
}

/// Chooses `count` stances for `side`, each with `heads` head postures that keep the whole
/// board in view of the lower camera, facing it (with `near_border`, see
/// [`SimOptions::near_border`]). The other leg rests in a random relaxed posture; both
/// HipYawPitch angles are equal (one motor).
pub fn choose_stances(
    model: &Model,
    side: Side,
    params: &[f64],
    count: usize,
    heads: usize,
    near_border: bool,
    rng: &mut impl Rng,
) -> Result<Vec<Stance>, SimError> {
    choose_stances_for(
        model,
        CameraId::Lower,
        side,
        params,
        count,
        heads,
        near_border,
        rng,
    )
}

/// [`choose_stances`] for the camera `camera`: a simple search over random stances, each
/// kept when the head can be turned so that `camera` sees the whole board.
#[allow(clippy::too_many_arguments)]
pub fn choose_stances_for(
    model: &Model,
    camera: CameraId,
    side: Side,
    params: &[f64],
    count: usize,
    heads: usize,
    near_border: bool,
    rng: &mut impl Rng,
) -> Result<Vec<Stance>, SimError> {
    let mut stances = Vec::with_capacity(count);
    let other = match side {
        Side::Left => Side::Right,
        Side::Right => Side::Left,
    };
    let intrinsics = model.intrinsics(camera);
    let (w, h) = (intrinsics.width as f64, intrinsics.height as f64);
    let max_tries = 20_000 * count.max(1);
    for _ in 0..max_tries {
        if stances.len() == count {
            break;
        }
        let mut joints = JointAngles::default();
        random_leg(rng, side, &mut joints);
        for joint in other.leg_joints() {
            let (lo, hi) = joint.limits();
            joints.set(joint, rng.random_range(lo * 0.2..hi * 0.2));
        }
        let hyp = joints.get(side.leg_joints()[0]);
        joints.set(other.leg_joints()[0], hyp);
        let mut postures = Vec::with_capacity(heads);
        for k in 0..heads * 8 {
            if postures.len() == heads {
                break;
            }
            let target = if k == 0 {
                [w / 2.0, h / 2.0]
            } else if near_border {
                [
                    w * rng.random_range(0.0..1.0),
                    h * rng.random_range(0.0..1.0),
                ]
            } else {
                [
                    w * rng.random_range(0.3..0.7),
                    h * rng.random_range(0.3..0.7),
                ]
            };
            let Some(aimed) = aim_head(model, camera, side, &joints, params, target) else {
                if k == 0 {
                    break;
                }
                continue;
            };
            let partial = near_border && k > 0;
            let chains = model.chains_for(camera, side, &aimed);
            if board_in_view(model, camera, &chains, params, partial).is_some() {
                postures.push(aimed);
            } else if k == 0 {
                break;
            }
        }
        if postures.len() == heads {
            stances.push(Stance { side, postures });
        }
    }
    if stances.len() < count {
        return Err(SimError::NoStances {
            camera: camera.name(),
            side: side.name(),
            found: stances.len(),
            wanted: count,
        });
    }
    Ok(stances)
}

/// Simulates a whole dataset for `model`: captures, noisy corners and the truth.
///
/// With [`SimOptions::images`], the images are written into `images/` of the dataset
/// directory before the dataset is returned (for the caller to write with
/// [`Dataset::write`]); unless `force`, an existing image or dataset file there is refused
/// before anything is written, so a refusal leaves the directory as it was.
pub fn simulate(model: &Model, options: &SimOptions) -> Result<Dataset, SimError> {
    if options.stances == 0 || options.heads == 0 {
        return Err(SimError::Options(
            "--stances and --heads must be at least 1".into(),
        ));
    }
    let valid = |x: f64| x.is_finite() && x >= 0.0;
    if !valid(options.px_noise) || !valid(options.joint_noise) {
        return Err(SimError::Options(
            "noise levels must be finite and not negative".into(),
        ));
    }
    if let Some(out) = &options.images {
        out.options.validate()?;
        crate::dataset::check_writable(&out.dir, true, out.force)?;
    }
    let upper = match &options.schedule {
        Some(_) => options.schedule_cameras.contains(&CameraId::Upper),
        None => options.upper_stances > 0,
    };
    let mut rng = ChaCha8Rng::seed_from_u64(options.seed);
    let truth = match options.truth {
        Some(t) => t,
        None if options.team_offsets => {
            let mut t = draw_team_truth(&mut rng);
            draw_effects(&mut rng, &options.effects, &mut t);
            t
        }
        None => {
            let mut t = draw_truth(&mut rng);
            draw_effects(&mut rng, &options.effects, &mut t);
            if upper {
                draw_upper_camera(&mut rng, &mut t);
            }
            t
        }
    };
    // Each stance with the camera that photographs it.
    let mut stances: Vec<(CameraId, Stance)> = match &options.schedule {
        Some(schedule) => schedule
            .iter()
            .enumerate()
            .map(|(k, s)| {
                let camera = options.schedule_cameras.get(k).copied().unwrap_or_default();
                (camera, s.clone())
            })
            .collect(),
        None => Vec::new(),
    };
    if options.schedule.is_none() {
        for (camera, count) in [
            (CameraId::Lower, options.stances),
            (CameraId::Upper, options.upper_stances),
        ] {
            for side in Side::BOTH.into_iter().filter(|_| count > 0) {
                let chosen = choose_stances_for(
                    model,
                    camera,
                    side,
                    &truth,
                    count,
                    options.heads,
                    options.near_border,
                    &mut rng,
                )?;
                stances.extend(chosen.into_iter().map(|s| (camera, s)));
            }
        }
    }
    let mut noise_rng = match options.noise_seed {
        Some(seed) => ChaCha8Rng::seed_from_u64(seed),
        None => rng,
    };
    let px = Normal::new(0.0, options.px_noise).map_err(|e| SimError::Options(e.to_string()))?;
    let joint =
        Normal::new(0.0, options.joint_noise).map_err(|e| SimError::Options(e.to_string()))?;
    let vertices: Vec<_> = model.board.vertices().collect();
    let mut captures = Vec::new();
    let mut corners = Vec::new();
    let mut image_jobs = Vec::new();
    for (camera, stance) in &stances {
        let camera = *camera;
        for logged in &stance.postures {
            let id = captures.len() as u64;
            let actual = logged.map(|q| q + joint.sample(&mut noise_rng));
            let chains = model.chains_for(camera, stance.side, &actual);
            let projected = model.project(&chains, &truth, &vertices);
            let hidden = match &options.body {
                Some(body) => crate::body::sight::hidden(
                    model,
                    body,
                    camera,
                    stance.side,
                    &actual,
                    &truth,
                    crate::body::sight::Growth::NONE,
                ),
                None => Vec::new(),
            };
            for (v, uv) in vertices.iter().zip(projected) {
                let Some(uv) = uv else { continue };
                if options.near_border && !model.intrinsics(camera).contains(uv, 0.0) {
                    continue;
                }
                let pixel = [
                    uv[0] + px.sample(&mut noise_rng),
                    uv[1] + px.sample(&mut noise_rng),
                ];
                // Drawn before the body's test: the body decides which vertices are seen,
                // not the noise of the others (the same robot with and without it).
                if hidden.iter().any(|h| h.vertex == *v) {
                    continue;
                }
                corners.push(Corner {
                    capture: id,
                    vertex: *v,
                    pixel,
                    line: 0,
                });
            }
            if options.images.is_some() {
                image_jobs.push(render::ImageJob {
                    id,
                    camera,
                    side: stance.side,
                    joints: actual,
                });
            }
            captures.push(Capture {
                id,
                side: stance.side,
                camera,
                image: options.images.as_ref().map(|_| render::image_name(id)),
                joints: *logged,
                line: 0,
            });
        }
    }
    if let Some(out) = &options.images {
        render::render_all(
            model,
            &truth,
            &image_jobs,
            &out.options,
            &out.dir,
            out.force,
        )?;
    }
    let mut simulation = toml::Table::new();
    simulation.insert("seed".into(), toml::Value::Integer(options.seed as i64));
    if let Some(seed) = options.noise_seed {
        simulation.insert("noise_seed".into(), toml::Value::Integer(seed as i64));
    }
    simulation.insert(
        "stances_per_leg".into(),
        toml::Value::Integer(options.stances as i64),
    );
    simulation.insert(
        "head_postures".into(),
        toml::Value::Integer(options.heads as i64),
    );
    if options.upper_stances > 0 && options.schedule.is_none() {
        simulation.insert(
            "upper_stances_per_leg".into(),
            toml::Value::Integer(options.upper_stances as i64),
        );
    }
    if options.team_offsets && options.truth.is_none() {
        simulation.insert("team_offsets".into(), toml::Value::Boolean(true));
    }
    if options.near_border {
        simulation.insert("near_border".into(), toml::Value::Boolean(true));
    }
    if options.body.is_some() {
        simulation.insert("body".into(), toml::Value::Boolean(true));
    }
    if options.images.is_none() {
        simulation.insert("px_noise".into(), toml::Value::Float(options.px_noise));
    }
    simulation.insert(
        "joint_noise_deg".into(),
        toml::Value::Float(options.joint_noise.to_degrees()),
    );
    if let Some(out) = &options.images {
        // The corners then come from detection in the images, not from a pixel noise.
        let o = &out.options;
        simulation.insert("images".into(), toml::Value::Boolean(true));
        simulation.insert("image_blur_px".into(), toml::Value::Float(o.blur));
        simulation.insert("image_grey_noise".into(), toml::Value::Float(o.noise));
        simulation.insert("image_vignetting".into(), toml::Value::Float(o.vignetting));
    }
    // Upper captures simulated without `[upper_camera]` used the lower camera's intrinsics
    // (Model::intrinsics); the dataset says so, so that it can be written and read.
    let mut model = *model;
    if upper && model.upper_camera.is_none() {
        model.upper_camera = Some(model.camera);
    }
    Ok(Dataset {
        dir: Default::default(),
        model,
        captures,
        corners,
        truth: Some(Truth {
            values: truth,
            simulation,
        }),
        angles: Default::default(),
    })
}
