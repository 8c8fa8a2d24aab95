//! The bounds a planned capture must keep on a real, not yet calibrated robot
//! ([`Feasibility`]): margins from the joint limits, the box of offsets the board must stay
//! in view for, what the image must show, and the body planned past. [`super::feasible`]
//! checks captures against them, [`super::view`] the view.

use super::collision::BodyModel;
use crate::model::{CameraId, Joint, PARAMETER_COUNT};

/// How far the planned captures must stay from the limits of what can be seen and reached.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Feasibility {
    /// Distance of every planned angle from its joint's mechanical limit (rad).
    pub joint_margin: f64,
    /// The board must stay in view for every angle offset (camera rotation, head and leg
    /// joints, sandal rotation) within ± this (rad) …
    pub offset_angle: f64,
    /// … and every sandal mounting translation within ± this (mm) …
    pub offset_length: f64,
    /// … and the head joint offsets (not part of the paper's model, held at zero by
    /// default) within ± this (rad).
    pub head_offset: f64,
    /// Smallest distance of a vertex from the image border (px).
    pub margin_px: f64,
    /// Smallest projected square edge at the nominal model (px).
    pub min_square_px: f64,
    /// Largest angle between the board normal and the line of sight (rad).
    pub max_view_angle: f64,
    /// For upper-camera captures, the bound (rad, and mm for the sandal translations)
    /// that replaces [`Feasibility::offset_angle`] and [`Feasibility::offset_length`]:
    /// lying on its back the NAO sees a sandal through its upper camera only from
    /// 220–390 mm, where the board spans most of the image, so a ±3° box admits no
    /// capture; the box is centred on the robot's calibration
    /// ([`Feasibility::centre`]), whose offsets are known far better than ±3°. Default
    /// 0.5°: around a robot whose upper camera pitch correction is −8.5° (the median of
    /// SPQR's per-robot files), ±1° leaves 0–2 feasible stances per 6000 drawn per leg,
    /// ±0.5° 14–15; a board that a larger miss moves partly out of the image is detected
    /// partly or dropped by `detect`, never a safety matter.
    pub upper_offset: f64,
    /// For upper-camera captures, the distance of the head joints from their limits (rad),
    /// in place of [`Feasibility::joint_margin`]: the upper camera sees a sandal only with
    /// the head pitched near its ceiling, and a robot whose upper camera pitch correction
    /// is a team-sized −8.5° (the camera looks 8.5° higher than nominal) would have none
    /// left under a 5° margin. The head's
    /// offsets are bounded by [`Feasibility::head_offset`] (0.5°), and capture refuses a
    /// posture within 2° of a limit, so 2° keeps every commanded head angle safe.
    pub upper_head_margin: f64,
    /// The collision model.
    pub body: BodyModel,
    /// Plan past the robot's own body (`naocalib plan`, unless `--ignore-body`): a capture
    /// is kept only when at least [`MIN_IN_SIGHT`] of its board's vertices have their
    /// refinement window in plain sight past this body model ([`crate::body::sight`], at
    /// [`Feasibility::centre`]), and only those vertices count in its information; its
    /// posture touches nothing in this model (the resting leg parked where it does not),
    /// and the straight move from rest touches nothing either. `None` (the default here,
    /// `plan --ignore-body`): every vertex counts, and only the resting leg is held
    /// against the lines of sight.
    pub sight: Option<crate::body::BodyModel>,
    /// The robot's current calibration (internal units) the box of offsets is centred on
    /// (`naocalib plan --around`); zero by default. Real lower-camera tilt corrections of
    /// −2° to −8° lie outside a ±3° box around zero.
    pub centre: [f64; PARAMETER_COUNT],
}

impl Default for Feasibility {
    /// Joint margin 5° (more than the offsets of ±3°), offsets ±3° and ±3 mm (head ±0.5°,
    /// the simulator's realistic range), vertices 12 px
    /// from the border, squares of at least 14 px, boards seen at most 60° off their normal.
    fn default() -> Self {
        Feasibility {
            joint_margin: 5f64.to_radians(),
            offset_angle: 3f64.to_radians(),
            offset_length: 3.0,
            head_offset: 0.5f64.to_radians(),
            margin_px: 12.0,
            min_square_px: 14.0,
            max_view_angle: 60f64.to_radians(),
            upper_offset: 0.5f64.to_radians(),
            upper_head_margin: 2f64.to_radians(),
            body: BodyModel::default(),
            sight: None,
            centre: [0.0; PARAMETER_COUNT],
        }
    }
}

/// The fraction of a board's vertices a capture planned past the body
/// ([`Feasibility::sight`]) must leave in plain sight.
pub const MIN_IN_SIGHT: f64 = 0.5;

impl Feasibility {
    /// The body the camera sees the boards past, at the centre, when planning past it.
    pub fn past_body(&self) -> Option<super::information::PastBody<'_>> {
        self.sight
            .as_ref()
            .map(|body| super::information::PastBody {
                body,
                params: &self.centre,
            })
    }

    /// The distance of `joint` from its limits for a capture by `camera`:
    /// [`Feasibility::upper_head_margin`] for the head in upper-camera captures,
    /// [`Feasibility::joint_margin`] otherwise.
    pub fn margin(&self, camera: CameraId, joint: Joint) -> f64 {
        match (camera, joint) {
            (CameraId::Upper, Joint::HeadYaw | Joint::HeadPitch) => self.upper_head_margin,
            _ => self.joint_margin,
        }
    }
}
