// edgeplane against PCL's OrganizedMultiPlaneSegmentation (with its IntegralImageNormalEstimation
// normals), side by side in one run on the same frames: the room scene of bench_cpu.cpp at
// 256x212, 512x424 and 640x480 and, when built with OpenCV, the three real sample frames of
// examples/data (TUM RGB-D, ICL-NUIM, CAPE; 640x480).  Built only when PCL is found.
//
// Each iteration of `ratio` runs PCL once and edgeplane once (uint16 depth in; PCL's time includes
// building its organized point cloud, as a PCL user must) and times each with a steady clock; the
// counters are the medians of those times and their ratio (PCL / edgeplane: how many times
// faster edgeplane is).  edgeplane runs its `thesis_full` preset on both cores (`cpu`) and on one
// (`cpu serial`), and the thesis's half-scale preset `thesis_half` (2x downscale) on both cores
// (`cpu_half`: the targets are for full scale; this row says what half scale buys).  PCL
// runs the configuration of its organized segmentation demo: average 3-D gradient normals (max
// depth change 0.02, smoothing 10), 1000 minimum inliers, 3 degrees, 2 cm, with refinement.
// PCL's normal estimation and segmentation are single-threaded.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <vector>


#ifdef EDGEPLANE_BENCH_WITH_OPENCV
#include <opencv2/imgcodecs.hpp>
#endif

#include "bench_frames.hpp"
#include "edgeplane/edgeplane.hpp"
#include "pcl_peer.hpp"

namespace {
namespace ep = edgeplane;

struct depth_frame {
  int w = 0, h = 0;
  ep::intrinsics k;
  float scale = 0.001f;  // metres per unit
  std::vector<std::uint16_t> depth;
};

using edgeplane_peer::pcl_segmenter;

depth_frame room(int w, int h) {
  const auto& f = ep::bench::scene_at(w, h);
  return {w, h, f.r.k, 0.001f, f.mm};
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

void ratio(benchmark::State& st, depth_frame f, ep::cpu backend, const ep::params& preset) {
  pcl_segmenter pcl_seg;
  ep::segmenter<ep::cpu> seg(preset, backend);
  std::vector<std::uint16_t> labels(f.depth.size());
  ep::segmentation_result res;
  const auto depth = ep::make_view(static_cast<const std::uint16_t*>(f.depth.data()), f.w, f.h);
  const auto out = ep::make_view(labels.data(), f.w, f.h);
  std::size_t pcl_planes = pcl_seg.run(f.depth.data(), f.w, f.h, f.w, f.scale, f.k);  // warm-up of both
  seg.segment(depth, f.scale, f.k, out, res);
  std::vector<double> t_pcl, t_ep;
  using clock = std::chrono::steady_clock;
  for (auto _ : st) {
    const auto t0 = clock::now();
    pcl_planes = pcl_seg.run(f.depth.data(), f.w, f.h, f.w, f.scale, f.k);
    const auto t1 = clock::now();
    seg.segment(depth, f.scale, f.k, out, res);
    const auto t2 = clock::now();
    benchmark::DoNotOptimize(labels.data());
    t_pcl.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
    t_ep.push_back(std::chrono::duration<double, std::milli>(t2 - t1).count());
    st.SetIterationTime(std::chrono::duration<double>(t2 - t0).count());
  }
  const double mp = median(t_pcl), me = median(t_ep);
  st.counters["pcl_ms"] = mp;
  st.counters["edgeplane_ms"] = me;
  st.counters["pcl_over_edgeplane"] = me > 0 ? mp / me : 0.0;
  st.counters["pcl_planes"] = static_cast<double>(pcl_planes);
  st.counters["edgeplane_planes"] = static_cast<double>(res.planes.size());
}

void register_all() {
  const ep::cpu both{ep::cpu::mode::parallel}, one{ep::cpu::mode::serial};
  std::vector<std::pair<std::string, depth_frame>> frames;
  for (auto [w, h] : {std::pair{256, 212}, std::pair{512, 424}, std::pair{640, 480}})
    frames.emplace_back("room/" + std::to_string(w) + "x" + std::to_string(h), room(w, h));
#ifdef EDGEPLANE_BENCH_WITH_OPENCV
  struct sample {
    const char* name;
    const char* file;
    ep::intrinsics k;
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
  const ep::params full = ep::presets::thesis_full(), half = ep::presets::thesis_half();
  for (const auto& [name, f] : frames) {
    benchmark::RegisterBenchmark(("ratio/" + name + "/cpu").c_str(), ratio, f, both, full)
        ->UseManualTime()->Unit(benchmark::kMillisecond)->MinTime(1.0);
    benchmark::RegisterBenchmark(("ratio/" + name + "/cpu_serial").c_str(), ratio, f, one, full)
        ->UseManualTime()->Unit(benchmark::kMillisecond)->MinTime(1.0);
    benchmark::RegisterBenchmark(("ratio/" + name + "/cpu_half").c_str(), ratio, f, both, half)
        ->UseManualTime()->Unit(benchmark::kMillisecond)->MinTime(1.0);
  }
}
}  // namespace

int main(int argc, char** argv) {
  register_all();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
