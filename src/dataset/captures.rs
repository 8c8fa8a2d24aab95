//! `captures.csv`: one row per captured image (docs/MODEL.md §7).

use std::collections::HashMap;
use std::path::{Component, Path, PathBuf};

use crate::model::{CameraId, Joint, JointAngles, Model, Side};

use super::Capture;
use super::csv_table::CsvTable;
use super::error::{DatasetError, Location};
use super::units::csv_float;

/// The most captures a dataset may have (the paper's datasets have a few hundred).
pub(crate) const MAX_CAPTURES: usize = 100_000;

/// The largest magnitude of a logged joint angle (rad) (a NAO's joints turn less than
/// ±2.1 rad; more than a full turn is a unit or logging error).
pub(crate) const MAX_ANGLE_RAD: f64 = std::f64::consts::TAU;

/// Reads the captures from the content of `captures.csv` at `path`.
pub(crate) fn parse(path: &Path, bytes: &[u8]) -> Result<Vec<Capture>, DatasetError> {
    let table = CsvTable::parse(path, bytes)?;
    table.refuse_near_misses(&known_columns())?;
    let id_col = table.require("capture")?;
    let board_col = table.require("board")?;
    let joint_cols = Joint::ALL.map(|j| table.require(j.name()));
    let joint_cols: Vec<usize> = joint_cols.into_iter().collect::<Result<_, _>>()?;
    let image_col = table.column("image")?;
    let camera_col = table.column("camera")?;
    let mut captures = Vec::new();
    for row in table.rows() {
        if captures.len() == MAX_CAPTURES {
            return Err(DatasetError::invalid(
                Location::line(path, row.line),
                format!(
                    "more than {MAX_CAPTURES} captures; a dataset may have at most {MAX_CAPTURES}"
                ),
            ));
        }
        let id = row.uint::<u64>(id_col, "capture")?;
        let board = row.str(board_col);
        let side = Side::from_name(board).ok_or_else(|| {
            let message = if board.is_empty() {
                "missing value, expected 'left' or 'right'".to_string()
            } else {
                format!("unknown board '{board}', expected 'left' or 'right'")
            };
            DatasetError::invalid(row.at("board"), message)
        })?;
        let camera = match camera_col.map(|c| row.str(c)) {
            None | Some("") => CameraId::Lower,
            Some(name) => CameraId::from_name(name).ok_or_else(|| {
                DatasetError::invalid(
                    row.at("camera"),
                    format!("unknown camera '{name}', expected 'lower' or 'upper'"),
                )
            })?,
        };
        let image = match image_col.map(|c| row.str(c)) {
            None | Some("") => None,
            Some(image) => {
                let image = PathBuf::from(image);
                check_image_path(&image).map_err(|m| DatasetError::invalid(row.at("image"), m))?;
                Some(image)
            }
        };
        let mut joints = JointAngles::default();
        for (joint, &col) in Joint::ALL.iter().zip(&joint_cols) {
            joints.set(*joint, row.f64(col, joint.name())?);
        }
        captures.push(Capture {
            id,
            side,
            camera,
            image,
            joints,
            line: row.line,
        });
    }
    Ok(captures)
}

/// Checks that an image path is relative and stays inside the dataset directory.
pub(crate) fn check_image_path(image: &Path) -> Result<(), String> {
    let shown = image.display();
    if image.as_os_str().is_empty() {
        return Err("the image path is empty (leave the image out instead)".into());
    }
    let mut depth = 0usize;
    for component in image.components() {
        match component {
            Component::Prefix(_) | Component::RootDir => {
                return Err(format!(
                    "image path '{shown}' is absolute; it must be relative to the dataset \
                     directory"
                ));
            }
            Component::CurDir => {}
            Component::ParentDir if depth == 0 => {
                return Err(format!(
                    "image path '{shown}' leaves the dataset directory ('..'); it must stay \
                     inside it"
                ));
            }
            Component::ParentDir => depth -= 1,
            Component::Normal(_) => depth += 1,
        }
    }
    Ok(())
}

/// Checks captures in memory: unique ids, finite angles, valid image paths. `line` gives
/// the line of each capture (by index) for the messages.
pub(crate) fn validate(
    path: &Path,
    captures: &[Capture],
    line: impl Fn(usize, &Capture) -> u64,
) -> Result<HashMap<u64, u64>, DatasetError> {
    if captures.len() > MAX_CAPTURES {
        return Err(DatasetError::invalid(
            Location::file(path),
            format!(
                "{} captures; a dataset may have at most {MAX_CAPTURES}",
                captures.len()
            ),
        ));
    }
    let mut seen: HashMap<u64, u64> = HashMap::with_capacity(captures.len());
    for (i, capture) in captures.iter().enumerate() {
        let here = line(i, capture);
        let at = |field: &str| Location::line(path, here).field(field);
        if let Some(first) = seen.insert(capture.id, here) {
            return Err(DatasetError::invalid(
                at("capture"),
                format!(
                    "capture id {} is used twice: on line {first} and on line {here}",
                    capture.id
                ),
            ));
        }
        for (joint, angle) in capture.joints.iter() {
            if !angle.is_finite() {
                return Err(DatasetError::invalid(
                    at(joint.name()),
                    format!("{angle} is not a finite number"),
                ));
            }
            if angle.abs() > MAX_ANGLE_RAD {
                return Err(DatasetError::invalid(
                    at(joint.name()),
                    format!(
                        "{angle} rad is more than a full turn (joint angles are in radians, \
                         within ±{MAX_ANGLE_RAD:.4})"
                    ),
                ));
            }
        }
        if let Some(image) = &capture.image {
            check_image_path(image).map_err(|m| DatasetError::invalid(at("image"), m))?;
        }
    }
    Ok(seen)
}

/// Checks that every upper-camera capture has the upper camera's intrinsics: `model`
/// must have `[upper_camera]` when any capture names the upper camera. `line` gives the line
/// of each capture (by index) for the message.
pub(crate) fn check_cameras(
    path: &Path,
    captures: &[Capture],
    model: &Model,
    line: impl Fn(usize, &Capture) -> u64,
) -> Result<(), DatasetError> {
    if model.upper_camera.is_some() {
        return Ok(());
    }
    match captures
        .iter()
        .enumerate()
        .find(|(_, c)| c.camera == CameraId::Upper)
    {
        None => Ok(()),
        Some((i, c)) => Err(DatasetError::invalid(
            Location::line(path, line(i, c)).field("camera"),
            format!(
                "capture {} was taken with the upper camera, but dataset.toml has no \
                 [upper_camera] table (the upper camera's intrinsics, with the keys of \
                 [camera])",
                c.id
            ),
        )),
    }
}

/// Every column a `captures.csv` (or a plan) may have that naocalib reads or writes:
/// [`header`]'s and the quality columns capture adds (`spread_deg`, `frames`).
pub(crate) fn known_columns() -> Vec<&'static str> {
    let mut known = header(true);
    known.extend(["spread_deg", "frames"]);
    known
}

/// The header of `captures.csv` as written: with a `camera` column after `image` when
/// `with_camera`.
pub(crate) fn header(with_camera: bool) -> Vec<&'static str> {
    let mut header = vec!["capture", "board", "image"];
    if with_camera {
        header.push("camera");
    }
    header.extend(Joint::ALL.iter().map(|j| j.name()));
    header
}

/// `captures.csv` for `captures` (already validated); the `camera` column only when a
/// capture was taken with the upper camera, so that a lower-camera dataset is written as
/// one without the column.
pub(crate) fn render(captures: &[Capture]) -> Result<Vec<u8>, csv::Error> {
    let with_camera = captures.iter().any(|c| c.camera == CameraId::Upper);
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(header(with_camera))?;
    for c in captures {
        let mut record = vec![
            c.id.to_string(),
            c.side.name().to_string(),
            c.image
                .as_ref()
                .map(|p| p.to_string_lossy().into_owned())
                .unwrap_or_default(),
        ];
        if with_camera {
            record.push(c.camera.name().to_string());
        }
        record.extend(c.joints.iter().map(|(_, q)| csv_float(q)));
        w.write_record(&record)?;
    }
    w.into_inner().map_err(|e| e.into_error().into())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn header_line() -> String {
        header(false).join(",")
    }

    fn row(id: &str, board: &str, image: &str, knee: &str) -> String {
        let mut fields = vec![id.to_string(), board.to_string(), image.to_string()];
        fields.extend(Joint::ALL.iter().map(|j| {
            if *j == Joint::LKneePitch {
                knee.to_string()
            } else {
                format!("0.{}", j.index())
            }
        }));
        fields.join(",")
    }

    fn parse_str(text: &str) -> Result<Vec<Capture>, String> {
        parse(Path::new("d/captures.csv"), text.as_bytes()).map_err(|e| e.to_string())
    }

    #[test]
    fn reads_rows() {
        let text = format!(
            "{}\n{}\n\n{}\n",
            header_line(),
            row("3", "left", "images/3.png", "1.5"),
            row("0", "right", "", "-0.25")
        );
        let c = parse_str(&text).unwrap();
        assert_eq!(c.len(), 2);
        assert_eq!((c[0].id, c[0].side, c[0].line), (3, Side::Left, 2));
        assert_eq!(c[0].image.as_deref(), Some(Path::new("images/3.png")));
        assert_eq!(c[0].joints.get(Joint::LKneePitch), 1.5);
        assert_eq!(c[0].joints.get(Joint::HeadPitch), 0.1);
        assert_eq!(
            (c[1].id, c[1].side, c[1].line, c[1].image.clone()),
            (0, Side::Right, 4, None)
        );
    }

    #[test]
    fn columns_by_name_in_any_order_extras_ignored() {
        let mut names: Vec<&str> = Joint::ALL.iter().rev().map(|j| j.name()).collect();
        names.insert(3, "note");
        names.push("board");
        names.push("capture");
        let mut values: Vec<String> = Joint::ALL
            .iter()
            .rev()
            .map(|j| format!("{}", j.index() as f64 / 10.0))
            .collect();
        values.insert(3, "hello".into());
        values.push("right".into());
        values.push("7".into());
        let text = format!("{}\n{}\n", names.join(","), values.join(","));
        let c = parse_str(&text).unwrap();
        assert_eq!(c[0].id, 7);
        assert_eq!(c[0].side, Side::Right);
        assert_eq!(c[0].image, None);
        for j in Joint::ALL {
            assert_eq!(c[0].joints.get(j), j.index() as f64 / 10.0);
        }
    }

    /// Any near miss of any known column (case, a letter off, a plural, `_`) is refused
    /// with the column and the known one named; extras resembling none stay ignored.
    #[test]
    fn a_near_miss_of_a_known_column_is_refused_with_the_column_named() {
        let known = known_columns();
        for name in &known {
            let mut misses = vec![
                name.to_uppercase(),
                format!("{name}s"),
                format!("_{name}"),
                name.chars().skip(1).collect::<String>(),
            ];
            if name.len() > 6 {
                misses.push(name[..name.len() - 2].to_string());
            }
            for miss in misses.into_iter().filter(|m| !known.contains(&m.as_str())) {
                // The miss beside every known column but the one it stands for (a plan
                // whose `camera` column is spelt `Camera` has no `camera` column).
                let header: Vec<&str> = header(true)
                    .into_iter()
                    .map(|c| if c == *name { miss.as_str() } else { c })
                    .collect();
                let mut header = header;
                if !header.contains(&miss.as_str()) {
                    header.push(&miss);
                }
                let width = header.len();
                let text = format!("{}\n{}\n", header.join(","), vec!["0"; width].join(","));
                let e = parse_str(&text).unwrap_err();
                let col = header.iter().position(|c| *c == miss).unwrap() + 1;
                assert!(
                    e.contains(&format!("line 1, field {miss}: column {col} '{miss}'"))
                        && e.contains("did you mean '"),
                    "{miss}: {e}"
                );
            }
        }
        for extra in [
            "LShoulderPitch",
            "RElbowRoll",
            "LWristYaw",
            "LHand",
            "RHand",
            "time",
            "timestamp",
            "note",
            "x",
        ] {
            assert!(
                known
                    .iter()
                    .all(|k| !crate::dataset::csv_table::near_miss(extra, k)),
                "{extra} is no near miss"
            );
        }
        assert!(crate::dataset::csv_table::near_miss("Camera", "camera"));
    }

    #[test]
    fn row_errors() {
        let h = header_line();
        let cases = [
            (
                row("1", "left", "", "abc"),
                "line 2, field LKneePitch: 'abc' is not a number",
            ),
            (
                row("1", "left", "", "NaN"),
                "line 2, field LKneePitch: 'NaN' is not a finite number",
            ),
            (
                row("1", "left", "", ""),
                "line 2, field LKneePitch: missing value, expected a number",
            ),
            (
                row("-1", "left", "", "0"),
                "line 2, field capture: must not be negative, got -1",
            ),
            (
                row("x", "left", "", "0"),
                "line 2, field capture: 'x' is not a non-negative integer",
            ),
            (
                row("1", "Left", "", "0"),
                "line 2, field board: unknown board 'Left', expected",
            ),
            (
                row("1", "left", "/tmp/a.png", "0"),
                "line 2, field image: image path '/tmp/a.png' is absolute",
            ),
            (
                row("1", "left", "a/../../b.png", "0"),
                "line 2, field image: image path 'a/../../b.png' leaves",
            ),
        ];
        for (r, expected) in cases {
            let e = parse_str(&format!("{h}\n{r}\n")).unwrap_err();
            assert!(e.starts_with("d/captures.csv "), "{e}");
            assert!(e.contains(expected), "{e:?} should contain {expected:?}");
        }
        let e = parse_str(&format!("{}\n", h.replace(",RAnkleRoll", ""))).unwrap_err();
        assert_eq!(
            e,
            "d/captures.csv line 1, field RAnkleRoll: the header has no column 'RAnkleRoll'"
        );
    }

    #[test]
    fn camera_column() {
        let h = header(true).join(",");
        let mut fields: Vec<String> = row("1", "left", "", "0")
            .split(',')
            .map(String::from)
            .collect();
        fields.insert(3, "upper".into());
        let upper = fields.join(",");
        fields[3] = String::new();
        let empty = fields.join(",");
        let c = parse_str(&format!("{h}\n{upper}\n{}\n", empty.replacen('1', "2", 1))).unwrap();
        assert_eq!(
            (c[0].camera, c[1].camera),
            (CameraId::Upper, CameraId::Lower)
        );
        let c = parse_str(&format!(
            "{}\n{}\n",
            header_line(),
            row("1", "left", "", "0")
        ))
        .unwrap();
        assert_eq!(c[0].camera, CameraId::Lower);
        fields[3] = "Upper".into();
        let e = parse_str(&format!("{h}\n{}\n", fields.join(","))).unwrap_err();
        assert_eq!(
            e,
            "d/captures.csv line 2, field camera: unknown camera 'Upper', expected 'lower' or 'upper'"
        );
        // An upper capture needs [upper_camera].
        let c = parse_str(&format!("{h}\n{upper}\n")).unwrap();
        let path = Path::new("d/captures.csv");
        let e = check_cameras(path, &c, &Model::default(), |_, c| c.line).unwrap_err();
        assert!(
            e.to_string().starts_with(
                "d/captures.csv line 2, field camera: capture 1 was taken with the upper camera, \
                 but dataset.toml has no [upper_camera] table"
            ),
            "{e}"
        );
        let model = Model {
            upper_camera: Some(Default::default()),
            ..Model::default()
        };
        assert!(check_cameras(path, &c, &model, |_, c| c.line).is_ok());
        // Written with the column only when a capture is upper.
        let text = String::from_utf8(render(&c).unwrap()).unwrap();
        assert!(
            text.starts_with("capture,board,image,camera,HeadYaw"),
            "{text}"
        );
        let mut lower = c.clone();
        lower[0].camera = CameraId::Lower;
        let text = String::from_utf8(render(&lower).unwrap()).unwrap();
        assert!(text.starts_with("capture,board,image,HeadYaw"), "{text}");
    }

    #[test]
    fn image_paths() {
        assert!(check_image_path(Path::new("images/a.png")).is_ok());
        assert!(check_image_path(Path::new("./a/../b.png")).is_ok());
        assert!(check_image_path(Path::new("../b.png")).is_err());
        assert!(check_image_path(Path::new("/b.png")).is_err());
        assert!(check_image_path(Path::new("")).is_err());
    }

    #[test]
    fn duplicates_name_both_lines() {
        let h = header_line();
        let text = format!(
            "{h}\n{}\n{}\n{}\n",
            row("4", "left", "", "0"),
            row("5", "left", "", "0"),
            row("4", "right", "", "0")
        );
        let captures = parse_str(&text).unwrap();
        let e = validate(Path::new("d/captures.csv"), &captures, |_, c| c.line).unwrap_err();
        assert_eq!(
            e.to_string(),
            "d/captures.csv line 4, field capture: capture id 4 is used twice: on line 2 and on line 4"
        );
    }
}
