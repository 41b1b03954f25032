// Tests of include/edgeplane/backend/cuda.cuh: the CUDA backend's memory calls and scan, and every
// stage of the pipeline on CUDA against the CPU backend on the same input: union-find on random
// pairs, the depth filters, edges, line segments, candidates and moments kernels (identical
// outputs), and the whole segmenter (labels equal up to renumbering, planes within float
// tolerance) on the synthetic scenes of tests/support/scenes.hpp.  The comparisons are
// tests/support/backend_equivalence.hpp, which tests/pipeline/test_device_path.cpp also runs
// (compiled by g++) on the device code paths without a GPU.
//
// Compiled by nvcc with --fmad=false (see tests/CMakeLists.txt): with fused multiply-adds off,
// device float arithmetic is IEEE-exact like the host's (+ - * / and sqrtf round to nearest), so
// the two backends must agree bit for bit; moments are integer sums, exact in any order.
//
// Exit status 77 (CTest: skipped) when the machine has no CUDA device or no driver, unless
// EDGEPLANE_REQUIRE_CUDA=1 is set (then it fails: for GPU CI, where a skip would hide a problem).
#define DOCTEST_CONFIG_IMPLEMENT
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <numeric>
#include <string>
#include <vector>

#include "edgeplane/edgeplane.cuh"
#include "support/backend_equivalence.hpp"
#include "support/test_backends.hpp"

// No `using namespace edgeplane`: with CCCL's ::cuda namespace in scope, an unqualified `cuda`
// would be ambiguous.
namespace ep = edgeplane;
using edgeplane_test::device_array;
namespace eq = edgeplane_test::equivalence;
using eq::mask_active;

TYPE_TO_STRING(edgeplane::cuda);

namespace {

// ---- small helpers ------------------------------------------------------------------------------

/// A CUDA stream owned by the test (the backend never owns its stream).
struct owned_stream {
  cudaStream_t s = nullptr;
  owned_stream() { ep::detail::cuda_check(cudaStreamCreateWithFlags(&s, cudaStreamNonBlocking), "cudaStreamCreate"); }
  ~owned_stream() { (void)cudaStreamDestroy(s); }
  owned_stream(const owned_stream&) = delete;
  owned_stream& operator=(const owned_stream&) = delete;
};

/// out[i] = 3 i + 1.
struct affine_kernel {
  std::int64_t* out;
  EDGEPLANE_HD void operator()(std::int64_t i) const { out[i] = 3 * i + 1; }
};

}  // namespace

// ---- the backend's own calls ----------------------------------------------------------------------

TEST_CASE("cuda backend: copies, memset, for_each_index and synchronize") {
  const ep::cuda b{};
  std::vector<std::int32_t> host(10007);
  std::iota(host.begin(), host.end(), -500);
  device_array<std::int32_t, ep::cuda> a(b, host), c(b, host.size(), 0);
  b.copy(c.data(), a.data(), host.size() * sizeof(std::int32_t));
  CHECK(c.host() == host);
  b.memset(c.data() + 10, 0xff, 5 * sizeof(std::int32_t));
  std::vector<std::int32_t> want = host;
  std::fill_n(want.begin() + 10, 5, -1);
  CHECK(c.host() == want);
  // zero-byte calls are no-ops (even on null pointers)
  b.copy(nullptr, nullptr, 0);
  b.memset(nullptr, 0, 0);
  b.copy_from_host(nullptr, nullptr, 0);
  b.copy_to_host(nullptr, nullptr, 0);

  // more elements than one grid of 2^21 threads, and n = 0 launching nothing
  const std::int64_t n = (std::int64_t(1) << 22) + 3;
  device_array<std::int64_t, ep::cuda> out(b, static_cast<std::size_t>(n), -1);
  b.for_each_index(0, affine_kernel{nullptr});
  b.for_each_index(n, affine_kernel{out.data()});
  b.synchronize();
  const auto got = out.host();
  long long bad = 0;
  for (std::int64_t i = 0; i < n; ++i) bad += got[static_cast<std::size_t>(i)] != 3 * i + 1;
  CHECK(bad == 0);
}

TEST_CASE("cuda backend: inclusive_scan equals std::inclusive_scan, also in place and on a stream") {
  edgeplane_test::lcg_noise rng(5);
  owned_stream s;
  for (const ep::cuda b : {ep::cuda{}, ep::cuda{s.s}})
    for (const std::int64_t n : {std::int64_t(1), std::int64_t(7), std::int64_t(4096), std::int64_t(1) << 20,
                                 (std::int64_t(1) << 21) + 77}) {
      CAPTURE(n);
      std::vector<std::int32_t> flags(static_cast<std::size_t>(n));
      for (auto& f : flags) f = static_cast<std::int32_t>(rng.next_u32(3)) - 1;  // -1, 0, 1
      std::vector<std::int32_t> want(flags.size());
      std::inclusive_scan(flags.begin(), flags.end(), want.begin());
      device_array<std::int32_t, ep::cuda> in(b, flags), out(b, flags.size(), 0);
      b.inclusive_scan(in.data(), n, out.data());
      CHECK(out.host() == want);
      b.inclusive_scan(in.data(), n, in.data());
      CHECK(in.host() == want);
      std::vector<std::int64_t> big(flags.size(), std::int64_t(1) << 33), big_want(flags.size());
      std::inclusive_scan(big.begin(), big.end(), big_want.begin());
      device_array<std::int64_t, ep::cuda> bin(b, big);
      b.inclusive_scan(bin.data(), n, bin.data());
      CHECK(bin.host() == big_want);
    }
}

TEST_CASE("cuda backend: a failed call throws backend_error naming the CUDA error, and the backend goes on") {
  const ep::cuda b{};
  std::string what;
  try {
    void* p = b.allocate(std::size_t(1) << 60);  // 1 EiB
    b.deallocate(p);
  } catch (const ep::backend_error& e) {
    what = e.what();
  }
  CAPTURE(what);
  CHECK(what.find("cudaErrorMemoryAllocation") != std::string::npos);
  CHECK(what.find("cudaMalloc") != std::string::npos);
  // the failure was not sticky and was cleared: launches and copies still work
  device_array<std::int64_t, ep::cuda> out(b, 1000, 0);
  b.for_each_index(1000, affine_kernel{out.data()});
  b.synchronize();
  CHECK(out.host()[999] == 2998);
  b.deallocate(nullptr);
}

// ---- union-find ------------------------------------------------------------------------------------

TEST_CASE("cuda union-find: random pairs give the CPU's parent array (roots are component minima)") {
  eq::check_union_find_matches_cpu(ep::cuda{});
}

TEST_CASE("cuda union-find: under contention (every pair names one hub) the result is the CPU's") {
  const int n = 1 << 18;
  std::vector<std::int32_t> a, b;
  for (int i = 0; i < n; ++i) {
    a.push_back(n / 2);
    b.push_back(n - 1 - i);
  }
  const std::vector<std::uint8_t> on(static_cast<std::size_t>(n), 1);
  const ep::cuda g{};
  device_array<std::uint8_t, ep::cuda> act(g, on);
  device_array<std::int32_t, ep::cuda> fa(g, a), fb(g, b), parent(g, static_cast<std::size_t>(n), -7);
  ep::connected_components(g, n, mask_active{act.data()}, n, ep::detail::pair_list_adjacency{fa.data(), fb.data()},
                           parent.data());
  CHECK(parent.host() == std::vector<std::int32_t>(static_cast<std::size_t>(n), 0));
}

// ---- the kernels of every stage ----------------------------------------------------------------------

TEST_CASE("cuda kernels: filters, edges, segments, candidates and moments are identical to the CPU's") {
  eq::check_kernels_match_cpu(ep::cuda{});
}

TEST_CASE("cuda kernels: the final-label kernels (sweeps, growth, closing) are identical to the CPU's") {
  eq::check_label_kernels_match_cpu(ep::cuda{});
}

// ---- the whole segmenter ---------------------------------------------------------------------------------

TEST_CASE("cuda segmenter: labels and planes equal the CPU segmenter's on the test scenes") {
  eq::check_segmenter_matches_cpu(ep::cuda{});
}

TEST_CASE("cuda segmenter: float depth, pitched rows, half resolution with odd sizes, and a stream") {
  owned_stream s;
  eq::check_segmenter_inputs_match_cpu(ep::cuda{s.s});
}

TEST_CASE("cuda pipeline: frames in flight on three streams give the CPU segmenter's results in order") {
  owned_stream s1, s2, s3;
  eq::check_pipeline_matches_cpu(std::vector<ep::cuda>{ep::cuda{s1.s}, ep::cuda{s2.s}, ep::cuda{s3.s}});
}

// ---- main: skip (77) without a device ------------------------------------------------------------------------

int main(int argc, char** argv) {
  int devices = 0;
  const cudaError_t e = cudaGetDeviceCount(&devices);
  const char* req = std::getenv("EDGEPLANE_REQUIRE_CUDA");
  const bool required = req != nullptr && std::string(req) != "" && std::string(req) != "0";
  if (e == cudaErrorNoDevice || e == cudaErrorInsufficientDriver || (e == cudaSuccess && devices == 0)) {
    (void)cudaGetLastError();
    std::printf("edgeplane_tests_cuda: no CUDA device (%s): %s\n",
                e == cudaSuccess ? "0 devices" : cudaGetErrorName(e),
                required ? "FAILED (EDGEPLANE_REQUIRE_CUDA is set)" : "skipped");
    return required ? 1 : 77;
  }
  if (e != cudaSuccess) {  // a device is there but unusable: a failure, not a skip
    std::printf("edgeplane_tests_cuda: cudaGetDeviceCount failed: %s: %s\n", cudaGetErrorName(e),
                cudaGetErrorString(e));
    return 1;
  }
  cudaDeviceProp prop{};
  if (cudaGetDeviceProperties(&prop, 0) == cudaSuccess)
    std::printf("edgeplane_tests_cuda: device 0: %s (sm_%d%d)\n", prop.name, prop.major, prop.minor);
  doctest::Context ctx(argc, argv);
  return ctx.run();
}
