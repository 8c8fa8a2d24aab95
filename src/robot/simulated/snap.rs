//! The simulated robot's cameras: what the lower or the upper camera sees of the robot in
//! a state file, set as a V6 camera is (its sensor's flip, exposure and gain).

use std::path::Path;

use crate::model::{CameraId, JointAngles, Model, PARAMETER_COUNT, Side};
use crate::output::{WriteOptions, write_atomic};
use crate::sim::render::{self, RenderOptions};

use super::{RobotError, State};

/// How the simulated robot's camera is set when [`snap`] takes a picture, as a V6 camera
/// is (`simulate-robot snap`'s `--flip`, `--exposure`, `--gain`; `capture` gives them to
/// its `command:` camera as `{flip}`, `{exposure}`, `{gain}`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SnapSettings {
    /// Both sensor flips set. The V6's upper sensor is mounted turned by 180°, so its
    /// picture is upright only flipped, the lower's only unflipped
    /// ([`crate::robot::camera::settings::CameraSettings::defaults`]). False: the
    /// registers as the sensor starts.
    pub flip: bool,
    /// Manual exposure and gain (the driver's units); `None`: automatic exposure (the
    /// scene as rendered).
    pub manual: Option<(u32, u32)>,
}

/// The brightness of the simulated `camera`'s picture relative to the scene as rendered,
/// at manual `exposure` and `gain`: their product over the product of the camera's team
/// settings (rUNSWift's, naocalib's defaults), so that those give the rendered scene —
/// the scene each camera sees is lit as the teams' values expect — and the brightness
/// scales with exposure × gain (a sensor's response, linear until it saturates).
pub fn exposure_factor(camera: CameraId, exposure: u32, gain: u32) -> f64 {
    let team = crate::robot::camera::settings::CameraSettings::defaults(camera, 0, 0);
    (f64::from(exposure) * f64::from(gain)) / (f64::from(team.exposure) * f64::from(team.gain))
}

/// Renders what `camera` of the robot in `state` (read from `state_path`) sees (the sandal
/// in view, the one whose centre is nearest the image centre; the true intrinsics of the
/// lower camera, the `[upper_camera]` ones of the upper), as its sensor set to `settings`
/// gives it — turned by 180° unless flipped as the camera's mounting needs, brightened or
/// darkened by [`exposure_factor`] — and writes it as PNG to `out` (replacing a picture
/// there, never the state file or the `dataset.toml` it names).
pub fn snap(
    state: &State,
    state_path: &Path,
    camera: CameraId,
    settings: &SnapSettings,
    out: &Path,
    options: &RenderOptions,
) -> Result<(), RobotError> {
    let write = WriteOptions::new(true)
        .protecting([state_path.to_path_buf()])
        .protecting(state.config.clone());
    crate::output::check_writable(out, &write)?;
    let model = crate::dataset::read_model_or_unconfigured(state.config.as_deref())?;
    if camera == CameraId::Upper && model.upper_camera.is_none() {
        return Err(RobotError::Read {
            path: state
                .config
                .clone()
                .unwrap_or_else(|| state_path.to_path_buf()),
            message: "names no upper camera ([upper_camera] of dataset.toml): nothing to \
                      render the upper camera's view with"
                .into(),
        });
    }
    let truth: [f64; PARAMETER_COUNT] = std::array::from_fn(|k| state.truth[k]);
    let model = Model {
        camera: model.intrinsics_at(camera, &truth),
        ..model
    };
    let joints = JointAngles::from_fn(|j| state.joints[j.index()]);
    let (cx, cy) = (
        model.camera.width as f64 / 2.0,
        model.camera.height as f64 / 2.0,
    );
    let side = Side::BOTH
        .into_iter()
        .filter_map(|side| {
            let pose = model
                .chains_for(camera, side, &joints)
                .camera_to_board(&truth);
            let uv = model.camera.project(&pose.translation)?;
            model
                .camera
                .contains(uv, 0.0)
                .then(|| (side, (uv[0] - cx).hypot(uv[1] - cy)))
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map_or(Side::Left, |(s, _)| s);
    let pose = model
        .chains_for(camera, side, &joints)
        .camera_to_board(&truth);
    // The noise of the picture follows the posture (to 1e-7 rad) and the camera, not the
    // cycle it is taken in, so that a run gives the same pictures however fast the robot
    // is played.
    let posture = state.joints.iter().fold(0u64, |h, q| {
        (h ^ ((q * 1e7).round() as i64 as u64)).wrapping_mul(0x0100_0000_01B3)
    });
    let seed = state.seed
        ^ posture.wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ (camera as u64).wrapping_mul(0xD1B5_4A32_D192_ED03);
    // The body drawn with its arms where the robot holds them (a state without them: the
    // body model's own arm posture).
    let view = options.body.as_ref().map(|body| {
        let mut body = *body;
        if let Ok(arms) = <[f64; 10]>::try_from(state.arms.as_slice()) {
            body.arms = crate::body::ArmPosture(arms);
        }
        crate::sim::scene::body_view(&model, &body, camera, side, &joints, &truth)
    });
    let mut image = render::render_with(&model, &pose, view.as_ref(), options, seed)?;
    let upright = crate::robot::camera::settings::CameraSettings::defaults(camera, 0, 0).flip;
    if settings.flip != upright {
        image.turn_half();
    }
    if let Some((exposure, gain)) = settings.manual {
        image.expose(exposure_factor(camera, exposure, gain));
    }
    let bytes = image
        .to_png()
        .map_err(|message| render::RenderError::Encode {
            path: out.to_path_buf(),
            message,
        })?;
    write_atomic(out, &bytes, &write)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The simulated cameras as a V6's: the upper picture upright only flipped, the lower
    /// only unflipped (else turned by 180°); at the team exposure and gain the scene as
    /// rendered, at the old 100 × 32 near black, twice the product twice as bright.
    #[test]
    fn snapped_pictures_obey_the_flip_and_the_exposure() {
        use crate::robot::camera::{decode_grey, settings::Brightness};
        let dir = tempfile::tempdir().unwrap();
        let cfg = dir.path().join("cfg");
        let mut model = Model::default();
        model.upper_camera = Some(model.camera);
        crate::dataset::Dataset::new(&cfg, model)
            .write(&cfg, false)
            .unwrap();
        let state_path = dir.path().join("state.json");
        let state = State {
            config: Some(cfg.join("dataset.toml")),
            truth: vec![0.0; PARAMETER_COUNT],
            joints: vec![0.0; crate::model::JOINT_COUNT],
            cycle: 0,
            seed: 3,
            stiffness: Vec::new(),
            arms: Vec::new(),
        };
        let mut n = 0;
        let mut snap_with = |camera, flip, manual| {
            n += 1;
            let out = dir.path().join(format!("{n}.png"));
            let settings = SnapSettings { flip, manual };
            snap(
                &state,
                &state_path,
                camera,
                &settings,
                &out,
                &RenderOptions::default(),
            )
            .unwrap();
            decode_grey(&std::fs::read(&out).unwrap(), (640, 480))
                .unwrap()
                .1
        };
        let upright = snap_with(CameraId::Upper, true, None);
        let mut turned = snap_with(CameraId::Upper, false, None);
        assert_ne!(turned, upright);
        turned.reverse();
        assert_eq!(
            turned, upright,
            "unflipped, the upper picture is turned by 180°"
        );
        assert_eq!(snap_with(CameraId::Upper, true, Some((700, 800))), upright);
        let old = Brightness::of_grey(&snap_with(CameraId::Upper, true, Some((100, 32))));
        assert!(
            old.mean < crate::robot::camera::settings::DARK_MEAN,
            "{old:?}"
        );
        let team = Brightness::of_grey(&upright).mean;
        assert!(team > 60.0 && team < 200.0, "{team}");
        let lower = snap_with(CameraId::Lower, false, Some((1700, 250)));
        let mut flipped = snap_with(CameraId::Lower, true, Some((850, 250)));
        flipped.reverse();
        for (half, full) in flipped.iter().zip(&lower) {
            assert!((f64::from(*half) - f64::from(*full) / 2.0).abs() <= 0.5 + 1e-9);
        }
        assert!((exposure_factor(CameraId::Upper, 1400, 800) - 2.0).abs() < 1e-12);
    }
}
