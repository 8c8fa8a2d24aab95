//! The measurement phase on a NAO V6 (docs/CAPTURE.md): `naocalib capture` drives a plan's
//! stances over LoLA ([`lola`]) with the arms out of the way ([`arms`]), safely ([`motion`], [`safety`], [`plausible`]), photographs the sandals
//! ([`camera`]) and writes the dataset capture by capture ([`capture`]); [`simulated`] is a
//! simulated robot that serves LoLA for tests.

pub mod arms;
pub mod body;
pub mod camera;
pub mod capture;
pub mod check;
pub mod lola;
pub mod motion;
pub mod plausible;
pub mod safety;
pub mod simulated;

pub use capture::{
    CaptureError, CaptureOptions, DatasetOut, End, Event, PlanRow, Report, Session, Start,
};
