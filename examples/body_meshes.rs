//! Checks naocalib's body model (`naocalib::body`) against the NAO's official meshes: every
//! vertex of every link's mesh, placed by the model's own leg and arm frames at several
//! postures, must lie inside the solids that stand for that link. Prints per link the
//! vertices checked, how many lie outside (must be 0), the smallest margin (a vertex's
//! distance inside the nearest surface of its solids) and the largest gap (how far the solids
//! reach past the mesh in any direction); then per posture the vertices outside and the least
//! margin; then per solid the size that encloses every vertex it holds with
//! [`BodyModel::MARGIN`]. Exits with 1 when a vertex lies outside, 2 on bad input.
//!
//! The meshes are Aldebaran's and are not part of naocalib; fetch them yourself, either or
//! both of (all figures are taken over every set given):
//!
//! - the V4.0 parts and the fingers: `git clone https://github.com/jrl-umi3218/nao_description`,
//!   then pass the directory `nao_description/meshes/V40` (COLLADA, metres);
//! - the V6 parts of B-Human's SimRobot scene: `curl -LO https://raw.githubusercontent.com/bhuman/BHumanCodeRelease/master/Config/Scenes/Includes/NaoV6H25.rsi3`,
//!   then pass the file `NaoV6H25.rsi3` (vertices in metres).
//!
//!     cargo run --release --example body_meshes -- nao_description/meshes/V40 NaoV6H25.rsi3

use std::collections::HashMap;
use std::f64::consts::FRAC_PI_2;
use std::path::{Path, PathBuf};

use naocalib::body::posture::arm_frames;
use naocalib::body::{ArmPosture, BodyModel, Kind, Part, Shape, leg_frames};
use naocalib::model::{Axis, Board, Joint, JointAngles, Pose, RobotGeometry, Side};

/// The URDF `torso` frame above `O` (mm).
const TORSO_Z: f64 = 85.0;

/// The frame a mesh is drawn in: the URDF link frame after the named joint.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Frame {
    Torso,
    Neck,
    Head,
    HipYawPitch,
    HipRoll,
    HipPitch,
    KneePitch,
    AnklePitch,
    AnkleRoll,
    ShoulderPitch,
    ShoulderRoll,
    ElbowRoll,
    WristYaw,
}

/// One link's mesh: its URDF name, the files that hold it, its frame and the solids of the
/// body model that must enclose it.
struct Link {
    name: String,
    side: Option<Side>,
    frame: Frame,
    /// The COLLADA file names (without `.dae`) in the V40 directory, with a fixed pose in the
    /// link frame per file (fingers, at several hand openings).
    dae: Vec<(String, Pose<f64>)>,
    /// The `<Vertices name=…>` of the SimRobot scene.
    rsi: Vec<String>,
    enclosed_by: &'static [Kind],
}

/// The links: URDF name, frame, COLLADA file, SimRobot vertices, the solids that enclose it
/// (the thigh's top, the HipPitch motor's housing, may be the pelvis's; the sole stands on
/// the sandal); `{s}` stands for `L`/`R`, `{l}` for `l`/`r` (the paired links listed once).
#[rustfmt::skip]
const TABLE: [(&str, Frame, &str, &str, &[Kind]); 13] = {
    use Frame::*;
    [
        ("torso", Torso, "Torso", "naoTorsoV6", &[Kind::Torso, Kind::Pelvis, Kind::Shoulder]),
        ("Neck", Neck, "HeadYaw", "naoHeadYaw", &[Kind::Head]),
        ("Head", Head, "HeadPitch", "naoHeadPitchV6", &[Kind::Head]),
        ("{s}Pelvis", HipYawPitch, "{s}HipYawPitch", "nao{s}HipYawPitch", &[Kind::Pelvis, Kind::Thigh]),
        ("{s}Hip", HipRoll, "{s}HipRoll", "nao{s}HipRoll", &[Kind::Pelvis, Kind::Thigh]),
        ("{s}Thigh", HipPitch, "{s}HipPitch", "nao{s}HipPitch", &[Kind::Thigh, Kind::Pelvis]),
        ("{s}Tibia", KneePitch, "{s}KneePitch", "nao{s}KneePitchV6", &[Kind::Tibia]),
        ("{s}AnklePitch", AnklePitch, "{s}AnklePitch", "nao{s}AnklePitch", &[Kind::Tibia, Kind::Foot]),
        ("{l}_ankle", AnkleRoll, "{s}AnkleRoll", "nao{s}AnkleRollV6", &[Kind::Foot, Kind::Toe, Kind::Sandal]),
        ("{s}Shoulder", ShoulderPitch, "{s}ShoulderPitch", "nao{s}ShoulderPitch", &[Kind::Shoulder]),
        ("{s}Bicep", ShoulderRoll, "{s}ShoulderRoll", "nao{s}ShoulderRollV6", &[Kind::Shoulder, Kind::UpperArm]),
        ("{s}ForeArm", ElbowRoll, "{s}ElbowRoll", "nao{s}ElbowRoll", &[Kind::Forearm]),
        ("{l}_wrist", WristYaw, "{s}WristYaw", "naoWristYawV6", &[Kind::Forearm]),
    ]
};

fn links() -> Vec<Link> {
    let mut all = Vec::new();
    for (name, frame, dae, rsi, enclosed_by) in TABLE {
        let sides: &[Option<Side>] = if name.contains('{') {
            &[Some(Side::Left), Some(Side::Right)]
        } else {
            &[None]
        };
        for &side in sides {
            let s = if side == Some(Side::Right) { "R" } else { "L" };
            let named = |t: &str| t.replace("{s}", s).replace("{l}", &s.to_lowercase());
            let mut dae = vec![(named(dae), Pose::identity())];
            if frame == Frame::WristYaw {
                dae.extend(fingers(s));
            }
            all.push(Link {
                name: named(name),
                side,
                frame,
                dae,
                rsi: vec![named(rsi)],
                enclosed_by,
            });
        }
    }
    all
}

/// The finger and thumb meshes in the wrist frame at the hand closed, half open and open
/// (URDF `nao_description`: the finger joints turn about their z axes by the `LHand`/`RHand`
/// angle, 0 = closed … 1 = open).
fn fingers(s: &str) -> Vec<(String, Pose<f64>)> {
    let rpy = |x: f64, y: f64, z: f64, r: f64, p: f64, w: f64| {
        Pose::translation(x, y, z)
            .compose(&Pose::rotation(Axis::Z, w))
            .compose(&Pose::rotation(Axis::Y, p))
            .compose(&Pose::rotation(Axis::X, r))
    };
    let next = || rpy(14.36, 0.0, 0.0, 0.0, 0.0, -0.999899);
    let chains = [
        (
            "Finger1",
            rpy(69.07, 11.57, -3.04, 1.8862, 0.976662, 0.264067),
            3,
        ),
        (
            "Finger2",
            rpy(69.07, -11.57, -3.04, 1.25539, 0.976662, -0.264067),
            3,
        ),
        // The URDF rounds the thumb's roll to −1.5708.
        (
            "Thumb",
            rpy(48.95, 0.0, -26.38, -FRAC_PI_2, 0.0472984, 0.0),
            2,
        ),
    ];
    let mut out = Vec::new();
    for hand in [0.0, 0.5, 1.0] {
        let turn = Pose::rotation(Axis::Z, 0.999899 * hand);
        for (name, base, segments) in &chains {
            let mut pose = base.compose(&turn);
            for k in 1..=*segments {
                out.push((format!("{s}{name}{k}"), pose.clone()));
                pose = pose.compose(&next()).compose(&turn);
            }
        }
    }
    out
}

/// The vertices (mm, link frame) of every link, from the files given.
fn read_meshes(paths: &[PathBuf], links: &[Link]) -> Result<Vec<Vec<[f64; 3]>>, String> {
    let mut out = vec![Vec::new(); links.len()];
    for path in paths {
        if path.is_dir() {
            for (k, link) in links.iter().enumerate() {
                for (file, pose) in &link.dae {
                    let file = path.join(format!("{file}.dae"));
                    out[k].extend(read_dae(&file)?.iter().map(|p| pose.apply(p)));
                }
            }
        } else {
            let text = read(path)?;
            let sets = read_rsi(path, &text)?;
            for (k, link) in links.iter().enumerate() {
                for name in &link.rsi {
                    let v = sets.get(name.as_str()).ok_or_else(|| {
                        format!(
                            "{}: no <Vertices name=\"{name}\"> (link {})",
                            path.display(),
                            link.name
                        )
                    })?;
                    out[k].extend(v);
                }
            }
        }
    }
    Ok(out)
}

fn read(path: &Path) -> Result<String, String> {
    std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))
}

/// The numbers of `text`; `what` names the place in messages.
fn floats(what: &str, text: &str) -> Result<Vec<f64>, String> {
    text.split_whitespace()
        .map(|t| {
            t.parse::<f64>()
                .map_err(|_| format!("{what}: {t:?} is not a number"))
        })
        .collect()
}

/// The numbers of `text` in threes, times `scale`.
fn numbers(what: &str, text: &str, scale: f64) -> Result<Vec<[f64; 3]>, String> {
    let values = floats(what, text)?;
    if values.len() % 3 != 0 {
        return Err(format!(
            "{what}: {} numbers, not a multiple of 3",
            values.len()
        ));
    }
    Ok(values
        .chunks(3)
        .map(|c| [c[0] * scale, c[1] * scale, c[2] * scale])
        .collect())
}

/// The positions of every geometry of a COLLADA file, in mm, each moved by the node that
/// instantiates it.
fn read_dae(path: &Path) -> Result<Vec<[f64; 3]>, String> {
    let text = read(path)?;
    let doc = roxmltree::Document::parse(&text).map_err(|e| format!("{}: {e}", path.display()))?;
    let named = |n: &roxmltree::Node, tag: &str| n.tag_name().name() == tag;
    let metre = doc
        .descendants()
        .find(|n| named(n, "unit"))
        .and_then(|n| n.attribute("meter"))
        .map_or(Ok(1.0), |m| {
            m.parse::<f64>()
                .map_err(|_| format!("{}: <unit meter={m:?}>", path.display()))
        })?;
    let mut out = Vec::new();
    for geometry in doc.descendants().filter(|n| named(n, "geometry")) {
        let id = geometry.attribute("id").unwrap_or("");
        let at = |what: &str| format!("{}: geometry {id:?}: {what}", path.display());
        let source = geometry
            .descendants()
            .filter(|n| named(n, "vertices"))
            .flat_map(|v| v.children())
            .find(|i| named(i, "input") && i.attribute("semantic") == Some("POSITION"))
            .and_then(|i| i.attribute("source"))
            .ok_or_else(|| at("no <vertices><input semantic=\"POSITION\">"))?
            .trim_start_matches('#');
        let array = geometry
            .descendants()
            .find(|n| named(n, "source") && n.attribute("id") == Some(source))
            .and_then(|s| s.descendants().find(|n| named(n, "float_array")))
            .ok_or_else(|| at(&format!("no <source id={source:?}> with a <float_array>")))?;
        let points = numbers(&at("positions"), array.text().unwrap_or(""), metre * 1000.0)?;
        // The node that places the geometry (identity in the official files).
        let url = format!("#{id}");
        let matrix = doc
            .descendants()
            .filter(|n| named(n, "instance_geometry") && n.attribute("url") == Some(url.as_str()))
            .filter_map(|g| g.parent())
            .find_map(|node| node.children().find(|c| named(c, "matrix")));
        let pose = match matrix {
            None => Pose::identity(),
            Some(m) => {
                let flat = floats(&at("node <matrix>"), m.text().unwrap_or(""))?;
                if flat.len() != 16 {
                    return Err(at("node <matrix> does not hold 16 numbers"));
                }
                Pose {
                    rotation: std::array::from_fn(|i| std::array::from_fn(|k| flat[4 * i + k])),
                    translation: std::array::from_fn(|i| flat[4 * i + 3] * metre * 1000.0),
                }
            }
        };
        out.extend(points.iter().map(|p| pose.apply(p)));
    }
    if out.is_empty() {
        return Err(format!("{}: no geometry", path.display()));
    }
    Ok(out)
}

/// Every `<Vertices name=…>` list of a SimRobot scene, in mm.
fn read_rsi(path: &Path, text: &str) -> Result<HashMap<String, Vec<[f64; 3]>>, String> {
    let doc = roxmltree::Document::parse(text).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut out = HashMap::new();
    for node in doc
        .descendants()
        .filter(|n| n.tag_name().name() == "Vertices")
    {
        let (Some(name), Some(list)) = (node.attribute("name"), node.text()) else {
            continue;
        };
        let scale = match node.attribute("unit") {
            None | Some("m") => 1000.0,
            Some("mm") => 1.0,
            Some(u) => {
                return Err(format!(
                    "{}: <Vertices name={name:?} unit={u:?}>: unknown unit",
                    path.display()
                ));
            }
        };
        let what = format!("{}: <Vertices name={name:?}>", path.display());
        out.insert(name.to_string(), numbers(&what, list, scale)?);
    }
    Ok(out)
}

/// A posture: the leg and head angles, and the arms.
struct Posture {
    name: &'static str,
    joints: JointAngles,
    arms: ArmPosture,
}

fn postures() -> Vec<Posture> {
    let deg = f64::to_radians;
    // Leg angles (HipYawPitch, HipRoll, HipPitch, KneePitch, AnklePitch, AnkleRoll) of the
    // left leg, mirrored in the rolls for the right; then HeadYaw, HeadPitch.
    let legs = |q: [f64; 6], head: [f64; 2]| {
        let mut j = JointAngles::default();
        for side in Side::BOTH {
            for (k, joint) in side.leg_joints().into_iter().enumerate() {
                let roll = k == 1 || k == 5;
                j.set(joint, deg(if roll { side.sign() * q[k] } else { q[k] }));
            }
        }
        j.set(Joint::HeadYaw, deg(head[0]));
        j.set(Joint::HeadPitch, deg(head[1]));
        j
    };
    let zero_arms = ArmPosture([0.0; 10]);
    vec![
        Posture {
            name: "zero",
            joints: legs([0.0; 6], [0.0; 2]),
            arms: zero_arms,
        },
        Posture {
            name: "capture arms",
            joints: legs([0.0; 6], [0.0; 2]),
            arms: ArmPosture::CAPTURE,
        },
        Posture {
            name: "arms beside the body",
            joints: legs([0.0; 6], [0.0; 2]),
            arms: ArmPosture::BESIDE_BODY,
        },
        Posture {
            name: "crouch",
            joints: legs([0.0, 0.0, -22.0, 44.0, -22.0, 0.0], [0.0; 2]),
            arms: ArmPosture::CAPTURE,
        },
        Posture {
            name: "legs raised",
            joints: legs([-30.0, 20.0, -60.0, 90.0, -40.0, 15.0], [30.0, 20.0]),
            arms: ArmPosture::CAPTURE,
        },
        Posture {
            name: "legs up, spread",
            joints: legs([-60.0, 40.0, -85.0, 10.0, 50.0, -20.0], [-60.0, -35.0]),
            arms: ArmPosture::CAPTURE,
        },
        Posture {
            name: "knees bent, feet rolled",
            joints: legs([10.0, -20.0, -40.0, 120.0, -65.0, 40.0], [0.0, 29.0]),
            arms: ArmPosture::CAPTURE,
        },
    ]
}

/// The pose in `O` of every mesh frame of the link on `side` at a posture.
fn frame_pose(robot: &RobotGeometry, frame: Frame, side: Option<Side>, p: &Posture) -> Pose<f64> {
    let side = side.unwrap_or(Side::Left);
    let s = side.sign();
    let legs = leg_frames(robot, side, &p.joints);
    let q = side.leg_joints().map(|j| p.joints.get(j));
    let hip_yaw = || {
        Pose::translation(0.0, s * robot.hip_offset_y, 0.0)
            .compose(&Pose::rotation(Axis::X, s * std::f64::consts::FRAC_PI_4))
            .compose(&Pose::rotation(Axis::Z, -s * q[0]))
            .compose(&Pose::rotation(Axis::X, -s * std::f64::consts::FRAC_PI_4))
    };
    let [shoulder, elbow, wrist] = arm_frames(side, &p.arms);
    match frame {
        Frame::Torso => Pose::translation(0.0, 0.0, TORSO_Z),
        Frame::Neck => Pose::translation(0.0, 0.0, robot.hip_to_neck_z)
            .compose(&Pose::rotation(Axis::Z, p.joints.get(Joint::HeadYaw))),
        Frame::Head => Pose::translation(0.0, 0.0, robot.hip_to_neck_z)
            .compose(&Pose::rotation(Axis::Z, p.joints.get(Joint::HeadYaw)))
            .compose(&Pose::rotation(Axis::Y, p.joints.get(Joint::HeadPitch))),
        Frame::HipYawPitch => hip_yaw(),
        Frame::HipRoll => hip_yaw().compose(&Pose::rotation(Axis::X, q[1])),
        Frame::HipPitch => legs.hip,
        Frame::KneePitch => legs.knee,
        Frame::AnklePitch => legs.ankle.compose(&Pose::rotation(Axis::Y, q[4])),
        Frame::AnkleRoll => legs
            .sole
            .compose(&Pose::translation(0.0, 0.0, robot.foot_height)),
        Frame::ShoulderPitch => shoulder.compose(&Pose::rotation(Axis::Z, -p.arms.arm(side)[1])),
        Frame::ShoulderRoll => shoulder,
        Frame::ElbowRoll => elbow,
        Frame::WristYaw => wrist,
    }
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

/// How far `p` lies inside the solid (its distance to the surface), negative outside.
fn margin(shape: &Shape, p: [f64; 3]) -> f64 {
    match shape {
        Shape::Sphere(s) => s.radius - norm(sub(p, s.centre)),
        Shape::Capsule(c) => c.radius - norm(sub(p, closest(c.a, c.b, p))),
        Shape::Box(b) => {
            let d = sub(p, b.centre);
            let q: [f64; 3] = std::array::from_fn(|k| dot(d, b.axes[k]).abs() - b.half[k]);
            let out = norm(q.map(|x| x.max(0.0)));
            if out > 0.0 {
                -out
            } else {
                -q[0].max(q[1]).max(q[2])
            }
        }
    }
}

fn closest(a: [f64; 3], b: [f64; 3], p: [f64; 3]) -> [f64; 3] {
    let ab = sub(b, a);
    let t = (dot(sub(p, a), ab) / dot(ab, ab).max(1e-12)).clamp(0.0, 1.0);
    std::array::from_fn(|i| a[i] + t * ab[i])
}

/// How far the solid reaches along the unit vector `u` (its support function).
fn support(shape: &Shape, u: [f64; 3]) -> f64 {
    match shape {
        Shape::Sphere(s) => dot(u, s.centre) + s.radius,
        Shape::Capsule(c) => dot(u, c.a).max(dot(u, c.b)) + c.radius,
        Shape::Box(b) => {
            dot(u, b.centre)
                + (0..3)
                    .map(|k| b.half[k] * dot(u, b.axes[k]).abs())
                    .sum::<f64>()
        }
    }
}

/// Unit vectors spread evenly over the sphere (Fibonacci lattice).
fn directions(n: usize) -> Vec<[f64; 3]> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
            let r = (1.0 - z * z).sqrt();
            let phi = golden * i as f64;
            [r * phi.cos(), r * phi.sin(), z]
        })
        .collect()
}

/// Per link, over every posture.
#[derive(Default)]
struct LinkStats {
    checked: usize,
    outside: usize,
    min_margin: f64,
    max_gap: f64,
}

/// Per solid (by its place in the posed body, the same at every posture): what the vertices
/// it holds need. Each vertex is held by the solid of its link that it lies deepest in, so
/// the solids sized as printed hold every vertex with the margin together.
struct Need {
    /// The smallest margin of its vertices (negative: outside).
    min_margin: f64,
    /// For boxes: how far its vertices reach past each face, along the box's axes, low and
    /// high side (y in the left side's terms: a right-side box is mirrored).
    past_lo: [f64; 3],
    past_hi: [f64; 3],
}

fn main() {
    let paths: Vec<PathBuf> = std::env::args().skip(1).map(PathBuf::from).collect();
    if paths.is_empty() {
        eprintln!(
            "usage: body_meshes MESH_DIR_OR_RSI3...  (see the top of examples/body_meshes.rs)"
        );
        std::process::exit(2);
    }
    let links = links();
    let meshes = match read_meshes(&paths, &links) {
        Ok(m) => m,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    };
    let robot = RobotGeometry::default();
    let board = Board::default();
    let body = BodyModel::default();
    let dirs = directions(400);
    let mut stats: Vec<LinkStats> = links
        .iter()
        .map(|_| LinkStats {
            min_margin: f64::INFINITY,
            max_gap: f64::NEG_INFINITY,
            ..LinkStats::default()
        })
        .collect();
    let mut needs: HashMap<usize, Need> = HashMap::new();
    let postures = postures();
    let mut solids_at_zero = Vec::new();
    // Per posture: vertices outside, the smallest margin and the link it is on.
    let mut per_posture: Vec<(usize, f64, &str)> = Vec::new();
    for posture in &postures {
        let mut worst = (0usize, f64::INFINITY, "");
        let model = BodyModel {
            arms: posture.arms,
            ..body
        };
        let posed = model.pose(&robot, &board, &posture.joints);
        if solids_at_zero.is_empty() {
            solids_at_zero = posed.parts.clone();
        }
        for ((link, mesh), st) in links.iter().zip(&meshes).zip(&mut stats) {
            let solids: Vec<(usize, &Part)> = posed
                .parts
                .iter()
                .enumerate()
                .filter(|(_, p)| {
                    link.enclosed_by.contains(&p.kind)
                        && (p.side.is_none() || link.side.is_none() || p.side == link.side)
                })
                .collect();
            if solids.is_empty() {
                eprintln!("error: the body model has no solid for link {}", link.name);
                std::process::exit(2);
            }
            let pose = frame_pose(&robot, link.frame, link.side, posture);
            let placed: Vec<[f64; 3]> = mesh.iter().map(|v| pose.apply(v)).collect();
            for p in &placed {
                let (index, part, m) = solids
                    .iter()
                    .map(|(k, s)| (*k, *s, margin(&s.shape, *p)))
                    .max_by(|a, b| a.2.total_cmp(&b.2))
                    .expect("a solid");
                st.checked += 1;
                st.outside += usize::from(m < 0.0);
                st.min_margin = st.min_margin.min(m);
                worst.0 += usize::from(m < 0.0);
                if m < worst.1 {
                    (worst.1, worst.2) = (m, link.name.as_str());
                }
                let need = needs.entry(index).or_insert(Need {
                    min_margin: f64::INFINITY,
                    past_lo: [f64::NEG_INFINITY; 3],
                    past_hi: [f64::NEG_INFINITY; 3],
                });
                need.min_margin = need.min_margin.min(m);
                if let Shape::Box(b) = part.shape {
                    let d = sub(*p, b.centre);
                    for k in 0..3 {
                        let x = dot(d, b.axes[k]);
                        let (lo, hi) = (-x - b.half[k], x - b.half[k]);
                        let (lo, hi) = if k == 1 && part.side == Some(Side::Right) {
                            (hi, lo)
                        } else {
                            (lo, hi)
                        };
                        need.past_lo[k] = need.past_lo[k].max(lo);
                        need.past_hi[k] = need.past_hi[k].max(hi);
                    }
                }
            }
            let gap = dirs
                .iter()
                .map(|u| {
                    let reach = solids
                        .iter()
                        .map(|(_, s)| support(&s.shape, *u))
                        .fold(f64::NEG_INFINITY, f64::max);
                    let mesh_reach = placed
                        .iter()
                        .map(|p| dot(*u, *p))
                        .fold(f64::NEG_INFINITY, f64::max);
                    reach - mesh_reach
                })
                .fold(f64::NEG_INFINITY, f64::max);
            st.max_gap = st.max_gap.max(gap);
        }
        per_posture.push(worst);
    }
    print_links(&links, &stats, &postures, &paths);
    println!();
    println!("| posture | vertices outside | smallest margin (mm) | on link |");
    println!("| --- | --- | --- | --- |");
    for (posture, (outside, least, link)) in postures.iter().zip(&per_posture) {
        println!("| {} | {outside} | {least:.1} | {link} |", posture.name);
    }
    print_solids(&solids_at_zero, &needs);
    if stats.iter().any(|s| s.outside > 0) {
        std::process::exit(1);
    }
}

fn print_links(links: &[Link], stats: &[LinkStats], postures: &[Posture], paths: &[PathBuf]) {
    let names: Vec<String> = paths.iter().map(|p| p.display().to_string()).collect();
    let postures: Vec<&str> = postures.iter().map(|p| p.name).collect();
    println!(
        "Meshes: {}; postures: {}.",
        names.join(", "),
        postures.join(", ")
    );
    println!();
    println!(
        "| link | enclosed by | vertices checked | outside | smallest margin (mm) | largest gap (mm) |"
    );
    println!("| --- | --- | --- | --- | --- | --- |");
    for (link, st) in links.iter().zip(stats) {
        let by: Vec<&str> = link.enclosed_by.iter().map(|k| k.name()).collect();
        println!(
            "| {} | {} | {} | {} | {:.1} | {:.1} |",
            link.name,
            by.join(", "),
            st.checked,
            st.outside,
            st.min_margin,
            st.max_gap
        );
    }
}

/// Per solid of the left side and the middle (the right mirrors the left; the larger need
/// of the two is printed), the size that holds its vertices with [`BodyModel::MARGIN`].
fn print_solids(parts: &[Part], needs: &HashMap<usize, Need>) {
    let m = BodyModel::MARGIN;
    println!();
    println!(
        "Per solid (the larger need of both sides, every posture), the size that holds each of its vertices with the margin of {m} mm; a box's faces move outward by the amounts given (negative: inward), along its own axes, y as for the left side:"
    );
    println!();
    println!("| solid | model | smallest margin (mm) | encloses with the margin |");
    println!("| --- | --- | --- | --- |");
    let fmt = |v: [f64; 3]| format!("({:.1}, {:.1}, {:.1})", v[0], v[1], v[2]);
    for (k, part) in parts.iter().enumerate() {
        // The right side mirrors the left; the sandal's plate is sized by its pattern.
        if part.side == Some(Side::Right) || part.kind == Kind::Sandal {
            continue;
        }
        // The same solid of the other side, if any: the same kind, the same rank among them.
        let rank = parts[..k]
            .iter()
            .filter(|p| p.kind == part.kind && p.side == part.side)
            .count();
        let twin = part.side.and_then(|_| {
            parts
                .iter()
                .enumerate()
                .filter(|(_, p)| p.kind == part.kind && p.side == Some(Side::Right))
                .nth(rank)
                .map(|(j, _)| j)
        });
        let both: Vec<&Need> = std::iter::once(k)
            .chain(twin)
            .filter_map(|j| needs.get(&j))
            .collect();
        if both.is_empty() {
            continue;
        }
        let count = parts
            .iter()
            .filter(|p| p.kind == part.kind && p.side == part.side)
            .count();
        let name = if count > 1 {
            format!("{} {}", part.kind.name(), rank + 1)
        } else {
            part.kind.name().to_string()
        };
        let min_margin = both
            .iter()
            .map(|n| n.min_margin)
            .fold(f64::INFINITY, f64::min);
        let (model, fits) = match part.shape {
            Shape::Capsule(c) => (
                format!("capsule r {:.1}", c.radius),
                format!("r ≥ {:.1}", c.radius - min_margin + m),
            ),
            Shape::Sphere(s) => (
                format!("sphere r {:.1}", s.radius),
                format!("r ≥ {:.1}", s.radius - min_margin + m),
            ),
            Shape::Box(b) => {
                let grow = |f: fn(&Need) -> [f64; 3]| -> [f64; 3] {
                    std::array::from_fn(|i| {
                        both.iter()
                            .map(|n| f(n)[i])
                            .fold(f64::NEG_INFINITY, f64::max)
                            + m
                    })
                };
                let half = b.half.map(|h| 2.0 * h);
                (
                    format!("box {} (edges)", fmt(half)),
                    format!(
                        "low faces {}, high faces {}",
                        fmt(grow(|n| n.past_lo)),
                        fmt(grow(|n| n.past_hi))
                    ),
                )
            }
        };
        println!("| {name} | {model} | {min_margin:.1} | {fits} |");
    }
}
