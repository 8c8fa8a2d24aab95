//! The NAO V6's body as solids: one capsule, box or sphere per link, a little larger than
//! the real part, posed by the joint angles. The one model of the body that the planner
//! (self-collision, lines of sight past the body), the simulator (the robot drawn into its
//! own pictures) and detection (vertices next to an occluding edge) all read.
//!
//! The frames are the model's (docs/MODEL.md §1): `O` midway between the hip joints, the
//! legs by the nominal leg chain, the arms by the official URDF's arm chain
//! (ros-naoqi `nao_robot`, `naoV6` / `nao_description`: `LShoulderPitch` at (0, 98, 100) mm
//! from the `torso` frame, 85 mm above `O`; the elbow 105 mm along the upper arm and 15 mm
//! aside; the wrist 55.95 mm along the forearm). The sizes are the extents of the official
//! meshes (the V4.0 set of `jrl-umi3218/nao_description` and B-Human's SimRobot V6 scene
//! `Config/Scenes/Includes/NaoV6H25.rsi3`) in each link's frame, grown by
//! [`BodyModel::MARGIN`]; docs/BODY.md gives them part by part, and
//! `examples/body_meshes.rs` checks every mesh vertex inside its solids.

mod contact;
pub mod posture;
pub mod shapes;
pub mod sight;

pub use contact::{
    Clearance, MOVE_STEP, any_contact, clearance, collision, contact, first_blocking, head_contact,
    move_contact, sight_blocked, sight_blocked_by_body,
};
pub use posture::{ARM_JOINTS, ArmPosture};
pub use shapes::{Capsule, OrientedBox, Shape, Sphere};

use std::f64::consts::FRAC_PI_4;

use crate::model::{Axis, Board, Joint, JointAngles, Pose, RobotGeometry, Side};

/// What a solid of the body is: the link it stands for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Kind {
    /// The chest and back, from above the hips to the neck.
    Torso,
    /// The hips' housing between the thighs (HipYawPitch and HipRoll at zero).
    Pelvis,

    /// The head (never in its own cameras' way: it is left out of the lines of sight).
    Head,
    /// A shoulder's housing.
    Shoulder,
    /// Shoulder → elbow.
    UpperArm,
    /// Elbow → fingertips.
    Forearm,
    /// Hip → knee.
    Thigh,
    /// Knee → ankle.
    Tibia,
    /// The foot from the heel to the ball, with the ankle's height.
    Foot,
    /// The toe in front of the ball, lower than the foot.
    Toe,
    /// The sandal's plate carrying the pattern, under the foot.
    Sandal,
}

impl Kind {
    /// The part's name in messages ("thigh").
    pub fn name(self) -> &'static str {
        match self {
            Kind::Torso => "torso",
            Kind::Pelvis => "pelvis",
            Kind::Head => "head",
            Kind::Shoulder => "shoulder",
            Kind::UpperArm => "upper arm",
            Kind::Forearm => "forearm",
            Kind::Thigh => "thigh",
            Kind::Tibia => "tibia",
            Kind::Foot => "foot",
            Kind::Toe => "toe",
            Kind::Sandal => "sandal",
        }
    }

    /// Whether the part belongs to a leg (moves with the leg joints).
    pub fn is_leg(self) -> bool {
        matches!(
            self,
            Kind::Thigh | Kind::Tibia | Kind::Foot | Kind::Toe | Kind::Sandal
        )
    }

    /// Whether the part belongs to an arm.
    pub fn is_arm(self) -> bool {
        matches!(self, Kind::Shoulder | Kind::UpperArm | Kind::Forearm)
    }
}

/// One solid of the posed body.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Part {
    /// The link.
    pub kind: Kind,
    /// Its side, for the links that come in pairs.
    pub side: Option<Side>,
    /// The solid, in `O`.
    pub shape: Shape,
}

impl Part {
    /// The part's name in messages ("left thigh", "torso").
    pub fn name(&self) -> String {
        part_name(self.kind, self.side)
    }
}

/// A part's name in messages ("left thigh", "torso").
pub fn part_name(kind: Kind, side: Option<Side>) -> String {
    match side {
        Some(side) => format!("{} {}", side.name(), kind.name()),
        None => kind.name().to_string(),
    }
}

/// The sizes of the body's solids (mm), each in its link's frame, grown by
/// [`BodyModel::MARGIN`] over the real part (docs/BODY.md).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyModel {
    /// The thigh as boxes in the left HipPitch frame (origin at the hip joints; mirrored in
    /// y for the right leg), the knee's end and the hip's end: `(lo, hi)` each.
    pub thighs: [([f64; 3], [f64; 3]); 2],
    /// Tibia box in the left KneePitch frame (origin at the knee): low corner.
    pub tibia_lo: [f64; 3],
    /// Tibia box: high corner.
    pub tibia_hi: [f64; 3],
    /// The foot as boxes in the left sole frame, from the sole's plane: the plate from the
    /// heel to the ball, and the ankle's housing above it: `(lo, hi)` each.
    pub feet: [([f64; 3], [f64; 3]); 2],
    /// The toe, lower than the foot and lowest at its tip, as boxes in the left sole frame:
    /// `(lo, hi)` each.
    pub toes: [([f64; 3], [f64; 3]); 2],
    /// The sandal plate's heel end (x in the sole frame).
    pub sandal_heel: f64,
    /// Thickness of the sandal plate below the sole (mm).
    pub sandal_thickness: f64,
    /// The plate's margin around the printed pattern (mm).
    pub sandal_margin: f64,
    /// The torso as boxes in `O` (waist, chest, shoulder girdle, neck): `(lo, hi)` each.
    pub torso: [([f64; 3], [f64; 3]); 4],
    /// Pelvis box in `O` (the HipYawPitch and HipRoll housings at zero): low corner.
    pub pelvis_lo: [f64; 3],
    /// Pelvis box in `O`: high corner.
    pub pelvis_hi: [f64; 3],
    /// The head's sphere: centre in the HeadPitch frame.
    pub head_centre: [f64; 3],
    /// Radius of the head's sphere.
    pub head_radius: f64,
    /// Radius of the shoulder spheres, centred on the shoulder joints.
    pub shoulder_radius: f64,
    /// The upper arm capsule's ends along the left ShoulderRoll frame's x axis.
    pub upper_arm: [f64; 2],
    /// Radius of the upper arm capsules.
    pub upper_arm_radius: f64,
    /// The forearm-and-hand capsule's ends along the ElbowRoll frame's x axis (the hand at
    /// any WristYaw, fingers open or closed).
    pub forearm: [f64; 2],
    /// Radius of the forearm-and-hand capsules.
    pub forearm_radius: f64,
    /// The floor under the robot: nothing may reach below this `x_O`. Lying on its back
    /// with the legs straight, the NAO rests on its back (−52.7 mm) and its heels (−59.4 mm
    /// in the sole frame); the floor lies at the heels' depth grown by the margin, so that
    /// the legs may move as low as they lie, no lower.
    pub floor_x: f64,
    /// Where the arms are for the whole capture run ([`ArmPosture::CAPTURE`]).
    pub arms: ArmPosture,
}

impl BodyModel {
    /// How much every solid is larger than the real part it stands for (mm), at least.
    pub const MARGIN: f64 = 5.0;

    /// The shoulder joints in `O` (left): the URDF's (0, 98, 100) from the torso frame,
    /// which lies 85 mm above `O`.
    pub const SHOULDER: [f64; 3] = [0.0, 98.0, 185.0];
    /// The elbow joint in the shoulder frame (left): URDF `LElbowYaw` origin.
    pub const ELBOW: [f64; 3] = [105.0, 15.0, 0.0];
    /// The wrist joint in the elbow frame: URDF `LWristYaw` origin.
    pub const WRIST: [f64; 3] = [55.95, 0.0, 0.0];
}

impl Default for BodyModel {
    /// The NAO V6 (H25): the official meshes' extents in each link's frame (docs/BODY.md),
    /// each grown by [`BodyModel::MARGIN`].
    fn default() -> Self {
        let m = BodyModel::MARGIN;
        let grow = |lo: [f64; 3], hi: [f64; 3]| (lo.map(|x| x - m), hi.map(|x| x + m));
        // The thigh below the hip's axis; above it (at most 19 mm), the HipPitch motor's
        // round housing is the pelvis box's. Two boxes overlapping by 10 mm: the knee's end
        // (z below −80) reaches 18.6 mm less far back than the hip's end.
        let thigh = |lo: [f64; 3], hi: [f64; 3]| {
            let (lo, mut hi) = grow(lo, hi);
            hi[2] = hi[2].min(0.7);
            (lo, hi)
        };
        // With the AnklePitch bracket at any ankle pitch.
        let (tibia_lo, tibia_hi) = grow([-47.0, -41.3, -129.7], [50.1, 52.0, 21.8]);
        // The sole stands on the sandal: the foot's boxes start at the sole's plane. Above
        // 33.5 mm only the ankle's housing rises, to 65.8 mm (y −25.8 … 20.6 mm, with the
        // AnklePitch bracket).
        let on_sole = |lo: [f64; 3], hi: [f64; 3]| {
            let (mut lo, hi) = grow(lo, hi);
            lo[2] = 0.0;
            (lo, hi)
        };
        BodyModel {
            thighs: [
                thigh([-26.1, -41.3, -124.2], [51.2, 48.8, -80.0]),
                thigh([-44.7, -41.3, -90.0], [49.6, 44.8, 19.0]),
            ],
            tibia_lo,
            tibia_hi,
            feet: [
                on_sole([-59.4, -38.8, 0.0], [60.0, 51.7, 33.5]),
                on_sole([-50.7, -25.8, 0.0], [44.4, 20.6, 65.8]),
            ],
            toes: [
                on_sole([55.0, -38.8, 0.0], [85.0, 48.2, 33.5]),
                on_sole([80.0, -37.3, 0.0], [102.4, 42.7, 28.7]),
            ],
            sandal_heel: -64.4,
            sandal_thickness: 8.0,
            sandal_margin: 20.0,
            torso: [
                grow([-52.6, -48.1, 44.4], [52.0, 48.1, 105.0]),
                grow([-52.7, -72.2, 105.0], [58.9, 72.2, 165.0]),
                grow([-52.7, -87.0, 165.0], [57.6, 87.0, 195.0]),
                grow([-31.0, -87.0, 195.0], [29.0, 87.0, 218.3]),
            ],
            // The hips' housings at zero hip angles (x −58.9 … 24.2, |y| ≤ 64.6,
            // z −34.8 … 43.3) and the thighs' tops above the hip axis (x −44.7 … 51.2,
            // |y| ≤ 98.8, z ≤ 19).
            // Swept over HipYawPitch and HipRoll as the meshes' check found them.
            pelvis_lo: [-64.5, -103.8, -50.4],
            pelvis_hi: [56.2, 103.8, 50.1],
            head_centre: [0.6, 0.0, 54.3],
            head_radius: 73.7 + m,
            shoulder_radius: 42.0 + m,
            upper_arm: [-7.0, 82.0],
            upper_arm_radius: 45.6 + m,
            forearm: [0.0, 125.0],
            forearm_radius: 50.6 + m,
            floor_x: -65.0,
            arms: ArmPosture::CAPTURE,
        }
    }
}

/// The body posed: every solid in `O`.
#[derive(Debug, Clone, PartialEq)]
pub struct PosedBody {
    /// The parts, legs first (left, right), then torso, pelvis, head, arms.
    pub parts: Vec<Part>,
}

impl PosedBody {
    /// The parts of the leg on `side`.
    pub fn leg(&self, side: Side) -> impl Iterator<Item = &Part> {
        self.parts
            .iter()
            .filter(move |p| p.kind.is_leg() && p.side == Some(side))
    }

    /// The first part (not the head) that the segment from `eye` to `target` passes
    /// through, grown by `grow` mm, or `None` when the line of sight is clear.
    pub fn blocking(&self, eye: [f64; 3], target: [f64; 3], grow: f64) -> Option<&Part> {
        self.parts
            .iter()
            .filter(|p| p.kind != Kind::Head)
            .find(|p| p.shape.blocks(eye, target, grow))
    }

    /// The nearest part (not the head) that the ray from `origin` along the unit vector
    /// `dir` meets: the part, the distance along the ray and the outward normal there.
    pub fn first_hit(&self, origin: [f64; 3], dir: [f64; 3]) -> Option<(&Part, f64, [f64; 3])> {
        let mut best: Option<(&Part, f64, [f64; 3])> = None;
        for part in self.parts.iter().filter(|p| p.kind != Kind::Head) {
            if let Some((t, n)) = part.shape.ray(origin, dir, 0.0)
                && best.is_none_or(|(_, b, _)| t < b)
            {
                best = Some((part, t, n));
            }
        }
        best
    }

    /// The body moved by `pose` (into another frame, e.g. a camera's: `T_CO`).
    pub fn moved(&self, pose: &Pose<f64>) -> PosedBody {
        PosedBody {
            parts: self
                .parts
                .iter()
                .map(|p| Part {
                    shape: p.shape.moved(pose),
                    ..*p
                })
                .collect(),
        }
    }
}

/// The frames of one leg at its joint angles (nominal geometry): hip, knee, ankle, sole.
#[derive(Debug, Clone, PartialEq)]
pub struct LegFrames {
    /// The hip joints' frame (after HipPitch).
    pub hip: Pose<f64>,
    /// The knee's frame (after KneePitch).
    pub knee: Pose<f64>,
    /// The ankle joint (before AnklePitch).
    pub ankle: Pose<f64>,
    /// The sole frame `S`.
    pub sole: Pose<f64>,
}

/// The frames of the leg on `side` at `joints` (docs/MODEL.md §2.3, no offsets).
pub fn leg_frames(robot: &RobotGeometry, side: Side, joints: &JointAngles) -> LegFrames {
    let s = side.sign();
    let q = side.leg_joints().map(|j| joints.get(j));
    let hip = Pose::translation(0.0, s * robot.hip_offset_y, 0.0)
        .compose(&Pose::rotation(Axis::X, s * FRAC_PI_4))
        .compose(&Pose::rotation(Axis::Z, -s * q[0]))
        .compose(&Pose::rotation(Axis::X, -s * FRAC_PI_4))
        .compose(&Pose::rotation(Axis::X, q[1]))
        .compose(&Pose::rotation(Axis::Y, q[2]));
    let knee = hip
        .compose(&Pose::translation(0.0, 0.0, -robot.thigh))
        .compose(&Pose::rotation(Axis::Y, q[3]));
    let ankle = knee.compose(&Pose::translation(0.0, 0.0, -robot.tibia));
    let sole = ankle
        .compose(&Pose::rotation(Axis::Y, q[4]))
        .compose(&Pose::rotation(Axis::X, q[5]))
        .compose(&Pose::translation(0.0, 0.0, -robot.foot_height));
    LegFrames {
        hip,
        knee,
        ankle,
        sole,
    }
}

/// The sandal plate in the board frame `B`: the pattern with [`BodyModel::sandal_margin`]
/// around it, reaching back to the heel, its top face the printed one (z = 0).
fn sandal_in_board(body: &BodyModel, board: &Board) -> ([f64; 3], [f64; 3]) {
    let hx = board.squares_x as f64 * board.square / 2.0 + body.sandal_margin;
    let hy = board.squares_y as f64 * board.square / 2.0 + body.sandal_margin;
    // The heel end, measured from the pattern's centre along its x axis (the board is
    // mounted along the foot unless turned; a turned mount keeps the plate around the
    // pattern and the foot's own box covers the heel).
    let heel = (body.sandal_heel - board.mount_origin[0]).min(-hx);
    let (lo_x, hi_x) = if board.mount_rpy[2].abs() < 1e-9 {
        (heel, hx)
    } else {
        (-hx, hx)
    };
    ([lo_x, -hy, -body.sandal_thickness], [hi_x, hy, 0.0])
}

impl BodyModel {
    /// The whole body at the leg and head angles `joints`, the arms at [`BodyModel::arms`],
    /// with the sandals of `board` (nominal geometry, no offsets).
    pub fn pose(&self, robot: &RobotGeometry, board: &Board, joints: &JointAngles) -> PosedBody {
        let soles = Side::BOTH.map(|side| leg_frames(robot, side, joints).sole);
        self.pose_with_soles(robot, board, joints, &soles)
    }

    /// [`BodyModel::pose`] with each sole's pose given (`[left, right]`): the simulator
    /// gives the soles of the true model so that each foot stands exactly on its sandal.
    pub fn pose_with_soles(
        &self,
        robot: &RobotGeometry,
        board: &Board,
        joints: &JointAngles,
        soles: &[Pose<f64>; 2],
    ) -> PosedBody {
        let mut parts = Vec::with_capacity(24);
        for (k, side) in Side::BOTH.into_iter().enumerate() {
            let frames = leg_frames(robot, side, joints);
            let mirror = |p: [f64; 3]| [p[0], side.sign() * p[1], p[2]];
            let sole = &soles[k];
            let board_frame = sole.compose(&board.mount());
            let (sandal_lo, sandal_hi) = sandal_in_board(self, board);
            let (kl, kh) = (mirror(self.tibia_lo), mirror(self.tibia_hi));
            let mut leg: Vec<(Kind, Shape)> = self
                .thighs
                .iter()
                .map(|(lo, hi)| (Kind::Thigh, boxed(&frames.hip, mirror(*lo), mirror(*hi))))
                .collect();
            leg.push((Kind::Tibia, boxed(&frames.knee, kl, kh)));
            for (lo, hi) in self.feet {
                leg.push((Kind::Foot, boxed(sole, mirror(lo), mirror(hi))));
            }
            for (lo, hi) in self.toes {
                leg.push((Kind::Toe, boxed(sole, mirror(lo), mirror(hi))));
            }
            leg.push((Kind::Sandal, boxed(&board_frame, sandal_lo, sandal_hi)));
            parts.extend(leg.into_iter().map(|(kind, shape)| Part {
                kind,
                side: Some(side),
                shape,
            }));
        }
        let origin = Pose::identity();
        for (lo, hi) in self.torso {
            parts.push(Part {
                kind: Kind::Torso,
                side: None,
                shape: boxed(&origin, lo, hi),
            });
        }
        parts.push(Part {
            kind: Kind::Pelvis,
            side: None,
            shape: boxed(&origin, self.pelvis_lo, self.pelvis_hi),
        });
        let head = Pose::translation(0.0, 0.0, robot.hip_to_neck_z)
            .compose(&Pose::rotation(Axis::Z, joints.get(Joint::HeadYaw)))
            .compose(&Pose::rotation(Axis::Y, joints.get(Joint::HeadPitch)));
        parts.push(Part {
            kind: Kind::Head,
            side: None,
            shape: Shape::Sphere(Sphere {
                centre: head.apply(&self.head_centre),
                radius: self.head_radius,
            }),
        });
        for side in Side::BOTH {
            parts.extend(posture::arm_parts(self, side, &self.arms));
        }
        PosedBody { parts }
    }
}

fn boxed(frame: &Pose<f64>, lo: [f64; 3], hi: [f64; 3]) -> Shape {
    let lo2 = std::array::from_fn(|k| lo[k].min(hi[k]));
    let hi2 = std::array::from_fn(|k| lo[k].max(hi[k]));
    Shape::Box(OrientedBox::in_frame(frame, lo2, hi2))
}

/// A posture for tests: the legs rolled 0.15 rad out, the left one raised with its sole
/// towards the head, the head pitched down and turned to it.
#[cfg(test)]
pub(crate) fn raised_left() -> JointAngles {
    let mut j = JointAngles::default();
    for (joint, q) in [
        (Joint::LHipRoll, 0.15),
        (Joint::RHipRoll, -0.15),
        (Joint::LHipPitch, -1.2),
        (Joint::LKneePitch, 0.3),
        (Joint::LAnklePitch, -0.9),
        (Joint::HeadPitch, 0.4),
        (Joint::HeadYaw, 0.3),
    ] {
        j.set(joint, q);
    }
    j
}
