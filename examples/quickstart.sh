#!/usr/bin/env bash
# Sets up a fresh Debian 12 machine (as root, or with sudo), builds edgeplane_segment and segments the
# bundled sample depth frames into out/samples (label PNGs, plane JSON, colour overlays), printing
# the per-stage timings.  Usage: bash examples/quickstart.sh [OUT_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO=sudo
PKGS="cmake g++ make libeigen3-dev libtbb-dev libopencv-dev"
if ! dpkg -s $PKGS >/dev/null 2>&1; then
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq $PKGS >/dev/null
fi
# -march=native: built and run on this machine (the labels are the same as a portable build's)
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DEDGEPLANE_BUILD_TESTS=OFF -DEDGEPLANE_BUILD_BENCHMARKS=OFF \
  -DEDGEPLANE_ENABLE_CUDA=OFF -DEDGEPLANE_NATIVE_ARCH=ON
cmake --build build -j"$(nproc)" --target edgeplane_segment
bash examples/run_samples.sh "${1:-out/samples}" build/examples/edgeplane_segment
