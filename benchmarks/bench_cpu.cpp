// CPU benchmarks on a realistic room scene (a box on the floor in a room corner, Kinect-v2-like
// noise and 2 % pepper holes) at 256x212, 512x424 and 640x480:
//  - every kernel alone, on the inputs the pipeline gives it (bench_stages.hpp): depth conversion,
//    the depth closing, smoothing, each edge type over the four directions, the fused edge pass,
//    the edge-map closing, diagonal-run extraction with the line test, the union-find, the moments
//    by label, validation (fit and tests) and merging;
//  - the whole pipeline per preset (segmenter reused, uint16 frame in, labels and planes out),
//    with pixels per second and time per pixel (the cost growth across sizes);
//  - throughput over a 24-frame sequence of a moving camera through one segmenter: frames per
//    second, the segmenter's scratch bytes and the process's peak resident memory; and the same
//    sequence through a two-lane edgeplane::pipeline (serial lanes: a frame per core; parallel
//    lanes), whose frames per second against it is the gain of frame-level parallelism.
// Every benchmark reports real (wall) time: the CPU backend is synchronous.
#include <benchmark/benchmark.h>
#include <sys/resource.h>

#include <cmath>
#include <vector>

#include "bench_counters.hpp"
#include "bench_frames.hpp"
#include "bench_stages.hpp"
#include "edgeplane/edgeplane.hpp"

namespace {
using namespace edgeplane;

using edgeplane::bench::frame;
using edgeplane::bench::scene_at;
using edgeplane::bench::stage_data;

const stage_data& stages_at(int w, int h) {
  static std::vector<stage_data> cache;
  for (const auto& s : cache)
    if (s.w == w && s.h == h) return s;
  cache.push_back(edgeplane::bench::make_stage_data(w, h, "thesis_full"));
  return cache.back();
}

using edgeplane::bench::per_pixel_counters;

#define EDGEPLANE_STAGE_BENCH(name, ...)                                        \
  void name(benchmark::State& st) {                                              \
    const int w = static_cast<int>(st.range(0)), h = static_cast<int>(st.range(1)); \
    const stage_data& s = stages_at(w, h);                                       \
    const cpu b{};                                                               \
    (void)b;                                                                     \
    __VA_ARGS__;                                                                 \
    per_pixel_counters(st, w, h);                                                \
  }

// ---- 1. preprocessing -----------------------------------------------------------------------------
EDGEPLANE_STAGE_BENCH(convert, {
  const frame& f = scene_at(w, h);
  std::vector<float> out(f.mm.size());
  for (auto _ : st) {
    convert_depth(b, make_view(f.mm.data(), w, h), 0.001f, s.p.min_depth, s.p.max_depth, make_view(out.data(), w, h));
    benchmark::DoNotOptimize(out.data());
  }
})
EDGEPLANE_STAGE_BENCH(depth_closing, {
  std::vector<float> in = s.z_raw, scratch(in.size()), out(in.size());
  for (auto _ : st) {
    close_depth(b, make_view(in.data(), w, h), make_view(scratch.data(), w, h), make_view(out.data(), w, h), 1);
    benchmark::DoNotOptimize(out.data());
  }
})
EDGEPLANE_STAGE_BENCH(smoothing, {
  std::vector<float> out(s.z_closed.size());
  for (auto _ : st) {
    smooth_depth(b, make_view(s.z_closed.data(), w, h), make_view(out.data(), w, h), s.p.smooth_radius, s.p.smooth_k,
                 s.p.noise.sigma0, s.p.noise.sigma2);
    benchmark::DoNotOptimize(out.data());
  }
})

// ---- 2. edges -------------------------------------------------------------------------------------
template <class EdgeType>
void edge_type_bench(benchmark::State& st, EdgeType detail::edge_set::*member) {
  const int w = static_cast<int>(st.range(0)), h = static_cast<int>(st.range(1));
  const stage_data& s = stages_at(w, h);
  const EdgeType t = detail::make_edge_set(s.p).*member;
  std::vector<std::uint8_t> e(s.edges.size());
  for (auto _ : st) {
    std::fill(e.begin(), e.end(), 0);
    const auto ev = make_view(e.data(), w, h);
    detect_edge<direction::horizontal>(cpu{}, s.depth(), s.k, t, ev);
    detect_edge<direction::vertical>(cpu{}, s.depth(), s.k, t, ev);
    detect_edge<direction::left_diagonal>(cpu{}, s.depth(), s.k, t, ev);
    detect_edge<direction::right_diagonal>(cpu{}, s.depth(), s.k, t, ev);
    benchmark::DoNotOptimize(e.data());
  }
  per_pixel_counters(st, w, h);
}
void edge_jump(benchmark::State& st) { edge_type_bench(st, &detail::edge_set::jump); }
void edge_extrema(benchmark::State& st) { edge_type_bench(st, &detail::edge_set::extrema); }
void edge_corner(benchmark::State& st) { edge_type_bench(st, &detail::edge_set::corner); }
void edge_curved(benchmark::State& st) { edge_type_bench(st, &detail::edge_set::curved); }

EDGEPLANE_STAGE_BENCH(edges_fused, {
  std::vector<std::uint8_t> e(s.edges.size());
  for (auto _ : st) {
    detect_edges(b, s.depth(), s.k, s.p, make_view(e.data(), w, h));
    benchmark::DoNotOptimize(e.data());
  }
})
EDGEPLANE_STAGE_BENCH(edge_closing, {
  std::vector<std::uint8_t> scratch(s.edges.size()), mask(s.edges.size());
  for (auto _ : st) {
    close_edges(b, make_view(s.edges.data(), w, h), make_view(scratch.data(), w, h), make_view(mask.data(), w, h),
                s.p.edge_closing_radius);
    benchmark::DoNotOptimize(mask.data());
  }
})

// ---- 3.-5. candidates, validation, merging ----------------------------------------------------------
EDGEPLANE_STAGE_BENCH(segments, {
  std::vector<std::uint8_t> l(s.edges.size()), r(s.edges.size());
  const auto mask = make_view(s.mask.data(), w, h);
  for (auto _ : st) {
    extract_segments<direction::left_diagonal>(b, s.depth(), mask, s.k, s.p, make_view(l.data(), w, h));
    extract_segments<direction::right_diagonal>(b, s.depth(), mask, s.k, s.p, make_view(r.data(), w, h));
    benchmark::DoNotOptimize(l.data());
    benchmark::DoNotOptimize(r.data());
  }
})
EDGEPLANE_STAGE_BENCH(union_find, {
  std::vector<std::int32_t> parent(s.parent.size());
  const auto adj = s.adjacency();
  const auto n = static_cast<std::int64_t>(parent.size());
  for (auto _ : st) {
    connected_components(b, n, adj.active, n, adj, parent.data());
    benchmark::DoNotOptimize(parent.data());
  }
  st.counters["candidates"] = s.num_cand;
})
EDGEPLANE_STAGE_BENCH(moments, {
  std::vector<std::uint64_t> m(s.moments.size());
  std::vector<std::int32_t> bb(s.bbox.size());
  const detail::candidate_image_labels labels{make_view(s.cand.data(), w, h)};
  for (auto _ : st) {
    accumulate_moments(b, s.depth(), s.k, labels, s.num_cand, m.data(), bb.data());
    benchmark::DoNotOptimize(m.data());
  }
})
EDGEPLANE_STAGE_BENCH(validation, {
  std::vector<char> keep(static_cast<std::size_t>(s.num_cand));
  for (auto _ : st) {
    for (std::int32_t c = 1; c <= s.num_cand; ++c) {
      const plane_fit f = fit_plane(s.moments.data() + static_cast<std::size_t>(c) * moment_slots,
                                    s.bbox.data() + static_cast<std::size_t>(c) * 4);
      keep[static_cast<std::size_t>(c - 1)] = is_plane(f, s.p) ? 1 : 0;
    }
    benchmark::DoNotOptimize(keep.data());
  }
  st.counters["candidates"] = s.num_cand;
})
EDGEPLANE_STAGE_BENCH(merging, {
  std::vector<int> group, scratch;
  for (auto _ : st) {
    merge_groups(s.fits, s.keep, s.p, group, scratch);
    benchmark::DoNotOptimize(group.data());
  }
  st.counters["candidates"] = s.num_cand;
})

// ---- the whole pipeline ---------------------------------------------------------------------------
void pipeline(benchmark::State& st, const char* preset_name) {
  const int w = static_cast<int>(st.range(0)), h = static_cast<int>(st.range(1));
  const frame& f = scene_at(w, h);
  segmenter<cpu> seg(preset(preset_name));
  std::vector<std::uint16_t> labels(f.mm.size());
  segmentation_result res;
  edgeplane::bench::stage_sums stages;
  for (auto _ : st) {
    seg.segment(make_view(f.mm.data(), w, h), 0.001f, f.r.k, make_view(labels.data(), w, h), res);
    benchmark::DoNotOptimize(labels.data());
    stages.add(res.times);
  }
  per_pixel_counters(st, w, h);
  st.counters["planes"] = static_cast<double>(res.planes.size());
  stages.report(st);  // the mean of each stage (ms), from the segmenter's own stage_times
}

// ---- throughput over a sequence ---------------------------------------------------------------------
const std::vector<std::vector<std::uint16_t>>& sequence_at(int w, int h, intrinsics& k) {
  static std::vector<std::pair<int, std::vector<std::vector<std::uint16_t>>>> cache;
  k = test::kinect2_intrinsics(w, h);
  for (const auto& [key, seq] : cache)
    if (key == w * 100000 + h) return seq;
  std::vector<std::vector<std::uint16_t>> seq;
  const auto scene = test::room_with_box();
  for (int i = 0; i < 24; ++i) {  // the camera walks and turns a little from frame to frame
    const double a = 0.02 * i;
    const auto pose = test::look_at({0.05 * i, -1.2 + 0.02 * i, 1.3}, {2.6 * std::cos(a), 0.9 + 2.6 * std::sin(a), 0.4});
    seq.push_back(test::render(scene, pose, w, h, k, {0.0015, 0.0005, 0.02, static_cast<std::uint64_t>(7 + i)}).depth_mm());
  }
  cache.emplace_back(w * 100000 + h, std::move(seq));
  return cache.back().second;
}

void sequence(benchmark::State& st, const char* preset_name) {
  const int w = static_cast<int>(st.range(0)), h = static_cast<int>(st.range(1));
  intrinsics k;
  const auto& seq = sequence_at(w, h, k);
  segmenter<cpu> seg(preset(preset_name));
  std::vector<std::uint16_t> labels(static_cast<std::size_t>(w) * h);
  segmentation_result res;
  for (auto _ : st)
    for (const auto& frame_mm : seq) {
      seg.segment(make_view(frame_mm.data(), w, h), 0.001f, k, make_view(labels.data(), w, h), res);
      benchmark::DoNotOptimize(labels.data());
    }
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  st.counters["frames_per_second"] =
      benchmark::Counter(static_cast<double>(seq.size()), benchmark::Counter::kIsIterationInvariantRate);
  st.counters["scratch_MiB"] = static_cast<double>(seg.scratch_bytes()) / (1024.0 * 1024.0);
  st.counters["peak_rss_MiB"] = static_cast<double>(ru.ru_maxrss) / 1024.0;
}

// The same sequence through an edgeplane::pipeline: `lanes` segmenters side by side, each on its
// own thread (serial: a whole frame per core; parallel: every lane's kernels on TBB too), frames
// submitted while there is room and retrieved in order.  Frames per second against `sequence`
// above is the gain of frame-level parallelism.
void sequence_pipelined(benchmark::State& st, const char* preset_name, bool serial_lanes) {
  const int w = static_cast<int>(st.range(0)), h = static_cast<int>(st.range(1));
  const int lanes = static_cast<int>(st.range(2));
  intrinsics k;
  const auto& seq = sequence_at(w, h, k);
  edgeplane::pipeline<cpu> pl(preset(preset_name), lanes, cpu{serial_lanes ? cpu::mode::serial : cpu::mode::parallel});
  std::vector<std::uint16_t> labels(static_cast<std::size_t>(w) * h);
  segmentation_result res;
  for (auto _ : st) {
    for (const auto& frame_mm : seq) {
      if (pl.full()) pl.retrieve(make_view(labels.data(), w, h), res);
      pl.submit(make_view(frame_mm.data(), w, h), 0.001f, k);
    }
    while (pl.in_flight() > 0) pl.retrieve(make_view(labels.data(), w, h), res);
    benchmark::DoNotOptimize(labels.data());
  }
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  st.counters["frames_per_second"] =
      benchmark::Counter(static_cast<double>(seq.size()), benchmark::Counter::kIsIterationInvariantRate);
  st.counters["peak_rss_MiB"] = static_cast<double>(ru.ru_maxrss) / 1024.0;
}

#define EDGEPLANE_SIZES Args({256, 212})->Args({512, 424})->Args({640, 480})->Unit(benchmark::kMillisecond)->UseRealTime()
BENCHMARK(convert)->EDGEPLANE_SIZES;
BENCHMARK(depth_closing)->EDGEPLANE_SIZES;
BENCHMARK(smoothing)->EDGEPLANE_SIZES;
BENCHMARK(edge_jump)->EDGEPLANE_SIZES;
BENCHMARK(edge_extrema)->EDGEPLANE_SIZES;
BENCHMARK(edge_corner)->EDGEPLANE_SIZES;
BENCHMARK(edge_curved)->EDGEPLANE_SIZES;
BENCHMARK(edges_fused)->EDGEPLANE_SIZES;
BENCHMARK(edge_closing)->EDGEPLANE_SIZES;
BENCHMARK(segments)->EDGEPLANE_SIZES;
BENCHMARK(union_find)->EDGEPLANE_SIZES;
BENCHMARK(moments)->EDGEPLANE_SIZES;
BENCHMARK(validation)->EDGEPLANE_SIZES;
BENCHMARK(merging)->EDGEPLANE_SIZES;
BENCHMARK_CAPTURE(pipeline, thesis_full, "thesis_full")->EDGEPLANE_SIZES;
BENCHMARK_CAPTURE(pipeline, thesis_half, "thesis_half")->EDGEPLANE_SIZES;
BENCHMARK_CAPTURE(pipeline, kinect2, "kinect2")->EDGEPLANE_SIZES;
BENCHMARK_CAPTURE(sequence, thesis_full, "thesis_full")->EDGEPLANE_SIZES;
#define EDGEPLANE_LANES(n) Args({256, 212, n})->Args({512, 424, n})->Args({640, 480, n})->Unit(benchmark::kMillisecond)->UseRealTime()
BENCHMARK_CAPTURE(sequence_pipelined, thesis_full_serial_lanes, "thesis_full", true)->EDGEPLANE_LANES(2);
BENCHMARK_CAPTURE(sequence_pipelined, thesis_full_parallel_lanes, "thesis_full", false)->EDGEPLANE_LANES(2);
}  // namespace

BENCHMARK_MAIN();
