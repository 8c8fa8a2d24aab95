#!/usr/bin/env bash
# The whole test suite, as CI runs it (the README's test command): formatting, clippy with
# and without default features, the docs without warnings, the pure-Rust build's tests and
# the full build's tests (unit, the one integration binary, doc tests).
set -euo pipefail
cd "$(dirname "$0")/.."
cargo fmt --check
cargo clippy --all-targets -- -D warnings
cargo clippy --all-targets --no-default-features -- -D warnings
RUSTDOCFLAGS="-D warnings" cargo doc --no-deps --quiet
cargo test --no-default-features
cargo test
