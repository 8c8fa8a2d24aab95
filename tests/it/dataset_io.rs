//! Datasets on disk: a write/load round trip, and one test per kind of broken input, each
//! checking that the error names the file, the line and the field.

use std::path::{Path, PathBuf};

use naocalib::dataset::{
    CAPTURES_CSV, CORNERS_CSV, Capture, Corner, DATASET_TOML, Dataset, DatasetError, TRUTH_TOML,
    Truth, read_truth, write_corners,
};
use naocalib::model::{Joint, JointAngles, Model, PARAMETER_COUNT, Param, Side, Vertex};

use crate::util::naocalib;

// ---------------------------------------------------------------------------------------
// Round trip
// ---------------------------------------------------------------------------------------

/// A small deterministic generator, so the test needs no dependency.
struct XorShift(u64);

impl XorShift {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
}

fn rich_dataset(dir: &Path) -> Dataset {
    let mut rng = XorShift(0x9e37_79b9_7f4a_7c15);
    let mut model = Model::default();
    model.camera.width = 1280;
    model.camera.height = 960;
    model.camera.fx = rng.range(500.0, 1200.0);
    model.camera.fy = rng.range(500.0, 1200.0);
    model.camera.cx = rng.range(600.0, 700.0);
    model.camera.cy = rng.range(400.0, 500.0);
    model.camera.distortion = [rng.range(-0.3, 0.3), 1e-9, -0.0, 3.0, rng.range(-1.0, 1.0)];
    model.board.squares_x = 9;
    model.board.squares_y = 6;
    model.board.square = 100.0 / 3.0;
    model.board.mount_origin = [rng.range(150.0, 200.0), -0.0, 1e-12];
    // Angles stored in degrees in dataset.toml: any angle that is some float of degrees
    // converted reads back bit for bit.
    model.board.mount_rpy = [rng.range(-5.0, 5.0), 90.0, -179.99].map(f64::to_radians);
    model.robot.thigh = rng.range(99.0, 101.0);
    model.board.mass_g = rng.range(50.0, 150.0);
    model.board.com_mm = [rng.range(100.0, 200.0), -0.0, 1.0 / 7.0];
    let g = [
        rng.range(-1.0, -0.5),
        rng.range(-0.2, 0.2),
        rng.range(-0.2, 0.2),
    ];
    let norm = g.iter().map(|x| x * x).sum::<f64>().sqrt();
    model.robot.gravity = g.map(|x| x / norm);
    model.robot.lower_camera_offset = [50.71, 1e-300, 17.74];
    model.robot.lower_camera_tilt = rng.range(39.0, 40.0).to_radians();

    let mut captures = Vec::new();
    let mut corners = Vec::new();
    for (i, id) in [3u64, 0, 17, 4, 1 << 40].into_iter().enumerate() {
        let mut joints = JointAngles::default();
        for j in Joint::ALL {
            joints.set(j, rng.range(-2.0, 2.0));
        }
        joints.set(
            Joint::HeadYaw,
            if i == 1 {
                -0.0
            } else {
                joints.get(Joint::HeadYaw)
            },
        );
        joints.set(
            Joint::RAnkleRoll,
            if i == 2 {
                1e-17
            } else {
                joints.get(Joint::RAnkleRoll)
            },
        );
        let image = match i {
            0 => Some(PathBuf::from("images/3.png")),
            1 => Some(PathBuf::from("a b/c,d \"quoted\".png")),
            _ => None,
        };
        let side = if i % 2 == 0 { Side::Left } else { Side::Right };
        captures.push(Capture {
            id,
            side,
            camera: Default::default(),
            image,
            joints,
            line: 0,
        });
        if i == 3 {
            continue; // a capture without corners
        }
        for row in 0..5 {
            for col in (0..8).rev() {
                if (row + col + i as u32).is_multiple_of(3) {
                    let pixel = [rng.range(0.0, 1280.0), rng.range(0.0, 960.0)];
                    corners.push(Corner {
                        capture: id,
                        vertex: Vertex { row, col },
                        pixel,
                        line: 0,
                    });
                }
            }
        }
    }

    let mut values = [0.0; PARAMETER_COUNT];
    for p in Param::ALL {
        // True values as they are given in report units (deg / mm).
        let report = (rng.range(-5.0, 5.0) * 1e4).round() / 1e4;
        values[p.index()] = p.unit().from_report(report);
    }
    values[Param::CamYaw.index()] = rng.range(-3.0, 3.0).to_radians();
    let mut simulation = toml::Table::new();
    simulation.insert("seed".into(), toml::Value::Integer(42));
    simulation.insert("px_noise".into(), toml::Value::Float(rng.next()));
    simulation.insert("label".into(), toml::Value::String("round \"trip\"".into()));
    simulation.insert(
        "levels".into(),
        toml::Value::Array(vec![toml::Value::Float(0.5), toml::Value::Integer(2)]),
    );

    Dataset {
        dir: dir.to_path_buf(),
        model,
        captures,
        corners,
        truth: Some(Truth { values, simulation }),
        angles: naocalib::dataset::AngleSource {
            kind: naocalib::dataset::AngleKind::Corrected,
            corrected_by: Some("Config/Robots/Nao22/jointCalibration.cfg".into()),
        },
    }
}

fn bits(values: impl IntoIterator<Item = f64>) -> Vec<u64> {
    values.into_iter().map(f64::to_bits).collect()
}

#[test]
fn round_trip_is_exact() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("fresh/dataset");
    let mut written = rich_dataset(&dir);
    written.write(&dir, false).unwrap();
    let loaded = Dataset::load(&dir).unwrap();

    // The rows come back with the lines they were written to.
    for (i, c) in written.captures.iter_mut().enumerate() {
        c.line = i as u64 + 2;
    }
    for (i, c) in written.corners.iter_mut().enumerate() {
        c.line = i as u64 + 2;
    }
    assert_eq!(loaded, written);

    // PartialEq says -0.0 == 0.0; the bits must match too.
    for (a, b) in loaded.captures.iter().zip(&written.captures) {
        assert_eq!(bits(a.joints.0), bits(b.joints.0), "capture {}", a.id);
    }
    for (a, b) in loaded.corners.iter().zip(&written.corners) {
        assert_eq!(bits(a.pixel), bits(b.pixel), "corner on line {}", a.line);
    }
    let (lm, wm) = (&loaded.model, &written.model);
    assert_eq!(bits(lm.camera.distortion), bits(wm.camera.distortion));
    assert_eq!(bits(lm.board.mount_origin), bits(wm.board.mount_origin));
    assert_eq!(bits(lm.board.mount_rpy), bits(wm.board.mount_rpy));
    assert_eq!(
        bits(lm.robot.lower_camera_offset),
        bits(wm.robot.lower_camera_offset)
    );
    assert_eq!(
        lm.robot.lower_camera_tilt.to_bits(),
        wm.robot.lower_camera_tilt.to_bits()
    );
    let (lt, wt) = (
        loaded.truth.as_ref().unwrap(),
        written.truth.as_ref().unwrap(),
    );
    assert_eq!(bits(lt.values), bits(wt.values));

    // Writing what was loaded gives the same files.
    let again = tmp.path().join("again");
    loaded.write(&again, false).unwrap();
    for file in [DATASET_TOML, CAPTURES_CSV, CORNERS_CSV, TRUTH_TOML] {
        let a = std::fs::read(dir.join(file)).unwrap();
        let b = std::fs::read(again.join(file)).unwrap();
        assert_eq!(a, b, "{file}");
    }
}

#[test]
fn written_files_follow_the_spec() {
    let tmp = tempfile::tempdir().unwrap();
    let mut ds = Dataset::new(tmp.path(), Model::default());
    let mut joints = JointAngles::default();
    joints.set(Joint::LKneePitch, 1.25);
    ds.captures.push(Capture {
        id: 7,
        side: Side::Right,
        camera: Default::default(),
        image: None,
        joints,
        line: 0,
    });
    ds.corners.push(Corner {
        capture: 7,
        vertex: Vertex { row: 3, col: 5 },
        pixel: [0.5, 2.0],
        line: 0,
    });
    ds.write(tmp.path(), false).unwrap();

    let captures = std::fs::read_to_string(tmp.path().join(CAPTURES_CSV)).unwrap();
    let header: Vec<&str> = captures.lines().next().unwrap().split(',').collect();
    let mut expected = vec!["capture", "board", "image"];
    expected.extend(Joint::ALL.iter().map(|j| j.name()));
    assert_eq!(header, expected);
    assert_eq!(
        captures.lines().nth(1).unwrap(),
        "7,right,,0,0,0,0,0,1.25,0,0,0,0,0,0,0,0"
    );

    let corners = std::fs::read_to_string(tmp.path().join(CORNERS_CSV)).unwrap();
    assert_eq!(corners, "capture,row,col,u,v\n7,3,5,0.5,2\n");

    let toml = std::fs::read_to_string(tmp.path().join(DATASET_TOML)).unwrap();
    for line in [
        "[camera]",
        "width = 640",
        "fx = 562.5",
        "cy = 189.0",
        "[board]",
        "squares_x = 7",
        "square_mm = 25.0",
        "mount_origin_mm = [170.0, 0.0, 0.0]",
        "[robot]",
        "hip_to_neck_z_mm = 211.5",
        "foot_height_mm = 45.19",
        "lower_camera_offset_mm = [50.71, 0.0, 17.74]",
        "lower_camera_tilt_deg = 39.7",
    ] {
        assert!(
            toml.lines().any(|l| l.starts_with(line)),
            "{line:?} missing in\n{toml}"
        );
    }
    assert!(!tmp.path().join(TRUTH_TOML).exists());
}

#[test]
fn write_refuses_to_replace_without_force() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let ds = rich_dataset(dir);
    ds.write(dir, false).unwrap();
    let before = std::fs::read(dir.join(CAPTURES_CSV)).unwrap();

    let mut other = ds.clone();
    other.captures.truncate(1);
    other.corners.retain(|c| c.capture == other.captures[0].id);
    let e = other.write(dir, false).unwrap_err();
    assert!(matches!(e, DatasetError::Exists { .. }));
    let message = e.to_string();
    assert!(
        message.contains(&dir.join(DATASET_TOML).display().to_string()),
        "{message}"
    );
    assert!(message.contains("--force"), "{message}");
    assert_eq!(
        std::fs::read(dir.join(CAPTURES_CSV)).unwrap(),
        before,
        "nothing replaced"
    );

    other.write(dir, true).unwrap();
    assert_eq!(Dataset::load(dir).unwrap().captures.len(), 1);
}

#[test]
fn write_corners_for_detection() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let ds = rich_dataset(dir);
    let mut no_corners = ds.clone();
    no_corners.corners.clear();
    no_corners.write(dir, false).unwrap();
    assert!(Dataset::load(dir).unwrap().corners.is_empty());

    let e = write_corners(dir, &ds.corners, false).unwrap_err();
    assert_eq!(
        e.to_string(),
        format!(
            "{}: already exists; use --force to overwrite",
            dir.join(CORNERS_CSV).display()
        )
    );
    write_corners(dir, &ds.corners, true).unwrap();
    let loaded = Dataset::load(dir).unwrap();
    assert_eq!(loaded.corners.len(), ds.corners.len());
    assert_eq!(
        bits(loaded.corners.iter().flat_map(|c| c.pixel)),
        bits(ds.corners.iter().flat_map(|c| c.pixel))
    );
}

#[test]
fn missing_corners_and_truth_are_fine() {
    let tmp = tempfile::tempdir().unwrap();
    write_files(
        tmp.path(),
        &[(DATASET_TOML, GOOD_TOML), (CAPTURES_CSV, &good_captures())],
    );
    let ds = Dataset::load(tmp.path()).unwrap();
    assert_eq!(ds.captures.len(), 3);
    assert!(ds.corners.is_empty());
    assert!(ds.truth.is_none());
    assert_eq!(ds.model, Model::default());
    assert_eq!(ds.corners_by_capture().len(), 3);
}

#[test]
fn hand_written_dataset_loads() {
    let tmp = tempfile::tempdir().unwrap();
    let ds = load_with(tmp.path(), &[]).unwrap();
    assert_eq!(
        ds.captures.iter().map(|c| c.id).collect::<Vec<_>>(),
        [0, 1, 2]
    );
    assert_eq!(ds.captures[2].side, Side::Right);
    assert_eq!(
        ds.captures[0].image.as_deref(),
        Some(Path::new("images/0.png"))
    );
    assert_eq!(ds.captures[1].image, None);
    assert_eq!(ds.captures[1].joints.get(Joint::LKneePitch), 1.1);
    assert_eq!(ds.corners.len(), 4);
    assert_eq!(ds.corners[3].line, 5);
    let truth = ds.truth.unwrap();
    assert_eq!(truth.value(Param::CamPitch), (-4.5627f64).to_radians());
    assert_eq!(truth.value(Param::LBoardTransY), 0.8058);
    assert_eq!(truth.value(Param::RKneePitch), 0.0);
}

// ---------------------------------------------------------------------------------------
// Broken inputs: a good hand-written dataset with one file replaced
// ---------------------------------------------------------------------------------------

const GOOD_TOML: &str = "\
[camera]
width = 640
height = 480
fx = 562.5
fy = 562.5
cx = 324.0
cy = 189.0
distortion = [0.0, 0.0, 0.0, 0.0, 0.0]

[board]
squares_x = 7
squares_y = 5
square_mm = 25.0
";

const HEADER: &str = "capture,board,image,HeadYaw,HeadPitch,LHipYawPitch,LHipRoll,LHipPitch,\
LKneePitch,LAnklePitch,LAnkleRoll,RHipYawPitch,RHipRoll,RHipPitch,RKneePitch,RAnklePitch,RAnkleRoll";

/// A captures.csv row; `knee` is the LKneePitch field.
fn row(id: &str, board: &str, image: &str, knee: &str) -> String {
    format!(
        "{id},{board},{image},0.1,0.2,-0.3,0.1,-0.4,{knee},-0.35,-0.05,-0.3,-0.1,-0.5,0.9,-0.4,0.07"
    )
}

fn good_captures() -> String {
    format!(
        "{HEADER}\n{}\n{}\n{}\n",
        row("0", "left", "images/0.png", "0.8"),
        row("1", "left", "", "1.1"),
        row("2", "right", "", "0.9")
    )
}

const GOOD_CORNERS: &str =
    "capture,row,col,u,v\n0,0,0,107.9,323.1\n0,3,5,199.0,123.2\n2,1,1,10,20\n2,0,5,30,40\n";

const GOOD_TRUTH: &str = "[parameters]\nCamYaw = 0.4764\nCamPitch = -4.5627\nLBoardTransY = 0.8058\n\n[simulation]\nseed = 1\n";

fn write_files(dir: &Path, files: &[(&str, &str)]) {
    for (name, text) in files {
        std::fs::write(dir.join(name), text).unwrap();
    }
}

/// Writes the good dataset into `dir` with `replace` applied (an empty text stands for
/// "remove the file"), then loads it.
fn load_with(dir: &Path, replace: &[(&str, &str)]) -> Result<Dataset, DatasetError> {
    let captures = good_captures();
    let good = [
        (DATASET_TOML, GOOD_TOML),
        (CAPTURES_CSV, captures.as_str()),
        (CORNERS_CSV, GOOD_CORNERS),
        (TRUTH_TOML, GOOD_TRUTH),
    ];
    for (name, text) in good {
        let text = replace
            .iter()
            .find(|(n, _)| *n == name)
            .map_or(text, |(_, t)| *t);
        if text.is_empty() {
            let _ = std::fs::remove_file(dir.join(name));
        } else {
            std::fs::write(dir.join(name), text).unwrap();
        }
    }
    Dataset::load(dir)
}

/// Loads the good dataset with `file` replaced by `text`, and checks that the error names
/// the file, the line (when `line` is given) and the field (when given), and contains
/// `message`.
#[track_caller]
fn assert_broken(file: &str, text: &str, line: Option<u64>, field: Option<&str>, message: &str) {
    let tmp = tempfile::tempdir().unwrap();
    let e = load_with(tmp.path(), &[(file, text)]).expect_err("the dataset should not load");
    let shown = e.to_string();
    let path = tmp.path().join(file);
    assert_eq!(e.path(), path, "{shown}");
    let mut prefix = path.display().to_string();
    if let Some(line) = line {
        prefix.push_str(&format!(" line {line}"));
    }
    if let Some(field) = field {
        prefix.push_str(&format!(", field {field}"));
    }
    assert!(
        shown.starts_with(&format!("{prefix}: ")),
        "{shown:?} should start with {prefix:?}"
    );
    assert_eq!(e.line(), line, "{shown}");
    assert_eq!(e.field(), field, "{shown}");
    assert!(
        shown.contains(message),
        "{shown:?} should contain {message:?}"
    );
}

fn captures_with(rows: &[String]) -> String {
    format!("{HEADER}\n{}\n", rows.join("\n"))
}

fn toml_with(from: &str, to: &str) -> String {
    assert!(GOOD_TOML.contains(from));
    GOOD_TOML.replacen(from, to, 1)
}

// --- missing and empty files ----------------------------------------------------------------

#[test]
fn missing_dataset_toml() {
    let tmp = tempfile::tempdir().unwrap();
    let e = load_with(tmp.path(), &[(DATASET_TOML, "")]).unwrap_err();
    assert!(matches!(e, DatasetError::NotFound { .. }));
    let path = tmp.path().join(DATASET_TOML).display().to_string();
    assert_eq!(
        e.to_string(),
        format!("{path}: no such file (a dataset directory needs dataset.toml and captures.csv)")
    );
}

#[test]
fn missing_captures_csv() {
    let tmp = tempfile::tempdir().unwrap();
    let e = load_with(tmp.path(), &[(CAPTURES_CSV, "")]).unwrap_err();
    assert!(matches!(e, DatasetError::NotFound { .. }));
    assert!(e.to_string().starts_with(&format!(
        "{}: no such file",
        tmp.path().join(CAPTURES_CSV).display()
    )));
}

#[test]
fn missing_directory() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("nope");
    let e = Dataset::load(&dir).unwrap_err();
    assert_eq!(
        e.to_string(),
        format!(
            "{}: no such file (the directory {} does not exist)",
            dir.join(DATASET_TOML).display(),
            dir.display()
        )
    );
}

#[test]
fn empty_files() {
    for (file, hint) in [
        (DATASET_TOML, "(it needs at least a [camera] table)"),
        (CAPTURES_CSV, "(it needs at least its header line)"),
        (CORNERS_CSV, "(it needs at least its header line)"),
        (TRUTH_TOML, "(it needs a [parameters] table)"),
    ] {
        let tmp = tempfile::tempdir().unwrap();
        let e = load_with(tmp.path(), &[(file, " \n\n")]).unwrap_err();
        assert!(matches!(e, DatasetError::Empty { .. }), "{e}");
        assert_eq!(
            e.to_string(),
            format!(
                "{}: the file is empty {hint}",
                tmp.path().join(file).display()
            )
        );
    }
}

// --- headers and columns ------------------------------------------------------------------

#[test]
fn captures_without_header() {
    let text = format!(
        "{}\n{}\n",
        row("0", "left", "", "0.8"),
        row("1", "left", "", "0.8")
    );
    assert_broken(
        CAPTURES_CSV,
        &text,
        Some(1),
        Some("capture"),
        "the header has no column 'capture'",
    );
}

#[test]
fn captures_missing_joint_column() {
    let text = format!("{}\n", HEADER.replace(",LKneePitch", ""));
    assert_broken(
        CAPTURES_CSV,
        &text,
        Some(1),
        Some("LKneePitch"),
        "the header has no column 'LKneePitch'",
    );
}

#[test]
fn captures_missing_board_column_after_blank_lines() {
    let text = format!("\n\n{}\n", HEADER.replace("board,", "side,"));
    assert_broken(
        CAPTURES_CSV,
        &text,
        Some(3),
        Some("board"),
        "the header has no column 'board'",
    );
}

#[test]
fn corners_missing_column() {
    assert_broken(
        CORNERS_CSV,
        "capture,row,col,u\n0,0,0,1\n",
        Some(1),
        Some("v"),
        "the header has no column 'v'",
    );
}

#[test]
fn columns_in_any_order_with_extras() {
    let tmp = tempfile::tempdir().unwrap();
    let names: Vec<&str> = HEADER.split(',').rev().chain(["comment"]).collect();
    let fields: Vec<String> = row("5", "right", "img.png", "1.5")
        .split(',')
        .rev()
        .map(String::from)
        .chain(["hi".into()])
        .collect();
    let captures = format!("{}\n{}\n", names.join(","), fields.join(","));
    let corners = "v,extra,u,col,row,capture\n2.5,x,1.5,4,3,5\n";
    let ds = load_with(
        tmp.path(),
        &[(CAPTURES_CSV, &captures), (CORNERS_CSV, corners)],
    )
    .unwrap();
    assert_eq!(ds.captures[0].id, 5);
    assert_eq!(ds.captures[0].side, Side::Right);
    assert_eq!(ds.captures[0].joints.get(Joint::LKneePitch), 1.5);
    assert_eq!(ds.captures[0].joints.get(Joint::RAnkleRoll), 0.07);
    assert_eq!(ds.corners[0].vertex, Vertex { row: 3, col: 4 });
    assert_eq!(ds.corners[0].pixel, [1.5, 2.5]);
}

#[test]
fn captures_row_with_too_many_fields() {
    let text = captures_with(&[
        row("0", "left", "", "0.8"),
        format!("{},9", row("1", "left", "", "0.8")),
    ]);
    assert_broken(
        CAPTURES_CSV,
        &text,
        Some(3),
        None,
        "has 18 fields but the header has 17 columns",
    );
}

// --- numbers ----------------------------------------------------------------------------------

#[test]
fn unparsable_number_in_captures() {
    let text = captures_with(&[row("0", "left", "", "0.8"), row("1", "left", "", "abc")]);
    assert_broken(
        CAPTURES_CSV,
        &text,
        Some(3),
        Some("LKneePitch"),
        "'abc' is not a number",
    );
}

#[test]
fn missing_number_in_captures() {
    let text = captures_with(&[row("0", "left", "", "")]);
    assert_broken(
        CAPTURES_CSV,
        &text,
        Some(2),
        Some("LKneePitch"),
        "missing value, expected a number",
    );
}

#[test]
fn unparsable_number_in_corners() {
    let text = "capture,row,col,u,v\n0,0,0,1.0,2,5\n";
    assert_broken(
        CORNERS_CSV,
        text,
        Some(2),
        None,
        "has 6 fields but the header has 5 columns",
    );
    let text = "capture,row,col,u,v\n0,0,0,1.0,2..5\n";
    assert_broken(
        CORNERS_CSV,
        text,
        Some(2),
        Some("v"),
        "'2..5' is not a number",
    );
}

#[test]
fn nan_and_infinity_in_captures() {
    let text = captures_with(&[row("0", "left", "", "NaN")]);
    assert_broken(
        CAPTURES_CSV,
        &text,
        Some(2),
        Some("LKneePitch"),
        "'NaN' is not a finite number",
    );
    let text = captures_with(&[row("0", "left", "", "0.8"), row("1", "left", "", "-inf")]);
    assert_broken(
        CAPTURES_CSV,
        &text,
        Some(3),
        Some("LKneePitch"),
        "'-inf' is not a finite number",
    );
}

#[test]
fn nan_and_infinity_in_corners() {
    let text = "capture,row,col,u,v\n0,0,0,1.0,2\n0,0,1,inf,2\n";
    assert_broken(
        CORNERS_CSV,
        text,
        Some(3),
        Some("u"),
        "'inf' is not a finite number",
    );
    let text = "capture,row,col,u,v\n0,0,0,1.0,nan\n";
    assert_broken(
        CORNERS_CSV,
        text,
        Some(2),
        Some("v"),
        "'nan' is not a finite number",
    );
}

#[test]
fn nan_and_infinity_in_dataset_toml() {
    let text = toml_with("cx = 324.0", "cx = nan");
    assert_broken(
        DATASET_TOML,
        &text,
        Some(6),
        Some("camera.cx"),
        "nan is not a finite number",
    );
    let text = toml_with(
        "distortion = [0.0, 0.0, 0.0, 0.0, 0.0]",
        "distortion = [0.0, 0.0, -inf, 0.0, 0.0]",
    );
    assert_broken(
        DATASET_TOML,
        &text,
        Some(8),
        Some("camera.distortion[2]"),
        "-inf is not a finite number",
    );
}

#[test]
fn nan_and_infinity_in_truth_toml() {
    let text = "[parameters]\nCamYaw = 0.5\nCamRoll = +inf\n";
    assert_broken(
        TRUTH_TOML,
        text,
        Some(3),
        Some("parameters.CamRoll"),
        "+inf is not a finite number",
    );
    let text = "[parameters]\n\n[simulation]\npx_noise = nan\n";
    assert_broken(
        TRUTH_TOML,
        text,
        Some(4),
        Some("simulation.px_noise"),
        "nan is not a finite number",
    );
}

#[test]
fn unparsable_number_in_dataset_toml() {
    let text = toml_with("fx = 562.5", "fx = \"562.5\"");
    assert_broken(
        DATASET_TOML,
        &text,
        Some(4),
        Some("camera.fx"),
        "expected a number, found a string",
    );
    let text = toml_with("width = 640", "width = 640.0");
    assert_broken(
        DATASET_TOML,
        &text,
        Some(2),
        Some("camera.width"),
        "expected an integer, found a float",
    );
}

#[test]
fn toml_syntax_error() {
    let text = toml_with("fy = 562.5", "fy = 562.5.1");
    assert_broken(DATASET_TOML, &text, Some(5), None, "invalid TOML");
}

// --- captures -----------------------------------------------------------------------------------

#[test]
fn duplicate_capture_ids() {
    let text = captures_with(&[
        row("0", "left", "", "0.8"),
        row("2", "left", "", "0.8"),
        row("1", "right", "", "0.8"),
        row("2", "right", "", "0.8"),
    ]);
    assert_broken(
        CAPTURES_CSV,
        &text,
        Some(5),
        Some("capture"),
        "capture id 2 is used twice: on line 3 and on line 5",
    );
}

#[test]
fn negative_capture_id() {
    let text = captures_with(&[row("0", "left", "", "0.8"), row("-4", "left", "", "0.8")]);
    assert_broken(
        CAPTURES_CSV,
        &text,
        Some(3),
        Some("capture"),
        "must not be negative, got -4",
    );
    let text = "capture,row,col,u,v\n-1,0,0,1,1\n";
    assert_broken(
        CORNERS_CSV,
        text,
        Some(2),
        Some("capture"),
        "must not be negative, got -1",
    );
}

#[test]
fn non_integer_capture_id() {
    let text = captures_with(&[row("1.5", "left", "", "0.8")]);
    assert_broken(
        CAPTURES_CSV,
        &text,
        Some(2),
        Some("capture"),
        "'1.5' is not a non-negative integer",
    );
}

#[test]
fn unknown_board_value() {
    let text = captures_with(&[row("0", "left", "", "0.8"), row("1", "both", "", "0.8")]);
    assert_broken(
        CAPTURES_CSV,
        &text,
        Some(3),
        Some("board"),
        "unknown board 'both', expected 'left' or 'right'",
    );
    let text = captures_with(&[row("0", "", "", "0.8")]);
    assert_broken(
        CAPTURES_CSV,
        &text,
        Some(2),
        Some("board"),
        "missing value, expected 'left' or 'right'",
    );
}

#[test]
fn absolute_image_path() {
    let text = captures_with(&[row("0", "left", "/home/nao/img.png", "0.8")]);
    assert_broken(
        CAPTURES_CSV,
        &text,
        Some(2),
        Some("image"),
        "image path '/home/nao/img.png' is absolute",
    );
}

#[test]
fn image_path_leaving_the_dataset() {
    let text = captures_with(&[row("0", "left", "images/../../other/img.png", "0.8")]);
    assert_broken(
        CAPTURES_CSV,
        &text,
        Some(2),
        Some("image"),
        "leaves the dataset directory ('..')",
    );
    // Staying inside is fine.
    let tmp = tempfile::tempdir().unwrap();
    let text = captures_with(&[row("0", "left", "images/../img.png", "0.8")]);
    let ds = load_with(
        tmp.path(),
        &[
            (CAPTURES_CSV, &text),
            (CORNERS_CSV, "capture,row,col,u,v\n"),
        ],
    )
    .unwrap();
    assert_eq!(
        ds.image_path(&ds.captures[0]),
        Some(tmp.path().join("images/../img.png"))
    );
}

#[test]
fn captures_without_image_column() {
    let tmp = tempfile::tempdir().unwrap();
    let drop_image = |line: &str| {
        let mut fields: Vec<&str> = line.split(',').collect();
        fields.remove(2);
        fields.join(",")
    };
    let text: Vec<String> = good_captures().lines().map(drop_image).collect();
    assert!(!text[0].contains("image"));
    let ds = load_with(tmp.path(), &[(CAPTURES_CSV, &text.join("\n"))]).unwrap();
    assert_eq!(ds.captures.len(), 3);
    assert!(ds.captures.iter().all(|c| c.image.is_none()));
}

// --- corners --------------------------------------------------------------------------------------

#[test]
fn corners_of_unknown_capture() {
    let text = "capture,row,col,u,v\n0,0,0,1,1\n\n9,0,0,1,1\n";
    assert_broken(
        CORNERS_CSV,
        text,
        Some(4),
        Some("capture"),
        "capture 9 is not in captures.csv",
    );
}

#[test]
fn vertex_outside_the_board() {
    let text = "capture,row,col,u,v\n0,4,0,1,1\n";
    assert_broken(
        CORNERS_CSV,
        text,
        Some(2),
        Some("row"),
        "row 4 is outside the board: a board of 7 × 5 squares has vertex rows 0 to 3",
    );
    let text = "capture,row,col,u,v\n0,0,0,1,1\n0,0,6,1,1\n";
    assert_broken(
        CORNERS_CSV,
        text,
        Some(3),
        Some("col"),
        "col 6 is outside the board: a board of 7 × 5 squares has vertex columns 0 to 5",
    );
}

#[test]
fn vertex_range_follows_the_board() {
    // A 9 × 6 board has vertex columns 0 to 7 and rows 0 to 4.
    let toml = toml_with(
        "squares_x = 7\nsquares_y = 5",
        "squares_x = 9\nsquares_y = 6",
    );
    let tmp = tempfile::tempdir().unwrap();
    let corners = "capture,row,col,u,v\n0,4,7,1,1\n";
    assert!(load_with(tmp.path(), &[(DATASET_TOML, &toml), (CORNERS_CSV, corners)]).is_ok());
    let corners = "capture,row,col,u,v\n0,5,7,1,1\n";
    let e = load_with(tmp.path(), &[(DATASET_TOML, &toml), (CORNERS_CSV, corners)]).unwrap_err();
    assert!(
        e.to_string().ends_with(
            "row 5 is outside the board: a board of 9 × 6 squares has vertex rows 0 to 4"
        ),
        "{e}"
    );
}

#[test]
fn duplicate_corner() {
    let text = "capture,row,col,u,v\n0,1,2,1,1\n2,1,2,1,1\n0,1,2,3,3\n";
    assert_broken(
        CORNERS_CSV,
        text,
        Some(4),
        Some("capture"),
        "capture 0, row 1, col 2 is given twice: on line 2 and on line 4",
    );
}

// --- dataset.toml ---------------------------------------------------------------------------------

#[test]
fn camera_width_or_height_zero() {
    assert_broken(
        DATASET_TOML,
        &toml_with("width = 640", "width = 0"),
        Some(2),
        Some("camera.width"),
        "must be 16 … 8192 px, got 0",
    );
    assert_broken(
        DATASET_TOML,
        &toml_with("height = 480", "height = 0"),
        Some(3),
        Some("camera.height"),
        "must be 16 … 8192 px, got 0",
    );
    assert_broken(
        DATASET_TOML,
        &toml_with("height = 480", "height = -480"),
        Some(3),
        Some("camera.height"),
        "-480 is out of range (a whole number from 0 to 4294967295)",
    );
}

#[test]
fn focal_length_not_positive() {
    assert_broken(
        DATASET_TOML,
        &toml_with("fx = 562.5", "fx = 0"),
        Some(4),
        Some("camera.fx"),
        "must be 50 … 20000 px (a camera's focal length), got 0",
    );
    assert_broken(
        DATASET_TOML,
        &toml_with("fy = 562.5", "fy = -562.5"),
        Some(5),
        Some("camera.fy"),
        "must be 50 … 20000 px (a camera's focal length), got -562.5",
    );
}

#[test]
fn camera_key_missing() {
    assert_broken(
        DATASET_TOML,
        &toml_with("cy = 189.0\n", ""),
        Some(1),
        Some("camera.cy"),
        "[camera] has no key 'cy'",
    );
}

#[test]
fn camera_table_missing() {
    let text = "[board]\nsquares_x = 7\n";
    assert_broken(
        DATASET_TOML,
        text,
        None,
        Some("camera"),
        "missing table [camera]",
    );
}

#[test]
fn board_too_small() {
    assert_broken(
        DATASET_TOML,
        &toml_with("squares_x = 7", "squares_x = 1"),
        Some(11),
        Some("board.squares_x"),
        "must be 3 … 64 squares (the vertex finder needs at least 2 × 2 inner vertices), got 1",
    );
    assert_broken(
        DATASET_TOML,
        &toml_with("squares_y = 5", "squares_y = 0"),
        Some(12),
        Some("board.squares_y"),
        "must be 3 … 64 squares (the vertex finder needs at least 2 × 2 inner vertices), got 0",
    );
}

#[test]
fn board_square_not_positive() {
    assert_broken(
        DATASET_TOML,
        &toml_with("square_mm = 25.0", "square_mm = 0.0"),
        Some(13),
        Some("board.square_mm"),
        "must be 1 … 500 mm, got 0",
    );
    assert_broken(
        DATASET_TOML,
        &toml_with("square_mm = 25.0", "square_mm = -25"),
        Some(13),
        Some("board.square_mm"),
        "must be 1 … 500 mm, got -25",
    );
}

#[test]
fn wrong_distortion_length() {
    let text = toml_with(
        "distortion = [0.0, 0.0, 0.0, 0.0, 0.0]",
        "distortion = [0.1, 0.0, 0.0, 0.0]",
    );
    assert_broken(
        DATASET_TOML,
        &text,
        Some(8),
        Some("camera.distortion"),
        "expected exactly 5 numbers, found 4",
    );
    let text = toml_with("distortion = [0.0, 0.0, 0.0, 0.0, 0.0]", "distortion = 0.0");
    assert_broken(
        DATASET_TOML,
        &text,
        Some(8),
        Some("camera.distortion"),
        "expected an array of 5 numbers, found a float",
    );
}

#[test]
fn unknown_keys_in_dataset_toml() {
    let text = toml_with("cy = 189.0", "cy = 189.0\nskew = 0.0");
    assert_broken(
        DATASET_TOML,
        &text,
        Some(8),
        Some("camera.skew"),
        "unknown key 'skew' in [camera] (known keys: width, height, fx, fy, cx, cy, distortion, flip, exposure, gain, white_balance_k, fps)",
    );
    let text = format!("{GOOD_TOML}\n[robot]\nthigh_mm = 100.0\nknee_mm = 3\n");
    assert_broken(
        DATASET_TOML,
        &text,
        Some(17),
        Some("robot.knee_mm"),
        "unknown key 'knee_mm' in [robot]",
    );
    let text = format!("{GOOD_TOML}\n[lens]\nk1 = 0.0\n");
    assert_broken(
        DATASET_TOML,
        &text,
        Some(15),
        Some("lens"),
        "unknown key 'lens' at the top level (known keys: camera, upper_camera, board, robot, joints)",
    );
}

#[test]
fn robot_overrides_and_degrees() {
    let text = format!(
        "{GOOD_TOML}mount_rpy_deg = [10.0, -20.0, 90]\n\n[robot]\nthigh_mm = 101.5\nlower_camera_tilt_deg = 40\n"
    );
    let tmp = tempfile::tempdir().unwrap();
    let ds = load_with(tmp.path(), &[(DATASET_TOML, &text)]).unwrap();
    assert_eq!(
        ds.model.board.mount_rpy,
        [
            10f64.to_radians(),
            (-20f64).to_radians(),
            90f64.to_radians()
        ]
    );
    assert_eq!(ds.model.robot.thigh, 101.5);
    assert_eq!(ds.model.robot.tibia, 102.9);
    assert_eq!(ds.model.robot.lower_camera_tilt, 40f64.to_radians());
}

// --- truth.toml ------------------------------------------------------------------------------------

#[test]
fn unknown_parameter_name() {
    let text = "[parameters]\nCamYaw = 0.5\nLKneePich = 1.0\n";
    assert_broken(
        TRUTH_TOML,
        text,
        Some(3),
        Some("parameters.LKneePich"),
        "unknown parameter 'LKneePich' (known: CamYaw, CamPitch, CamRoll,",
    );
}

#[test]
fn truth_without_parameters_table() {
    assert_broken(
        TRUTH_TOML,
        "[simulation]\nseed = 3\n",
        None,
        Some("parameters"),
        "missing table [parameters]",
    );
}

#[test]
fn truth_file_on_its_own() {
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("my truth.toml");
    let e = read_truth(&path).unwrap_err();
    assert_eq!(e.to_string(), format!("{}: no such file", path.display()));
    std::fs::write(&path, GOOD_TRUTH).unwrap();
    let truth = read_truth(&path).unwrap();
    assert_eq!(truth.report_value(Param::LBoardTransY), 0.8058);
    assert_eq!(truth.value(Param::CamYaw), 0.4764f64.to_radians());
    std::fs::write(&path, "[parameters]\nCamYaw = 1\nFoo = 2\n").unwrap();
    let e = read_truth(&path).unwrap_err();
    assert!(
        e.to_string().starts_with(&format!(
            "{} line 3, field parameters.Foo: unknown parameter 'Foo'",
            path.display()
        )),
        "{e}"
    );
}

// ---------------------------------------------------------------------------------------
// Every key of dataset.toml
// ---------------------------------------------------------------------------------------

/// A `dataset.toml` with every key of every table given.
const EVERY_KEY: &str = "[camera]
width = 640
height = 480
fx = 562.5
fy = 562.5
cx = 320.0
cy = 240.0
distortion = [0.0, 0.0, 0.0, 0.0, 0.0]
flip = false
exposure = 1700
gain = 250
white_balance_k = 4000
fps = 30

[upper_camera]
width = 640
height = 480
fx = 562.5
fy = 562.5
cx = 320.0
cy = 240.0
distortion = [0.0, 0.0, 0.0, 0.0, 0.0]
flip = true
exposure = 700
gain = 800
white_balance_k = 4000
fps = 30

[board]
squares_x = 7
squares_y = 5
square_mm = 25.0
mount_origin_mm = [170.0, 0.0, 0.0]
mount_rpy_deg = [0.0, 0.0, 0.0]
mass_g = 120.0
com_mm = [150.0, 0.0, 0.0]

[robot]
hip_offset_y_mm = 50.0
hip_to_neck_z_mm = 211.5
thigh_mm = 100.0
tibia_mm = 102.9
foot_height_mm = 45.19
lower_camera_offset_mm = [50.71, 0.0, 17.74]
lower_camera_tilt_deg = 39.7
upper_camera_offset_mm = [58.71, 0.0, 63.64]
upper_camera_tilt_deg = 1.2
gravity = [-1.0, 0.0, 0.0]

[joints]
angles = \"corrected\"
corrected_by = \"the robot's calibration of May\"
";

/// The first error any reader of `dataset.toml` at `path` gives: the model (with the
/// joints table), the capture settings.
fn config_error(path: &Path) -> Option<String> {
    if let Err(e) = naocalib::dataset::read_model(path) {
        return Some(e.to_string());
    }
    naocalib::dataset::read_camera_settings(path)
        .err()
        .map(|e| e.to_string())
}

/// The keys a table of dataset.toml knows, as its unknown-key error lists them (the
/// readers' own registry of keys).
fn known_keys(dir: &Path, table: &str) -> Vec<String> {
    let path = dir.join("known.toml");
    std::fs::write(
        &path,
        EVERY_KEY.replace(
            &format!("[{table}]\n"),
            &format!("[{table}]\nzz_unknown = 1\n"),
        ),
    )
    .unwrap();
    let e = config_error(&path).expect("an unknown key is refused");
    let list = e.split("known keys: ").nth(1).expect(&e);
    list.trim_end_matches(')')
        .split(", ")
        .map(str::to_string)
        .collect()
}

/// Every key of every table of dataset.toml (the readers' own list of them), given a value
/// of the wrong kind or out of range: whatever is refused — by the dataset's readers, and
/// for `[board]` by `naocalib sandal` too, with its own rules (a plate is flat: no
/// height, roll or pitch; a bounded pattern near the ankle) — is refused naming the
/// file, the line of the key and the key.
#[test]
fn every_key_error_of_dataset_toml_names_the_file_its_line_and_the_key() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let path = dir.join("dataset.toml");
    std::fs::write(&path, EVERY_KEY).unwrap();
    assert_eq!(config_error(&path), None, "the full file is valid");
    let mut keys = Vec::new();
    let mut table = String::new();
    for (k, line) in EVERY_KEY.lines().enumerate() {
        if let Some(t) = line.strip_prefix('[') {
            table = t.trim_end_matches(']').to_string();
        } else if let Some((key, value)) = line.split_once(" = ") {
            keys.push((k, table.clone(), key.to_string(), value.to_string()));
        }
    }
    for t in ["camera", "upper_camera", "board", "robot", "joints"] {
        for known in known_keys(dir, t) {
            assert!(
                keys.iter()
                    .any(|(_, table, key, _)| table == t && *key == known),
                "[{t}] {known} is not in the test's file"
            );
        }
    }
    let mut refused = 0;
    for (k, table, key, value) in &keys {
        let field = format!("{table}.{key}");
        let wrong_kind = if value.starts_with('"') {
            "5".to_string()
        } else {
            "\"x\"".to_string()
        };
        let out_of_range = if value.starts_with('[') {
            format!("[1e9, {}", value.split_once(", ").unwrap().1)
        } else if value.starts_with('"') {
            "\"bogus\"".to_string()
        } else if value == "true" || value == "false" {
            continue;
        } else if value.contains('.') {
            "1e9".to_string()
        } else {
            "1000000000".to_string()
        };
        let mut variants = vec![(wrong_kind, true), (out_of_range, false)];
        if table == "board" {
            // What no sandal can be: lifted, rolled, pitched, too long, too far.
            variants.extend(
                match key.as_str() {
                    "mount_origin_mm" => vec!["[170.0, 0.0, 5.0]", "[900.0, 0.0, 0.0]"],
                    "mount_rpy_deg" => vec!["[4.0, 0.0, 0.0]", "[0.0, -3.0, 0.0]"],
                    "square_mm" => vec!["200.0"],
                    _ => vec![],
                }
                .into_iter()
                .map(|v| (v.to_string(), false)),
            );
        }
        for (bad, must_fail) in variants {
            let text: String = EVERY_KEY
                .lines()
                .enumerate()
                .map(|(i, l)| {
                    if i == *k {
                        format!("{key} = {bad}\n")
                    } else {
                        format!("{l}\n")
                    }
                })
                .collect();
            std::fs::write(&path, &text).unwrap();
            let at = format!("dataset.toml line {}, field {field}", k + 1);
            let mut errors: Vec<String> = config_error(&path).into_iter().collect();
            if table == "board" {
                let out = naocalib()
                    .arg("sandal")
                    .arg(dir.join("sandal"))
                    .arg("--config")
                    .arg(&path)
                    .output()
                    .unwrap();
                if !out.status.success() {
                    assert_eq!(out.status.code(), Some(1));
                    errors.push(String::from_utf8_lossy(&out.stderr).into_owned());
                }
                let _ = std::fs::remove_dir_all(dir.join("sandal"));
            }
            assert!(
                !must_fail || !errors.is_empty(),
                "{field} = {bad}: accepted"
            );
            for e in &errors {
                assert!(e.contains(&at), "{field} = {bad}: '{e}' lacks '{at}'");
                refused += 1;
            }
        }
    }
    // Most out-of-range values are refused too (not only the wrong kinds).
    assert!(
        refused > 2 * keys.len(),
        "{refused} refusals over {} keys",
        keys.len()
    );
}
