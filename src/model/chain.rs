//! Kinematic chains as data: a short list of elementary transforms.
//!
//! The model is written once, here in Rust, as a [`Chain`]. Rust evaluates it on any
//! [`Scalar`] (values or dual numbers), and the Ceres shim evaluates the very same list on
//! Jets, so there is no second, hand-written copy of the kinematics.

use super::parameters::{PARAMETER_COUNT, Param};
use super::pose::{Axis, Pose};
use super::scalar::{Scalar, lift};

/// Most parameters one amount may depend on: a leg joint's angle carries its offset, its
/// compliance and its play.
pub const MAX_TERMS: usize = 3;

/// A scalar that is a constant plus a few multiples of calibration parameters:
/// `constant + Σ scale_k · α[param_k]`. A joint rotation `q = θ + α` is
/// `Affine::joint(1, θ, param)`; compliance and play add terms with per-capture
/// coefficients (the gravity torque, half its sign).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Affine {
    /// The constant part (e.g. the measured joint angle, in radians).
    pub constant: f64,
    terms: [Option<(Param, f64)>; MAX_TERMS],
}

impl Affine {
    /// A constant.
    pub fn constant(value: f64) -> Self {
        Affine {
            constant: value,
            terms: [None; MAX_TERMS],
        }
    }

    /// `sign · (θ + α[param])`: a measured joint angle plus its offset, possibly mirrored.
    pub fn joint(sign: f64, measured: f64, param: Param) -> Self {
        Affine::constant(sign * measured).plus(param, sign)
    }

    /// `α[param]` alone.
    pub fn param(param: Param) -> Self {
        Affine::constant(0.0).plus(param, 1.0)
    }

    /// This amount plus `scale · α[param]`.
    ///
    /// # Panics
    /// When it already has [`MAX_TERMS`] terms (a bug in the model's construction).
    pub fn plus(mut self, param: Param, scale: f64) -> Self {
        let slot = self
            .terms
            .iter_mut()
            .find(|t| t.is_none())
            .expect("an amount depends on at most MAX_TERMS parameters");
        *slot = Some((param, scale));
        self
    }

    /// The parameters and their coefficients.
    pub fn terms(&self) -> impl Iterator<Item = (Param, f64)> + '_ {
        self.terms.iter().flatten().copied()
    }

    /// Whether the amount depends on any parameter.
    pub fn depends(&self) -> bool {
        self.terms[0].is_some()
    }

    /// The amount with every parameter in `held` replaced by its value in `values`.
    pub fn freeze(&self, held: &[bool; PARAMETER_COUNT], values: &[f64]) -> Affine {
        let mut out = Affine::constant(self.constant);
        for (p, scale) in self.terms() {
            if held[p.index()] {
                out.constant += scale * values[p.index()];
            } else {
                out = out.plus(p, scale);
            }
        }
        out
    }

    /// Evaluates the value for the parameter vector `params`.
    pub fn eval<T: Scalar>(&self, params: &[T]) -> T {
        let mut value = lift::<T>(self.constant);
        for (p, scale) in self.terms() {
            value += params[p.index()].clone() * scale;
        }
        value
    }
}

/// One elementary transform, applied in the current (local) frame.
#[derive(Debug, Clone, PartialEq)]
pub enum Step {
    /// A constant rigid transform (already folded link geometry).
    Fixed(Pose<f64>),
    /// A rotation about a local axis by an angle in radians.
    Rotate(Axis, Affine),
    /// A translation along a local axis by a length in millimetres.
    Translate(Axis, Affine),
}

/// A kinematic chain: the product of its steps, from the parent frame to the end frame.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Chain {
    steps: Vec<Step>,
}

impl Chain {
    /// An empty chain (the identity).
    pub fn new() -> Self {
        Chain::default()
    }

    /// Appends a constant transform, merging it with a preceding constant one.
    pub fn fixed(mut self, pose: Pose<f64>) -> Self {
        if let Some(Step::Fixed(last)) = self.steps.last_mut() {
            *last = last.compose(&pose);
        } else {
            self.steps.push(Step::Fixed(pose));
        }
        self
    }

    /// Appends a rotation; a constant one is folded into the preceding constant transform.
    pub fn rotate(self, axis: Axis, angle: Affine) -> Self {
        if angle.depends() {
            self.push(Step::Rotate(axis, angle))
        } else {
            self.fixed(Pose::rotation(axis, angle.constant))
        }
    }

    /// Appends a translation; a constant one is folded into the preceding constant transform.
    pub fn translate(self, axis: Axis, distance: Affine) -> Self {
        if distance.depends() {
            self.push(Step::Translate(axis, distance))
        } else {
            let mut t = [0.0; 3];
            t[axis.index()] = distance.constant;
            self.fixed(Pose::translation(t[0], t[1], t[2]))
        }
    }

    /// Appends the steps of another chain.
    pub fn then(self, other: &Chain) -> Self {
        other.steps.iter().cloned().fold(self, Chain::push)
    }

    fn push(mut self, step: Step) -> Self {
        match step {
            Step::Fixed(p) => return self.fixed(p),
            s => self.steps.push(s),
        }
        self
    }

    /// The steps, in order.
    pub fn steps(&self) -> &[Step] {
        &self.steps
    }

    /// The chain with every parameter in `held` replaced by its value in `values`
    /// (radians / mm) and constant steps folded: what a solver needs for the free parameters.
    pub fn freeze(&self, held: &[bool; PARAMETER_COUNT], values: &[f64]) -> Chain {
        let freeze = |a: &Affine| a.freeze(held, values);
        self.steps
            .iter()
            .fold(Chain::new(), |chain, step| match step {
                Step::Fixed(p) => chain.fixed(p.clone()),
                Step::Rotate(axis, a) => chain.rotate(*axis, freeze(a)),
                Step::Translate(axis, a) => chain.translate(*axis, freeze(a)),
            })
    }

    /// The parameters the chain depends on, in order of first use, without repeats.
    pub fn params(&self) -> Vec<Param> {
        let mut out = Vec::new();
        for step in &self.steps {
            if let Step::Rotate(_, a) | Step::Translate(_, a) = step {
                for (p, _) in a.terms() {
                    if !out.contains(&p) {
                        out.push(p);
                    }
                }
            }
        }
        out
    }

    /// Evaluates the chain for the parameter vector `params` (indexed by [`Param::index`]).
    pub fn eval<T: Scalar>(&self, params: &[T]) -> Pose<T> {
        let mut pose = Pose::identity();
        for (i, step) in self.steps.iter().enumerate() {
            match step {
                Step::Fixed(p) if i == 0 => pose = Pose::lift(p),
                Step::Fixed(p) => pose = pose.then_fixed(p),
                Step::Rotate(axis, a) => pose.rotate(*axis, &a.eval(params)),
                Step::Translate(axis, a) => pose.translate(*axis, &a.eval(params)),
            }
        }
        pose
    }
}
