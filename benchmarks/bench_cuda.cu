// CUDA benchmarks: the whole pipeline (segmenter<cuda>, host depth in, host labels out, as an
// application calls it) and the fused edge pass alone, on the room scene of bench_cpu.cpp (a box on
// the floor in a room corner, Kinect-v2-like noise and 2 % pepper holes) at 256x212, 512x424 and
// 640x480 (the edge pass also at 4096x3392, with a device-to-device copy of as many bytes as its
// floor).  Manual timing: the pipeline's segment() returns only when its labels are on the host
// (it synchronizes), so a host clock around it is honest; the edge pass and the copy are timed
// with CUDA events on the stream.  Without a CUDA device the program says so and exits 0 without
// running anything.
#include <benchmark/benchmark.h>

#include <chrono>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "edgeplane/edgeplane.cuh"
#include "bench_counters.hpp"
#include "bench_frames.hpp"

namespace {
namespace ep = edgeplane;

using edgeplane::bench::frame;
using edgeplane::bench::scene_at;

/// A stream and two events owned by one benchmark run.
struct cuda_timing {
  cudaStream_t stream = nullptr;
  cudaEvent_t start = nullptr, stop = nullptr;
  cuda_timing() {
    ep::detail::cuda_check(cudaStreamCreateWithFlags(&stream, cudaStreamNonBlocking), "cudaStreamCreate");
    ep::detail::cuda_check(cudaEventCreate(&start), "cudaEventCreate");
    ep::detail::cuda_check(cudaEventCreate(&stop), "cudaEventCreate");
  }
  ~cuda_timing() {
    (void)cudaEventDestroy(start);
    (void)cudaEventDestroy(stop);
    (void)cudaStreamDestroy(stream);
  }
  cuda_timing(const cuda_timing&) = delete;
  cuda_timing& operator=(const cuda_timing&) = delete;
};

/// segment() of one uint16 frame in host memory into host labels, synchronous; the first call
/// (scratch allocation, module load) is a warm-up outside the timing.  Counters: the mean of each
/// stage of edgeplane::stage_times over the timed iterations (ms).
void pipeline(benchmark::State& st, const char* preset_name) {
  const int w = static_cast<int>(st.range(0)), h = static_cast<int>(st.range(1));
  const frame& f = scene_at(w, h);
  cuda_timing t;
  ep::segmenter<ep::cuda> seg(ep::preset(preset_name), ep::cuda{t.stream});
  std::vector<std::uint16_t> labels(f.mm.size());
  ep::segmentation_result res;
  const auto depth = ep::make_view(f.mm.data(), w, h);
  const auto out = ep::make_view(labels.data(), w, h);
  seg.segment(depth, 0.001f, f.r.k, out, res);  // warm-up
  ep::bench::stage_sums stages;
  for (auto _ : st) {
    const auto t0 = std::chrono::steady_clock::now();
    seg.segment(depth, 0.001f, f.r.k, out, res);
    const auto t1 = std::chrono::steady_clock::now();
    st.SetIterationTime(std::chrono::duration<double>(t1 - t0).count());
    benchmark::DoNotOptimize(labels.data());
    stages.add(res.times);
  }
  ep::bench::per_pixel_counters(st, w, h);
  st.counters["planes"] = static_cast<double>(res.planes.size());
  stages.report(st);
}

/// The fused edge pass (four directions, all edge types) on device-resident depth, timed with CUDA
/// events around the launch on the benchmark's stream.
void edges_fused(benchmark::State& st) {
  const int w = static_cast<int>(st.range(0)), h = static_cast<int>(st.range(1));
  const frame& f = scene_at(w, h);
  cuda_timing t;
  const ep::cuda b{t.stream};
  ep::buffer<float, ep::cuda> z(b);
  ep::buffer<std::uint8_t, ep::cuda> edges(b);
  z.resize(f.r.depth.size());
  edges.resize(f.r.depth.size());
  b.copy_from_host(z.data(), f.r.depth.data(), f.r.depth.size() * sizeof(float));
  const ep::params p = ep::presets::thesis_full();
  const auto zv = ep::make_view<const float>(z.data(), w, h);
  const auto ev = ep::make_view(edges.data(), w, h);
  ep::detect_edges(b, zv, f.r.k, p, ev);  // warm-up
  b.synchronize();
  for (auto _ : st) {
    ep::detail::cuda_check(cudaEventRecord(t.start, t.stream), "cudaEventRecord");
    ep::detect_edges(b, zv, f.r.k, p, ev);
    ep::detail::cuda_check(cudaEventRecord(t.stop, t.stream), "cudaEventRecord");
    ep::detail::cuda_check(cudaEventSynchronize(t.stop), "cudaEventSynchronize");
    float ms = 0.f;
    ep::detail::cuda_check(cudaEventElapsedTime(&ms, t.start, t.stop), "cudaEventElapsedTime");
    st.SetIterationTime(ms / 1000.0);
  }
  ep::bench::per_pixel_counters(st, w, h);
  // the bytes the pass must move at least: each depth value read once, each edge byte written once
  st.counters["bytes_per_second"] = benchmark::Counter(5.0 * w * h, benchmark::Counter::kIsIterationInvariantRate);
}

/// The floor for edges_fused: a device-to-device copy of 2.5 bytes per pixel, which reads and
/// writes as many bytes (5 per pixel) as the edge pass must, timed the same way.
void device_copy(benchmark::State& st) {
  const std::int64_t n = st.range(0) * st.range(1);
  cuda_timing t;
  const ep::cuda b{t.stream};
  const std::size_t bytes = static_cast<std::size_t>(n) * 5 / 2;
  ep::buffer<std::uint8_t, ep::cuda> src(b), dst(b);
  src.resize(bytes);
  dst.resize(bytes);
  b.memset(src.data(), 7, bytes);
  b.copy(dst.data(), src.data(), bytes);  // warm-up
  b.synchronize();
  for (auto _ : st) {
    ep::detail::cuda_check(cudaEventRecord(t.start, t.stream), "cudaEventRecord");
    b.copy(dst.data(), src.data(), bytes);
    ep::detail::cuda_check(cudaEventRecord(t.stop, t.stream), "cudaEventRecord");
    ep::detail::cuda_check(cudaEventSynchronize(t.stop), "cudaEventSynchronize");
    float ms = 0.f;
    ep::detail::cuda_check(cudaEventElapsedTime(&ms, t.start, t.stop), "cudaEventElapsedTime");
    st.SetIterationTime(ms / 1000.0);
  }
  st.counters["bytes_per_second"] = benchmark::Counter(2.0 * static_cast<double>(bytes),
                                                       benchmark::Counter::kIsIterationInvariantRate);
}

#define EDGEPLANE_SIZES Args({256, 212})->Args({512, 424})->Args({640, 480})
BENCHMARK_CAPTURE(pipeline, thesis_full, "thesis_full")->EDGEPLANE_SIZES->Unit(benchmark::kMillisecond)->UseManualTime();
BENCHMARK_CAPTURE(pipeline, thesis_half, "thesis_half")->EDGEPLANE_SIZES->Unit(benchmark::kMillisecond)->UseManualTime();
BENCHMARK_CAPTURE(pipeline, kinect2, "kinect2")->EDGEPLANE_SIZES->Unit(benchmark::kMillisecond)->UseManualTime();
// 4096x3392 (8x a Kinect v2 frame each way): the edge pass and its copy floor where the launch
// overhead (a few microseconds) no longer hides the memory traffic.
BENCHMARK(edges_fused)->EDGEPLANE_SIZES->Args({4096, 3392})->Unit(benchmark::kMillisecond)->UseManualTime();
BENCHMARK(device_copy)->EDGEPLANE_SIZES->Args({4096, 3392})->Unit(benchmark::kMillisecond)->UseManualTime();
}  // namespace

int main(int argc, char** argv) {
  int devices = 0;
  const cudaError_t e = cudaGetDeviceCount(&devices);
  if (e != cudaSuccess || devices == 0) {
    (void)cudaGetLastError();
    std::printf("edgeplane_bench_cuda: no CUDA device (%s); nothing to benchmark\n",
                e != cudaSuccess ? cudaGetErrorName(e) : "0 devices");
    return 0;
  }
  cudaDeviceProp prop{};
  if (cudaGetDeviceProperties(&prop, 0) == cudaSuccess) {
    benchmark::AddCustomContext("cuda_device", prop.name);
    benchmark::AddCustomContext("cuda_sm", std::to_string(prop.major) + std::to_string(prop.minor));
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
