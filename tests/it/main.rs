//! naocalib's integration tests, one binary: each module is one concern, `util` holds the
//! helpers they share.
//!
//! The suite runs twice (`scripts/test.sh`): in the full build and in the robot's build
//! (`--no-default-features --features v4l2`). The planner's end-to-end runs (144-capture
//! plans, their statistics, a whole planned session) do not depend on the build's
//! features: they run once, in the full build (`feature = "detect"`).

mod util;

mod all_or_none;
mod batch_solve;
mod capture;
mod capture_arms;
mod capture_body;
mod capture_cameras;
mod capture_guard;
mod capture_honest;
#[cfg(feature = "ceres")]
mod ceres_agreement;
#[cfg(feature = "detect")]
mod cli_detect_solve;
mod cli_solve;
mod dataset_io;
#[cfg(feature = "detect")]
mod detect_border;
#[cfg(feature = "detect")]
mod detect_dark;
#[cfg(feature = "detect")]
mod detect_files;
#[cfg(feature = "detect")]
mod detect_occluded;
#[cfg(feature = "detect")]
mod detect_render;
#[cfg(feature = "detect")]
mod detect_robust;
#[cfg(feature = "detect")]
mod detect_tilted;
#[cfg(feature = "detect")]
mod detect_turned;
mod export_files;
mod export_intrinsics;
mod export_posture;
mod export_robustness;
mod export_roundtrip;
mod export_signs;
mod export_start_from;
mod export_teams;
mod export_update;
mod export_upper;
mod extended;
mod fuzz_readers;
mod held_honest;
mod hostile_inputs;
mod hostile_outputs;
mod lola_faults;
mod misfit;
#[cfg(feature = "detect")]
mod plan;
#[cfg(feature = "detect")]
mod plan_around;
#[cfg(feature = "detect")]
mod plan_cameras;
#[cfg(feature = "detect")]
mod plan_intrinsics;
#[cfg(feature = "detect")]
mod plan_moves;
mod plot_files;
mod pure_rust_agreement;
mod pure_rust_cli;
#[cfg(feature = "detect")]
mod readme;
mod report_html;
mod robot_file_bounds;
mod robot_state;
mod run_object;
mod sandal;
mod silently_wrong;
mod spec_reference;
#[cfg(feature = "ceres")]
mod uncertainty;
mod upper_camera;
#[cfg(feature = "detect")]
mod upper_session;
#[cfg(feature = "v4l2")]
mod v6cam;
