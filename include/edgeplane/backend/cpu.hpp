// edgeplane: the CPU backend.  Runs named functors with std::execution parallel algorithms
// (TBB underneath in libstdc++; link TBB::tbb, which edgeplane::edgeplane does when TBB is found).
#pragma once
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <execution>
#include <new>
#include <numeric>
#include <thread>

#include "edgeplane/backend/counting_iterator.hpp"
#include "edgeplane/config.hpp"

namespace edgeplane {

/// CPU backend.  All memory it hands out is host memory; every call has finished when it returns.
struct cpu {
  /// Parallelism: `parallel` uses std::execution::par; `serial` runs on the calling thread (for
  /// determinism checks and for callers that run one segmenter per core).
  enum class mode { parallel, serial };
  mode execution = mode::parallel;

  static constexpr bool host_accessible = true;

  /// Calls f(i) for i in [0, n).  f may run concurrently on several threads; it must only use
  /// edgeplane's atomic helpers for shared writes.  Synchronous.
  ///
  /// A kernel whose items cost alike (detail::even_work_v) runs as chunks_per_thread contiguous
  /// chunks per hardware thread: TBB's default partitioning splits the range item by item on
  /// demand, which cost about 4 us per call on the 2-core VM against about 1 us for a few chunks,
  /// and gives neighbouring items (rows, blocks of diagonals) to different threads.
  template <class F>
  void for_each_index(std::int64_t n, F f) const {
    if (n <= 0) return;
    detail::counting_iterator first(0), last(n);
    if (execution == mode::serial || n < detail::host_parallel_items) {
      std::for_each(first, last, f);
    } else if constexpr (detail::even_work_v<F>) {
      const std::int64_t k = std::min<std::int64_t>(n, chunks_per_thread * hardware_threads());
      detail::counting_iterator c0(0), c1(k);
      std::for_each(std::execution::par, c0, c1, [n, k, &f](std::int64_t c) {
        for (std::int64_t i = n * c / k, e = n * (c + 1) / k; i < e; ++i) f(i);
      });
    } else {
      std::for_each(std::execution::par, first, last, f);
    }
  }

  /// Chunks per hardware thread for even_work kernels (a thread held up elsewhere then delays a
  /// quarter of its share, not all of it).
  static constexpr std::int64_t chunks_per_thread = 4;

  /// The machine's hardware threads (at least 1), read once.
  static std::int64_t hardware_threads() {
    static const std::int64_t t = std::max<std::int64_t>(1, std::thread::hardware_concurrency());
    return t;
  }

  /// out[i] = in[0] + ... + in[i] (inclusive prefix sum).  Host pointers.  Synchronous.
  template <class T>
  void inclusive_scan(const T* in, std::int64_t n, T* out) const {
    if (n <= 0) return;
    if (execution == mode::serial || n < 4096)
      std::inclusive_scan(in, in + n, out);
    else
      std::inclusive_scan(std::execution::par, in, in + n, out);
  }

  void synchronize() const {}

  void* allocate(std::size_t bytes) const { return ::operator new(bytes == 0 ? 1 : bytes, std::align_val_t{64}); }
  void deallocate(void* p) const noexcept { ::operator delete(p, std::align_val_t{64}); }
  /// Copies between backend memory and host memory (both host here).
  void copy_to_host(void* dst, const void* src, std::size_t bytes) const {
    if (bytes) std::memcpy(dst, src, bytes);
  }
  void copy_from_host(void* dst, const void* src, std::size_t bytes) const {
    if (bytes) std::memcpy(dst, src, bytes);
  }
  void copy(void* dst, const void* src, std::size_t bytes) const {
    if (bytes) std::memcpy(dst, src, bytes);
  }
  void memset(void* dst, int value, std::size_t bytes) const {
    if (bytes) std::memset(dst, value, bytes);
  }
};

}  // namespace edgeplane
