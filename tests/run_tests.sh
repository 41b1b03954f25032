#!/usr/bin/env bash
# Sets up a fresh Debian 12 machine (as root, or with sudo), builds edgeplane's tests and runs them.
# Usage: bash tests/run_tests.sh [BUILD_DIR]   (default build/tests)
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${1:-build/tests}
SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO=sudo
PKGS="cmake g++ make libeigen3-dev doctest-dev libtbb-dev libopencv-dev libbenchmark-dev"
if ! dpkg -s $PKGS >/dev/null 2>&1; then
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq $PKGS >/dev/null
fi
cmake -S . -B "$BUILD" -DCMAKE_BUILD_TYPE=Release ${EDGEPLANE_CMAKE_ARGS:-}
cmake --build "$BUILD" -j"$(nproc)"
ctest --test-dir "$BUILD" --output-on-failure -j"$(nproc)"
