#!/usr/bin/env bash
# The robot's binary: naocalib with V4L2 and without OpenCV or Ceres
# (`--no-default-features --features v4l2`), linked statically so that it runs on any NAO V6
# OS image (the stock OS, B-Human's Ubuntu, HULKs' Yocto) whatever its glibc; built for
# the baseline x86-64 CPU (the V6's Atom has no AVX: never `-C target-cpu=native`).
# Uses x86_64-unknown-linux-musl when that target is installed, else the glibc target
# with `+crt-static`. Checks that the result is a static executable and prints its path.
#
#   scripts/robot-build.sh [--debug]
set -euo pipefail
cd "$(dirname "$0")/.."
profile=release
[ "${1:-}" = "--debug" ] && profile=debug
if rustup target list --installed 2>/dev/null | grep -qx x86_64-unknown-linux-musl; then
    target=x86_64-unknown-linux-musl
    flags="-C target-feature=+crt-static"
else
    target=x86_64-unknown-linux-gnu
    flags="-C target-feature=+crt-static"
fi
# These flags and no others (nothing from the environment, e.g. a target-cpu=native); with
# --target they apply to the robot's binary only, not to build scripts.
unset CARGO_ENCODED_RUSTFLAGS CARGO_BUILD_RUSTFLAGS
args=(build --locked --no-default-features --features v4l2 --target "$target" --bin naocalib)
[ "$profile" = release ] && args+=(--release)
RUSTFLAGS="$flags" cargo "${args[@]}"
bin="${CARGO_TARGET_DIR:-target}/$target/$profile/naocalib"
desc=$(file -b "$bin")
case "$desc" in
    *"statically linked"* | *"static-pie linked"*) ;;
    *) echo "robot-build: $bin is not static: $desc" >&2; exit 1 ;;
esac
deps=$(ldd "$bin" 2>&1 || true)
case "$deps" in
    *"not a dynamic executable"* | *"statically linked"*) ;;
    *) echo "robot-build: $bin has dynamic dependencies: $deps" >&2; exit 1 ;;
esac
"$bin" --help >/dev/null
echo "$bin"
