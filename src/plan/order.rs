//! Executing a plan as planned and quickly: an order of the captures in which every move,
//! from the rest posture to the first capture, between captures and from the last one
//! back to rest, has a collision-free way ([`route::route`]; the return to rest a straight
//! move), with a short predicted duration ([`route::Timing`]).

use super::collision::BodyModel;
use super::route::{self, Timing};
use crate::model::{JointAngles, Model};

/// The cost of a move without a collision-free way: larger than any tour's time.
const BLOCKED: f64 = 1e9;

/// The time of every move between the captures and the rest posture (node `n`), `BLOCKED`
/// where there is no way: row `i`, column `j` from `i` to `j` (to a capture: its way and
/// picture; to rest: the straight move). Rows computed on two threads.
fn costs(
    model: &Model,
    body: &BodyModel,
    rest: &JointAngles,
    captures: &[JointAngles],
    timing: &Timing,
) -> Vec<Vec<f64>> {
    let n = captures.len();
    let node = |i: usize| if i == n { rest } else { &captures[i] };
    let row = |i: usize| -> Vec<f64> {
        (0..=n)
            .map(|j| {
                if i == j {
                    0.0
                } else if j == n {
                    if route::move_is_free(model, body, node(i), rest) {
                        timing.motion(node(i), rest)
                    } else {
                        BLOCKED
                    }
                } else {
                    match route::route(model, body, node(i), node(j), rest) {
                        Ok(way) => timing.way(node(i), &way),
                        Err(_) => BLOCKED,
                    }
                }
            })
            .collect()
    };
    let rows: Vec<usize> = (0..=n).collect();
    let (even, odd): (Vec<usize>, Vec<usize>) = rows.iter().partition(|i| *i % 2 == 0);
    let (a, b) = std::thread::scope(|scope| {
        let first = scope.spawn(|| even.iter().map(|&i| row(i)).collect::<Vec<_>>());
        let second: Vec<Vec<f64>> = odd.iter().map(|&i| row(i)).collect();
        (first.join().expect("cost thread"), second)
    });
    let (mut a, mut b) = (a.into_iter(), b.into_iter());
    (0..=n)
        .map(|i| {
            if i % 2 == 0 {
                a.next().expect("even row")
            } else {
                b.next().expect("odd row")
            }
        })
        .collect()
}

/// An order of `captures` for a robot that starts and ends at `rest`: every move has a
/// collision-free way where one exists and the predicted duration is short. Nearest
/// neighbour from rest, then 2-opt (reversing stretches of the tour) and or-opt (moving
/// stretches of up to three captures elsewhere) while either shortens it, on the time of
/// each move's way ([`route::route`], [`Timing::way`]; moves are not symmetric: the
/// reversed stretch is costed in its new direction). Returns the indices in execution
/// order.
pub fn order(
    model: &Model,
    body: &BodyModel,
    rest: &JointAngles,
    captures: &[JointAngles],
    timing: &Timing,
) -> Vec<usize> {
    let n = captures.len();
    if n == 0 {
        return Vec::new();
    }
    let cost = costs(model, body, rest, captures, timing);
    let c = |i: usize, j: usize| cost[i][j];
    // Nearest neighbour from rest (node n).
    let mut tour = vec![n];
    let mut left: Vec<usize> = (0..n).collect();
    while !left.is_empty() {
        let last = *tour.last().expect("not empty");
        let (k, _) = left
            .iter()
            .enumerate()
            .map(|(k, &j)| (k, c(last, j)))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .expect("not empty");
        tour.push(left.swap_remove(k));
    }
    tour.push(n);
    let len = tour.len();
    let sums = |tour: &[usize], fwd: &mut Vec<f64>, bwd: &mut Vec<f64>| {
        for k in 1..tour.len() {
            fwd[k] = fwd[k - 1] + c(tour[k - 1], tour[k]);
            bwd[k] = bwd[k - 1] + c(tour[k], tour[k - 1]);
        }
    };
    let (mut fwd, mut bwd) = (vec![0.0; len], vec![0.0; len]);
    for _ in 0..1000 {
        let mut improved = false;
        // 2-opt: the sums of the tour's moves forwards and backwards give each reversed
        // stretch's cost at once.
        sums(&tour, &mut fwd, &mut bwd);
        for i in 1..len - 2 {
            for j in i + 1..len - 1 {
                let before = c(tour[i - 1], tour[i]) + (fwd[j] - fwd[i]) + c(tour[j], tour[j + 1]);
                let after = c(tour[i - 1], tour[j]) + (bwd[j] - bwd[i]) + c(tour[i], tour[j + 1]);
                if after < before - 1e-9 {
                    tour[i..=j].reverse();
                    sums(&tour, &mut fwd, &mut bwd);
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
                let inner: f64 = (i..j).map(|k| c(tour[k], tour[k + 1])).sum();
                let inner_rev: f64 = (i..j).map(|k| c(tour[k + 1], tour[k])).sum();
                let removed = c(p, tour[i]) + inner + c(tour[j], q) - c(p, q);
                for k in 0..len - 1 {
                    if k + 1 >= i && k <= j {
                        continue;
                    }
                    let (a, b) = (tour[k], tour[k + 1]);
                    let ahead = c(a, tour[i]) + inner + c(tour[j], b) - c(a, b);
                    let back = c(a, tour[j]) + inner_rev + c(tour[i], b) - c(a, b);
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
