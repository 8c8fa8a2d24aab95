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
pub mod feasible;
pub mod order;
pub mod report;
pub mod request;
pub mod route;

use std::path::Path;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::model::{CameraId, FixedSet, Joint, JointAngles, Model, PARAMETER_COUNT, Param, Side};
use crate::sim::Stance;
use crate::solve::noise::NoiseLevels;

pub use design::{DesignOptions, Prediction};
pub use feasible::{Feasibility, Infeasible};
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
    let design = pool.design(model, options, options.captures)?;
    pool.finish(model, options, design)
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
    pool.finish(model, options, design)
}

/// The most captures a budgeted plan takes without `--captures`.
pub const MOST_CAPTURES: usize = 5000;

/// The feasible captures to design from, with the information each carries.
struct Pool {
    /// The free parameters (the upper camera's when planned for).
    fixed: FixedSet,
    /// Whether the boards sweep the lower and the upper camera's image (their intrinsics
    /// are free).
    sweeps: [bool; 2],
    candidates: Vec<feasible::Candidate>,
    infos: Vec<design::CaptureInformation>,
    /// Lower-camera captures per leg.
    lower: [usize; 2],
    /// Stances numbered so far.
    stances: usize,
    /// The design's weights of the free parameters (see [`design::weights`]).
    focus: Vec<f64>,
}

/// A design of the pool, in execution order, before the comparison with random stances.
struct Design {
    captures: Vec<PlannedCapture>,
    prediction: Prediction,
    duration: f64,
    via: usize,
    pool: usize,
    stances: usize,
}

impl Pool {
    /// The pool of `options` for `model` (see the module documentation).
    fn new(model: &Model, options: &PlanOptions) -> Result<Pool, PlanError> {
        let positive = |x: f64| x.is_finite() && x > 0.0;
        let joint = options.levels.joint;
        if !(positive(options.levels.px) && joint.is_finite() && joint >= 0.0) {
            return Err(PlanError::Options(
                "the pixel noise must be positive and the joint noise not negative".into(),
            ));
        }
        if options.fixed.free().is_empty() {
            return Err(PlanError::Options("no parameter is free".into()));
        }
        let upper = options.cameras.contains(&CameraId::Upper);
        let fixed = options.fixed.clone().for_upper_camera(upper);
        // The boards sweep the image of a camera whose intrinsics are free.
        let sweeps = options.sweeps();
        let mut pools: Vec<Vec<feasible::Candidate>> = Vec::new();
        let mut lower = [0; 2];
        let mut first = 0;
        for camera in CameraId::ALL {
            if !options.cameras.contains(&camera) {
                continue;
            }
            let sweep = sweeps[camera as usize];
            let (stances, heads, seed) = match camera {
                CameraId::Lower => (options.pool_stances, options.heads, options.seed),
                CameraId::Upper => (
                    options.upper_pool_stances,
                    options.upper_heads,
                    options.seed ^ 0x0bbe_0000,
                ),
            };
            // Both legs drawn in parallel, each from its own seeded generator.
            let found: Vec<Vec<feasible::Candidate>> = std::thread::scope(|scope| {
                let handles: Vec<_> = Side::BOTH
                    .into_iter()
                    .enumerate()
                    .map(|(k, side)| {
                        scope.spawn(move || {
                            let mut rng = ChaCha8Rng::seed_from_u64(seed.wrapping_add(k as u64));
                            feasible::candidates(
                                model,
                                camera,
                                side,
                                stances,
                                heads,
                                sweep,
                                stances * 400,
                                &options.feasibility,
                                first + k * stances,
                                &mut rng,
                            )
                        })
                    })
                    .collect();
                handles
                    .into_iter()
                    .map(|h| h.join().expect("pool thread"))
                    .collect()
            });
            first += 2 * stances;
            match camera {
                CameraId::Lower => lower = [found[0].len(), found[1].len()],
                // Upper captures are optional, but a leg without any would leave its pool
                // to chance.
                CameraId::Upper => {
                    for (side, pool) in Side::BOTH.iter().zip(&found) {
                        if pool.is_empty() {
                            return Err(PlanError::Pool {
                                camera: camera.name(),
                                side: side.name(),
                                found: 0,
                            });
                        }
                    }
                }
            }
            pools.extend(found);
        }
        let free = fixed.free();
        // The parameters whose worst σ the design minimises: the 15 angle offsets (camera
        // rotation and leg joints) when free, otherwise every free parameter.
        let upper_focus = options.upper_sigma_ratio.powi(-2);
        let mut focus: Vec<f64> = free
            .iter()
            .map(|p| match p.group() {
                crate::model::ParamGroup::UpperCamera => upper_focus,
                _ if is_angle_offset(*p) => 1.0,
                _ => 0.0,
            })
            .collect();
        if focus.iter().all(|f| *f == 0.0) {
            focus.fill(1.0);
        }
        let mut pool = Pool {
            fixed,
            sweeps,
            candidates: Vec::new(),
            infos: Vec::new(),
            lower,
            stances: first,
            focus,
        };
        pool.admit(model, options, pools.into_iter().flatten().collect());
        Ok(pool)
    }

    /// Adds the candidates whose board is in front of the camera, with their information.
    fn admit(&mut self, model: &Model, options: &PlanOptions, new: Vec<feasible::Candidate>) {
        let pairs: Vec<(CameraId, Side, JointAngles)> =
            new.iter().map(|c| (c.camera, c.side, c.joints)).collect();
        let infos = information_parallel(model, &pairs, &self.fixed, options.levels);
        for (c, info) in new.into_iter().zip(infos) {
            if let Some(info) = info {
                self.candidates.push(c);
                self.infos.push(info);
            }
        }
    }

    /// The design of `count` captures from this pool (with its refinement, which adds to a
    /// copy of the pool), ordered for execution.
    fn design(
        &self,
        model: &Model,
        options: &PlanOptions,
        count: usize,
    ) -> Result<Design, PlanError> {
        // Lower captures must fill a quarter of the plan per leg.
        if options.cameras.contains(&CameraId::Lower) {
            for (side, found) in Side::BOTH.iter().zip(self.lower) {
                if found < count.div_ceil(4) {
                    return Err(PlanError::Pool {
                        camera: CameraId::Lower.name(),
                        side: side.name(),
                        found,
                    });
                }
            }
        }
        let mut pool = Pool {
            fixed: self.fixed.clone(),
            sweeps: self.sweeps,
            candidates: self.candidates.clone(),
            infos: self.infos.clone(),
            lower: self.lower,
            stances: self.stances,
            focus: self.focus.clone(),
        };
        let n = pool.focus.len();
        let mut chosen = design::select(
            &pool.infos.iter().collect::<Vec<_>>(),
            n,
            &pool.focus,
            count,
            &[],
            &options.design,
        );
        // Refinement: variants of the picked captures join the pool, and the design is
        // improved from where it is.
        let mut spread = options.spread;
        let sweeps = pool.sweeps;
        for round in 0..options.refine_rounds {
            let bases: Vec<feasible::Candidate> =
                chosen.iter().map(|&k| pool.candidates[k].clone()).collect();
            let half = bases.len() / 2;
            let per = options.variants;
            let next_stance = pool.stances;
            let found: Vec<feasible::Candidate> = std::thread::scope(|scope| {
                let handles: Vec<_> = [&bases[..half], &bases[half..]]
                    .into_iter()
                    .enumerate()
                    .map(|(k, part)| {
                        let first = next_stance + k * half * per;
                        scope.spawn(move || {
                            let mut rng = ChaCha8Rng::seed_from_u64(
                                options.seed ^ (0x5eed_0000 + 2 * round as u64 + k as u64),
                            );
                            let mut out = Vec::new();
                            for (i, base) in part.iter().enumerate() {
                                out.extend(feasible::variants(
                                    model,
                                    base,
                                    per,
                                    4 * per,
                                    spread,
                                    sweeps[base.camera as usize],
                                    &options.feasibility,
                                    first + i * per,
                                    &mut rng,
                                ));
                            }
                            out
                        })
                    })
                    .collect();
                handles
                    .into_iter()
                    .flat_map(|h| h.join().expect("refinement thread"))
                    .collect()
            });
            pool.stances += bases.len() * per;
            pool.admit(model, options, found);
            chosen = design::select(
                &pool.infos.iter().collect::<Vec<_>>(),
                n,
                &pool.focus,
                count,
                &chosen,
                &options.design,
            );
            spread /= 2.0;
        }
        let chosen_captures: Vec<(CameraId, Side, JointAngles)> = chosen
            .iter()
            .map(|&k| {
                let c = &pool.candidates[k];
                (c.camera, c.side, c.joints)
            })
            .collect();
        let prediction = honest_prediction(
            model,
            options,
            &chosen_captures,
            &pool.fixed,
            &chosen.iter().map(|&k| &pool.infos[k]).collect::<Vec<_>>(),
        );
        let angles: Vec<JointAngles> = chosen.iter().map(|&k| pool.candidates[k].joints).collect();
        let body = &options.feasibility.body;
        let rest = route::rest_posture();
        let tour = order::order(model, body, &rest, &angles, &options.timing);
        let captures: Vec<PlannedCapture> = tour
            .iter()
            .map(|&i| {
                let c = &pool.candidates[chosen[i]];
                PlannedCapture {
                    camera: c.camera,
                    side: c.side,
                    joints: c.joints,
                }
            })
            .collect();
        let postures: Vec<JointAngles> = captures.iter().map(|c| c.joints).collect();
        let moves = route::moves(model, body, &rest, &postures);
        if let Some(k) = moves.iter().position(Result::is_err) {
            return Err(PlanError::Moves(k));
        }
        let via = moves.iter().flatten().map(|way| way.len() - 1).sum();
        let duration = route::duration_of(&options.timing, &rest, &postures, &moves);
        let mut stances: Vec<usize> = chosen.iter().map(|&k| pool.candidates[k].stance).collect();
        stances.sort_unstable();
        stances.dedup();
        Ok(Design {
            captures,
            prediction,
            duration,
            via,
            pool: pool.candidates.len(),
            stances: stances.len(),
        })
    }

    /// The plan of `design`: compared with the simulator's random stances at its count.
    fn finish(
        &self,
        model: &Model,
        options: &PlanOptions,
        design: Design,
    ) -> Result<Plan, PlanError> {
        let count = design.captures.len();
        let random = random_stances(model, count, 3, options.seed)?;
        let random: Vec<(CameraId, Side, JointAngles)> = random
            .into_iter()
            .map(|(side, joints)| (CameraId::Lower, side, joints))
            .collect();
        // The random stances are the lower camera's: the upper camera's offsets stay out.
        let lower_fixed = options.fixed.clone().for_upper_camera(false);
        let random_infos = information_parallel(model, &random, &lower_fixed, options.levels);
        let random_refs: Vec<&design::CaptureInformation> = random_infos.iter().flatten().collect();
        let baseline = honest_prediction(model, options, &random, &lower_fixed, &random_refs);
        let body = &options.feasibility.body;
        let rest = route::rest_posture();
        let random_postures: Vec<JointAngles> = random.iter().map(|c| c.2).collect();
        let random_moves = route::moves(model, body, &rest, &random_postures);
        let baseline_duration =
            route::duration_of(&options.timing, &rest, &random_postures, &random_moves);
        let baseline_blocked = random_moves.iter().filter(|m| m.is_err()).count();
        let coverage = coverage::coverage(model, &design.captures, &options.feasibility.centre);
        let body = body_audit::audit(
            model,
            &crate::body::BodyModel::default(),
            &design.captures,
            &options.feasibility.centre,
        );
        Ok(Plan {
            captures: design.captures,
            prediction: design.prediction,
            baseline,
            duration: design.duration,
            via: design.via,
            baseline_duration,
            baseline_blocked,
            pool: design.pool,
            stances: design.stances,
            coverage,
            body,
        })
    }
}

/// The prediction for the captures `captures` (with their information `infos` about the
/// parameters `fixed` leaves free) as `solve` will fit them: a free parameter that `solve`
/// holds at its nominal value for such a dataset ([`design::held_by_solve`]) is predicted
/// undetermined, with the combination it forms, and the others' σ are those of the fit
/// without it.
fn honest_prediction(
    model: &Model,
    options: &PlanOptions,
    captures: &[(CameraId, Side, JointAngles)],
    fixed: &FixedSet,
    infos: &[&design::CaptureInformation],
) -> Prediction {
    let free = fixed.free();
    let held = design::held_by_solve(model, captures, fixed);
    if held.is_empty() {
        return design::predict(&free, infos);
    }
    let mut kept_fixed = fixed.clone();
    for u in &held {
        kept_fixed.set(u.param, true);
    }
    let infos = information_parallel(model, captures, &kept_fixed, options.levels);
    let kept = design::predict(
        &kept_fixed.free(),
        &infos.iter().flatten().collect::<Vec<_>>(),
    );
    let mut undetermined = kept.undetermined.clone();
    undetermined.extend(held.iter().map(|u| {
        format!(
            "{} (solve holds it at its nominal value: the captures cannot tell {} apart)",
            u.param,
            u.direction.describe()
        )
    }));
    Prediction {
        std: free
            .iter()
            .map(|p| kept.std_of(*p).unwrap_or(f64::INFINITY))
            .collect(),
        free,
        rank: kept.rank,
        undetermined,
    }
}

/// Whether `p` is one of the paper's 15 angle offsets: the camera rotation and the 12 leg
/// joints.
pub fn is_angle_offset(p: Param) -> bool {
    use crate::model::ParamGroup;
    matches!(
        p.group(),
        ParamGroup::Camera | ParamGroup::LeftLeg | ParamGroup::RightLeg
    )
}

/// [`design::capture_information_for`] on two threads.
fn information_parallel(
    model: &Model,
    captures: &[(CameraId, Side, JointAngles)],
    fixed: &FixedSet,
    levels: NoiseLevels,
) -> Vec<Option<design::CaptureInformation>> {
    let half = captures.len() / 2;
    let (a, b) = captures.split_at(half);
    std::thread::scope(|scope| {
        let first = scope.spawn(|| design::capture_information_for(model, a, fixed, levels));
        let mut second = design::capture_information_for(model, b, fixed, levels);
        let mut out = first.join().expect("information thread");
        out.append(&mut second);
        out
    })
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
    captures
        .iter()
        .map(|c| Stance {
            side: c.side,
            postures: vec![c.joints],
        })
        .collect()
}

/// The plan as the simulator's schedule: its stances ([`to_stances`]) and the camera of
/// each (`SimOptions::schedule` and `schedule_cameras`).
pub fn to_schedule(captures: &[PlannedCapture]) -> (Vec<Stance>, Vec<CameraId>) {
    (
        to_stances(captures),
        captures.iter().map(|c| c.camera).collect(),
    )
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
