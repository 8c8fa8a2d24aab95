//! The simple solids the body is made of — capsules, oriented boxes and spheres — with the
//! three questions every reader asks of them: how far is a point, does a line of sight pass,
//! and where does a ray first meet the surface (for drawing).

use crate::model::Pose;

/// An oriented box: a frame and the extent along its axes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OrientedBox {
    /// The box centre in `O`.
    pub centre: [f64; 3],
    /// The box axes in `O` (unit vectors).
    pub axes: [[f64; 3]; 3],
    /// Half the edge lengths along the box axes (mm).
    pub half: [f64; 3],
}

impl OrientedBox {
    /// The box spanning `lo..hi` in the coordinates of `frame` (a pose in `O`).
    pub fn in_frame(frame: &Pose<f64>, lo: [f64; 3], hi: [f64; 3]) -> OrientedBox {
        let mid: [f64; 3] = std::array::from_fn(|k| (lo[k] + hi[k]) / 2.0);
        OrientedBox {
            centre: frame.apply(&mid),
            axes: std::array::from_fn(|k| std::array::from_fn(|i| frame.rotation[i][k])),
            half: std::array::from_fn(|k| (hi[k] - lo[k]).abs() / 2.0),
        }
    }

    /// Distance of point `p` from the box (0 inside).
    pub fn distance(&self, p: [f64; 3]) -> f64 {
        let d = sub(p, self.centre);
        (0..3)
            .map(|k| (dot(d, self.axes[k]).abs() - self.half[k]).max(0.0).powi(2))
            .sum::<f64>()
            .sqrt()
    }

    /// The eight corners.
    pub fn corners(&self) -> [[f64; 3]; 8] {
        std::array::from_fn(|n| {
            let mut p = self.centre;
            for k in 0..3 {
                let s = if n >> k & 1 == 1 { 1.0 } else { -1.0 };
                for (pi, ai) in p.iter_mut().zip(self.axes[k]) {
                    *pi += s * self.half[k] * ai;
                }
            }
            p
        })
    }

    /// Whether two boxes overlap (separating-axis test). Boxes whose bounding spheres lie
    /// apart (by more than a micrometre, for rounding) are apart without it.
    pub fn overlaps(&self, other: &OrientedBox) -> bool {
        let d = sub(other.centre, self.centre);
        let reach = norm(self.half) + norm(other.half);
        if dot(d, d) > (reach + 1e-3) * (reach + 1e-3) {
            return false;
        }
        let mut axes = [[0.0; 3]; 15];
        axes[..3].copy_from_slice(&self.axes);
        axes[3..6].copy_from_slice(&other.axes);
        let mut n = 6;
        for a in self.axes {
            for b in other.axes {
                let c = cross(a, b);
                if dot(c, c) > 1e-12 {
                    axes[n] = c;
                    n += 1;
                }
            }
        }
        axes[..n].iter().all(|axis| {
            let radius = |b: &OrientedBox| {
                (0..3)
                    .map(|k| b.half[k] * dot(b.axes[k], *axis).abs())
                    .sum::<f64>()
            };
            dot(d, *axis).abs() <= radius(self) + radius(other)
        })
    }

    /// The first point where the ray `origin + t·dir` (`t > 0`) enters the box grown by
    /// `grow` mm on every side: `t` and the outward normal there (slab test).
    fn ray(&self, origin: [f64; 3], dir: [f64; 3], grow: f64) -> Option<(f64, [f64; 3])> {
        let o = sub(origin, self.centre);
        let (mut near, mut far) = (f64::NEG_INFINITY, f64::INFINITY);
        let mut normal = [0.0; 3];
        for k in 0..3 {
            let (ok, dk, h) = (
                dot(o, self.axes[k]),
                dot(dir, self.axes[k]),
                self.half[k] + grow,
            );
            if dk.abs() < 1e-15 {
                if ok.abs() > h {
                    return None;
                }
                continue;
            }
            let (t0, t1) = ((-h - ok) / dk, (h - ok) / dk);
            let (lo, hi) = if t0 < t1 { (t0, t1) } else { (t1, t0) };
            if lo > near {
                near = lo;
                let s = if dk > 0.0 { -1.0 } else { 1.0 };
                normal = self.axes[k].map(|a| s * a);
            }
            far = far.min(hi);
            if near > far {
                return None;
            }
        }
        (far > 0.0 && near > 0.0).then_some((near, normal))
    }

    /// The radius of the sphere around the centre that holds the box.
    fn reach(&self) -> f64 {
        norm(self.half)
    }
}

/// A segment swept by a sphere.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Capsule {
    /// One end of the segment (mm, in `O`).
    pub a: [f64; 3],
    /// The other end.
    pub b: [f64; 3],
    /// Radius (mm).
    pub radius: f64,
}

impl Capsule {
    /// Points along the segment, at most `step` mm apart.
    pub fn samples(&self, step: f64) -> impl Iterator<Item = [f64; 3]> + '_ {
        let n = (norm(sub(self.b, self.a)) / step).ceil().max(1.0) as usize;
        (0..=n).map(move |k| {
            let t = k as f64 / n as f64;
            std::array::from_fn(|i| self.a[i] + t * (self.b[i] - self.a[i]))
        })
    }

    /// Whether the capsule touches the box (one of the spheres along its segment, at most
    /// 5 mm apart, reaches into it).
    pub fn hits_box(&self, b: &OrientedBox) -> bool {
        // No point of the segment is nearer the box than its midpoint less half its
        // length (the distance to a box changes no faster than the point moves): a box
        // farther than that from every sphere is missed by all of them, and only a box
        // within reach needs the spheres counted (a micrometre spared for rounding).
        let mid: [f64; 3] = std::array::from_fn(|i| (self.a[i] + self.b[i]) / 2.0);
        let half = norm(sub(self.b, self.a)) / 2.0;
        if b.distance(mid) > self.radius + half + 1e-3 {
            return false;
        }
        self.samples(5.0).any(|p| b.distance(p) < self.radius)
    }

    /// Whether two capsules touch (exact segment distance).
    pub fn hits(&self, other: &Capsule) -> bool {
        segment_distance(self.a, self.b, other.a, other.b) < self.radius + other.radius
    }

    /// Distance of point `p` from the capsule (0 inside).
    pub fn distance(&self, p: [f64; 3]) -> f64 {
        (norm(sub(p, closest_on_segment(self.a, self.b, p))) - self.radius).max(0.0)
    }

    /// The first point where the ray `origin + t·dir` (`t > 0`, `dir` of unit length)
    /// enters the capsule grown by `grow` mm: `t` and the outward normal there.
    fn ray(&self, origin: [f64; 3], dir: [f64; 3], grow: f64) -> Option<(f64, [f64; 3])> {
        let r = self.radius + grow;
        let ba = sub(self.b, self.a);
        let oa = sub(origin, self.a);
        let (baba, bard, baoa) = (dot(ba, ba), dot(ba, dir), dot(ba, oa));
        let (rdoa, oaoa) = (dot(dir, oa), dot(oa, oa));
        let a = baba - bard * bard;
        let mut best: Option<f64> = None;
        if a > 1e-12 {
            // The cylinder's side.
            let b = baba * rdoa - baoa * bard;
            let c = baba * oaoa - baoa * baoa - r * r * baba;
            let h = b * b - a * c;
            if h >= 0.0 {
                let t = (-b - h.sqrt()) / a;
                let y = baoa + t * bard;
                if t > 0.0 && y > 0.0 && y < baba {
                    best = Some(t);
                }
            }
        }
        if best.is_none() {
            // The end caps.
            for centre in [self.a, self.b] {
                if let Some(t) = sphere_ray(centre, r, origin, dir)
                    && best.is_none_or(|b| t < b)
                {
                    best = Some(t);
                }
            }
        }
        let t = best?;
        let p = along(origin, dir, t);
        let n = sub(p, closest_on_segment(self.a, self.b, p));
        Some((t, scale(n, 1.0 / norm(n).max(1e-12))))
    }
}

/// A ball.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sphere {
    /// The centre (mm, in `O`).
    pub centre: [f64; 3],
    /// Radius (mm).
    pub radius: f64,
}

/// One solid of the body.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Shape {
    /// A segment swept by a sphere (thighs, tibias, arms).
    Capsule(Capsule),
    /// An oriented box (torso, feet, sandals).
    Box(OrientedBox),
    /// A ball (shoulders, head).
    Sphere(Sphere),
}

impl Shape {
    /// Distance of point `p` from the solid (0 inside).
    pub fn distance(&self, p: [f64; 3]) -> f64 {
        match self {
            Shape::Capsule(c) => c.distance(p),
            Shape::Box(b) => b.distance(p),
            Shape::Sphere(s) => (norm(sub(p, s.centre)) - s.radius).max(0.0),
        }
    }

    /// The first point where the ray `origin + t·dir` (`t > 0`, `dir` of unit length)
    /// enters the solid grown by `grow` mm on every side: `t` (mm) and the outward surface
    /// normal there. `None` when the ray misses it, or starts inside it.
    pub fn ray(&self, origin: [f64; 3], dir: [f64; 3], grow: f64) -> Option<(f64, [f64; 3])> {
        match self {
            Shape::Capsule(c) => c.ray(origin, dir, grow),
            Shape::Box(b) => b.ray(origin, dir, grow),
            Shape::Sphere(s) => {
                let t = sphere_ray(s.centre, s.radius + grow, origin, dir)?;
                let n = sub(along(origin, dir, t), s.centre);
                Some((t, scale(n, 1.0 / norm(n).max(1e-12))))
            }
        }
    }

    /// Whether the segment from `from` to `to` passes through the solid grown by `grow` mm.
    pub fn blocks(&self, from: [f64; 3], to: [f64; 3], grow: f64) -> bool {
        match self {
            Shape::Capsule(c) => segment_distance(from, to, c.a, c.b) < c.radius + grow,
            Shape::Sphere(s) => {
                norm(sub(closest_on_segment(from, to, s.centre), s.centre)) < s.radius + grow
            }
            Shape::Box(b) => {
                let d = sub(to, from);
                let length = norm(d);
                if length < 1e-12 {
                    return b.distance(from) < grow;
                }
                let dir = scale(d, 1.0 / length);
                if b.distance(from) < grow {
                    return true;
                }
                b.ray(from, dir, grow).is_some_and(|(t, _)| t < length)
            }
        }
    }

    /// A sphere holding the solid: its centre and radius.
    pub fn bounds(&self) -> ([f64; 3], f64) {
        match self {
            Shape::Capsule(c) => {
                let mid = std::array::from_fn(|i| (c.a[i] + c.b[i]) / 2.0);
                (mid, norm(sub(c.b, c.a)) / 2.0 + c.radius)
            }
            Shape::Box(b) => (b.centre, b.reach()),
            Shape::Sphere(s) => (s.centre, s.radius),
        }
    }

    /// The solid moved by `pose` (its coordinates taken as those of `pose`'s child frame).
    pub fn moved(&self, pose: &Pose<f64>) -> Shape {
        let turn = |v: [f64; 3]| -> [f64; 3] {
            std::array::from_fn(|i| (0..3).map(|k| pose.rotation[i][k] * v[k]).sum())
        };
        match self {
            Shape::Capsule(c) => Shape::Capsule(Capsule {
                a: pose.apply(&c.a),
                b: pose.apply(&c.b),
                radius: c.radius,
            }),
            Shape::Box(b) => Shape::Box(OrientedBox {
                centre: pose.apply(&b.centre),
                axes: b.axes.map(turn),
                half: b.half,
            }),
            Shape::Sphere(s) => Shape::Sphere(Sphere {
                centre: pose.apply(&s.centre),
                radius: s.radius,
            }),
        }
    }
}

/// The smallest `t > 0` where the ray `origin + t·dir` (unit `dir`) meets the sphere.
fn sphere_ray(centre: [f64; 3], radius: f64, origin: [f64; 3], dir: [f64; 3]) -> Option<f64> {
    let oc = sub(origin, centre);
    let b = dot(oc, dir);
    let c = dot(oc, oc) - radius * radius;
    let h = b * b - c;
    if h < 0.0 {
        return None;
    }
    let t = -b - h.sqrt();
    (t > 0.0).then_some(t)
}

fn along(origin: [f64; 3], dir: [f64; 3], t: f64) -> [f64; 3] {
    std::array::from_fn(|i| origin[i] + t * dir[i])
}

/// `a − b`.
pub fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// The dot product.
pub fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The Euclidean length.
pub fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

fn scale(a: [f64; 3], s: f64) -> [f64; 3] {
    a.map(|x| x * s)
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// The point of the segment `a–b` nearest `p`.
fn closest_on_segment(a: [f64; 3], b: [f64; 3], p: [f64; 3]) -> [f64; 3] {
    let ab = sub(b, a);
    let l2 = dot(ab, ab);
    let t = if l2 < 1e-12 {
        0.0
    } else {
        (dot(sub(p, a), ab) / l2).clamp(0.0, 1.0)
    };
    along(a, ab, t)
}

/// Distance of `p` from the segment `a–b`.
pub fn point_segment_distance(p: [f64; 3], a: [f64; 3], b: [f64; 3]) -> f64 {
    norm(sub(p, closest_on_segment(a, b, p)))
}

/// Smallest distance between the segments `p0–p1` and `q0–q1`.
pub fn segment_distance(p0: [f64; 3], p1: [f64; 3], q0: [f64; 3], q1: [f64; 3]) -> f64 {
    let d1 = sub(p1, p0);
    let d2 = sub(q1, q0);
    let r = sub(p0, q0);
    let (a, e, f) = (dot(d1, d1), dot(d2, d2), dot(d2, r));
    let (s, t) = if a <= 1e-12 && e <= 1e-12 {
        (0.0, 0.0)
    } else if a <= 1e-12 {
        (0.0, (f / e).clamp(0.0, 1.0))
    } else {
        let c = dot(d1, r);
        if e <= 1e-12 {
            ((-c / a).clamp(0.0, 1.0), 0.0)
        } else {
            let b = dot(d1, d2);
            let denom = a * e - b * b;
            let mut s = if denom > 1e-12 {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let mut t = (b * s + f) / e;
            if t < 0.0 {
                t = 0.0;
                s = (-c / a).clamp(0.0, 1.0);
            } else if t > 1.0 {
                t = 1.0;
                s = ((b - c) / a).clamp(0.0, 1.0);
            }
            (s, t)
        }
    };
    let closest_p: [f64; 3] = std::array::from_fn(|i| p0[i] + d1[i] * s);
    let closest_q: [f64; 3] = std::array::from_fn(|i| q0[i] + d2[i] * t);
    norm(sub(closest_p, closest_q))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Axis;
    use std::f64::consts::FRAC_PI_4;

    #[test]
    fn segment_distance_cases() {
        let d = segment_distance(
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.5, 1.0, 0.0],
            [0.5, 2.0, 0.0],
        );
        assert!((d - 1.0).abs() < 1e-12);
        let d = segment_distance(
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [2.0, 0.0, 1.0],
            [3.0, 0.0, 1.0],
        );
        assert!((d - 2f64.sqrt()).abs() < 1e-12);
        let d = segment_distance(
            [-1.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, -1.0, 0.0],
            [0.0, 1.0, 0.0],
        );
        assert!(d.abs() < 1e-12);
    }

    #[test]
    fn boxes_overlap_or_not() {
        let a = OrientedBox::in_frame(&Pose::identity(), [0.0; 3], [1.0; 3]);
        let b = OrientedBox::in_frame(&Pose::translation(0.9, 0.9, 0.9), [0.0; 3], [1.0; 3]);
        let c = OrientedBox::in_frame(&Pose::translation(1.5, 0.0, 0.0), [0.0; 3], [1.0; 3]);
        // Turned by 45° about z and placed beside a's corner edge: separated only along a
        // cross axis or the turned box's own axis.
        let turned = Pose::translation(2.3, 0.5, 0.5).compose(&Pose::rotation(Axis::Z, FRAC_PI_4));
        let d = OrientedBox::in_frame(&turned, [-0.5; 3], [0.5; 3]);
        assert!(a.overlaps(&b) && b.overlaps(&a));
        assert!(!a.overlaps(&c) && !c.overlaps(&a));
        assert!(!a.overlaps(&d) && !d.overlaps(&a));
        assert!((a.distance([2.0, 0.5, 0.5]) - 1.0).abs() < 1e-12);
        assert_eq!(a.distance([0.5, 0.5, 0.5]), 0.0);
    }

    /// Every solid's ray hit lies on its surface (distance 0 from the solid, and just
    /// outside a little before), its normal points out, and `blocks` agrees with `ray`.
    #[test]
    fn rays_meet_the_surface_where_distance_says() {
        let turned = Pose::translation(10.0, -5.0, 3.0)
            .compose(&Pose::rotation(Axis::Z, 0.4))
            .compose(&Pose::rotation(Axis::X, -0.7));
        let shapes = [
            Shape::Capsule(Capsule {
                a: [0.0, -20.0, 5.0],
                b: [30.0, 40.0, -10.0],
                radius: 12.0,
            }),
            Shape::Box(OrientedBox::in_frame(
                &turned,
                [-20.0, -10.0, -5.0],
                [30.0, 15.0, 25.0],
            )),
            Shape::Sphere(Sphere {
                centre: [5.0, 5.0, 5.0],
                radius: 20.0,
            }),
        ];
        let origin = [-150.0, 20.0, 60.0];
        let mut hits = 0;
        for shape in &shapes {
            for k in 0..400 {
                let target = [
                    ((k * 37) % 80) as f64 - 40.0,
                    ((k * 53) % 90) as f64 - 45.0,
                    ((k * 71) % 70) as f64 - 35.0,
                ];
                let d = sub(target, origin);
                let dir = scale(d, 1.0 / norm(d));
                match shape.ray(origin, dir, 0.0) {
                    Some((t, n)) => {
                        hits += 1;
                        let p = along(origin, dir, t);
                        assert!(shape.distance(p) < 1e-6, "{shape:?} {p:?}");
                        let before = along(origin, dir, t - 0.01);
                        assert!(shape.distance(before) > 0.0);
                        assert!(dot(n, dir) < 0.0, "the normal faces the ray");
                        assert!(shape.blocks(origin, target, 0.0) || t > norm(d));
                    }
                    None => {
                        // Missed: no point along the line comes inside.
                        for s in 0..400 {
                            let p = along(origin, dir, s as f64);
                            assert!(shape.distance(p) > -1e-9);
                            assert!(shape.distance(p) > 0.0 || s == 0, "{shape:?} {p:?}");
                        }
                        assert!(!shape.blocks(origin, target, 0.0));
                    }
                }
            }
        }
        assert!(hits > 200, "{hits}");
    }
}
