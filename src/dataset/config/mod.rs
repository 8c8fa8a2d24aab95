//! `dataset.toml`: camera intrinsics, board and robot geometry (docs/MODEL.md §7).
//!
//! The file is a [`DatasetToml`], read and written with serde; every key is named once, in
//! that struct and its tables (`tables.rs`). [`validate`] (`check.rs`) is the one check of
//! a model's values (finite, and within the ranges a NAO can have), for models read from a
//! file and for models about to be written.

mod check;
mod tables;

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::dataset::settings::SettingsChanges;
use crate::model::{Board, Camera, CameraId, Model, RobotGeometry};

use super::error::{DatasetError, Location};
use super::toml_doc::TomlDoc;
use super::units::degrees_for;
use super::{AngleKind, AngleSource};
use check::check;
pub(crate) use check::validate;
use tables::{BoardToml, CameraToml, JointsToml, Numbers, RobotToml};

/// The content of `dataset.toml`.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct DatasetToml {
    /// The lower camera's intrinsics (required; an `Option` so that a missing table gets
    /// its own message).
    camera: Option<CameraToml>,
    /// The upper camera's intrinsics, when the dataset has upper-camera captures.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    upper_camera: Option<CameraToml>,
    #[serde(default)]
    board: BoardToml,
    #[serde(default)]
    robot: RobotToml,
    /// What the logged joint angles are; raw when absent.
    #[serde(default)]
    joints: JointsToml,
}

/// The table of `dataset.toml` that holds `camera`'s intrinsics and capture settings:
/// `camera` (the lower camera) or `upper_camera`.
pub fn camera_table(camera: CameraId) -> &'static str {
    match camera {
        CameraId::Lower => "camera",
        CameraId::Upper => "upper_camera",
    }
}

/// `board` as the `[board]` table of `dataset.toml`, written as a dataset writes it.
pub fn render_board(board: &Board) -> Result<String, toml::ser::Error> {
    #[derive(Serialize)]
    struct OnlyBoard {
        board: BoardToml,
    }
    toml::to_string(&OnlyBoard {
        board: BoardToml::from(board),
    })
}

/// A problem with one key: its TOML key path and what is wrong.
type KeyError = (String, String);

impl DatasetToml {
    /// The file for `model`, every value written out.
    fn from_model(model: &Model, angles: &AngleSource) -> Self {
        let mut robot = RobotToml::from(&model.robot);
        if model.upper_camera.is_some() {
            robot.upper_camera_offset_mm = Some(Numbers(model.robot.upper_camera_offset));
            robot.upper_camera_tilt_deg = Some(degrees_for(model.robot.upper_camera_tilt));
        }
        DatasetToml {
            camera: Some(CameraToml::from(&model.camera)),
            upper_camera: model.upper_camera.as_ref().map(CameraToml::from),
            board: BoardToml::from(&model.board),
            robot,
            joints: JointsToml {
                angles: angles.kind,
                corrected_by: angles.corrected_by.clone(),
            },
        }
    }

    /// The model this file describes (not yet validated), or the first key whose value has
    /// the wrong shape. Angles become radians and gravity a unit vector.
    fn into_model(self) -> Result<Model, KeyError> {
        let Some(c) = self.camera else {
            return Err((
                "camera".into(),
                "missing table [camera] (the lower camera's intrinsics: width, height, fx, fy, \
                 cx, cy)"
                    .into(),
            ));
        };
        let camera = Camera::from(c);
        let upper_camera = self.upper_camera.map(Camera::from);
        let b = self.board;
        let board = Board {
            squares_x: b.squares_x,
            squares_y: b.squares_y,
            square: b.square_mm,
            mount_origin: b.mount_origin_mm.0,
            mount_rpy: b.mount_rpy_deg.0.map(f64::to_radians),
            mass_g: b.mass_g,
            com_mm: b.com_mm.0,
        };
        let r = self.robot;
        let nominal = RobotGeometry::default();
        let robot = RobotGeometry {
            hip_offset_y: r.hip_offset_y_mm,
            hip_to_neck_z: r.hip_to_neck_z_mm,
            thigh: r.thigh_mm,
            tibia: r.tibia_mm,
            foot_height: r.foot_height_mm,
            lower_camera_offset: r.lower_camera_offset_mm.0,
            lower_camera_tilt: r.lower_camera_tilt_deg.to_radians(),
            upper_camera_offset: r
                .upper_camera_offset_mm
                .map_or(nominal.upper_camera_offset, |o| o.0),
            upper_camera_tilt: r
                .upper_camera_tilt_deg
                .map_or(nominal.upper_camera_tilt, f64::to_radians),
            gravity: unit_vector(r.gravity.0)?,
        };
        Ok(Model {
            robot,
            camera,
            board,
            upper_camera,
        })
    }
}

/// `g` scaled to length 1 (left as it is when it already has length 1 to within rounding,
/// so that a written model reads back bit for bit).
fn unit_vector(g: [f64; 3]) -> Result<[f64; 3], KeyError> {
    let norm = g.iter().map(|x| x * x).sum::<f64>().sqrt();
    if !(norm.is_finite() && norm > 0.0) {
        return Err((
            "robot.gravity".into(),
            format!(
                "must be a non-zero direction (e.g. [-1, 0, 0] for a NAO on its back), got \
                 [{}, {}, {}]",
                g[0], g[1], g[2]
            ),
        ));
    }
    if (norm - 1.0).abs() <= UNIT_TOLERANCE {
        return Ok(g);
    }
    Ok(g.map(|x| x / norm))
}

/// How far from 1 the length of a stored gravity direction may be.
const UNIT_TOLERANCE: f64 = 1e-12;

/// Reads a model from the content of `dataset.toml` at `path`, and validates it.
pub(crate) fn parse(path: &Path, bytes: &[u8]) -> Result<Model, DatasetError> {
    parse_with_angles(path, bytes).map(|(model, _)| model)
}

/// Reads a model and what its joint angles are from the content of `dataset.toml` at
/// `path`, and validates them.
pub(crate) fn parse_with_angles(
    path: &Path,
    bytes: &[u8],
) -> Result<(Model, AngleSource), DatasetError> {
    let doc = TomlDoc::new(path, bytes)?;
    let mut file: DatasetToml = doc.deserialize()?;
    let joints = std::mem::take(&mut file.joints);
    if joints.angles == AngleKind::Raw && joints.corrected_by.is_some() {
        return Err(doc.error(
            "joints.corrected_by",
            "is only meaningful with angles = \"corrected\" (raw angles were corrected by \
             nothing)",
        ));
    }
    let angles = AngleSource {
        kind: joints.angles,
        corrected_by: joints.corrected_by,
    };
    let at = |(key, message): KeyError| {
        if key == "camera" {
            // A missing table has no line.
            DatasetError::invalid(Location::file(path).field(key), message)
        } else {
            doc.error(&key, message)
        }
    };
    let model = file.into_model().map_err(at)?;
    check(&model).map_err(|(key, message)| doc.error(&key, message))?;
    Ok((model, angles))
}

/// The capture settings (flip, exposure, gain, white balance, frame rate) that
/// `dataset.toml` at `path` (content `bytes`) gives in `[camera]` (the lower camera) and
/// `[upper_camera]`, checked; what a table does not give is left to the defaults.
pub(crate) fn parse_settings(
    path: &Path,
    bytes: &[u8],
) -> Result<Vec<(CameraId, SettingsChanges)>, DatasetError> {
    let doc = TomlDoc::new(path, bytes)?;
    let file: DatasetToml = doc.deserialize()?;
    let mut out = Vec::new();
    for (id, table) in [
        (CameraId::Lower, &file.camera),
        (CameraId::Upper, &file.upper_camera),
    ] {
        let name = camera_table(id);
        if let Some(table) = table {
            let changes = table.settings();
            changes
                .check()
                .map_err(|(key, message)| doc.error(&format!("{name}.{key}"), message))?;
            out.push((id, changes));
        }
    }
    Ok(out)
}

/// `dataset.toml` for `model`, every value written out. Floats round-trip exactly; angles
/// are written in degrees chosen so that reading them back gives the same radians whenever
/// such a decimal exists.
pub(crate) fn render(model: &Model, angles: &AngleSource) -> Result<String, toml::ser::Error> {
    render_with_settings(model, angles, &[], &[])
}

/// [`render`], with each camera's capture settings (`settings`: the keys `flip`,
/// `exposure`, `gain`, `white_balance_k`, `fps` of its table, those it gives) and `notes`
/// as comment lines after the header (a camera without a table is left out).
pub(crate) fn render_with_settings(
    model: &Model,
    angles: &AngleSource,
    settings: &[(CameraId, SettingsChanges)],
    notes: &[String],
) -> Result<String, toml::ser::Error> {
    let mut file = DatasetToml::from_model(model, angles);
    for (id, changes) in settings {
        let table = match id {
            CameraId::Lower => file.camera.as_mut(),
            CameraId::Upper => file.upper_camera.as_mut(),
        };
        if let Some(table) = table {
            table.set_settings(changes);
        }
    }
    let body = toml::to_string(&file)?;
    let notes: String = notes
        .iter()
        .map(|n| format!("# {}\n", n.replace(['\n', '\r'], " ")))
        .collect();
    Ok(format!(
        "# naocalib dataset: lengths in mm, angles in degrees, masses in g; \
         distortion is OpenCV's [k1, k2, p1, p2, k3];\n# gravity is a direction in the origin \
         frame.\n{notes}\n{body}"
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    const MINIMAL: &str = "[camera]\nwidth = 640\nheight = 480\nfx = 562.5\nfy = 562.5\n\
                           cx = 324.0\ncy = 189\n";

    fn parse_str(text: &str) -> Result<Model, String> {
        parse(Path::new("d/dataset.toml"), text.as_bytes()).map_err(|e| e.to_string())
    }

    /// The capture settings of `[camera]` and `[upper_camera]`: read per camera, left out
    /// of the model (a file with them gives the same model), a value out of range refused
    /// with its key and line.
    #[test]
    fn camera_settings_are_read_per_camera_and_checked() {
        let path = Path::new("d/dataset.toml");
        let text = format!(
            "{MINIMAL}exposure = 900\nflip = false\n[upper_camera]\nwidth = 1280\n\
             height = 960\nfx = 1125\nfy = 1125\ncx = 640\ncy = 480\ngain = 300\n"
        );
        let settings = parse_settings(path, text.as_bytes()).unwrap();
        assert_eq!(settings.len(), 2);
        assert_eq!(settings[0].0, CameraId::Lower);
        assert_eq!(
            (settings[0].1.exposure, settings[0].1.flip),
            (Some(900), Some(false))
        );
        assert_eq!(
            (settings[1].0, settings[1].1.gain),
            (CameraId::Upper, Some(300))
        );
        assert_eq!(
            parse_str(&format!("{MINIMAL}exposure = 900\n")).unwrap(),
            parse_str(MINIMAL).unwrap()
        );
        let bad = format!("{MINIMAL}exposure = 2000000\n");
        let e = parse_settings(path, bad.as_bytes())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("camera.exposure") && e.contains("0 … 1048575"),
            "{e}"
        );
        assert!(e.contains("line 8"), "{e}");
    }

    /// The capture settings written into a camera's table read back as written, with
    /// the notes as comments; the model is the same as without them.
    #[test]
    fn settings_written_into_the_camera_tables_read_back() {
        let path = Path::new("d/dataset.toml");
        let mut model = Model::default();
        model.upper_camera = Some(model.camera);
        let lower = SettingsChanges {
            flip: Some(false),
            exposure: Some(1700),
            gain: Some(250),
            white_balance_k: None,
            fps: Some(30),
        };
        let upper = SettingsChanges {
            white_balance_k: Some(4000),
            ..lower
        };
        let text = render_with_settings(
            &model,
            &AngleSource::default(),
            &[(CameraId::Lower, lower), (CameraId::Upper, upper)],
            &["how\nthey were set".into()],
        )
        .unwrap();
        assert!(text.contains("\n# how they were set\n"), "{text}");
        assert_eq!(parse(path, text.as_bytes()).unwrap(), model);
        assert_eq!(
            parse_settings(path, text.as_bytes()).unwrap(),
            vec![(CameraId::Lower, lower), (CameraId::Upper, upper)]
        );
        assert_eq!(
            render_with_settings(&model, &AngleSource::default(), &[], &[]).unwrap(),
            render(&model, &AngleSource::default()).unwrap()
        );
    }

    #[test]
    fn minimal_file_gives_defaults() {
        let model = parse_str(MINIMAL).unwrap();
        assert_eq!(model, Model::default());
    }

    #[test]
    fn spec_example_gives_defaults() {
        let text = format!(
            "{MINIMAL}distortion = [0.0, 0.0, 0.0, 0.0, 0.0]\n\n[board]\nsquares_x = 7\n\
             squares_y = 5\nsquare_mm = 25.0\nmount_origin_mm = [170.0, 0.0, 0.0]\n\
             mount_rpy_deg = [0.0, 0.0, 0.0]\n\n[robot]\nhip_offset_y_mm = 50.0\n\
             hip_to_neck_z_mm = 211.5\nthigh_mm = 100.0\ntibia_mm = 102.9\n\
             foot_height_mm = 45.19\nlower_camera_offset_mm = [50.71, 0.0, 17.74]\n\
             lower_camera_tilt_deg = 39.7\n"
        );
        assert_eq!(parse_str(&text).unwrap(), Model::default());
    }

    #[test]
    fn upper_camera_table_and_mount() {
        let m = parse_str(MINIMAL).unwrap();
        assert_eq!(m.upper_camera, None);
        let text = format!(
            "{MINIMAL}[upper_camera]\nwidth = 1280\nheight = 960\nfx = 1100\nfy = 1100\n\
             cx = 640\ncy = 480\n[robot]\nupper_camera_tilt_deg = 2\n"
        );
        let m = parse_str(&text).unwrap();
        let upper = m.upper_camera.unwrap();
        assert_eq!(
            (upper.width, upper.fx, upper.distortion),
            (1280, 1100.0, [0.0; 5])
        );
        assert_eq!(m.robot.upper_camera_tilt, 2f64.to_radians());
        assert_eq!(m.robot.upper_camera_offset, [58.71, 0.0, 63.64]);
        // Written with the table and the mount, read back the same.
        let written = render(&m, &AngleSource::default()).unwrap();
        assert!(written.contains("[upper_camera]") && written.contains("upper_camera_offset_mm"));
        assert_eq!(parse_str(&written).unwrap(), m);
        // A model without an upper camera is written without either.
        let written = render(&Model::default(), &AngleSource::default()).unwrap();
        assert!(!written.contains("upper"), "{written}");
        let e = parse_str(&text.replace("fx = 1100", "fx = 1")).unwrap_err();
        assert!(
            e.contains("line 11, field upper_camera.fx: must be 50 … 20000 px"),
            "{e}"
        );
    }

    #[test]
    fn overrides_and_degrees() {
        let text = format!(
            "{MINIMAL}distortion = [0.1, -0.2, 0.001, 0.002, 0.03]\n[board]\nsquares_x = 9\n\
             mount_rpy_deg = [90, 0, -45.0]\n[robot]\nthigh_mm = 101\nlower_camera_tilt_deg = 40\n"
        );
        let m = parse_str(&text).unwrap();
        assert_eq!(m.camera.distortion, [0.1, -0.2, 0.001, 0.002, 0.03]);
        assert_eq!(m.board.squares_x, 9);
        assert_eq!(m.board.squares_y, 5);
        assert_eq!(
            m.board.mount_rpy,
            [90f64.to_radians(), 0.0, (-45f64).to_radians()]
        );
        assert_eq!(m.robot.thigh, 101.0);
        assert_eq!(m.robot.tibia, 102.9);
        assert_eq!(m.robot.lower_camera_tilt, 40f64.to_radians());
    }

    #[test]
    fn errors() {
        let cases = [
            ("", "d/dataset.toml, field camera: missing table [camera]"),
            (
                "[camera]\nwidth = 1\n",
                "d/dataset.toml line 1, field camera.height: [camera] has no key",
            ),
            (
                "foo = 1\n",
                "d/dataset.toml line 1, field foo: unknown key 'foo' at the top level",
            ),
            (
                &format!("{MINIMAL}focal = 3\n"),
                "d/dataset.toml line 8, field camera.focal: unknown key 'focal' in [camera]",
            ),
            (
                &MINIMAL.replace("640", "0"),
                "line 2, field camera.width: must be 16 … 8192 px, got 0",
            ),
            (
                &MINIMAL.replace("fy = 562.5", "fy = -1"),
                "line 5, field camera.fy: must be 50 … 20000 px (a camera's focal length), got -1",
            ),
            (
                &MINIMAL.replace("cx = 324.0", "cx = nan"),
                "line 6, field camera.cx: nan is not a finite",
            ),
            (
                &format!("{MINIMAL}distortion = [0, 0, 0, 0]\n"),
                "line 8, field camera.distortion: expected exactly 5 numbers, found 4",
            ),
            (
                &format!("{MINIMAL}[board]\nsquares_y = 1\n"),
                "line 9, field board.squares_y: must be 3 … 64 squares",
            ),
            (
                &format!("{MINIMAL}[board]\nsquare_mm = 0\n"),
                "line 9, field board.square_mm: must be 1 … 500 mm, got 0",
            ),
            (
                &format!("{MINIMAL}[robot]\nthigh_mm = inf\n"),
                "line 9, field robot.thigh_mm: inf is not a finite",
            ),
            (
                &format!("{MINIMAL}[robot]\nknee = 1\n"),
                "line 9, field robot.knee: unknown key 'knee' in [robot]",
            ),
            (
                &format!("{MINIMAL}board = 3\n"),
                "line 8, field camera.board: unknown key",
            ),
            (
                "camera = 3\n",
                "line 1, field camera: expected a table, found an integer",
            ),
            (
                &MINIMAL.replace("640", "'640'"),
                "line 2, field camera.width: expected an integer, found a string",
            ),
        ];
        for (text, expected) in cases {
            let e = parse_str(text).unwrap_err();
            assert!(e.contains(expected), "{e:?} should contain {expected:?}");
        }
    }

    #[test]
    fn render_round_trips() {
        let mut model = Model::default();
        model.camera.distortion = [0.1, -1e-7, 3.0, 1e20, -0.0];
        model.camera.width = 1280;
        model.board.mount_rpy = [
            10f64.to_radians(),
            -0.2f64.to_radians(),
            180f64.to_radians(),
        ];
        model.board.mount_origin = [1.0 / 3.0, 2.5, -7.0];
        model.robot.lower_camera_tilt = 39.5f64.to_radians();
        let text = render(&model, &AngleSource::default()).unwrap();
        let back = parse(Path::new("x"), text.as_bytes()).unwrap();
        assert_eq!(back, model);
        assert!(
            render(&Model::default(), &AngleSource::default())
                .unwrap()
                .contains("lower_camera_tilt_deg = 39.7\n"),
            "{text}"
        );
    }

    #[test]
    fn physical_ranges_name_line_and_key() {
        let cases = [
            (
                "[camera]\nwidth = 640\nheight = 480\nfx = 1e9\nfy = 562.5\ncx = 324\ncy = 189\n",
                "d/dataset.toml line 4, field camera.fx: must be 50 … 20000 px",
            ),
            (
                &MINIMAL.replace("cx = 324.0", "cx = 1000"),
                "d/dataset.toml line 6, field camera.cx: must be -320 … 960 px (the principal \
                 point lies within the image ± 50 %), got 1000",
            ),
            (
                &MINIMAL.replace("height = 480", "height = 100000"),
                "d/dataset.toml line 3, field camera.height: must be 16 … 8192 px, got 100000",
            ),
            (
                &format!("{MINIMAL}[robot]\nthigh_mm = 0\n"),
                "d/dataset.toml line 9, field robot.thigh_mm: must be 1 … 1000 mm (a link length)",
            ),
            (
                &format!("{MINIMAL}[robot]\ngravity = [0, 0, 0]\n"),
                "d/dataset.toml line 9, field robot.gravity: must be a non-zero direction",
            ),
            (
                &format!("{MINIMAL}[robot]\ngravity = [0, 1]\n"),
                "d/dataset.toml line 9, field robot.gravity: expected exactly 3 numbers, found 2",
            ),
            (
                &format!("{MINIMAL}[board]\nmass_g = -5\n"),
                "d/dataset.toml line 9, field board.mass_g: must be 0 … 10000 g, got -5",
            ),
            (
                &format!("{MINIMAL}[board]\ncom_mm = [1, 2, nan]\n"),
                "d/dataset.toml line 9, field board.com_mm[2]: nan is not a finite number",
            ),
            (
                &format!("{MINIMAL}[board]\nmount_rpy_deg = [0, 0, 720]\n"),
                "d/dataset.toml line 9, field board.mount_rpy_deg[2]: must be within ±360 °",
            ),
        ];
        for (text, expected) in cases {
            let e = parse_str(text).unwrap_err();
            assert!(
                e.starts_with(expected),
                "{e:?} should start with {expected:?}"
            );
        }
    }

    #[test]
    fn gravity_mass_and_centre_of_mass() {
        let text = format!(
            "{MINIMAL}[board]\nmass_g = 95.5\ncom_mm = [140, -2, 3.5]\n[robot]\n\
             gravity = [0, -3, 4]\n"
        );
        let m = parse_str(&text).unwrap();
        assert_eq!(m.board.mass_g, 95.5);
        assert_eq!(m.board.com_mm, [140.0, -2.0, 3.5]);
        assert_eq!(m.robot.gravity, [0.0, -0.6, 0.8], "stored as a unit vector");
        // Written and read again: the very same bits.
        let mut m = m;
        m.robot.gravity = [1.0, 1.0, 1.0].map(|x: f64| x / 3f64.sqrt());
        let back = parse(
            Path::new("x"),
            render(&m, &AngleSource::default()).unwrap().as_bytes(),
        )
        .unwrap();
        assert_eq!(back, m);
        assert_eq!(
            back.robot.gravity.map(f64::to_bits),
            m.robot.gravity.map(f64::to_bits)
        );
    }

    #[test]
    fn joint_angle_source_reads_back_and_is_checked() {
        let corrected = AngleSource {
            kind: AngleKind::Corrected,
            corrected_by: Some("jointCalibration.cfg".into()),
        };
        let text = render(&Model::default(), &corrected).unwrap();
        let (_, back) = parse_with_angles(Path::new("x"), text.as_bytes()).unwrap();
        assert_eq!(back, corrected);
        let minimal =
            "[camera]\nwidth = 640\nheight = 480\nfx = 560.0\nfy = 560.0\ncx = 320.0\ncy = 240.0\n";
        let (_, absent) = parse_with_angles(Path::new("x"), minimal.as_bytes()).unwrap();
        assert_eq!(absent.kind, AngleKind::Raw);
        let wrong = format!("{minimal}[joints]\nangles = \"raw\"\ncorrected_by = \"x\"\n");
        let e = parse_with_angles(Path::new("x"), wrong.as_bytes()).unwrap_err();
        assert!(e.to_string().contains("corrected_by"), "{e}");
        let bad = format!("{minimal}[joints]\nangles = \"cooked\"\n");
        let e = parse_with_angles(Path::new("x"), bad.as_bytes()).unwrap_err();
        assert!(e.to_string().contains("angles"), "{e}");
    }
}
