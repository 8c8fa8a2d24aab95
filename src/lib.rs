//! # naocalib
//!
//! Automatic kinematic calibration of the NAO humanoid robot after Kastner, Röfer and Laue,
//! "Automatic Robot Calibration for the NAO": a NAO lying on its back looks at checkerboard
//! sandals on its feet in many stances, and a non-linear least-squares fit finds the joint,
//! camera and board offsets that make the kinematic model explain the images.
//!
//! Data flows one way: [`dataset`] → [`solve::Problem`] → [`solve::Solution`] →
//! [`run::Run`] (the solution with its [`calibration`], change and provenance) → [`report`],
//! [`export`] and [`batch`].
//!
//! The least-squares fit of a dataset from Rust ([`run::calibrate`] wraps it into the run
//! `naocalib solve` prints: calibration, change and provenance):
//!
//! ```
//! use std::path::Path;
//! use naocalib::dataset::Dataset;
//! use naocalib::model::{FixedSet, Param};
//! use naocalib::solve::{Problem, UncertaintyOptions, backend, backend_names, calibrate};
//!
//! let dataset = Dataset::load(Path::new("data/sample"))?;
//! let problem = Problem::from_dataset(&dataset, FixedSet::default())?;
//! let solver = backend(backend_names()[0], false).expect("a listed backend");
//! let solution = calibrate(&problem, solver.as_ref(), &UncertaintyOptions::default())?;
//! let (value, sigma) = (
//!     solution.report_value(Param::LKneePitch),
//!     solution.report_std(Param::LKneePitch),
//! );
//! println!("LKneePitch offset {value:.3}° ± {sigma:.3}°");
//! assert!(solution.summary.converged && sigma > 0.0 && sigma < 0.5);
//! println!("{}", naocalib::report::table(&solution, None));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![warn(missing_docs)]

pub mod batch;
pub mod body;
pub mod calibration;
pub mod dataset;
#[cfg(feature = "detect")]
pub mod detect;
pub mod export;
pub mod model;
pub mod output;
pub mod plan;
pub mod report;
pub mod robot;
pub mod run;
pub mod sandal;
pub mod sim;
pub mod solve;
