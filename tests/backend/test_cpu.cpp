// The CPU backend's for_each_index must call f(i) exactly once for every i in [0, n), in both of
// its parallel paths: TBB's own partitioning, and contiguous chunks for kernels that declare
// even_work (detail::even_work_v).  Counts below, at and above the parallel threshold, around the
// number of chunks (cpu::chunks_per_thread per hardware thread) and far above it.
#include <doctest/doctest.h>

#include <atomic>
#include <cstdint>
#include <memory>
#include <vector>

#include "edgeplane/backend/cpu.hpp"

using namespace edgeplane;

namespace {

struct uneven_kernel {
  std::atomic<int>* hits;
  void operator()(std::int64_t i) const { hits[i].fetch_add(1, std::memory_order_relaxed); }
};

struct even_kernel {
  static constexpr bool even_work = true;
  std::atomic<int>* hits;
  void operator()(std::int64_t i) const { hits[i].fetch_add(1, std::memory_order_relaxed); }
};

struct even_false_kernel {
  static constexpr bool even_work = false;
  void operator()(std::int64_t) const {}
};

static_assert(!detail::even_work_v<uneven_kernel>);
static_assert(detail::even_work_v<even_kernel>);
static_assert(!detail::even_work_v<even_false_kernel>);
static_assert(detail::even_work_v<detail::pixel_rows<even_kernel>>);
static_assert(!detail::even_work_v<detail::pixel_rows<uneven_kernel>>);

// Whether b.for_each_index(n, K{hits}) touched every index exactly once.
template <class K>
bool each_once(const cpu& b, std::int64_t n) {
  const auto hits = std::make_unique<std::atomic<int>[]>(static_cast<std::size_t>(n) + 1);
  for (std::int64_t i = 0; i <= n; ++i) hits[i] = 0;
  b.for_each_index(n, K{hits.get()});
  for (std::int64_t i = 0; i < n; ++i)
    if (hits[i].load() != 1) return false;
  return hits[n].load() == 0;  // nothing past the end
}

}  // namespace

TEST_CASE("cpu::for_each_index: every index exactly once, chunked or not, serial or parallel") {
  const std::int64_t k = cpu::chunks_per_thread * cpu::hardware_threads();
  CHECK(cpu::hardware_threads() >= 1);
  std::vector<std::int64_t> counts = {1, 2, 63, 64, 65, 100, 424, 1000, 4099, 100003};
  for (const std::int64_t d : {-1, 0, 1}) counts.push_back(std::max<std::int64_t>(1, k + d));
  for (const auto m : {cpu::mode::parallel, cpu::mode::serial}) {
    const cpu b{m};
    for (const std::int64_t n : counts) {
      CAPTURE(n);
      CHECK(each_once<even_kernel>(b, n));
      CHECK(each_once<uneven_kernel>(b, n));
    }
  }
  // n <= 0 calls nothing.
  cpu{}.for_each_index(0, even_kernel{nullptr});
  cpu{}.for_each_index(-5, uneven_kernel{nullptr});
}
