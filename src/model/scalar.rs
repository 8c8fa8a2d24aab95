//! The scalar type the model is generic over.
//!
//! The same model code yields plain values (`f64`) and exact derivatives (num-dual's dual
//! numbers, static or dynamic), so the pure-Rust solvers never need a second model.

use num_dual::DualNum;

/// A number the kinematic model can be evaluated on: `f64` or a num-dual dual number.
pub trait Scalar: DualNum<f64> + Clone {}

impl<T: DualNum<f64> + Clone> Scalar for T {}

/// Lifts a constant into the scalar type.
#[inline]
pub fn lift<T: Scalar>(value: f64) -> T {
    T::from(value)
}
