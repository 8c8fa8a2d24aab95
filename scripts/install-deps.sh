#!/usr/bin/env bash
# Installs the system libraries naocalib builds against: Ceres (with Eigen, glog, gflags) for
# the Ceres backend, a C++ compiler for the shim, and OpenCV with clang for the detection
# plugin's bindings. Checked on Debian 12 (Ceres 2.1, OpenCV 4.6, clang 14) and Debian 13
# (Ceres 2.2, OpenCV 4.10, clang 19). Rust itself comes from rustup: the locked dependencies
# need 1.89 or newer (`rust-version` in Cargo.toml), newer than Debian's own cargo.
set -euo pipefail
need_rust=1.89
# Rust first: an older cargo stops the build on a list of crates, far from the cause.
if ! command -v cargo >/dev/null 2>&1; then
  echo "install-deps: no cargo on the PATH; naocalib needs Rust $need_rust or newer:" >&2
  echo "  install it with rustup (https://rustup.rs), then run this script again" >&2
  exit 1
fi
have=$(cargo --version | awk '{ print $2 }')
if [ "$(printf '%s\n%s\n' "$need_rust" "${have%%-*}" | sort -V | head -n1)" != "$need_rust" ]; then
  echo "install-deps: $(command -v cargo) is cargo $have; naocalib needs Rust $need_rust or newer" >&2
  echo "  (Debian's own cargo is older): install rustup's stable (https://rustup.rs, or" >&2
  echo "  \`rustup update stable\`) and put ~/.cargo/bin first on the PATH" >&2
  exit 1
fi
packages=(libceres-dev libeigen3-dev libgoogle-glog-dev g++ pkg-config
          libopencv-dev clang libclang-dev file)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: cargo $have and all system packages present"
  exit 0
fi
sudo=""
[ "$(id -u)" -eq 0 ] || sudo="sudo"
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
