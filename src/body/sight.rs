//! Which inner vertices of a board the body leaves in plain sight of the camera: a vertex
//! counts only when its refinement window (the squares around it, to half a square either
//! way) is in line of sight past every part of the body. The one prediction the planner
//! (the vertices a capture is planned for) and detection (the vertices it drops as
//! behind the body) both make.
//!
//! The lines of sight are those of the model at the given parameters, the body grown for
//! what the parameters may be off by: 3 mm for the board's own foot and toe (rigid with
//! the board; only the camera's place moves against them) and for the torso, pelvis and
//! arms (rigid with the head but for its two joints), 10 mm for the legs' other parts. A
//! part whose grown solid holds the camera is taken as it is. The sandal that carries the
//! pattern is left out (the pattern is its top face).

use super::shapes::{dot, norm, point_segment_distance, sub};
use super::{BodyModel, Kind, Part};
use crate::model::{CameraId, JointAngles, Model, PARAMETER_COUNT, Side, StanceChains, Vertex};

/// How much the board's own foot and toe, the torso, pelvis and arms are grown (mm).
pub const GROW_OWN: f64 = 3.0;
/// How much the legs' other parts are grown (mm).
pub const GROW_OTHER: f64 = 10.0;

/// How much the parts are grown for what the parameters may be off by (mm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Growth {
    /// The board's own foot and toe, the torso, pelvis and arms.
    pub own: f64,
    /// The legs' other parts.
    pub other: f64,
}

impl Growth {
    /// For a prediction from parameters that may be off by a robot's offsets:
    /// [`GROW_OWN`] and [`GROW_OTHER`].
    pub const FOR_OFFSETS: Growth = Growth {
        own: GROW_OWN,
        other: GROW_OTHER,
    };
    /// The body as it is, for parameters known exactly (the simulator's truth).
    pub const NONE: Growth = Growth {
        own: 0.0,
        other: 0.0,
    };

    /// The growth of `part` for the board of leg `side` seen from `eye`: none for a part
    /// whose grown solid holds the camera.
    fn of(&self, part: &Part, side: Side, eye: [f64; 3]) -> f64 {
        let g = if own_foot(part, side) || !part.kind.is_leg() {
            self.own
        } else {
            self.other
        };
        if part.shape.distance(eye) <= g {
            0.0
        } else {
            g
        }
    }
}

/// A vertex the body hides, with the part in front of it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hidden {
    /// Which vertex.
    pub vertex: Vertex,
    /// The part of the body in front of its window.
    pub kind: Kind,
    /// Its side, for a part of a leg or an arm.
    pub side: Option<Side>,
}

impl Hidden {
    /// The part's name ("left toe").
    pub fn by(&self) -> String {
        super::part_name(self.kind, self.side)
    }
}

/// The vertices of the board of leg `side` that `body` hides from `camera` at the logged
/// angles `logged`, predicted with the parameters `params` (the logged angles plus their
/// offsets pose the body), the parts grown by `growth`.
pub fn hidden(
    model: &Model,
    body: &BodyModel,
    camera: CameraId,
    side: Side,
    logged: &JointAngles,
    params: &[f64; PARAMETER_COUNT],
    growth: Growth,
) -> Vec<Hidden> {
    Sightlines::new(model, body, camera, side, logged, params, growth).hidden()
}

/// The lines of sight from the camera to the lattice at half a square over a board's
/// inner squares (the windows overlap: the lattice holds every window's points, each
/// tested once), with the posed body's parts that may stand in the way: what [`hidden`]
/// and the planner's count ([`Sightlines::at_least_in_sight`]) test.
pub struct Sightlines {
    eye: [f64; 3],
    /// The lattice's points in `O`, row by row.
    lattice: Vec<[f64; 3]>,
    /// Points per lattice row.
    nx: usize,
    /// The board's inner vertices.
    vertices: Vec<Vertex>,
    posed: super::PosedBody,
    /// The parts that may stand in the way (indices into `posed.parts`), each with its
    /// growth and the cone from the eye that holds it grown ([`Cone`]).
    near: Vec<(usize, f64, Option<Cone>)>,
}

/// The cone from the eye that holds a part's bounding sphere: a line of sight outside it
/// cannot meet the part (a test of one product instead of the part's distance).
#[derive(Debug, Clone, Copy)]
struct Cone {
    /// The unit direction from the eye to the sphere's centre.
    axis: [f64; 3],
    /// The cosine of the cone's half-angle, lowered a little against rounding.
    cos_half: f64,
}

impl Cone {
    /// The cone of the ball `(centre, radius)` seen from `eye`; `None` when the eye is in
    /// it or next to it (every direction then may meet it).
    fn of(eye: [f64; 3], centre: [f64; 3], radius: f64) -> Option<Cone> {
        let to = sub(centre, eye);
        let d = norm(to);
        if d <= 1.01 * radius {
            return None;
        }
        let sin_half = radius / d;
        Some(Cone {
            axis: to.map(|x| x / d),
            cos_half: (1.0 - sin_half * sin_half).sqrt() - 1e-9,
        })
    }

    /// Whether the unit direction `dir` lies outside the cone: every point along it is
    /// farther from the sphere's centre than its radius.
    fn misses(&self, dir: [f64; 3]) -> bool {
        dot(self.axis, dir) < self.cos_half
    }
}

impl Sightlines {
    /// The lines of sight to the board of leg `side` from `camera` at the logged angles
    /// `logged`, predicted with the parameters `params` (the logged angles plus their
    /// offsets pose the body), the parts grown by `growth`.
    pub fn new(
        model: &Model,
        body: &BodyModel,
        camera: CameraId,
        side: Side,
        logged: &JointAngles,
        params: &[f64; PARAMETER_COUNT],
        growth: Growth,
    ) -> Self {
        let chains = model.chains_for(camera, side, logged);
        Self::with_chains(model, body, side, logged, &chains, params, growth)
    }

    /// [`Sightlines::new`] with the stance's chains ([`Model::chains_for`] of the camera,
    /// `side` and `logged`) already built.
    pub fn with_chains(
        model: &Model,
        body: &BodyModel,
        side: Side,
        logged: &JointAngles,
        chains: &StanceChains,
        params: &[f64; PARAMETER_COUNT],
        growth: Growth,
    ) -> Self {
        let joints = JointAngles::from_fn(|j| logged.get(j) + params[j.offset().index()]);
        let posed = body.pose(&model.robot, &model.board, &joints);
        let eye = chains.camera.eval(params).translation;
        let board = chains.board.eval(params);
        let b = &model.board;
        let (nx, ny) = (2 * b.cols() + 1, 2 * b.rows() + 1);
        let first = b.vertex_position(Vertex { row: 0, col: 0 });
        let h = b.square / 2.0;
        let lattice: Vec<[f64; 3]> = (0..ny)
            .flat_map(|j| (0..nx).map(move |i| (i, j)))
            .map(|(i, j)| {
                board.apply(&[
                    first[0] + (i as f64 - 1.0) * h,
                    first[1] + (j as f64 - 1.0) * h,
                    0.0,
                ])
            })
            .collect();
        // Not the head, not the sandal carrying the pattern, only the parts whose bounding
        // sphere reaches the lines of sight to the lattice's corners' hull (the lines to
        // any lattice point lie in the cone over the lattice's bounding sphere).
        let (centre, reach) = bounding_sphere(&lattice);
        let near: Vec<(usize, f64, Option<Cone>)> = posed
            .parts
            .iter()
            .enumerate()
            .filter(|(_, p)| {
                p.kind != Kind::Head && !(p.kind == Kind::Sandal && p.side == Some(side))
            })
            .filter_map(|(k, p)| {
                let g = growth.of(p, side, eye);
                let (c, r) = p.shape.bounds();
                in_cone(eye, centre, reach, c, r + g).then(|| (k, g, Cone::of(eye, c, r + g)))
            })
            .collect();
        Sightlines {
            eye,
            lattice,
            nx: nx as usize,
            vertices: b.vertices().collect(),
            posed,
            near,
        }
    }

    /// The vertices whose window a part hides, each with the part.
    pub fn hidden(&self) -> Vec<Hidden> {
        let blocked: Vec<Option<&Part>> =
            (0..self.lattice.len()).map(|k| self.blocked(k)).collect();
        self.vertices
            .iter()
            .filter_map(|&v| {
                self.window(v).find_map(|k| blocked[k]).map(|part| Hidden {
                    vertex: v,
                    kind: part.kind,
                    side: part.side,
                })
            })
            .collect()
    }

    /// Whether at least `need` vertices are in plain sight (`need` of those [`hidden`]
    /// leaves), found without testing every line of sight: the count stops once it decides.
    pub fn at_least_in_sight(&self, need: usize) -> bool {
        let mut known: Vec<Option<bool>> = vec![None; self.lattice.len()];
        let mut blocked = |k: usize| *known[k].get_or_insert_with(|| self.blocked(k).is_some());
        let of = self.vertices.len();
        let (mut seen, mut hidden) = (0, 0);
        for &v in &self.vertices {
            if seen >= need {
                return true;
            }
            if of - hidden < need {
                return false;
            }
            if self.window(v).any(&mut blocked) {
                hidden += 1;
            } else {
                seen += 1;
            }
        }
        seen >= need
    }

    /// The first part in the way of the line of sight to lattice point `k`.
    fn blocked(&self, k: usize) -> Option<&Part> {
        let to = sub(self.lattice[k], self.eye);
        let length = norm(to);
        let dir = to.map(|x| x / length);
        self.near
            .iter()
            .filter(|(_, _, cone)| length == 0.0 || !cone.is_some_and(|c| c.misses(dir)))
            .map(|&(i, g, _)| (&self.posed.parts[i], g))
            .find(|(p, g)| p.shape.blocks(self.eye, self.lattice[k], *g))
            .map(|(p, _)| p)
    }

    /// The lattice points of vertex `v`'s refinement window.
    fn window(&self, v: Vertex) -> impl Iterator<Item = usize> + use<> {
        let (i0, j0) = (2 * v.col as usize, 2 * v.row as usize);
        let nx = self.nx;
        (0..3).flat_map(move |dj| (0..3).map(move |di| (j0 + dj) * nx + i0 + di))
    }
}

/// The centre and radius of a sphere holding `points` (their centroid and the farthest).
fn bounding_sphere(points: &[[f64; 3]]) -> ([f64; 3], f64) {
    let n = points.len().max(1) as f64;
    let c: [f64; 3] = std::array::from_fn(|k| points.iter().map(|p| p[k]).sum::<f64>() / n);
    let r = points.iter().map(|p| norm(sub(*p, c))).fold(0.0, f64::max);
    (c, r)
}

/// Whether the ball `(c, r)` may meet a segment from `eye` to a point of the ball
/// `(centre, reach)`: a point of such a segment at parameter `t` lies within `t·reach` of
/// the segment from `eye` to `centre` at the same `t`.
fn in_cone(eye: [f64; 3], centre: [f64; 3], reach: f64, c: [f64; 3], r: f64) -> bool {
    point_segment_distance(c, eye, centre) < r + reach
}

/// The inner vertices [`hidden`] leaves in plain sight, row by row, the parts grown for the
/// offsets ([`Growth::FOR_OFFSETS`]).
pub fn in_sight(
    model: &Model,
    body: &BodyModel,
    camera: CameraId,
    side: Side,
    logged: &JointAngles,
    params: &[f64; PARAMETER_COUNT],
) -> Vec<Vertex> {
    let hidden = hidden(
        model,
        body,
        camera,
        side,
        logged,
        params,
        Growth::FOR_OFFSETS,
    );
    model
        .board
        .vertices()
        .filter(|v| !hidden.iter().any(|h| h.vertex == *v))
        .collect()
}

/// Whether `p` is the foot or toe of the leg on `side`.
fn own_foot(p: &Part, side: Side) -> bool {
    p.side == Some(side) && matches!(p.kind, Kind::Foot | Kind::Toe)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::body::first_blocking;
    use crate::model::{Board, Joint};

    /// The points of `v`'s refinement window in the board frame: the vertex and the eight
    /// points half a square from it.
    fn window(board: &Board, v: Vertex) -> impl Iterator<Item = [f64; 3]> {
        let [x, y, _] = board.vertex_position(v);
        let h = board.square / 2.0;
        (-1..=1).flat_map(move |i| (-1..=1).map(move |j| [x + i as f64 * h, y + j as f64 * h, 0.0]))
    }

    /// The shared lattice, the cone around it and the cones around the parts find, vertex
    /// by vertex, what testing each window's nine lines of sight against every part finds.
    #[test]
    fn the_lattice_finds_what_each_window_tested_alone_finds() {
        let model = Model::default();
        let body = BodyModel::default();
        let params = [0.0; PARAMETER_COUNT];
        let mut some_hidden = 0;
        let mut some_clear = 0;
        for (k, pitch) in [-1.4, -1.2, -0.9, -0.6].into_iter().enumerate() {
            let mut joints = crate::body::raised_left();
            joints.set(Joint::LHipPitch, pitch);
            joints.set(Joint::LKneePitch, 0.2 * k as f64);
            for camera in [CameraId::Lower, CameraId::Upper] {
                let found = hidden(
                    &model,
                    &body,
                    camera,
                    Side::Left,
                    &joints,
                    &params,
                    Growth::FOR_OFFSETS,
                );
                let chains = model.chains_for(camera, Side::Left, &joints);
                let eye = chains.camera.eval(&params).translation;
                let board = chains.board.eval(&params);
                let posed = body.pose(&model.robot, &model.board, &joints);
                let grow = |p: &Part| Growth::FOR_OFFSETS.of(p, Side::Left, eye);
                let carrier = |p: &Part| p.kind == Kind::Sandal && p.side == Some(Side::Left);
                for v in model.board.vertices() {
                    let targets: Vec<[f64; 3]> =
                        window(&model.board, v).map(|p| board.apply(&p)).collect();
                    let alone = first_blocking(&posed, eye, &targets, grow, carrier);
                    let shared = found.iter().find(|h| h.vertex == v);
                    assert_eq!(
                        alone.is_some(),
                        shared.is_some(),
                        "{camera:?} {pitch} {v:?}"
                    );
                    if alone.is_some() {
                        some_hidden += 1;
                    } else {
                        some_clear += 1;
                    }
                }
            }
        }
        assert!(
            some_hidden > 10 && some_clear > 10,
            "{some_hidden} {some_clear}"
        );
    }

    /// A direction a part's cone misses passes the part's bounding ball at every distance
    /// from the eye; and directions that pass near it are not missed.
    #[test]
    fn a_cone_misses_only_directions_that_pass_the_ball() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let (mut missed, mut kept) = (0, 0);
        for _ in 0..20_000 {
            let eye = std::array::from_fn(|_| rng.random_range(-100.0..100.0));
            let centre = std::array::from_fn(|_| rng.random_range(-300.0..300.0));
            let radius = rng.random_range(1.0..80.0);
            let Some(cone) = Cone::of(eye, centre, radius) else {
                continue;
            };
            // Directions towards points near the ball, so that both outcomes occur.
            let target: [f64; 3] =
                std::array::from_fn(|i| centre[i] + rng.random_range(-3.0..3.0) * radius);
            let to = sub(target, eye);
            let dir = to.map(|x| x / norm(to));
            let far: [f64; 3] = std::array::from_fn(|i| eye[i] + 2000.0 * dir[i]);
            let nearest = point_segment_distance(centre, eye, far);
            if cone.misses(dir) {
                missed += 1;
                assert!(
                    nearest > radius,
                    "missed but {nearest} from a ball of {radius}"
                );
            } else {
                kept += 1;
            }
        }
        assert!(missed > 1000 && kept > 1000, "{missed} {kept}");
    }
}
