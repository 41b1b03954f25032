// CPU benchmarks: the fused edge pass and the whole pipeline on a realistic room scene (a box on
// the floor in a room corner, Kinect-v2-like noise and 2 % pepper holes), at three resolutions.
#include <benchmark/benchmark.h>

#include <vector>

#include "edgeplane/edgeplane.hpp"
#include "bench_frames.hpp"

namespace {
using namespace edgeplane;

using edgeplane::bench::frame;
using edgeplane::bench::scene_at;

void pipeline(benchmark::State& st, const char* preset_name) {
  const int w = static_cast<int>(st.range(0)), h = static_cast<int>(st.range(1));
  const frame& f = scene_at(w, h);
  segmenter<cpu> seg(preset(preset_name));
  std::vector<std::uint16_t> labels(f.mm.size());
  segmentation_result res;
  for (auto _ : st) {
    seg.segment(make_view(f.mm.data(), w, h), 0.001f, f.r.k, make_view(labels.data(), w, h), res);
    benchmark::DoNotOptimize(labels.data());
  }
  st.counters["pixels_per_second"] = benchmark::Counter(static_cast<double>(w) * h, benchmark::Counter::kIsIterationInvariantRate);
  st.counters["planes"] = static_cast<double>(res.planes.size());
}

void edges_fused(benchmark::State& st) {
  const int w = static_cast<int>(st.range(0)), h = static_cast<int>(st.range(1));
  const frame& f = scene_at(w, h);
  std::vector<std::uint8_t> edges(f.mm.size());
  const params p = presets::thesis_full();
  for (auto _ : st) {
    detect_edges(cpu{}, make_view(f.r.depth.data(), w, h), f.r.k, p, make_view(edges.data(), w, h));
    benchmark::DoNotOptimize(edges.data());
  }
  st.counters["pixels_per_second"] = benchmark::Counter(static_cast<double>(w) * h, benchmark::Counter::kIsIterationInvariantRate);
}

#define EDGEPLANE_SIZES Args({256, 212})->Args({512, 424})->Args({640, 480})
BENCHMARK_CAPTURE(pipeline, thesis_full, "thesis_full")->EDGEPLANE_SIZES->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(pipeline, thesis_half, "thesis_half")->EDGEPLANE_SIZES->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(pipeline, kinect2, "kinect2")->EDGEPLANE_SIZES->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(edges_fused)->EDGEPLANE_SIZES->Unit(benchmark::kMillisecond)->UseRealTime();
}  // namespace

BENCHMARK_MAIN();
