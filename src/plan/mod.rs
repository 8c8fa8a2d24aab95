//! Stance design: a schedule of captures that a robot can execute safely before it is
//! calibrated, chosen so that the calibration determines the free parameters as well as
//! possible, and ordered so that it runs quickly.
//!
//! How a plan is made ([`plan`]):
//! 1. **Pool** ([`feasible::candidates`]): random leg stances within the joint limits less
//!    a margin, drawn mostly near the limits (the informative stances), the other leg
//!    resting straight with the same HipYawPitch (one motor), free of self-collision
//!    ([`collision`]), each with the head aiming the board at the image centre (or points
//!    around it); a capture enters the pool only if its board stays fully in the image and
//!    facing the camera for every offset within ±3° (and ±3 mm of the sandal mounting).
//!    For the upper camera ([`PlanOptions::cameras`]) the pool is searched where it can
//!    see a sandal (the hips flexed and turned in, the board aimed below the image
//!    centre), with its own box of offsets ([`Feasibility::upper_offset`]) around the
//!    robot's calibration.
//! 2. **Design** ([`design::select`]): each candidate's Fisher information under the
//!    per-capture noise model (pixel noise plus joint noise shared by a capture's vertices);
//!    a greedy selection, then exchange passes that minimise the worst predicted σ of the
//!    15 angle offsets (and of the upper camera's 3, aimed at
//!    [`PlanOptions::upper_sigma_ratio`] of them), with the other free parameters
//!    column-scaled beside them.
//! 3. **Refinement**: variants of the picked captures (leg angles moved by up to 0.15 rad,
//!    then 0.075, 0.0375) join the pool and the exchange continues from the design.
//! 4. **Order** ([`order::order`]): a short tour from the rest posture through the captures
//!    and back, every move along a collision-free way ([`route::route`], the same search
//!    `capture` drives), and its predicted duration, every move included.
//!
//! One head posture per leg stance: each capture draws its own joint noise, so a new leg
//! stance tells more than the same stance with the head turned (with up to four postures
//! per pool stance the design took one per stance all the same and ended no better).
//!
//! The same prediction is made for the simulator's random stances at equal capture count,
//! so that the gain is visible before the robot moves.

pub mod body_audit;
pub mod collision;
pub mod coverage;
pub mod design;
pub mod feasibility;
pub mod feasible;
pub mod information;
pub mod order;
mod pool;
pub mod report;
pub mod request;
pub mod route;
pub mod view;

use std::path::Path;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::model::{CameraId, FixedSet, Joint, JointAngles, Model, PARAMETER_COUNT, Param, Side};
use crate::sim::Stance;
use crate::solve::noise::NoiseLevels;

pub use design::{DesignOptions, Prediction};
pub use feasible::{Feasibility, Infeasible};
use pool::{Design, Pool};
pub use route::Timing;

/// What to plan.
#[derive(Debug, Clone, PartialEq)]
pub struct PlanOptions {
    /// Number of captures (both legs together).
    pub captures: usize,
    /// Which parameters the calibration will free (the others are held).
    pub fixed: FixedSet,
    /// The noise the prediction assumes: pixel σ (px) and joint σ (rad) per capture.
    pub levels: NoiseLevels,
    /// Seed of the random candidate pool (and of the random stances compared against).
    pub seed: u64,
    /// The cameras to plan captures for (the upper camera's parameters are freed when it
    /// is among them, unless held on purpose).
    pub cameras: Vec<CameraId>,
    /// Leg stances drawn into the pool per leg.
    pub pool_stances: usize,
    /// Leg stances drawn into the upper camera's pool per leg (when it is planned for).
    pub upper_pool_stances: usize,
    /// Head postures tried per upper-camera pool stance (its stances are rare: the board
    /// aimed at points across the image makes more of each).
    pub upper_heads: usize,
    /// The σ the design aims at for the upper camera's rotation offsets, as a fraction of
    /// the worst σ of the 15 angle offsets (the upper camera has fewer captures to share).
    pub upper_sigma_ratio: f64,
    /// Head postures tried per pool stance.
    pub heads: usize,
    /// Refinement rounds: variants of every picked capture (its leg angles moved a little)
    /// join the pool and the selection is improved from the design it has.
    pub refine_rounds: usize,
    /// Variants per picked capture and refinement round.
    pub variants: usize,
    /// Largest move of each leg angle in a variant of the first round (rad); halved in
    /// each further round.
    pub spread: f64,
    /// What a capture must satisfy.
    pub feasibility: Feasibility,
    /// The selection.
    pub design: DesignOptions,
    /// The timing model of the measurement phase.
    pub timing: Timing,
}

impl Default for PlanOptions {
    /// 144 captures of the paper's 21 parameters at 0.1 px and 0.1° per capture.
    fn default() -> Self {
        PlanOptions {
            captures: 144,
            fixed: FixedSet::default(),
            levels: NoiseLevels {
                px: 0.1,
                joint: 0.1f64.to_radians(),
            },
            seed: 1,
            cameras: vec![CameraId::Lower],
            pool_stances: 300,
            upper_pool_stances: 300,
            upper_heads: 2,
            upper_sigma_ratio: 0.88,
            heads: 1,
            refine_rounds: 3,
            variants: 2,
            spread: 0.15,
            feasibility: Feasibility::default(),
            design: DesignOptions::default(),
            timing: Timing::default(),
        }
    }
}

impl PlanOptions {
    /// Per camera ([`CameraId`] order), whether the boards sweep its image: it is planned
    /// for and its intrinsics are free in the problem the plan is for (the upper camera's
    /// as [`FixedSet::for_upper_camera`] has them).
    pub fn sweeps(&self) -> [bool; 2] {
        let upper = self.cameras.contains(&CameraId::Upper);
        let fixed = self.fixed.clone().for_upper_camera(upper);
        CameraId::ALL.map(|camera| {
            self.cameras.contains(&camera)
                && camera
                    .projection_params()
                    .iter()
                    .any(|p| !fixed.is_fixed(*p))
        })
    }
}

/// One capture of a plan.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlannedCapture {
    /// The camera that takes the picture.
    pub camera: CameraId,
    /// The leg whose board is in view.
    pub side: Side,
    /// The joint angles to command (radians).
    pub joints: JointAngles,
}

/// A stance schedule with its predicted outcome.
#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    /// The captures in execution order.
    pub captures: Vec<PlannedCapture>,
    /// Predicted uncertainty of the free parameters after calibrating from the plan.
    pub prediction: Prediction,
    /// The same for the simulator's random stances at equal capture count.
    pub baseline: Prediction,
    /// Predicted duration of the measurement phase, from rest through every capture and
    /// back, every move along its collision-free way (s).
    pub duration: f64,
    /// Intermediate postures of the plan's moves (where the straight move collides).
    pub via: usize,
    /// Predicted duration of the random stances in the simulator's order (s), a stance
    /// without a collision-free way skipped.
    pub baseline_duration: f64,
    /// Random stances without a collision-free way in the simulator's order.
    pub baseline_blocked: usize,
    /// Number of feasible captures in the pool.
    pub pool: usize,
    /// Number of distinct leg stances in the plan.
    pub stances: usize,
    /// Where the boards lie in each camera's image ([`coverage::coverage`] at the centre
    /// of feasibility).
    pub coverage: Vec<coverage::Coverage>,
    /// The captures held against the whole body model (docs/BODY.md): clearance, contact,
    /// vertices hidden.
    pub body: body_audit::BodyAudit,
}

/// Why no plan could be made.
#[derive(Debug, thiserror::Error)]
pub enum PlanError {
    /// An option is out of range.
    #[error("{0}")]
    Options(String),
    /// Too few feasible captures were found for a leg.
    #[error(
        "found only {found} feasible {camera}-camera captures for the {side} leg (board in \
         view for all offsets, no collision, within the limits; a search stops after {} \
         draws without any); check the camera intrinsics and board, and for the upper \
         camera its box of offsets (--upper-offset-deg, --around)",
        feasible::FUTILE_TRIES
    )]
    Pool {
        /// The camera.
        camera: &'static str,
        /// The leg.
        side: &'static str,
        /// Feasible captures found.
        found: usize,
    },
    /// Not even the shortest plan's measurement phase fits the budget.
    #[error(
        "no plan fits a measurement phase of {budget} s: the shortest planned (2 captures) \
         takes {shortest:.0} s"
    )]
    Budget {
        /// The budget (s).
        budget: f64,
        /// The predicted duration of the 2-capture plan (s).
        shortest: f64,
    },
    /// No order of the captures has a collision-free way for every move (the move to
    /// capture `k` in execution order, or the return to rest when `k` is the number of
    /// captures).
    #[error("no collision-free order of the captures was found (move {0})")]
    Moves(usize),
    /// The random stances to compare with could not be drawn.
    #[error(transparent)]
    Sim(#[from] crate::sim::SimError),
}

/// Makes a plan for `model` (see the module documentation).
pub fn plan(model: &Model, options: &PlanOptions) -> Result<Plan, PlanError> {
    if options.captures < 2 {
        return Err(PlanError::Options("--captures must be at least 2".into()));
    }
    let pool = Pool::new(model, options)?;
    // The random stances it is compared with depend on the count alone: found beside the
    // design's order.
    let (design, baseline) = pool.design_beside(model, options, options.captures, || {
        pool::Baseline::of(model, options, options.captures)
    });
    pool.finish(model, options, design?, Some(baseline?))
}

/// Makes a plan for `model` whose measurement phase, every move included
/// ([`Plan::duration`], [`route::duration`]), takes at most `budget` seconds of robot time:
/// as many captures as fit, at most `most` (none fewer than 2). The plan is the one
/// [`plan`] makes for that count (the same pool, design and order); the count is found by
/// planning counts in turn, each guessed from the durations of those planned before, until
/// it fits and one more would not (or it is `most`).
pub fn plan_within(
    model: &Model,
    options: &PlanOptions,
    budget: f64,
    most: Option<usize>,
) -> Result<Plan, PlanError> {
    if !(budget.is_finite() && budget > 0.0) {
        return Err(PlanError::Options(
            "the budget must be a positive number of seconds".into(),
        ));
    }
    let most = most.unwrap_or(MOST_CAPTURES);
    if most < 2 {
        return Err(PlanError::Options("--captures must be at least 2".into()));
    }
    let pool = Pool::new(model, options)?;
    // Durations found so far, by count.
    let mut tried: Vec<(usize, Design)> = Vec::new();
    let mut count = most.min(options.captures.max(2));
    loop {
        let design = pool.design(model, options, count)?;
        tried.push((count, design));
        let fits = |d: &Design| d.duration <= budget;
        let best = tried.iter().filter(|(_, d)| fits(d)).map(|(n, _)| *n).max();
        let over = tried
            .iter()
            .filter(|(_, d)| !fits(d))
            .map(|(n, _)| *n)
            .min();
        let next = match (best, over) {
            (Some(n), _) if n == most => None,
            (Some(n), Some(m)) if m == n + 1 => None,
            (None, Some(2)) => {
                let shortest = tried
                    .iter()
                    .find(|(n, _)| *n == 2)
                    .map_or(f64::NAN, |(_, d)| d.duration);
                return Err(PlanError::Budget { budget, shortest });
            }
            _ => {
                // The count where the durations of the two counts planned nearest the
                // budget meet it (a line through them; through zero with one).
                let mut near: Vec<(usize, f64)> =
                    tried.iter().map(|(n, d)| (*n, d.duration)).collect();
                near.sort_by(|a, b| (a.1 - budget).abs().total_cmp(&(b.1 - budget).abs()));
                let (n, d) = near[0];
                let per = match near.get(1) {
                    Some(&(m, e)) if m != n && (e - d) / (m as f64 - n as f64) > 0.0 => {
                        (e - d) / (m as f64 - n as f64)
                    }
                    _ => d / n as f64,
                };
                let guess = (n as f64 + (budget - d) / per).floor().max(0.0) as usize;
                let lo = best.map_or(2, |b| b + 1);
                let hi = over.map_or(most, |o| o - 1);
                Some(guess.clamp(lo, hi))
            }
        };
        match next {
            Some(n) => count = n,
            None => break,
        }
    }
    let n = tried
        .iter()
        .filter(|(_, d)| d.duration <= budget)
        .map(|(n, _)| *n)
        .max()
        .expect("a count that fits");
    let design = tried
        .into_iter()
        .find(|(m, _)| *m == n)
        .map(|(_, d)| d)
        .expect("planned");
    pool.finish(model, options, design, None)
}

/// The most captures a budgeted plan takes without `--captures`.
pub const MOST_CAPTURES: usize = 5000;

/// Whether `p` is one of the paper's 15 angle offsets: the camera rotation and the 12 leg
/// joints.
pub fn is_angle_offset(p: Param) -> bool {
    use crate::model::ParamGroup;
    matches!(
        p.group(),
        ParamGroup::Camera | ParamGroup::LeftLeg | ParamGroup::RightLeg
    )
}

/// The simulator's random stances (as `naocalib simulate` draws them, at the nominal
/// model): `count` captures, half per leg, `heads` head postures per stance.
pub fn random_stances(
    model: &Model,
    count: usize,
    heads: usize,
    seed: u64,
) -> Result<Vec<(Side, JointAngles)>, crate::sim::SimError> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let zero = [0.0; PARAMETER_COUNT];
    let mut out = Vec::with_capacity(count);
    for (k, side) in Side::BOTH.into_iter().enumerate() {
        let share = if k == 0 { count / 2 } else { count - count / 2 };
        let stances = crate::sim::choose_stances(
            model,
            side,
            &zero,
            share.div_ceil(heads),
            heads,
            false,
            &mut rng,
        )?;
        out.extend(
            stances
                .iter()
                .flat_map(|s| s.postures.iter().map(move |p| (s.side, *p)))
                .take(share),
        );
    }
    Ok(out)
}

/// The plan as CSV: `capture,board,HeadYaw,…,RAnkleRoll` (the columns of `captures.csv`
/// without `image`), then the arm joints `LShoulderPitch,…,RWristYaw` (the posture capture
/// holds the arms in, [`crate::body::ArmPosture::CAPTURE`], the same in every row), one row
/// per capture in execution order, angles in radians; and a last column `camera`
/// (`lower`/`upper`) when some capture is by the upper camera.
pub fn render_csv(captures: &[PlannedCapture]) -> Vec<u8> {
    let cameras = captures.iter().any(|c| c.camera != CameraId::Lower);
    let arms = crate::body::ArmPosture::CAPTURE;
    let mut out = String::from("capture,board");
    for name in Joint::ALL
        .map(Joint::name)
        .iter()
        .chain(&crate::body::ARM_JOINTS)
    {
        out.push(',');
        out.push_str(name);
    }
    if cameras {
        out.push_str(",camera");
    }
    out.push('\n');
    for (id, c) in captures.iter().enumerate() {
        out.push_str(&format!("{id},{}", c.side.name()));
        for q in c.joints.iter().map(|(_, q)| q).chain(arms.0) {
            // Shortest text that reads back to the same number.
            out.push_str(&format!(",{q}"));
        }
        if cameras {
            out.push(',');
            out.push_str(c.camera.name());
        }
        out.push('\n');
    }
    out.into_bytes()
}

/// Reads a plan (or any captures table: columns by name, `image` and others ignored),
/// checked as `captures.csv` is; errors name the file, line and field.
pub fn read_csv(path: &Path) -> Result<Vec<PlannedCapture>, crate::dataset::DatasetError> {
    Ok(crate::dataset::read_captures(path)?
        .into_iter()
        .map(|c| PlannedCapture {
            camera: c.camera,
            side: c.side,
            joints: c.joints,
        })
        .collect())
}

/// The plan's captures as the simulator's stances (one posture each), in plan order.
pub fn to_stances(captures: &[PlannedCapture]) -> Vec<Stance> {
    to_schedule(captures).0
}

/// The plan as the simulator's schedule: its stances ([`to_stances`]) and the camera of
/// each ([`crate::sim::schedule`]).
pub fn to_schedule(captures: &[PlannedCapture]) -> (Vec<Stance>, Vec<CameraId>) {
    crate::sim::schedule(captures.iter().map(|c| (c.camera, c.side, c.joints)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The boards sweep a planned camera whose intrinsics are free, the upper one's as its
    /// problem has them: named or by family, and never a camera not planned for.
    #[test]
    fn the_boards_sweep_the_planned_cameras_whose_intrinsics_are_free() {
        let options = |free: &str, cameras: &[CameraId]| PlanOptions {
            fixed: FixedSet::from_lists(free, "").unwrap(),
            cameras: cameras.to_vec(),
            ..PlanOptions::default()
        };
        let both = [CameraId::Lower, CameraId::Upper];
        assert_eq!(options("", &both).sweeps(), [false, false]);
        assert_eq!(
            options("intrinsics", &[CameraId::Lower]).sweeps(),
            [true, false]
        );
        assert_eq!(options("intrinsics", &both).sweeps(), [true, true]);
        assert_eq!(options("UpperFx", &both).sweeps(), [false, true]);
        assert_eq!(
            options("UpperFx", &[CameraId::Lower]).sweeps(),
            [false, false]
        );
        assert_eq!(
            options("intrinsics", &[CameraId::Upper]).sweeps(),
            [false, true]
        );
    }

    /// The CSV carries every capture's arm joints after the leg joints, before the camera,
    /// and reads back as the plan.
    #[test]
    fn the_csv_carries_the_arm_posture_of_every_capture() {
        let mut joints = JointAngles::default();
        joints.set(Joint::LKneePitch, 0.5);
        let captures = [
            PlannedCapture {
                camera: CameraId::Lower,
                side: Side::Left,
                joints,
            },
            PlannedCapture {
                camera: CameraId::Upper,
                side: Side::Right,
                joints,
            },
        ];
        let text = String::from_utf8(render_csv(&captures)).unwrap();
        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let first_arm = header.iter().position(|h| *h == "LShoulderPitch").unwrap();
        assert_eq!(header[first_arm - 1], "RAnkleRoll");
        assert_eq!(&header[first_arm..first_arm + 10], crate::body::ARM_JOINTS);
        assert_eq!(header.last(), Some(&"camera"));
        for line in lines {
            let fields: Vec<&str> = line.split(',').collect();
            let arms: Vec<f64> = fields[first_arm..first_arm + 10]
                .iter()
                .map(|f| f.parse().unwrap())
                .collect();
            assert_eq!(arms, crate::body::ArmPosture::CAPTURE.0);
        }
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("plan.csv");
        std::fs::write(&path, text).unwrap();
        assert_eq!(read_csv(&path).unwrap(), captures);
    }

    /// A small plan's options: few stances in the pool, one refinement round.
    fn small(captures: usize) -> PlanOptions {
        PlanOptions {
            captures,
            pool_stances: 30,
            refine_rounds: 1,
            ..PlanOptions::default()
        }
    }

    #[test]
    fn a_budgeted_plan_takes_as_many_captures_as_fit_and_is_the_plan_of_that_count() {
        let model = Model::default();
        let budget = 40.0;
        let within = plan_within(&model, &small(12), budget, None).expect("a plan");
        let n = within.captures.len();
        assert!(within.duration <= budget, "{} s", within.duration);
        // One more does not fit; the plan is the one made for its count.
        let more = plan(&model, &small(n + 1)).expect("a plan");
        assert!(
            more.duration > budget,
            "{} captures take {} s",
            n + 1,
            more.duration
        );
        assert_eq!(plan(&model, &small(n)).expect("a plan"), within);
        // At most --captures, within the budget.
        let capped = plan_within(&model, &small(12), budget, Some(n - 3)).expect("a plan");
        assert_eq!(capped.captures.len(), n - 3);
        assert!(capped.duration <= budget);
        // A budget nothing fits, and one that is no budget.
        match plan_within(&model, &small(12), 3.0, None) {
            Err(PlanError::Budget { budget, shortest }) => {
                assert_eq!(budget, 3.0);
                assert!(shortest > 3.0);
            }
            other => panic!("{other:?}"),
        }
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(matches!(
                plan_within(&model, &small(12), bad, None),
                Err(PlanError::Options(_))
            ));
        }
    }
}
