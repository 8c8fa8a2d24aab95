//! What the judgement of a camera's pictures, and of one picture, concludes: the rule that
//! calls a camera's pictures turned, and what the user is told.

use std::fmt;

use crate::dataset::camera_table;
use crate::model::CameraId;
use crate::robot::camera::settings::CameraSettings;

/// Fewest boards of a camera before its pictures are judged.
pub const MIN_BOARDS: usize = 3;
/// Most boards of a camera the hypotheses are fitted to (spread over its captures).
pub const MAX_BOARDS: usize = 20;
/// How many times the upright hypothesis's RMS must exceed the turned one's.
pub const RATIO: f64 = 3.0;
/// Least RMS (px, in a picture 640 pixels wide; in proportion for other sizes) that the
/// upright hypothesis leaves before a camera is called turned: pictures the model explains
/// better as taken are upright.
pub const MIN_UPRIGHT_PX: f64 = 3.0;
/// Most (deg) the turned hypothesis's fit may turn the camera from the prediction (the
/// largest correction of a real robot's camera, about 10°, with head offsets): beyond it,
/// neither hypothesis explains the boards.
pub const MAX_FIT_DEG: f64 = 25.0;

/// How the two hypotheses explain one camera's boards.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Turned {
    /// The camera.
    pub camera: CameraId,
    /// Its boards found (at most [`MAX_BOARDS`] of them fitted).
    pub boards: usize,
    /// RMS (px per coordinate) of its vertices against the fitted model, the pictures as
    /// taken.
    pub upright_px: f64,
    /// The same with the pictures turned back by 180°.
    pub turned_px: f64,
    /// How far (deg) the fit of the turned hypothesis turned the camera from the
    /// prediction.
    pub turned_deg: f64,
    /// The camera's picture width (px).
    pub width: u32,
}

impl Turned {
    /// Whether the camera's pictures are turned by 180° (see the module's rule).
    pub fn is_turned(&self) -> bool {
        let scale = f64::from(self.width) / 640.0;
        self.boards >= MIN_BOARDS
            && self.upright_px > MIN_UPRIGHT_PX * scale
            && self.upright_px > RATIO * self.turned_px
            && self.turned_deg <= MAX_FIT_DEG
    }

    /// The flip the camera needs (both flips of its sensor set or clear): the V6's
    /// defaults, which capture applies unless told otherwise.
    pub fn needed_flip(&self) -> bool {
        CameraSettings::defaults(self.camera, self.width, 0).flip
    }
}

impl fmt::Display for Turned {
    /// What a user is told of a turned camera: the evidence and what to set.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "the {} camera's pictures are turned by 180°: its {} boards fit the model to \
             {:.1} px turned back but only to {:.1} px as taken. Its sensor's flip was not \
             as the camera needs when they were taken: set `flip = {}` in [{}] of \
             dataset.toml (both flips of the sensor, UVC extension unit 3, selectors 12 and \
             13; the opposite of what it was if this robot's sensor is mounted otherwise) \
             and take the pictures again; no calibration is given from these pictures",
            self.camera.name(),
            self.boards,
            self.turned_px,
            self.upright_px,
            self.needed_flip(),
            camera_table(self.camera)
        )
    }
}

/// What the judgement of one picture on its own says.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PictureTurn {
    /// Its board fits the model turned back by 180° far better than as taken, the model
    /// fitted to the camera's other boards: the picture is turned (RMS in px as taken,
    /// turned back).
    Turned {
        /// RMS (px per coordinate) as taken.
        upright_px: f64,
        /// RMS turned back by 180°.
        turned_px: f64,
    },
    /// Too few boards of its camera to judge whether it is turned (the boards found).
    Unjudged {
        /// The camera's boards found.
        boards: usize,
    },
}

impl fmt::Display for PictureTurn {
    /// What a user is told of one picture.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            PictureTurn::Turned {
                upright_px,
                turned_px,
            } => write!(
                f,
                "the picture is turned by 180°: its board fits the model to {turned_px:.1} px \
                 turned back but only to {upright_px:.1} px as taken (the camera's other \
                 boards fitted); left out"
            ),
            PictureTurn::Unjudged { boards } => write!(
                f,
                "whether the picture is turned by 180° cannot be judged: its camera has \
                 {boards} board(s), at least {MIN_BOARDS} are needed (the pattern looks the same \
                 turned)"
            ),
        }
    }
}
