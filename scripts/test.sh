#!/usr/bin/env bash
# The whole test suite, as CI runs it (the README's test command): formatting, clippy on
# the full build with its OpenCV plugin (crates/naocalib-opencv) and on the robot's build
# (no default features, V4L2 cameras), the docs without warnings, the robot build's tests
# and the full build's tests (unit, the one integration binary, doc tests), and the
# robot's static binary (scripts/robot-build.sh). The planner's end-to-end runs take part
# in the full build only (tests/it/main.rs).
set -euo pipefail
cd "$(dirname "$0")/.."
cargo fmt --all --check
cargo clippy --workspace --all-targets -- -D warnings
cargo clippy --all-targets --no-default-features --features v4l2 -- -D warnings
RUSTDOCFLAGS="-D warnings" cargo doc --no-deps --quiet
cargo test --no-default-features --features v4l2
cargo test
scripts/robot-build.sh --debug
