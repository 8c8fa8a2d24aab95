//! # naocalib
//!
//! Automatic kinematic calibration of the NAO humanoid robot after Kastner, Röfer and Laue,
//! "Automatic Robot Calibration for the NAO": a NAO lying on its back looks at checkerboard
//! sandals on its feet in many stances, and a non-linear least-squares fit finds the joint,
//! camera and board offsets that make the kinematic model explain the images.
//!
//! Data flows one way: [`dataset`] → [`solve::Problem`] → [`solve::Solution`] → [`report`].

pub mod batch;
pub mod cli;
pub mod dataset;
#[cfg(feature = "detect")]
pub mod detect;
pub mod model;
pub mod report;
pub mod sim;
pub mod solve;
