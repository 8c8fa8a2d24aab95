//! The one check of a model's values: every number finite, and within the ranges a NAO can
//! have (the ranges are in the messages), for models read from `dataset.toml` and for
//! models about to be written.

use std::path::Path;

use crate::model::{Board, Camera, Model, RobotGeometry};

use super::KeyError;
use crate::dataset::{DatasetError, Location};

/// Image width and height (px).
const IMAGE_SIZE: (u32, u32) = (16, 8192);
/// Focal lengths fx, fy (px).
const FOCAL: (f64, f64) = (50.0, 20000.0);
/// Squares of the board along either side.
const SQUARES: (u32, u32) = (3, 64);
/// Edge length of one square (mm).
const SQUARE_MM: (f64, f64) = (1.0, 500.0);
/// Link lengths (mm).
const LINK_MM: (f64, f64) = (1.0, 1000.0);
/// Largest magnitude of a position (board mount, centre of mass, camera offset) (mm).
const POSITION_MM: f64 = 1000.0;
/// Largest magnitude of a fixed angle (board mount, camera tilt) (deg).
const ANGLE_DEG: f64 = 360.0;
/// Largest sandal mass (g).
const MASS_G: f64 = 10_000.0;

/// The outcome of one check: `Err` names the TOML key and what is wrong.
type Checked = Result<(), KeyError>;

/// Checks a model in memory against the same rules as [`super::parse`]; errors name
/// `path` and the TOML key.
pub(crate) fn validate(path: &Path, model: &Model) -> Result<(), DatasetError> {
    check(model)
        .map_err(|(key, message)| DatasetError::invalid(Location::file(path).field(key), message))
}

/// The one check of a model's values: every number finite, and within the ranges a NAO team
/// would accept (the ranges are in the messages).
pub(super) fn check(model: &Model) -> Checked {
    let Model {
        robot,
        camera,
        board,
        upper_camera,
    } = model;
    check_camera("camera", camera)?;
    if let Some(upper) = upper_camera {
        check_camera("upper_camera", upper)?;
    }
    check_board(board)?;
    check_robot(robot)
}

/// The problem `message` with `key`.
fn fail(key: &str, message: String) -> Checked {
    Err((key.to_string(), message))
}

/// Every one of `values` (the value of `key`) is finite.
fn finite(key: &str, values: &[f64]) -> Checked {
    match values.iter().position(|x| !x.is_finite()) {
        None => Ok(()),
        Some(i) if values.len() == 1 => fail(key, format!("{} is not a finite number", values[i])),
        Some(i) => fail(
            &format!("{key}[{i}]"),
            format!("{} is not a finite number", values[i]),
        ),
    }
}

/// `x` (the value of `key`, in units `what`) is finite and within `lo … hi`.
fn within(key: &str, x: f64, (lo, hi): (f64, f64), what: &str) -> Checked {
    finite(key, &[x])?;
    if x < lo || x > hi {
        return fail(key, format!("must be {lo} … {hi} {what}, got {x}"));
    }
    Ok(())
}

/// Every one of `values` (the value of `key`, in units `what`) is finite and within
/// ±`limit`.
fn each_within(key: &str, values: &[f64], limit: f64, what: &str) -> Checked {
    finite(key, values)?;
    match values.iter().position(|x| x.abs() > limit) {
        None => Ok(()),
        Some(i) => fail(
            &format!("{key}[{i}]"),
            format!("must be within ±{limit} {what}, got {}", values[i]),
        ),
    }
}

/// The camera of the table `table` (`camera`, `upper_camera`).
fn check_camera(table: &str, camera: &Camera) -> Checked {
    let (lo, hi) = IMAGE_SIZE;
    for (key, n) in [
        (format!("{table}.width"), camera.width),
        (format!("{table}.height"), camera.height),
    ] {
        if n < lo || n > hi {
            return fail(&key, format!("must be {lo} … {hi} px, got {n}"));
        }
    }
    within(
        &format!("{table}.fx"),
        camera.fx,
        FOCAL,
        "px (a camera's focal length)",
    )?;
    within(
        &format!("{table}.fy"),
        camera.fy,
        FOCAL,
        "px (a camera's focal length)",
    )?;
    for (key, c, size) in [
        (format!("{table}.cx"), camera.cx, camera.width),
        (format!("{table}.cy"), camera.cy, camera.height),
    ] {
        let size = f64::from(size);
        within(
            &key,
            c,
            (-0.5 * size, 1.5 * size),
            "px (the principal point lies within the image ± 50 %)",
        )?;
    }
    finite(&format!("{table}.distortion"), &camera.distortion)
}

/// The `[board]` table.
fn check_board(board: &Board) -> Checked {
    let (lo, hi) = SQUARES;
    for (key, n) in [
        ("board.squares_x", board.squares_x),
        ("board.squares_y", board.squares_y),
    ] {
        if n < lo || n > hi {
            return fail(
                key,
                format!(
                    "must be {lo} … {hi} squares (the vertex finder needs at least 2 × 2 inner vertices), got {n}"
                ),
            );
        }
    }
    within("board.square_mm", board.square, SQUARE_MM, "mm")?;
    each_within(
        "board.mount_origin_mm",
        &board.mount_origin,
        POSITION_MM,
        "mm",
    )?;
    each_within(
        "board.mount_rpy_deg",
        &board.mount_rpy.map(f64::to_degrees),
        ANGLE_DEG,
        "°",
    )?;
    within("board.mass_g", board.mass_g, (0.0, MASS_G), "g")?;
    each_within("board.com_mm", &board.com_mm, POSITION_MM, "mm")
}

/// The `[robot]` table.
fn check_robot(robot: &RobotGeometry) -> Checked {
    for (key, x) in [
        ("robot.hip_offset_y_mm", robot.hip_offset_y),
        ("robot.hip_to_neck_z_mm", robot.hip_to_neck_z),
        ("robot.thigh_mm", robot.thigh),
        ("robot.tibia_mm", robot.tibia),
        ("robot.foot_height_mm", robot.foot_height),
    ] {
        within(key, x, LINK_MM, "mm (a link length)")?;
    }
    each_within(
        "robot.lower_camera_offset_mm",
        &robot.lower_camera_offset,
        POSITION_MM,
        "mm",
    )?;
    within(
        "robot.lower_camera_tilt_deg",
        robot.lower_camera_tilt.to_degrees(),
        (-ANGLE_DEG, ANGLE_DEG),
        "°",
    )?;
    each_within(
        "robot.upper_camera_offset_mm",
        &robot.upper_camera_offset,
        POSITION_MM,
        "mm",
    )?;
    within(
        "robot.upper_camera_tilt_deg",
        robot.upper_camera_tilt.to_degrees(),
        (-ANGLE_DEG, ANGLE_DEG),
        "°",
    )?;
    finite("robot.gravity", &robot.gravity)?;
    let norm = robot.gravity.iter().map(|x| x * x).sum::<f64>().sqrt();
    if (norm - 1.0).abs() > 1e-9 {
        return fail(
            "robot.gravity",
            format!("must be a unit vector, got one of length {norm}"),
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn validate_in_memory() {
        let path = Path::new("o/dataset.toml");
        assert!(validate(path, &Model::default()).is_ok());
        let mut m = Model::default();
        m.camera.fx = 0.0;
        let e = validate(path, &m).unwrap_err().to_string();
        assert_eq!(
            e,
            "o/dataset.toml, field camera.fx: must be 50 … 20000 px (a camera's focal length), \
             got 0"
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
            "o/dataset.toml, field board.squares_x: must be 3 … 64 squares (the vertex finder \
             needs at least 2 × 2 inner vertices), got 1"
        );
        let mut m = Model::default();
        m.robot.tibia = -102.9;
        let e = validate(path, &m).unwrap_err().to_string();
        assert_eq!(
            e,
            "o/dataset.toml, field robot.tibia_mm: must be 1 … 1000 mm (a link length), got -102.9"
        );
        let mut m = Model::default();
        m.robot.gravity = [0.0, 0.0, 2.0];
        let e = validate(path, &m).unwrap_err().to_string();
        assert_eq!(
            e,
            "o/dataset.toml, field robot.gravity: must be a unit vector, got one of length 2"
        );
        let mut m = Model::default();
        m.board.mass_g = -1.0;
        let e = validate(path, &m).unwrap_err().to_string();
        assert_eq!(
            e,
            "o/dataset.toml, field board.mass_g: must be 0 … 10000 g, got -1"
        );
    }
}
