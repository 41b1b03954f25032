#!/usr/bin/env bash
# Segments the three bundled sample depth frames (examples/data, see its README.md) and prints
# the per-stage timings of each.
#
#   examples/run_samples.sh [OUT_DIR [BINARY [OPTION...]]]
#
# OUT_DIR  where the labels, planes JSON and overlay of each frame go (default out/samples)
# BINARY   the edgeplane_segment program (default build/examples/edgeplane_segment)
# OPTION   passed on to every call, e.g. --preset thesis_half --repeat 20
# Paths are relative to the current directory; run it from the project root.
set -euo pipefail

data="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)/data"
out="${1:-out/samples}"
bin="${2:-build/examples/edgeplane_segment}"
shift $(( $# < 2 ? $# : 2 ))

if [[ ! -x "$bin" ]]; then
  echo "run_samples.sh: '$bin' is not an executable; build it first:" >&2
  echo "  cmake -S . -B build -DCMAKE_BUILD_TYPE=Release && cmake --build build --target edgeplane_segment" >&2
  exit 2
fi
mkdir -p "$out"

# TUM RGB-D fr3/long_office_household: value / 5000 = metres
"$bin" "$data/tum_fr3_long_office.png" --fx 535.4 --fy 539.2 --cx 320.1 --cy 247.6 \
  --depth-scale 0.0002 --out-dir "$out" "$@"
# ICL-NUIM living room: value / 5000 = metres; fy is negative (ICL-NUIM's y axis points up)
"$bin" "$data/icl_living_room.png" --fx 481.2 --fy -480.0 --cx 319.5 --cy 239.5 \
  --depth-scale 0.0002 --out-dir "$out" "$@"
# CAPE example frame (Kinect 1 class): millimetres; the IR (depth) camera's intrinsics
"$bin" "$data/cape_depth_0.png" --fx 575.9268544880447 --fy 576.4079160109325 \
  --cx 315.1502635638817 --cy 230.58580662101753 --depth-scale 0.001 --out-dir "$out" "$@"

echo "outputs in $out: <frame>_labels.png, <frame>_planes.json, <frame>_overlay.png"
