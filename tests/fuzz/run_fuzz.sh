#!/usr/bin/env bash
# Builds the libFuzzer target with clang (ASan + UBSan) and fuzzes the segmenter for SECONDS,
# starting from the committed seed corpus (tests/fuzz/corpus) and the regression inputs.
# New interesting inputs go to BUILD_DIR/work, crashes to BUILD_DIR/crashes.
#   Usage: bash tests/fuzz/run_fuzz.sh [SECONDS (default 600)] [BUILD_DIR (default build/fuzz)]
# Needs clang and libclang-rt-14-dev (Debian).  Exit 0 when nothing was found.
set -euo pipefail
cd "$(dirname "$0")/../.."
SECONDS_TO_RUN=${1:-600}
BUILD=${2:-build/fuzz}
cmake -S . -B "$BUILD" -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo -DEDGEPLANE_ENABLE_CUDA=OFF \
  -DEDGEPLANE_BUILD_FUZZERS=ON -DEDGEPLANE_BUILD_EXAMPLES=OFF -DEDGEPLANE_BUILD_BENCHMARKS=OFF >/dev/null
cmake --build "$BUILD" -j"$(nproc)" --target edgeplane_fuzz_segmenter
mkdir -p "$BUILD/work" "$BUILD/crashes"
# -max_len 40000: frames up to 160x120 uint16 (or 100x100 float); -timeout: no single input may
# take a minute (a hang is a finding too).
"$BUILD/tests/fuzz/edgeplane_fuzz_segmenter" -max_total_time="$SECONDS_TO_RUN" -max_len=40000 -timeout=60 \
  -rss_limit_mb=6000 -print_final_stats=1 -artifact_prefix="$BUILD/crashes/" \
  "$BUILD/work" tests/fuzz/corpus tests/fuzz/regressions
