//! Executing a plan quickly: the order of the captures (little joint travel between them)
//! and the predicted duration of the measurement phase.
//!
//! Timing model: the robot moves from one capture to the next by interpolating all joints
//! together, so a move takes as long as its slowest joint, `max_j |Δθ_j| / ω_j`, with a
//! cautious speed for the legs (which carry the sandals near the body) and a faster one for
//! the head; after a leg move it waits for the sandal to settle, after a head-only move for
//! the image to settle; then it takes the picture and logs the joints.

use crate::model::{Joint, JointAngles};

/// The timing model's constants.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Timing {
    /// Leg joint speed [rad/s].
    pub leg_speed: f64,
    /// Head joint speed [rad/s].
    pub head_speed: f64,
    /// Wait after a move of any leg joint (s).
    pub leg_settle: f64,
    /// Wait after a head-only move (s).
    pub head_settle: f64,
    /// Taking the picture and logging the joints (s).
    pub capture: f64,
}

impl Default for Timing {
    /// Legs at 30°/s, head at 90°/s, 1 s settling after a leg move, 0.3 s after a head move,
    /// 0.2 s per picture.
    fn default() -> Self {
        Timing {
            leg_speed: 30f64.to_radians(),
            head_speed: 90f64.to_radians(),
            leg_settle: 1.0,
            head_settle: 0.3,
            capture: 0.2,
        }
    }
}

impl Timing {
    /// Time of the move from `a` to `b` (s), without settling.
    pub fn motion(&self, a: &JointAngles, b: &JointAngles) -> f64 {
        Joint::ALL
            .iter()
            .map(|&j| {
                let speed = if j.leg_index().is_some() {
                    self.leg_speed
                } else {
                    self.head_speed
                };
                (a.get(j) - b.get(j)).abs() / speed
            })
            .fold(0.0, f64::max)
    }

    /// Time from `a` to the picture at `b` (s): motion, settling and the capture.
    pub fn step(&self, a: &JointAngles, b: &JointAngles) -> f64 {
        let legs_move = Joint::ALL
            .iter()
            .any(|&j| j.leg_index().is_some() && (a.get(j) - b.get(j)).abs() > 1e-9);
        let settle = if legs_move {
            self.leg_settle
        } else {
            self.head_settle
        };
        self.motion(a, b) + settle + self.capture
    }

    /// Duration of executing `captures` in order, starting from and returning to `home`
    /// (lying straight, all angles zero) (s).
    pub fn duration(&self, captures: &[JointAngles]) -> f64 {
        let home = JointAngles::default();
        let mut at = home;
        let mut total = 0.0;
        for c in captures {
            total += self.step(&at, c);
            at = *c;
        }
        total + self.motion(&at, &home)
    }
}

/// An order of `captures` with a short predicted duration: nearest neighbour from the home
/// posture, then 2-opt (reversing stretches of the tour while that shortens it; the cost of
/// a leg between two captures is [`Timing::step`], symmetric in its motion part). Returns
/// the indices in execution order.
pub fn order(captures: &[JointAngles], timing: &Timing) -> Vec<usize> {
    let n = captures.len();
    if n < 2 {
        return (0..n).collect();
    }
    let home = JointAngles::default();
    // Node n is home; cost between nodes.
    let node = |i: usize| if i == n { &home } else { &captures[i] };
    let cost = |i: usize, j: usize| {
        // The settling depends only on whether legs move: symmetric.
        if i == n || j == n {
            timing.motion(node(i), node(j))
        } else {
            timing.step(node(i), node(j))
        }
    };
    let mut tour = vec![n];
    let mut left: Vec<usize> = (0..n).collect();
    while !left.is_empty() {
        let last = *tour.last().expect("not empty");
        let (k, _) = left
            .iter()
            .enumerate()
            .map(|(k, &c)| (k, cost(last, c)))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .expect("not empty");
        tour.push(left.swap_remove(k));
    }
    tour.push(n);
    // 2-opt on the closed tour home → … → home.
    let len = tour.len();
    for _ in 0..50 {
        let mut improved = false;
        for i in 1..len - 2 {
            for j in i + 1..len - 1 {
                let before = cost(tour[i - 1], tour[i]) + cost(tour[j], tour[j + 1]);
                let after = cost(tour[i - 1], tour[j]) + cost(tour[i], tour[j + 1]);
                if after < before - 1e-9 {
                    tour[i..=j].reverse();
                    improved = true;
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

    #[test]
    fn ordering_shortens_a_shuffled_tour() {
        let mut captures = Vec::new();
        for k in 0..30 {
            let mut j = JointAngles::default();
            // Points on a line, visited in a scrambled order.
            let x = ((k * 17) % 30) as f64 * 0.05;
            j.set(Joint::LKneePitch, x);
            j.set(Joint::HeadYaw, x / 2.0);
            captures.push(j);
        }
        let timing = Timing::default();
        let before = timing.duration(&captures);
        let ordered: Vec<JointAngles> = order(&captures, &timing)
            .into_iter()
            .map(|i| captures[i])
            .collect();
        let after = timing.duration(&ordered);
        assert_eq!(ordered.len(), captures.len());
        // Out along the line and back: 2 × 1.45 rad of knee travel plus the stops.
        let stops = 30.0 * (timing.leg_settle + timing.capture);
        let best = 2.0 * 1.45 / timing.leg_speed + stops;
        assert!(after < before, "{after} vs {before}");
        assert!(after <= best + 1e-6, "{after} vs best {best}");
    }
}
