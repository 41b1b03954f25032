// edgeplane against a peer segmenter, side by side in one run on the same frames (bench_pcl.cpp,
// bench_cape.cpp): the room scene of bench_cpu.cpp at the sizes asked for and, when built with
// OpenCV, the three real 640x480 sample frames of examples/data (TUM RGB-D, ICL-NUIM, CAPE).
//
// Each iteration of `ratio` runs the peer once and edgeplane once (uint16 depth in; the peer's
// time includes building its own point cloud from the depth image, as its user must) and times
// each with a steady clock; the counters are the medians of those times and their ratio (peer /
// edgeplane: how many times faster edgeplane is).  edgeplane runs its `thesis_full` preset on
// both cores (`cpu`) and on one (`cpu_serial`), and the thesis's half-scale preset `thesis_half`
// (2x downscale) on both cores (`cpu_half`: the targets are for full scale; this row says
// what half scale buys).
#pragma once
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#ifdef EDGEPLANE_BENCH_WITH_OPENCV
#include <opencv2/imgcodecs.hpp>
#endif

#include "bench_frames.hpp"
#include "edgeplane/edgeplane.hpp"

namespace edgeplane::bench {

struct depth_frame {
  int w = 0, h = 0;
  intrinsics k;
  float scale = 0.001f;  // metres per unit
  std::vector<std::uint16_t> depth;
};

inline depth_frame room(int w, int h) {
  const auto& f = scene_at(w, h);
  return {w, h, f.r.k, 0.001f, f.mm};
}

inline double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

/// edgeplane set up on a frame, warmed up by one segmentation: run() segments it again.
struct edgeplane_on_frame {
  segmenter<cpu> seg;
  std::vector<std::uint16_t> labels;
  segmentation_result res;
  image_view<const std::uint16_t> depth;
  image_view<std::uint16_t> out;
  float scale;
  intrinsics k;
  edgeplane_on_frame(const depth_frame& f, cpu backend, const params& preset)
      : seg(preset, backend),
        labels(f.depth.size()),
        depth(make_view(f.depth.data(), f.w, f.h)),
        out(make_view(labels.data(), f.w, f.h)),
        scale(f.scale),
        k(f.k) {
    run();
  }
  void run() {
    seg.segment(depth, scale, k, out, res);
    benchmark::DoNotOptimize(labels.data());
  }
};

/// One benchmark of `Peer` (a default-constructible class with PCL's and CAPE's peers' `run`)
/// against edgeplane; counters `<peer>_ms`, `edgeplane_ms`, `<peer>_over_edgeplane` and both plane
/// counts.
template <class Peer>
void ratio(benchmark::State& st, const std::string& peer, depth_frame f, cpu backend, const params& preset) {
  Peer peer_seg;
  edgeplane_on_frame ep(f, backend, preset);
  std::size_t peer_planes = peer_seg.run(f.depth.data(), f.w, f.h, f.w, f.scale, f.k);  // warm-up
  std::vector<double> t_peer, t_ep;
  using clock = std::chrono::steady_clock;
  for (auto _ : st) {
    const auto t0 = clock::now();
    peer_planes = peer_seg.run(f.depth.data(), f.w, f.h, f.w, f.scale, f.k);
    const auto t1 = clock::now();
    ep.run();
    const auto t2 = clock::now();
    t_peer.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
    t_ep.push_back(std::chrono::duration<double, std::milli>(t2 - t1).count());
    st.SetIterationTime(std::chrono::duration<double>(t2 - t0).count());
  }
  const double mp = median(t_peer), me = median(t_ep);
  st.counters[peer + "_ms"] = mp;
  st.counters["edgeplane_ms"] = me;
  st.counters[peer + "_over_edgeplane"] = me > 0 ? mp / me : 0.0;
  st.counters[peer + "_planes"] = static_cast<double>(peer_planes);
  st.counters["edgeplane_planes"] = static_cast<double>(ep.res.planes.size());
}

/// One segmenter alone on a frame, warm (no other segmenter between its frames): `solo` rows.
/// Run with --benchmark_enable_random_interleaving=true and repetitions, so that the rows of one
/// frame are measured in alternation.
template <class Peer>
void solo_peer(benchmark::State& st, depth_frame f) {
  Peer peer_seg;
  std::size_t planes = peer_seg.run(f.depth.data(), f.w, f.h, f.w, f.scale, f.k);
  for (auto _ : st) planes = peer_seg.run(f.depth.data(), f.w, f.h, f.w, f.scale, f.k);
  st.counters["planes"] = static_cast<double>(planes);
}
inline void solo_edgeplane(benchmark::State& st, depth_frame f, cpu backend, const params& preset) {
  edgeplane_on_frame ep(f, backend, preset);
  for (auto _ : st) ep.run();
  st.counters["planes"] = static_cast<double>(ep.res.planes.size());
}

/// Registers ratio<Peer> as `ratio/<frame>/<edgeplane configuration>`, and each segmenter alone
/// as `solo/<frame>/<peer or edgeplane configuration>`, for the room scene at each of `sizes` and
/// the sample frames.
template <class Peer>
void register_ratios(const std::string& peer, const std::vector<std::pair<int, int>>& sizes) {
  const cpu both{cpu::mode::parallel}, one{cpu::mode::serial};
  std::vector<std::pair<std::string, depth_frame>> frames;
  for (auto [w, h] : sizes) frames.emplace_back("room/" + std::to_string(w) + "x" + std::to_string(h), room(w, h));
#ifdef EDGEPLANE_BENCH_WITH_OPENCV
  struct sample {
    const char* name;
    const char* file;
    intrinsics k;
    float scale;
  };
  const sample samples[] = {
      {"tum", "tum_fr3_long_office.png", {535.4f, 539.2f, 320.1f, 247.6f}, 0.0002f},
      {"icl", "icl_living_room.png", {481.2f, -480.0f, 319.5f, 239.5f}, 0.0002f},
      {"cape", "cape_depth_0.png", {575.9268544880447f, 576.4079160109325f, 315.1502635638817f, 230.58580662101753f},
       0.001f}};
  for (const sample& s : samples) {
    const cv::Mat m = cv::imread(std::string(EDGEPLANE_BENCH_DATA_DIR) + "/" + s.file, cv::IMREAD_UNCHANGED);
    if (m.empty() || m.type() != CV_16UC1) continue;
    depth_frame f{m.cols, m.rows, s.k, s.scale, {}};
    f.depth.assign(m.ptr<std::uint16_t>(0), m.ptr<std::uint16_t>(0) + m.total());
    frames.emplace_back(std::string("sample/") + s.name, std::move(f));
  }
#endif
  const params full = presets::thesis_full(), half = presets::thesis_half();
  for (const auto& [name, f] : frames) {
    benchmark::RegisterBenchmark(("solo/" + name + "/" + peer).c_str(), solo_peer<Peer>, f)
        ->Unit(benchmark::kMillisecond)->MinTime(1.0);
    benchmark::RegisterBenchmark(("solo/" + name + "/cpu").c_str(), solo_edgeplane, f, both, full)
        ->Unit(benchmark::kMillisecond)->MinTime(1.0);
    benchmark::RegisterBenchmark(("solo/" + name + "/cpu_serial").c_str(), solo_edgeplane, f, one, full)
        ->Unit(benchmark::kMillisecond)->MinTime(1.0);
    benchmark::RegisterBenchmark(("solo/" + name + "/cpu_half").c_str(), solo_edgeplane, f, both, half)
        ->Unit(benchmark::kMillisecond)->MinTime(1.0);
    benchmark::RegisterBenchmark(("ratio/" + name + "/cpu").c_str(), ratio<Peer>, peer, f, both, full)
        ->UseManualTime()->Unit(benchmark::kMillisecond)->MinTime(1.0);
    benchmark::RegisterBenchmark(("ratio/" + name + "/cpu_serial").c_str(), ratio<Peer>, peer, f, one, full)
        ->UseManualTime()->Unit(benchmark::kMillisecond)->MinTime(1.0);
    benchmark::RegisterBenchmark(("ratio/" + name + "/cpu_half").c_str(), ratio<Peer>, peer, f, both, half)
        ->UseManualTime()->Unit(benchmark::kMillisecond)->MinTime(1.0);
  }
}

inline int run_benchmarks(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}

}  // namespace edgeplane::bench
