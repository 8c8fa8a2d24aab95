// The Ceres side of the `cxx` bridge declared in src/solve/ceres/bridge.rs.
//
// Rust ships the calibration problem as data (each capture's camera and board chains as
// lists of elementary transforms over the free parameters, plus the observed vertices);
// this shim evaluates those lists on Jets inside an autodiff cost function (Jets over each
// capture's free amounts, chained through the affine amounts to the parameters) and runs
// Levenberg–Marquardt. The shared structs (FfiProblem, ...) are defined by the header that
// cxx generates from the bridge; only their names are needed here.
//
// Every entry point throws std::runtime_error on bad input or failure (cxx turns that into
// a Rust `Err`); nothing here is allowed to reach a Ceres/glog CHECK.

#pragma once

#include "rust/cxx.h"

namespace naocalib {

struct FfiProblem;
struct FfiOptions;
struct FfiSolution;
struct FfiEvaluation;

// Runs Levenberg–Marquardt (dense QR or normal equations, as `options` says) from
// `problem.params`: the values and the run's summary (the covariance is Rust's, from the
// Jacobian at the final fit).
FfiSolution solve(const FfiProblem& problem, const FfiOptions& options);

// Evaluates the cost, the (weighted) residuals and the dense row-major Jacobian over the
// free parameters at `params`.
FfiEvaluation evaluate(const FfiProblem& problem, rust::Slice<const double> params);

}  // namespace naocalib
