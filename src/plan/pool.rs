//! The pool of feasible captures and the design made from it (steps 1–3 of the
//! [module documentation](super), and the order of step 4): the candidates with the
//! information each carries, the selection and its refinement, the tour, and the
//! comparison with the simulator's random stances that completes a [`Plan`].

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::{
    Plan, PlanError, PlanOptions, PlannedCapture, Prediction, body_audit, coverage, design,
    feasible, is_angle_offset, order, random_stances, route,
};
use crate::model::{CameraId, FixedSet, JointAngles, Model, Side};

/// The feasible captures to design from, with the information each carries.
pub(super) struct Pool {
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
pub(super) struct Design {
    captures: Vec<PlannedCapture>,
    prediction: Prediction,
    pub(super) duration: f64,
    via: usize,
    /// The way to each capture and back to rest ([`route::moves`]).
    moves: Vec<Result<Vec<JointAngles>, route::NoRoute>>,
    pool: usize,
    stances: usize,
}

impl Pool {
    /// The pool of `options` for `model` (see the module documentation).
    pub(super) fn new(model: &Model, options: &PlanOptions) -> Result<Pool, PlanError> {
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
        let infos = information_parallel(model, &pairs, &self.fixed, options);
        for (c, info) in new.into_iter().zip(infos) {
            if let Some(info) = info {
                self.candidates.push(c);
                self.infos.push(info);
            }
        }
    }

    /// The design of `count` captures from this pool (with its refinement, which adds to a
    /// copy of the pool), ordered for execution.
    pub(super) fn design(
        &self,
        model: &Model,
        options: &PlanOptions,
        count: usize,
    ) -> Result<Design, PlanError> {
        self.select(model, options, count)?.arrange(model, options)
    }

    /// [`Pool::design`], with `beside` run on a second core while the captures are put in
    /// order (the design's one step on one core).
    pub(super) fn design_beside<T: Send>(
        &self,
        model: &Model,
        options: &PlanOptions,
        count: usize,
        beside: impl FnOnce() -> T + Send,
    ) -> (Result<Design, PlanError>, T) {
        let selected = match self.select(model, options, count) {
            Ok(selected) => selected,
            Err(e) => return (Err(e), beside()),
        };
        std::thread::scope(|scope| {
            let other = scope.spawn(beside);
            let design = selected.arrange(model, options);
            (design, other.join().expect("thread beside the order"))
        })
    }

    /// The captures of the design of `count` (steps 1–3), with their prediction.
    fn select(
        &self,
        model: &Model,
        options: &PlanOptions,
        count: usize,
    ) -> Result<Selected, PlanError> {
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
        Ok(Selected {
            pool,
            chosen,
            prediction,
        })
    }
}

/// The captures a design picked from its (refined) pool, before their order.
struct Selected {
    pool: Pool,
    /// Indices into the pool's candidates.
    chosen: Vec<usize>,
    prediction: Prediction,
}

impl Selected {
    /// The design in execution order (step 4), with every move's way.
    fn arrange(self, model: &Model, options: &PlanOptions) -> Result<Design, PlanError> {
        let Selected {
            pool,
            chosen,
            prediction,
        } = self;
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
            moves,
            pool: pool.candidates.len(),
            stances: stances.len(),
        })
    }
}

impl Pool {
    /// The plan of `design`: compared with the simulator's random stances at its count.
    pub(super) fn finish(
        &self,
        model: &Model,
        options: &PlanOptions,
        design: Design,
        baseline: Option<Baseline>,
    ) -> Result<Plan, PlanError> {
        let count = design.captures.len();
        let Baseline {
            prediction: baseline,
            duration: baseline_duration,
            blocked: baseline_blocked,
            ..
        } = match baseline {
            Some(b) if b.count == count => b,
            _ => Baseline::of(model, options, count)?,
        };
        let rest = route::rest_posture();
        let coverage = coverage::coverage(model, &design.captures, &options.feasibility.centre);
        // The plan's own moves, as `capture` drives them, walked in the body model too.
        let body = body_audit::audit(
            model,
            &crate::body::BodyModel::default(),
            &design.captures,
            &options.feasibility.centre,
            &rest,
            &design.moves,
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

/// The simulator's random stances at a plan's capture count, as the plan is compared with
/// them: their prediction, measurement phase and moves without a way. It depends on the
/// count alone, so [`super::plan`] finds it beside the design.
pub(super) struct Baseline {
    count: usize,
    prediction: Prediction,
    duration: f64,
    blocked: usize,
}

impl Baseline {
    /// The random stances of `count` captures (the lower camera's, seeded by the plan's
    /// seed).
    pub(super) fn of(
        model: &Model,
        options: &PlanOptions,
        count: usize,
    ) -> Result<Self, PlanError> {
        let random = random_stances(model, count, 3, options.seed)?;
        let random: Vec<(CameraId, Side, JointAngles)> = random
            .into_iter()
            .map(|(side, joints)| (CameraId::Lower, side, joints))
            .collect();
        // The random stances are the lower camera's: the upper camera's offsets stay out.
        let lower_fixed = options.fixed.clone().for_upper_camera(false);
        let random_infos = information_parallel(model, &random, &lower_fixed, options);
        let random_refs: Vec<&design::CaptureInformation> = random_infos.iter().flatten().collect();
        let prediction = honest_prediction(model, options, &random, &lower_fixed, &random_refs);
        let rest = route::rest_posture();
        let postures: Vec<JointAngles> = random.iter().map(|c| c.2).collect();
        let moves = route::moves(model, &options.feasibility.body, &rest, &postures);
        Ok(Baseline {
            count,
            prediction,
            duration: route::duration_of(&options.timing, &rest, &postures, &moves),
            blocked: moves.iter().filter(|m| m.is_err()).count(),
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
    let held = design::held_by_solve(model, captures, fixed, options.feasibility.past_body());
    if held.is_empty() {
        return design::predict(&free, infos);
    }
    let mut kept_fixed = fixed.clone();
    for u in &held {
        kept_fixed.set(u.param, true);
    }
    let infos = information_parallel(model, captures, &kept_fixed, options);
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

/// [`design::capture_information_for`] on two threads.
fn information_parallel(
    model: &Model,
    captures: &[(CameraId, Side, JointAngles)],
    fixed: &FixedSet,
    options: &PlanOptions,
) -> Vec<Option<design::CaptureInformation>> {
    let (levels, past) = (options.levels, options.feasibility.past_body());
    let half = captures.len() / 2;
    let (a, b) = captures.split_at(half);
    std::thread::scope(|scope| {
        let first = scope.spawn(|| design::capture_information_for(model, a, fixed, levels, past));
        let mut second = design::capture_information_for(model, b, fixed, levels, past);
        let mut out = first.join().expect("information thread");
        out.append(&mut second);
        out
    })
}
