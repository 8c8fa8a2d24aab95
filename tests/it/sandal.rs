//! `naocalib sandal`: the printed pattern is the model's board. Every vertex and pin read
//! back from the SVG and the PDFs lies where the model and B-Human's FSR positions put it
//! in the sole frame; the PDF pages have the paper's exact size and scale; the SVG rendered
//! by resvg is found by naocalib's detection with the model's numbering; bad input writes
//! nothing.

use std::path::{Path, PathBuf};

use naocalib::model::{Board, Side, Vertex};

use crate::util::{assert_clean_failure, naocalib};

/// How close a vertex or pin read back from a file must be to the model's (mm).
const TOLERANCE_MM: f64 = 0.01;
const PT_PER_MM: f64 = 72.0 / 25.4;

/// One foot's FSRs: name and position (mm from the ankle's projection).
type FsrTable = [(&'static str, [f64; 2]); 4];

/// B-Human `Config/Robots/Default/robotDimensions.cfg` (BHumanCodeRelease d89d603f) lines
/// 54–65, as the file writes them: `leftFsrPositions` and `rightFsrPositions`.
const FSR: [(Side, FsrTable); 2] = [
    (
        Side::Left,
        [
            ("fl", [70.25, 29.9]),
            ("fr", [70.25, -23.1]),
            ("bl", [-30.25, 29.9]),
            ("br", [-29.65, -19.1]),
        ],
    ),
    (
        Side::Right,
        [
            ("fl", [70.25, 23.1]),
            ("fr", [70.25, -29.9]),
            ("bl", [-29.65, 19.1]),
            ("br", [-30.25, -29.9]),
        ],
    ),
];

const CAMERA: &str = "[camera]\nwidth = 640\nheight = 480\nfx = 562.5\nfy = 562.5\ncx = 320\n\
                      cy = 240\n";

/// A board unlike the paper's: 9 × 6 squares of 20 mm (not symmetric under a 180° turn),
/// moved sideways and turned by 7° on the sole.
const OTHER_BOARD: &str = "[board]\nsquares_x = 9\nsquares_y = 6\nsquare_mm = 20.0\n\
                           mount_origin_mm = [160.0, 8.0, 0.0]\nmount_rpy_deg = [0.0, 0.0, 7.0]\n";

fn other_board() -> Board {
    Board {
        squares_x: 9,
        squares_y: 6,
        square: 20.0,
        mount_origin: [160.0, 8.0, 0.0],
        mount_rpy: [0.0, 0.0, 7f64.to_radians()],
        ..Board::default()
    }
}

/// Runs `naocalib sandal OUT [--config CONFIG]`, which must succeed; returns its stdout.
fn make(out: &Path, config: Option<&Path>) -> String {
    let mut cmd = naocalib();
    cmd.arg("sandal").arg(out);
    if let Some(c) = config {
        cmd.arg("--config").arg(c);
    }
    let run = cmd.output().expect("ran");
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    String::from_utf8(run.stdout).expect("utf-8")
}

fn write_config(dir: &Path, text: &str) -> PathBuf {
    let path = dir.join("dataset.toml");
    std::fs::write(&path, text).unwrap();
    path
}

/// Where the model puts every vertex of `board` in the sole frame (x, y) (mm): the
/// vertex's board position mounted by `T_SB` (the same on both feet).
fn model_vertices(board: &Board) -> Vec<(Vertex, [f64; 2])> {
    board
        .vertices()
        .map(|v| {
            let p = board.mount().apply(&board.vertex_position(v));
            (v, [p[0], p[1]])
        })
        .collect()
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// The inner vertices of a checkerboard drawn as black squares (corner lists): the points
/// where two black squares touch.
fn touching_corners(squares: &[Vec<[f64; 2]>]) -> Vec<[f64; 2]> {
    let mut corners: Vec<([f64; 2], usize)> = Vec::new();
    for (k, square) in squares.iter().enumerate() {
        assert_eq!(square.len(), 4, "a square has 4 corners: {square:?}");
        for &p in square {
            corners.push((p, k));
        }
    }
    let mut out: Vec<[f64; 2]> = Vec::new();
    for (i, (p, k)) in corners.iter().enumerate() {
        let shared = corners[i + 1..]
            .iter()
            .any(|(q, l)| l != k && dist(*p, *q) < 1e-3);
        if shared && !out.iter().any(|q| dist(*p, *q) < 1e-3) {
            out.push(*p);
        }
    }
    out
}

/// Matches `found` (sole frame) one to one with the model's vertices; returns the largest
/// distance and the numbering of each found point.
fn match_vertices(found: &[[f64; 2]], board: &Board) -> (f64, Vec<Vertex>) {
    let model = model_vertices(board);
    assert_eq!(
        found.len(),
        model.len(),
        "{} vertices read back, the model has {}",
        found.len(),
        model.len()
    );
    let mut worst = 0.0f64;
    let mut numbering = Vec::new();
    for p in found {
        let (v, q) = model
            .iter()
            .min_by(|a, b| dist(*p, a.1).total_cmp(&dist(*p, b.1)))
            .unwrap();
        worst = worst.max(dist(*p, *q));
        assert!(!numbering.contains(v), "two points read back near {v:?}");
        numbering.push(*v);
    }
    (worst, numbering)
}

/// What an SVG of `naocalib sandal` shows, in its user units (mm, `u` right, `v` down).
struct SvgRead {
    size_mm: [f64; 2],
    squares: Vec<Vec<[f64; 2]>>,
    /// The ankle mark's centre: where its two lines cross.
    origin: [f64; 2],
    pins: Vec<(String, [f64; 2])>,
    scale_bars: Vec<f64>,
}

impl SvgRead {
    /// A page point in the sole frame: `x` up the page, `y` to the left.
    fn sole(&self, p: [f64; 2]) -> [f64; 2] {
        [self.origin[1] - p[1], self.origin[0] - p[0]]
    }
}

fn numbers(text: &str) -> Vec<[f64; 2]> {
    text.split_whitespace()
        .map(|pair| {
            let (a, b) = pair.split_once(',').expect("x,y");
            [a.parse().unwrap(), b.parse().unwrap()]
        })
        .collect()
}

fn read_svg(path: &Path) -> SvgRead {
    let text = std::fs::read_to_string(path).unwrap();
    assert!(
        !text.contains("<style") && !text.contains("<pattern") && !text.contains("style="),
        "plain SVG: presentation attributes only"
    );
    let doc = roxmltree::Document::parse(&text).unwrap();
    let root = doc.root_element();
    let mm = |name: &str| -> f64 {
        root.attribute(name)
            .and_then(|w| w.strip_suffix("mm"))
            .expect("size in mm")
            .parse()
            .unwrap()
    };
    let size_mm = [mm("width"), mm("height")];
    let view: Vec<f64> = root
        .attribute("viewBox")
        .unwrap()
        .split_whitespace()
        .map(|x| x.parse().unwrap())
        .collect();
    assert_eq!(
        view,
        vec![0.0, 0.0, size_mm[0], size_mm[1]],
        "1 unit = 1 mm"
    );
    let group = |id: &str| {
        doc.descendants()
            .find(|n| n.has_tag_name("g") && n.attribute("id") == Some(id))
            .unwrap_or_else(|| panic!("no group {id}"))
    };
    let squares: Vec<Vec<[f64; 2]>> = group("squares")
        .children()
        .filter(|n| n.has_tag_name("polygon"))
        .map(|n| numbers(n.attribute("points").unwrap()))
        .collect();
    let lines: Vec<Vec<[f64; 2]>> = group("ankle")
        .children()
        .filter(|n| n.has_tag_name("polyline"))
        .map(|n| numbers(n.attribute("points").unwrap()))
        .collect();
    assert_eq!(lines.len(), 2, "the ankle mark is a cross");
    let mid = |l: &[[f64; 2]]| [(l[0][0] + l[1][0]) / 2.0, (l[0][1] + l[1][1]) / 2.0];
    let origin = mid(&lines[0]);
    assert!(
        dist(origin, mid(&lines[1])) < 1e-9,
        "the cross's lines meet"
    );
    let mut pins = Vec::new();
    for name in ["fl", "fr", "bl", "br"] {
        let circle = group(&format!("pin-{name}"))
            .children()
            .find(|n| n.has_tag_name("circle"))
            .unwrap();
        let c = |a: &str| circle.attribute(a).unwrap().parse::<f64>().unwrap();
        pins.push((name.to_string(), [c("cx"), c("cy")]));
    }
    let scale_bars = group("scale-bar")
        .children()
        .filter(|n| n.has_tag_name("polyline"))
        .map(|n| numbers(n.attribute("points").unwrap()))
        .map(|l| dist(l[0], l[1]))
        .filter(|len| *len > 50.0)
        .collect();
    SvgRead {
        size_mm,
        squares,
        origin,
        pins,
        scale_bars,
    }
}

/// Checks the SVG of `side` in `dir` against the model's `board`; returns the largest vertex
/// error (mm).
fn check_svg(dir: &Path, side: Side, board: &Board) -> f64 {
    let svg = read_svg(&dir.join(format!("sandal-{}.svg", side.name())));
    let corners = touching_corners(&svg.squares);
    for p in &corners {
        let inside =
            (0.0..=svg.size_mm[0]).contains(&p[0]) && (0.0..=svg.size_mm[1]).contains(&p[1]);
        assert!(inside, "{side:?} SVG: vertex {p:?} off the canvas");
    }
    let found: Vec<[f64; 2]> = corners.into_iter().map(|p| svg.sole(p)).collect();
    let (worst, _) = match_vertices(&found, board);
    assert!(
        worst <= TOLERANCE_MM,
        "{side:?} SVG: a vertex {worst} mm off"
    );
    check_pins(side, &svg.pins, |p| svg.sole(p), "SVG");
    assert_eq!(svg.scale_bars.len(), 2, "two scale bars");
    for len in &svg.scale_bars {
        assert!((len - 100.0).abs() < 1e-3, "scale bar {len} mm");
    }
    worst
}

fn check_pins(
    side: Side,
    pins: &[(String, [f64; 2])],
    sole: impl Fn([f64; 2]) -> [f64; 2],
    what: &str,
) {
    let expected = FSR.iter().find(|(s, _)| *s == side).unwrap().1;
    for (name, at) in expected {
        let (_, p) = pins
            .iter()
            .find(|(n, _)| n == name)
            .unwrap_or_else(|| panic!("{what}: no pin {name}"));
        let d = dist(sole(*p), at);
        assert!(
            d <= TOLERANCE_MM,
            "{what} {side:?} pin {name} at {:?}, the FSR at {at:?}",
            sole(*p)
        );
    }
}

/// One PDF page as read back with lopdf: its size, the drawing's transform and clip, and
/// the shapes of the groups the tests look at, all in points.
struct PdfPage {
    media_box: [f64; 4],
    /// The drawing's window on the page (points): `[x0, y0, x1, y1]`.
    clip: [f64; 4],
    squares: Vec<Vec<[f64; 2]>>,
    origin: [f64; 2],
    pins: Vec<(String, [f64; 2])>,
    scale_bars: Vec<f64>,
}

impl PdfPage {
    /// A point (points) in the sole frame: `x` up the page, `y` to the left.
    fn sole(&self, p: [f64; 2]) -> [f64; 2] {
        [
            (p[1] - self.origin[1]) / PT_PER_MM,
            (self.origin[0] - p[0]) / PT_PER_MM,
        ]
    }

    fn shows(&self, p: [f64; 2]) -> bool {
        let [x0, y0, x1, y1] = self.clip;
        p[0] >= x0.min(x1) && p[0] <= x0.max(x1) && p[1] >= y0.min(y1) && p[1] <= y0.max(y1)
    }
}

fn read_pdf(path: &Path) -> Vec<PdfPage> {
    use lopdf::content::Content;
    let doc = lopdf::Document::load(path).unwrap();
    let mut pages = Vec::new();
    for (_, id) in doc.get_pages() {
        let page = doc.get_object(id).unwrap().as_dict().unwrap();
        let media: Vec<f64> = page
            .get(b"MediaBox")
            .unwrap()
            .as_array()
            .unwrap()
            .iter()
            .map(|o| o.as_float().unwrap() as f64)
            .collect();
        let content = Content::decode(&doc.get_page_content(id)).unwrap();
        let mut ctm: Option<[f64; 6]> = None;
        let mut clip = None;
        let mut tag = String::new();
        let mut path: Vec<[f64; 2]> = Vec::new();
        let mut read = PdfPage {
            media_box: [media[0], media[1], media[2], media[3]],
            clip: [0.0; 4],
            squares: Vec::new(),
            origin: [f64::NAN; 2],
            pins: Vec::new(),
            scale_bars: Vec::new(),
        };
        let mut ankle_lines: Vec<Vec<[f64; 2]>> = Vec::new();
        for op in &content.operations {
            let nums: Vec<f64> = op
                .operands
                .iter()
                .filter_map(|o| o.as_float().ok().map(f64::from))
                .collect();
            let at = |x: f64, y: f64, m: [f64; 6]| {
                [m[0] * x + m[2] * y + m[4], m[1] * x + m[3] * y + m[5]]
            };
            match op.operator.as_str() {
                "cm" if ctm.is_none() => {
                    ctm = Some([nums[0], nums[1], nums[2], nums[3], nums[4], nums[5]])
                }
                "re" if clip.is_none() => {
                    let m = ctm.unwrap();
                    let a = at(nums[0], nums[1], m);
                    let b = at(nums[0] + nums[2], nums[1] + nums[3], m);
                    clip = Some([a[0], a[1], b[0], b[1]]);
                }
                "BMC" => tag = String::from_utf8_lossy(op.operands[0].as_name().unwrap()).into(),
                "EMC" => tag.clear(),
                "m" | "l" | "c" if ctm.is_some() && clip.is_some() => {
                    let m = ctm.unwrap();
                    let n = nums.len();
                    path.push(at(nums[n - 2], nums[n - 1], m));
                }
                "f" | "S" | "s" => {
                    let shape = std::mem::take(&mut path);
                    if tag == "squares" && op.operator == "f" {
                        read.squares.push(shape);
                    } else if tag == "ankle" && shape.len() == 2 {
                        ankle_lines.push(shape);
                    } else if let Some(name) = tag.strip_prefix("pin-")
                        && shape.len() == 5
                    {
                        // A circle: four arcs from its rightmost point round to it.
                        let c = shape[..4]
                            .iter()
                            .fold([0.0, 0.0], |s, p| [s[0] + p[0] / 4.0, s[1] + p[1] / 4.0]);
                        read.pins.push((name.to_string(), c));
                    } else if tag == "scale-bar"
                        && shape.len() == 2
                        && dist(shape[0], shape[1]) > 50.0
                    {
                        read.scale_bars.push(dist(shape[0], shape[1]));
                    }
                }
                "h" => {}
                _ => {}
            }
        }
        read.clip = clip.expect("the drawing is clipped to its window");
        assert_eq!(ankle_lines.len(), 2, "the ankle mark is a cross");
        let mid = |l: &[[f64; 2]]| [(l[0][0] + l[1][0]) / 2.0, (l[0][1] + l[1][1]) / 2.0];
        read.origin = mid(&ankle_lines[0]);
        assert!(dist(read.origin, mid(&ankle_lines[1])) < 1e-3);
        pages.push(read);
    }
    pages
}

/// Checks the PDFs of `side` in `dir`; returns the largest vertex error (mm) and the sheet
/// count of each paper.
fn check_pdfs(dir: &Path, side: Side, board: &Board) -> (f64, Vec<usize>) {
    let mut worst = 0.0f64;
    let mut sheets = Vec::new();
    for (paper, size_mm) in [("a4", [210.0, 297.0]), ("letter", [215.9, 279.4])] {
        let pages = read_pdf(&dir.join(format!("sandal-{}-{paper}.pdf", side.name())));
        sheets.push(pages.len());
        let mut found: Vec<([f64; 2], usize)> = Vec::new();
        for (k, page) in pages.iter().enumerate() {
            let expected = [0.0, 0.0, size_mm[0] * PT_PER_MM, size_mm[1] * PT_PER_MM];
            for (a, b) in page.media_box.iter().zip(expected) {
                assert!((a - b).abs() < 1e-3, "{paper} page {:?}", page.media_box);
            }
            assert_eq!(page.scale_bars.len(), 2);
            for len in &page.scale_bars {
                assert!(
                    (len - 100.0 * PT_PER_MM).abs() < 1e-3,
                    "{paper}: a 100 mm bar is {len} pt"
                );
            }
            check_pins(side, &page.pins, |p| page.sole(p), paper);
            for p in touching_corners(&page.squares) {
                if page.shows(p) {
                    found.push((page.sole(p), k));
                }
            }
        }
        // Seen on more than one sheet where they overlap: once each.
        let mut unique: Vec<([f64; 2], usize)> = Vec::new();
        for (p, k) in found {
            if !unique.iter().any(|(q, _)| dist(p, *q) < TOLERANCE_MM) {
                unique.push((p, k));
            }
        }
        let points: Vec<[f64; 2]> = unique.iter().map(|(p, _)| *p).collect();
        let (w, _) = match_vertices(&points, board);
        assert!(w <= TOLERANCE_MM, "{paper}: a vertex {w} mm off");
        worst = worst.max(w);
        if *board == Board::turned() {
            assert!(
                unique.iter().all(|(_, k)| *k == unique[0].1),
                "{paper}: the pattern is split across sheets"
            );
        }
    }
    (worst, sheets)
}

#[test]
fn vertices_and_pins_in_the_files_are_the_models() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("default");
    let stdout = make(&out, None);
    assert!(stdout.contains("sandal-left-a4.pdf") && stdout.contains("sandal-right.scad"));
    let config = write_config(dir.path(), &format!("{CAMERA}{OTHER_BOARD}"));
    let other = dir.path().join("other");
    make(&other, Some(&config));
    for (out, board) in [(&out, Board::turned()), (&other, other_board())] {
        for side in Side::BOTH {
            let svg = check_svg(out, side, &board);
            let (pdf, sheets) = check_pdfs(out, side, &board);
            println!(
                "{side:?} {}×{}: largest vertex error SVG {svg:.1e} mm, PDF {pdf:.1e} mm, \
                 sheets A4/Letter {sheets:?}",
                board.squares_x, board.squares_y
            );
        }
    }
}

#[test]
fn every_file_is_named_by_foot_and_paper() {
    let dir = tempfile::tempdir().unwrap();
    make(dir.path(), None);
    let mut names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    let mut expected = Vec::new();
    for side in ["left", "right"] {
        for f in [".svg", "-a4.pdf", "-letter.pdf", "-template.txt", ".scad"] {
            expected.push(format!("sandal-{side}{f}"));
        }
    }
    expected.sort();
    assert_eq!(names, expected);
    let scad = std::fs::read_to_string(dir.path().join("sandal-left.scad")).unwrap();
    for name in [
        "pin_diameter",
        "pin_height",
        "plate_thickness",
        "slot_width",
        "slot_length",
    ] {
        assert!(scad.contains(&format!("{name} = ")), "no parameter {name}");
    }
    let template = std::fs::read_to_string(dir.path().join("sandal-right-template.txt")).unwrap();
    assert!(
        template.contains("pin fl   x    70.25  y    23.10"),
        "{template}"
    );
}

#[test]
fn bad_input_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    for (board, needle) in [
        ("[board]\nsquare_mm = -25\n", "board.square_mm"),
        (
            "[board]\nmount_rpy_deg = [0, 4, 0]\n",
            "board.mount_rpy_deg[1]",
        ),
        (
            "[board]\nmount_origin_mm = [170, 0, 5]\n",
            "board.mount_origin_mm[2]",
        ),
    ] {
        let config = write_config(dir.path(), &format!("{CAMERA}{board}"));
        let out = dir.path().join("out");
        let run = naocalib()
            .arg("sandal")
            .arg(&out)
            .arg("--config")
            .arg(&config)
            .output()
            .unwrap();
        assert_clean_failure(&run, &[needle]);
        assert!(!out.exists(), "{board}: something was written");
    }
    // OUT_DIR is a file: refused, the file untouched.
    let file = dir.path().join("a-file");
    std::fs::write(&file, b"keep").unwrap();
    let run = naocalib().arg("sandal").arg(&file).output().unwrap();
    assert_clean_failure(&run, &["a-file", "not a directory"]);
    assert_eq!(std::fs::read(&file).unwrap(), b"keep");
    // An earlier run's files are replaced only with --force.
    let out = dir.path().join("again");
    make(&out, None);
    let before = std::fs::read(out.join("sandal-left.svg")).unwrap();
    let run = naocalib().arg("sandal").arg(&out).output().unwrap();
    assert_clean_failure(&run, &["already exists", "--force"]);
    assert_eq!(std::fs::read(out.join("sandal-left.svg")).unwrap(), before);
    let run = naocalib()
        .arg("sandal")
        .arg(&out)
        .arg("--force")
        .output()
        .unwrap();
    assert!(run.status.success());
}

/// What cannot be a sandal is refused before anything is written, the error naming the
/// `dataset.toml`, the line and the key: a pattern longer than the bound on a side (the
/// drawing, its PDFs and the memory they take stay bounded whatever the squares), a
/// pattern whose centre is farther than the bound from the ankle (a plate strapped to the
/// foot), a pattern wholly under the sole (the foot hides it), a plate not flat.
#[test]
fn what_cannot_be_a_sandal_is_refused_naming_file_line_and_key() {
    use naocalib::sandal::geometry::{MAX_MOUNT_MM, MAX_PATTERN_MM};
    let dir = tempfile::tempdir().unwrap();
    let long = MAX_PATTERN_MM / 4.0 + 1.0;
    let far = MAX_MOUNT_MM + 1.0;
    for (board, key, needle) in [
        (
            "[board]\nsquares_x = 64\nsquares_y = 64\nsquare_mm = 200\n".to_string(),
            "squares_x",
            "board.squares_x",
        ),
        (
            format!("[board]\nsquares_x = 3\nsquares_y = 4\nsquare_mm = {long}\n"),
            "square_mm",
            "board.square_mm",
        ),
        (
            format!(
                "[board]\nmount_origin_mm = [{}, {}, 0]\n",
                far * 0.8,
                far * 0.6
            ),
            "mount_origin_mm",
            "board.mount_origin_mm",
        ),
        (
            "[board]\nsquares_x = 3\nsquares_y = 3\nsquare_mm = 10\nmount_origin_mm = [30, 0, 0]\n"
                .to_string(),
            "mount_origin_mm",
            "under the left sole",
        ),
        (
            "[board]\nmount_rpy_deg = [4, 0, 0]\n".to_string(),
            "mount_rpy_deg",
            "board.mount_rpy_deg[0]",
        ),
    ] {
        let text = format!("{CAMERA}{board}");
        let line = text.lines().position(|l| l.starts_with(key)).unwrap() + 1;
        let config = write_config(dir.path(), &text);
        let out = dir.path().join("out");
        let run = naocalib()
            .arg("sandal")
            .arg(&out)
            .arg("--config")
            .arg(&config)
            .output()
            .unwrap();
        let at = format!("dataset.toml line {line}, field board.{key}");
        assert_clean_failure(&run, &[needle, at.as_str()]);
        assert!(!out.exists(), "{board}: something was written");
    }
}

/// Pixels per millimetre of the renderings.
#[cfg(feature = "detect")]
const PX_PER_MM: f64 = 4.0;

/// The SVG rendered by resvg at [`PX_PER_MM`] on white, as a PNG.
#[cfg(feature = "detect")]
fn render(svg: &Path, px_per_mm: f64) -> Vec<u8> {
    use resvg::{tiny_skia, usvg};
    let mut options = usvg::Options::default();
    options
        .fontdb_mut()
        .load_font_data(dejavu::sans::regular().to_vec());
    options.fontdb_mut().set_sans_serif_family("DejaVu Sans");
    let tree = usvg::Tree::from_data(&std::fs::read(svg).unwrap(), &options).unwrap();
    let read = read_svg(svg);
    // usvg sizes millimetres at 96 dpi.
    let scale = (px_per_mm * 25.4 / 96.0) as f32;
    let w = (read.size_mm[0] * px_per_mm).ceil() as u32;
    let h = (read.size_mm[1] * px_per_mm).ceil() as u32;
    let mut pixmap = tiny_skia::Pixmap::new(w, h).unwrap();
    pixmap.fill(tiny_skia::Color::WHITE);
    resvg::render(
        &tree,
        tiny_skia::Transform::from_scale(scale, scale),
        &mut pixmap.as_mut(),
    );
    pixmap.encode_png().unwrap()
}

#[cfg(feature = "detect")]
#[test]
fn detection_finds_the_rendered_pattern_with_the_models_numbering() {
    use naocalib::detect::guided;
    use naocalib::model::{Camera, Model, Pose};

    let dir = tempfile::tempdir().unwrap();
    make(dir.path(), None);
    let board = Board::turned();
    let mut worst = 0.0f64;
    for side in Side::BOTH {
        let path = dir.path().join(format!("sandal-{}.svg", side.name()));
        let png = render(&path, PX_PER_MM);
        let image = naocalib::detect::decode_grey(&path, &png).unwrap();
        let svg = read_svg(&path);
        // A camera straight above the printed face sees it as the renderer draws it:
        // x_C = −z_S, y_C = y_S, z_C = x_S, 1 m above the ankle, f/d = PX_PER_MM, and
        // pixel centres at integer coordinates (OpenCV) half a pixel from the renderer's.
        let d = 1000.0;
        let camera = Camera {
            width: (svg.size_mm[0] * PX_PER_MM).ceil() as u32,
            height: (svg.size_mm[1] * PX_PER_MM).ceil() as u32,
            fx: PX_PER_MM * d,
            fy: PX_PER_MM * d,
            cx: PX_PER_MM * svg.origin[0] - 0.5,
            cy: PX_PER_MM * svg.origin[1] - 0.5,
            distortion: [0.0; 5],
        };
        let sole_to_camera = Pose {
            rotation: [[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]],
            translation: [0.0, 0.0, d],
        };
        let pose = sole_to_camera.inverse_then(&board.mount());
        let model = Model {
            camera,
            board,
            ..Model::default()
        };
        let integral = guided::Integral::new(&image);
        let found = guided::detect(&image, &integral, &model, &camera, &pose, 0.3, 2.0)
            .unwrap()
            .unwrap_or_else(|e| panic!("{side:?}: not found: {e}"));
        assert_eq!(found.vertices.len(), 24, "{side:?}: {}", found.numbered);
        // Where the SVG puts each vertex, numbered by the model.
        let corners = touching_corners(&svg.squares);
        let sole: Vec<[f64; 2]> = corners.iter().map(|p| svg.sole(*p)).collect();
        let (_, numbering) = match_vertices(&sole, &board);
        for (v, px) in &found.vertices {
            let k = numbering.iter().position(|n| n == v).unwrap();
            let expected = [
                PX_PER_MM * corners[k][0] - 0.5,
                PX_PER_MM * corners[k][1] - 0.5,
            ];
            let e = dist(*px, expected);
            assert!(
                e <= 0.1,
                "{side:?} vertex {v:?} found {e} px from the SVG's"
            );
            worst = worst.max(e);
        }
    }
    println!("largest detection error {worst:.3} px at {PX_PER_MM} px/mm");
}

/// Writes the pictures of docs/SANDALS.md from the outputs (run on purpose:
/// `cargo test --test it sandal::docs_pictures -- --ignored`).
#[cfg(feature = "detect")]
#[test]
#[ignore]
fn docs_pictures() {
    let dir = tempfile::tempdir().unwrap();
    make(dir.path(), None);
    let docs = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs");
    for side in ["left", "right"] {
        let png = render(&dir.path().join(format!("sandal-{side}.svg")), 3.0);
        std::fs::write(docs.join(format!("sandal-{side}.png")), png).unwrap();
    }
}
