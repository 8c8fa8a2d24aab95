//! The NAO V6's body as solids: one capsule, box or sphere per link, a little larger than
//! the real part, posed by the joint angles. The one model of the body that the planner
//! (self-collision, lines of sight past the body), the simulator (the robot drawn into its
//! own pictures) and detection (vertices next to an occluding edge) all read.
//!
//! The frames are the model's (docs/MODEL.md §1): `O` midway between the hip joints, the
//! legs by the nominal leg chain, the arms by the official URDF's arm chain
//! (ros-naoqi `nao_robot`, `naoV6` / `nao_description`: `LShoulderPitch` at (0, 98, 100) mm
//! from the `torso` frame, 85 mm above `O`; the elbow 105 mm along the upper arm and 15 mm
//! aside; the wrist 55.95 mm along the forearm). The sizes come from B-Human's SimRobot V6
//! scene (`Config/Scenes/Includes/NaoV6H25.rsi3`: a box or sphere per link) and the V6
//! datasheet's outline, grown by [`BodyModel::MARGIN`]; docs/BODY.md gives them part by
//! part.

mod contact;
pub mod posture;
pub mod shapes;

pub use contact::{
    Clearance, LegShapes, clearance, collision, contact, head_contact, leg_shapes, sight_blocked,
    sight_blocked_by_body,
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
    /// The hips' housing between the thighs.
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
        match self.side {
            Some(side) => format!("{} {}", side.name(), self.kind.name()),
            None => self.kind.name().to_string(),
        }
    }
}

/// The sizes of the body's solids (mm), each in its link's frame, grown by
/// [`BodyModel::MARGIN`] over the real part.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyModel {
    /// Radius of the thigh capsules (hip → knee).
    pub thigh_radius: f64,
    /// Radius of the tibia capsules (knee → ankle).
    pub tibia_radius: f64,
    /// Foot box (heel to the ball, the ankle's height) in the left sole frame: low corner
    /// (mirrored in y for the right foot).
    pub foot_lo: [f64; 3],
    /// Foot box: high corner.
    pub foot_hi: [f64; 3],
    /// Toe box (in front of the ball, lower) in the left sole frame: low corner.
    pub toe_lo: [f64; 3],
    /// Toe box: high corner.
    pub toe_hi: [f64; 3],
    /// The sandal plate's heel end (x in the sole frame) and thickness below the sole.
    pub sandal_heel: f64,
    /// Thickness of the sandal plate below the sole (mm).
    pub sandal_thickness: f64,
    /// The plate's margin around the printed pattern (mm).
    pub sandal_margin: f64,
    /// Torso box in `O`: low corner.
    pub torso_lo: [f64; 3],
    /// Torso box in `O`: high corner.
    pub torso_hi: [f64; 3],
    /// Pelvis box in `O`: low corner.
    pub pelvis_lo: [f64; 3],
    /// Pelvis box in `O`: high corner.
    pub pelvis_hi: [f64; 3],
    /// The head's sphere: centre in the HeadPitch frame and radius.
    pub head_centre: [f64; 3],
    /// Radius of the head's sphere.
    pub head_radius: f64,
    /// Radius of the shoulder spheres, centred on the shoulder joints.
    pub shoulder_radius: f64,
    /// Radius of the upper arm capsules (shoulder → elbow).
    pub upper_arm_radius: f64,
    /// Radius of the forearm capsules (elbow → fingertips).
    pub forearm_radius: f64,
    /// From the wrist to the fingertips along the hand (mm).
    pub hand_length: f64,
    /// The floor under the robot's back: nothing may reach below this `x_O`.
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
    /// The NAO V6 (H25), each part grown by [`BodyModel::MARGIN`].
    fn default() -> Self {
        BodyModel {
            thigh_radius: 37.0,
            tibia_radius: 35.0,
            foot_lo: [-60.0, -45.0, 0.0],
            foot_hi: [60.0, 55.0, 60.0],
            toe_lo: [60.0, -45.0, 0.0],
            toe_hi: [115.0, 55.0, 32.0],
            sandal_heel: -60.0,
            sandal_thickness: 8.0,
            sandal_margin: 20.0,
            torso_lo: [-62.0, -80.0, 45.0],
            torso_hi: [65.0, 80.0, 215.0],
            pelvis_lo: [-50.0, -45.0, -20.0],
            pelvis_hi: [50.0, 45.0, 45.0],
            head_centre: [0.0, 0.0, 60.0],
            head_radius: 80.0,
            shoulder_radius: 45.0,
            upper_arm_radius: 35.0,
            forearm_radius: 32.0,
            hand_length: 110.0,
            floor_x: -62.0,
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
            let leg = [
                (
                    Kind::Thigh,
                    Shape::Capsule(Capsule {
                        a: frames.hip.translation,
                        b: frames.knee.translation,
                        radius: self.thigh_radius,
                    }),
                ),
                (
                    Kind::Tibia,
                    Shape::Capsule(Capsule {
                        a: frames.knee.translation,
                        b: frames.ankle.translation,
                        radius: self.tibia_radius,
                    }),
                ),
                (
                    Kind::Foot,
                    boxed(sole, mirror(self.foot_lo), mirror(self.foot_hi)),
                ),
                (
                    Kind::Toe,
                    boxed(sole, mirror(self.toe_lo), mirror(self.toe_hi)),
                ),
                (Kind::Sandal, boxed(&board_frame, sandal_lo, sandal_hi)),
            ];
            parts.extend(leg.into_iter().map(|(kind, shape)| Part {
                kind,
                side: Some(side),
                shape,
            }));
        }
        let origin = Pose::identity();
        parts.push(Part {
            kind: Kind::Torso,
            side: None,
            shape: boxed(&origin, self.torso_lo, self.torso_hi),
        });
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
