//! Executing a plan as planned and quickly: an order of the captures in which every move,
//! from the rest posture to the first capture, between captures and from the last one
//! back to rest, has a collision-free way ([`route::route`]; the return to rest a straight
//! move), with a short predicted duration ([`route::Timing`]).

use super::collision::BodyModel;
use super::route::{self, Timing};
use crate::model::{JointAngles, Model};

/// The cost of a move without a collision-free way: larger than any tour's time.
const BLOCKED: f64 = 1e9;

/// The time of a move between two nodes of a tour (the captures and, last, the rest
/// posture), as the tour search reads it: exactly, or as a lower bound that costs nothing.
trait Moves {
    /// The time of the move from node `i` to node `j`.
    fn cost(&mut self, i: usize, j: usize) -> f64;
    /// A lower bound of [`Moves::cost`]: the cost itself where it is known.
    fn bound(&mut self, i: usize, j: usize) -> f64;
}

/// The moves between the captures and the rest posture (node `n`), each found when the
/// search first needs its time (its way through [`route::route`] is most of the
/// planner's work), and bounded below before that by the straight move's time: row `i`,
/// column `j` from `i` to `j` (to a capture: its way and picture; to rest: the straight
/// move), `BLOCKED` where there is no way.
struct Lazy<'a> {
    model: &'a Model,
    body: &'a BodyModel,
    rest: &'a JointAngles,
    captures: &'a [JointAngles],
    timing: &'a Timing,
    /// Row-major, `NaN` where not found yet.
    known: Vec<f64>,
    /// The lower bounds ([`Moves::bound`]) as computed, `NaN` where not yet: the search
    /// asks for each many times.
    bounds: Vec<f64>,
}

impl Lazy<'_> {
    fn node(&self, i: usize) -> &JointAngles {
        if i == self.captures.len() {
            self.rest
        } else {
            &self.captures[i]
        }
    }

    /// The straight move's time from node `i` to node `j`, less a nanosecond.
    fn straight(&self, i: usize, j: usize) -> f64 {
        if i == j {
            return 0.0;
        }
        let (from, t) = (self.node(i), self.timing);
        let straight = if j == self.captures.len() {
            t.motion(from, self.rest)
        } else if t.leg_settle >= t.head_settle {
            t.step(from, self.node(j))
        } else {
            t.motion(from, self.node(j)) + t.leg_settle.min(t.head_settle) + t.capture
        };
        straight - 1e-9
    }

    /// The time of the move, from its way.
    fn find(&self, i: usize, j: usize) -> f64 {
        let n = self.captures.len();
        let (from, rest) = (self.node(i), self.rest);
        if i == j {
            0.0
        } else if j == n {
            if route::move_is_clear(self.model, self.body, from, rest) {
                self.timing.motion(from, rest)
            } else {
                BLOCKED
            }
        } else {
            match route::route(self.model, self.body, from, self.node(j), rest) {
                Ok(way) => self.timing.way(from, &way),
                Err(_) => BLOCKED,
            }
        }
    }
}

impl Moves for Lazy<'_> {
    fn cost(&mut self, i: usize, j: usize) -> f64 {
        let at = i * (self.captures.len() + 1) + j;
        if self.known[at].is_nan() {
            self.known[at] = self.find(i, j);
        }
        self.known[at]
    }

    /// The straight move's time (a way through other postures moves at least as far and
    /// settles once more), less a nanosecond against rounding.
    fn bound(&mut self, i: usize, j: usize) -> f64 {
        let n = self.captures.len();
        let at = i * (n + 1) + j;
        if !self.known[at].is_nan() {
            return self.known[at];
        }
        if self.bounds[at].is_nan() {
            self.bounds[at] = self.straight(i, j);
        }
        self.bounds[at]
    }
}

/// An order of `captures` for a robot that starts and ends at `rest`: every move has a
/// collision-free way where one exists and the predicted duration is short. Nearest
/// neighbour from rest, then 2-opt (reversing stretches of the tour) and or-opt (moving
/// stretches of up to three captures elsewhere) while either shortens it, on the time of
/// each move's way ([`route::route`], [`Timing::way`]; moves are not symmetric: the
/// reversed stretch is costed in its new direction). Returns the indices in execution
/// order.
///
/// A move's way is found only when a step of the search could depend on it: each step
/// first compares with the straight moves' times, a lower bound of the ways', and finds
/// the ways only where that bound leaves the decision open, so the order is the one the
/// search makes on the times of all the ways.
pub fn order(
    model: &Model,
    body: &BodyModel,
    rest: &JointAngles,
    captures: &[JointAngles],
    timing: &Timing,
) -> Vec<usize> {
    let n = captures.len();
    let mut moves = Lazy {
        model,
        body,
        rest,
        captures,
        timing,
        known: vec![f64::NAN; (n + 1) * (n + 1)],
        bounds: vec![f64::NAN; (n + 1) * (n + 1)],
    };
    tour(&mut moves, n)
}

/// The tour search of [`order`] on `n` captures (node `n` is rest), reading each move's
/// time exactly only where its lower bound does not settle a step.
fn tour(m: &mut impl Moves, n: usize) -> Vec<usize> {
    if n == 0 {
        return Vec::new();
    }
    // Nearest neighbour from rest (node n); of equally near captures the first left.
    let mut tour = vec![n];
    let mut left: Vec<usize> = (0..n).collect();
    while !left.is_empty() {
        let last = *tour.last().expect("not empty");
        let mut near: Vec<(f64, usize)> = left
            .iter()
            .enumerate()
            .map(|(k, &j)| (m.bound(last, j), k))
            .collect();
        near.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let mut best: Option<(usize, f64)> = None;
        for (bound, k) in near {
            if best.is_some_and(|(_, v)| bound > v) {
                break;
            }
            let v = m.cost(last, left[k]);
            if best.is_none_or(|(bk, bv)| v < bv || (v == bv && k < bk)) {
                best = Some((k, v));
            }
        }
        let (k, _) = best.expect("not empty");
        tour.push(left.swap_remove(k));
    }
    tour.push(n);
    let len = tour.len();
    let sums = |m: &mut dyn FnMut(usize, usize) -> f64,
                tour: &[usize],
                fwd: &mut Vec<f64>,
                bwd: &mut Vec<f64>| {
        for k in 1..tour.len() {
            fwd[k] = fwd[k - 1] + m(tour[k - 1], tour[k]);
            bwd[k] = bwd[k - 1] + m(tour[k], tour[k - 1]);
        }
    };
    let (mut fwd, mut bwd) = (vec![0.0; len], vec![0.0; len]);
    for _ in 0..1000 {
        let mut improved = false;
        // 2-opt: the sums of the tour's moves forwards and backwards give each reversed
        // stretch's cost at once.
        sums(&mut |i, j| m.cost(i, j), &tour, &mut fwd, &mut bwd);
        for i in 1..len - 2 {
            for j in i + 1..len - 1 {
                let before =
                    m.cost(tour[i - 1], tour[i]) + (fwd[j] - fwd[i]) + m.cost(tour[j], tour[j + 1]);
                let low = m.bound(tour[i - 1], tour[j])
                    + (bwd[j] - bwd[i])
                    + m.bound(tour[i], tour[j + 1]);
                if low >= before - 1e-9 {
                    continue;
                }
                let after =
                    m.cost(tour[i - 1], tour[j]) + (bwd[j] - bwd[i]) + m.cost(tour[i], tour[j + 1]);
                if after < before - 1e-9 {
                    tour[i..=j].reverse();
                    sums(&mut |i, j| m.cost(i, j), &tour, &mut fwd, &mut bwd);
                    improved = true;
                }
            }
        }
        // Or-opt: a stretch of 1 to 3 captures moved between two others, either way round.
        'or: for size in 1..=3 {
            for i in 1..len.saturating_sub(size) {
                let j = i + size - 1; // the stretch tour[i..=j]
                if j >= len - 1 {
                    break;
                }
                let (p, q) = (tour[i - 1], tour[j + 1]);
                let inner: f64 = (i..j).map(|k| m.cost(tour[k], tour[k + 1])).sum();
                let inner_rev: f64 = (i..j).map(|k| m.cost(tour[k + 1], tour[k])).sum();
                let kept = m.cost(p, tour[i]) + inner + m.cost(tour[j], q);
                // At most what removing the stretch saves (the move p → q at its bound).
                let most = kept - m.bound(p, q);
                let mut removed = None;
                for k in 0..len - 1 {
                    if k + 1 >= i && k <= j {
                        continue;
                    }
                    let (a, b) = (tour[k], tour[k + 1]);
                    let ab = m.cost(a, b);
                    let ahead_low = m.bound(a, tour[i]) + inner + m.bound(tour[j], b) - ab;
                    let back_low = m.bound(a, tour[j]) + inner_rev + m.bound(tour[i], b) - ab;
                    if most - ahead_low.min(back_low) <= 1e-9 {
                        continue;
                    }
                    let removed = *removed.get_or_insert_with(|| kept - m.cost(p, q));
                    let ahead = m.cost(a, tour[i]) + inner + m.cost(tour[j], b) - ab;
                    let back = m.cost(a, tour[j]) + inner_rev + m.cost(tour[i], b) - ab;
                    let (gain, reversed) = if back < ahead {
                        (removed - back, true)
                    } else {
                        (removed - ahead, false)
                    };
                    if gain > 1e-9 {
                        let mut stretch: Vec<usize> = tour.drain(i..=j).collect();
                        if reversed {
                            stretch.reverse();
                        }
                        let at = if k < i { k + 1 } else { k + 1 - size };
                        tour.splice(at..at, stretch);
                        improved = true;
                        break 'or;
                    }
                }
            }
        }
        if !improved {
            break;
        }
    }
    tour[1..len - 1].to_vec()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Joint;
    use crate::plan::route::rest_posture;

    /// Moves whose every time is read exactly (the search as it was written first), or
    /// bounded below by `low` until read.
    struct Matrix {
        cost: Vec<Vec<f64>>,
        low: Option<Vec<Vec<f64>>>,
    }

    impl Moves for Matrix {
        fn cost(&mut self, i: usize, j: usize) -> f64 {
            self.cost[i][j]
        }
        fn bound(&mut self, i: usize, j: usize) -> f64 {
            match &self.low {
                Some(low) => low[i][j],
                None => self.cost[i][j],
            }
        }
    }

    #[test]
    fn the_tour_on_lower_bounds_is_the_tour_on_the_times() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        for n in [1, 2, 3, 4, 7, 20, 45] {
            for _ in 0..6 {
                let mut cost = vec![vec![0.0; n + 1]; n + 1];
                let mut low = cost.clone();
                for i in 0..=n {
                    for j in (0..=n).filter(|j| *j != i) {
                        let straight: f64 = rng.random_range(1.0..10.0);
                        // A third of the moves go round (slower), a few have no way.
                        let (c, l) = match rng.random_range(0..12) {
                            0 => (BLOCKED, straight),
                            1..=4 => (straight + rng.random_range(0.3..5.0), straight),
                            // Equal times, so that ties are broken as before.
                            5 => (2.0, 2.0 - 1e-9),
                            _ => (straight, straight - 1e-9),
                        };
                        cost[i][j] = c;
                        low[i][j] = l;
                    }
                }
                let mut full = Matrix {
                    cost: cost.clone(),
                    low: None,
                };
                let mut lazy = Matrix {
                    cost,
                    low: Some(low),
                };
                assert_eq!(tour(&mut full, n), tour(&mut lazy, n), "{n} captures");
            }
        }
    }

    #[test]
    fn ordering_shortens_a_shuffled_tour() {
        let model = Model::default();
        let body = BodyModel::default();
        let rest = rest_posture();
        let mut captures = Vec::new();
        for k in 0..30 {
            let mut j = rest;
            // Points on a line (the left thigh raised, its knee bent as much, the head
            // turned), in a scrambled order.
            let x = ((k * 17) % 30) as f64 * 0.05;
            j.set(Joint::LHipPitch, -x);
            j.set(Joint::LKneePitch, x);
            j.set(Joint::HeadYaw, x / 2.0);
            captures.push(j);
        }
        let timing = Timing::default();
        let before = route::duration(&model, &body, &timing, &rest, &captures);
        let ordered: Vec<JointAngles> = order(&model, &body, &rest, &captures, &timing)
            .into_iter()
            .map(|i| captures[i])
            .collect();
        let after = route::duration(&model, &body, &timing, &rest, &ordered);
        assert_eq!(ordered.len(), captures.len());
        assert!(
            route::moves(&model, &body, &rest, &ordered)
                .iter()
                .all(Result::is_ok)
        );
        // Out along the line and back: 2 × 1.45 rad of knee travel plus the stops.
        let stops = 30.0 * (timing.leg_settle + timing.capture);
        let best = 2.0 * 1.45 / timing.leg_speed + stops;
        assert!(after < before, "{after} vs {before}");
        assert!(after <= best + 1e-6, "{after} vs best {best}");
    }
}
