//! `dataset.toml`: camera intrinsics, board and robot geometry (SPEC section 6).

use std::fmt::Write as _;
use std::path::Path;

use crate::model::{Board, Camera, Model, RobotGeometry};

use super::error::{DatasetError, Location};
use super::toml_doc::{Table, TomlDoc};
use super::units::{degrees_for, toml_float};

const CAMERA_KEYS: [&str; 7] = ["width", "height", "fx", "fy", "cx", "cy", "distortion"];
const BOARD_KEYS: [&str; 5] = [
    "squares_x",
    "squares_y",
    "square_mm",
    "mount_origin_mm",
    "mount_rpy_deg",
];
const ROBOT_KEYS: [&str; 7] = [
    "hip_offset_y_mm",
    "hip_to_neck_z_mm",
    "thigh_mm",
    "tibia_mm",
    "foot_height_mm",
    "lower_camera_offset_mm",
    "lower_camera_tilt_deg",
];

/// Reads a model from the content of `dataset.toml` at `path`.
pub(crate) fn parse(path: &Path, bytes: &[u8]) -> Result<Model, DatasetError> {
    let doc = TomlDoc::new(path, bytes)?;
    let parsed = doc.parse()?;
    let root = doc.root(&parsed);
    root.deny_unknown(&["camera", "board", "robot"])?;
    let camera = match root.table("camera")? {
        Some(table) => camera(&table)?,
        None => {
            return Err(DatasetError::invalid(
                Location::file(path).field("camera"),
                "missing table [camera] (the lower camera's intrinsics: width, height, fx, fy, \
                 cx, cy)",
            ));
        }
    };
    let board = match root.table("board")? {
        Some(table) => board(&table)?,
        None => Board::default(),
    };
    let robot = match root.table("robot")? {
        Some(table) => robot(&table)?,
        None => RobotGeometry::default(),
    };
    Ok(Model {
        robot,
        camera,
        board,
    })
}

fn camera(t: &Table<'_, '_>) -> Result<Camera, DatasetError> {
    t.deny_unknown(&CAMERA_KEYS)?;
    Ok(Camera {
        width: t.require("width")?.u32_at_least(1)?,
        height: t.require("height")?.u32_at_least(1)?,
        fx: t.require("fx")?.positive()?,
        fy: t.require("fy")?.positive()?,
        cx: t.require("cx")?.f64()?,
        cy: t.require("cy")?.f64()?,
        distortion: match t.get("distortion") {
            Some(v) => v.f64_array::<5>()?,
            None => [0.0; 5],
        },
    })
}

fn board(t: &Table<'_, '_>) -> Result<Board, DatasetError> {
    t.deny_unknown(&BOARD_KEYS)?;
    let mut board = Board::default();
    if let Some(v) = t.get("squares_x") {
        board.squares_x = v.u32_at_least(2)?;
    }
    if let Some(v) = t.get("squares_y") {
        board.squares_y = v.u32_at_least(2)?;
    }
    if let Some(v) = t.get("square_mm") {
        board.square = v.positive()?;
    }
    if let Some(v) = t.get("mount_origin_mm") {
        board.mount_origin = v.f64_array::<3>()?;
    }
    if let Some(v) = t.get("mount_rpy_deg") {
        board.mount_rpy = v.f64_array::<3>()?.map(f64::to_radians);
    }
    Ok(board)
}

fn robot(t: &Table<'_, '_>) -> Result<RobotGeometry, DatasetError> {
    t.deny_unknown(&ROBOT_KEYS)?;
    let mut robot = RobotGeometry::default();
    let lengths = [
        ("hip_offset_y_mm", &mut robot.hip_offset_y),
        ("hip_to_neck_z_mm", &mut robot.hip_to_neck_z),
        ("thigh_mm", &mut robot.thigh),
        ("tibia_mm", &mut robot.tibia),
        ("foot_height_mm", &mut robot.foot_height),
    ];
    for (key, slot) in lengths {
        if let Some(v) = t.get(key) {
            *slot = v.f64()?;
        }
    }
    if let Some(v) = t.get("lower_camera_offset_mm") {
        robot.lower_camera_offset = v.f64_array::<3>()?;
    }
    if let Some(v) = t.get("lower_camera_tilt_deg") {
        robot.lower_camera_tilt = v.f64()?.to_radians();
    }
    Ok(robot)
}

/// Checks a model in memory against the same rules as [`parse`]; errors name `path` and the
/// TOML key.
pub(crate) fn validate(path: &Path, model: &Model) -> Result<(), DatasetError> {
    let fail = |key: &str, message: String| {
        Err(DatasetError::invalid(
            Location::file(path).field(key),
            message,
        ))
    };
    let Model {
        robot,
        camera,
        board,
    } = model;
    let finite = |key: &str, values: &[f64]| -> Result<(), DatasetError> {
        match values.iter().position(|x| !x.is_finite()) {
            None => Ok(()),
            Some(i) if values.len() == 1 => {
                fail(key, format!("{} is not a finite number", values[i]))
            }
            Some(i) => fail(
                &format!("{key}[{i}]"),
                format!("{} is not a finite number", values[i]),
            ),
        }
    };
    for (key, n) in [
        ("camera.width", camera.width),
        ("camera.height", camera.height),
    ] {
        if n == 0 {
            return fail(key, "must be at least 1, got 0".into());
        }
    }
    for (key, x) in [("camera.fx", camera.fx), ("camera.fy", camera.fy)] {
        finite(key, &[x])?;
        if x <= 0.0 {
            return fail(key, format!("must be greater than 0, got {x}"));
        }
    }
    finite("camera.cx", &[camera.cx])?;
    finite("camera.cy", &[camera.cy])?;
    finite("camera.distortion", &camera.distortion)?;
    for (key, n) in [
        ("board.squares_x", board.squares_x),
        ("board.squares_y", board.squares_y),
    ] {
        if n < 2 {
            return fail(key, format!("must be at least 2, got {n}"));
        }
    }
    finite("board.square_mm", &[board.square])?;
    if board.square <= 0.0 {
        return fail(
            "board.square_mm",
            format!("must be greater than 0, got {}", board.square),
        );
    }
    finite("board.mount_origin_mm", &board.mount_origin)?;
    finite("board.mount_rpy_deg", &board.mount_rpy)?;
    finite("robot.hip_offset_y_mm", &[robot.hip_offset_y])?;
    finite("robot.hip_to_neck_z_mm", &[robot.hip_to_neck_z])?;
    finite("robot.thigh_mm", &[robot.thigh])?;
    finite("robot.tibia_mm", &[robot.tibia])?;
    finite("robot.foot_height_mm", &[robot.foot_height])?;
    finite("robot.lower_camera_offset_mm", &robot.lower_camera_offset)?;
    finite("robot.lower_camera_tilt_deg", &[robot.lower_camera_tilt])
}

/// `dataset.toml` for `model`, every value written out. Floats round-trip exactly; angles
/// are written in degrees chosen so that reading them back gives the same radians whenever
/// such a decimal exists.
pub(crate) fn render(model: &Model) -> String {
    let Model {
        robot,
        camera,
        board,
    } = model;
    let list = |values: &[f64]| {
        let items: Vec<_> = values.iter().map(|&x| toml_float(x)).collect();
        format!("[{}]", items.join(", "))
    };
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# naocalib dataset (SPEC section 6): lengths in mm, angles in degrees."
    );
    let _ = writeln!(s);
    let _ = writeln!(s, "[camera]");
    let _ = writeln!(s, "width = {}", camera.width);
    let _ = writeln!(s, "height = {}", camera.height);
    let _ = writeln!(s, "fx = {}", toml_float(camera.fx));
    let _ = writeln!(s, "fy = {}", toml_float(camera.fy));
    let _ = writeln!(s, "cx = {}", toml_float(camera.cx));
    let _ = writeln!(s, "cy = {}", toml_float(camera.cy));
    let _ = writeln!(
        s,
        "distortion = {}   # k1 k2 p1 p2 k3",
        list(&camera.distortion)
    );
    let _ = writeln!(s);
    let _ = writeln!(s, "[board]");
    let _ = writeln!(s, "squares_x = {}", board.squares_x);
    let _ = writeln!(s, "squares_y = {}", board.squares_y);
    let _ = writeln!(s, "square_mm = {}", toml_float(board.square));
    let _ = writeln!(s, "mount_origin_mm = {}", list(&board.mount_origin));
    let _ = writeln!(
        s,
        "mount_rpy_deg = {}   # roll, pitch, yaw",
        list(&board.mount_rpy.map(degrees_for))
    );
    let _ = writeln!(s);
    let _ = writeln!(s, "[robot]");
    let _ = writeln!(s, "hip_offset_y_mm = {}", toml_float(robot.hip_offset_y));
    let _ = writeln!(s, "hip_to_neck_z_mm = {}", toml_float(robot.hip_to_neck_z));
    let _ = writeln!(s, "thigh_mm = {}", toml_float(robot.thigh));
    let _ = writeln!(s, "tibia_mm = {}", toml_float(robot.tibia));
    let _ = writeln!(s, "foot_height_mm = {}", toml_float(robot.foot_height));
    let _ = writeln!(
        s,
        "lower_camera_offset_mm = {}",
        list(&robot.lower_camera_offset)
    );
    let _ = writeln!(
        s,
        "lower_camera_tilt_deg = {}",
        toml_float(degrees_for(robot.lower_camera_tilt))
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    const MINIMAL: &str = "[camera]\nwidth = 640\nheight = 480\nfx = 562.5\nfy = 562.5\n\
                           cx = 324.0\ncy = 189\n";

    fn parse_str(text: &str) -> Result<Model, String> {
        parse(Path::new("d/dataset.toml"), text.as_bytes()).map_err(|e| e.to_string())
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
                "line 2, field camera.width: must be at least 1, got 0",
            ),
            (
                &MINIMAL.replace("fy = 562.5", "fy = -1"),
                "line 5, field camera.fy: must be greater than 0",
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
                "line 9, field board.squares_y: must be at least 2, got 1",
            ),
            (
                &format!("{MINIMAL}[board]\nsquare_mm = 0\n"),
                "line 9, field board.square_mm: must be greater than 0",
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
        let text = render(&model);
        let back = parse(Path::new("x"), text.as_bytes()).unwrap();
        assert_eq!(back, model);
        assert!(
            render(&Model::default()).contains("lower_camera_tilt_deg = 39.7\n"),
            "{text}"
        );
    }

    #[test]
    fn validate_in_memory() {
        let path = Path::new("o/dataset.toml");
        assert!(validate(path, &Model::default()).is_ok());
        let mut m = Model::default();
        m.camera.fx = 0.0;
        let e = validate(path, &m).unwrap_err().to_string();
        assert_eq!(
            e,
            "o/dataset.toml, field camera.fx: must be greater than 0, got 0"
        );
        let mut m = Model::default();
        m.camera.distortion[3] = f64::NAN;
        let e = validate(path, &m).unwrap_err().to_string();
        assert_eq!(
            e,
            "o/dataset.toml, field camera.distortion[3]: NaN is not a finite number"
        );
        let mut m = Model::default();
        m.board.squares_x = 1;
        let e = validate(path, &m).unwrap_err().to_string();
        assert_eq!(
            e,
            "o/dataset.toml, field board.squares_x: must be at least 2, got 1"
        );
    }
}
