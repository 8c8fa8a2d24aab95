#!/usr/bin/env bash
# Installs the system libraries naocalib builds against (Debian 12 / Ubuntu 22.04+):
# Ceres 2.1 (with Eigen, glog, gflags) for the Ceres backend, a C++ compiler for the shim,
# and OpenCV 4.6 with clang for the detection bindings.
set -euo pipefail
packages=(libceres-dev libeigen3-dev libgoogle-glog-dev g++ pkg-config
          libopencv-dev clang libclang-dev file)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all system packages present"
  exit 0
fi
sudo=""
[ "$(id -u)" -eq 0 ] || sudo="sudo"
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
