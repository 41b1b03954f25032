// edgeplane tests: a backend that runs the DEVICE code paths on the host, so that every machine
// (and CI, which has no GPU) checks what edgeplane::cuda runs, short of Thrust and the CUDA runtime.
//
// It hands out host memory but declares host_accessible = false, so the stages and the segmenter
// take exactly the branches they take for edgeplane::cuda: a work item per pixel (no 16-pixel row
// kernels), the per-element union-find and root counting, the growth rounds without row skipping,
// and every frame's upload and download through copy_from_host / copy_to_host.  Like the CUDA
// backend it demands trivially copyable kernels.  Work items run either concurrently
// (std::execution::par over single indices: the same atomics and races as on a device), or on
// the calling thread in reverse index order (a device promises no order; a kernel that relied on
// raster order would give a different answer here).
//
// Optionally it records the traffic between host and backend memory (bytes and calls each way),
// so tests can hold the segmenter to "a frame costs one upload and one download at most" without
// a GPU, and its use of the CUDA backend's page-locked host memory and thread binding.
#pragma once
#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <execution>
#include <new>
#include <numeric>
#include <type_traits>

#include "edgeplane/backend/counting_iterator.hpp"

namespace edgeplane_test {

/// Host <-> backend traffic of a device_model (shared by every copy of the backend that points
/// at it: a segmenter and each of its buffers hold copies).
struct transfer_log {
  std::atomic<std::int64_t> upload_bytes{0}, upload_calls{0}, download_bytes{0}, download_calls{0};
  std::atomic<std::int64_t> largest_upload{0}, largest_download{0};
  std::atomic<std::int64_t> host_blocks{0};    ///< allocate_host() calls less deallocate_host() calls
  std::atomic<std::int64_t> bound_threads{0};  ///< bind_thread() calls with the binding handed out
  void reset() {
    upload_bytes = upload_calls = download_bytes = download_calls = largest_upload = largest_download = 0;
  }
};

struct device_model {
  enum class order { parallel, reversed };
  order run = order::parallel;
  transfer_log* log = nullptr;  ///< not owned; null = not recorded

  static constexpr bool host_accessible = false;

  template <class F>
  void for_each_index(std::int64_t n, F f) const {
    static_assert(std::is_trivially_copyable_v<F>, "edgeplane kernels are trivially copyable functors");
    if (n <= 0) return;
    if (run == order::reversed) {
      for (std::int64_t i = n - 1; i >= 0; --i) f(i);
    } else {
      edgeplane::detail::counting_iterator first(0), last(n);
      std::for_each(std::execution::par, first, last, f);
    }
  }
  template <class T>
  void inclusive_scan(const T* in, std::int64_t n, T* out) const {
    if (n > 0) std::inclusive_scan(in, in + n, out);
  }
  void synchronize() const {}
  void* allocate(std::size_t bytes) const { return ::operator new(bytes == 0 ? 1 : bytes, std::align_val_t{256}); }
  void deallocate(void* p) const noexcept { ::operator delete(p, std::align_val_t{256}); }
  void copy_to_host(void* dst, const void* src, std::size_t bytes) const {
    if (bytes == 0) return;
    std::memcpy(dst, src, bytes);
    record(false, bytes);
  }
  void copy_from_host(void* dst, const void* src, std::size_t bytes) const {
    if (bytes == 0) return;
    std::memcpy(dst, src, bytes);
    record(true, bytes);
  }
  void copy(void* dst, const void* src, std::size_t bytes) const {
    if (bytes) std::memcpy(dst, src, bytes);  // like cudaMemcpyAsync: the ranges must not overlap
  }
  void memset(void* dst, int value, std::size_t bytes) const {
    if (bytes) std::memset(dst, value, bytes);
  }
  // The CUDA backend's page-locked host memory and thread binding (edgeplane::pipeline uses them),
  // recorded in the log.
  void* allocate_host(std::size_t bytes) const {
    if (log) ++log->host_blocks;
    return ::operator new(bytes == 0 ? 1 : bytes, std::align_val_t{4096});
  }
  void deallocate_host(void* p) const noexcept {
    if (!p) return;
    if (log) --log->host_blocks;
    ::operator delete(p, std::align_val_t{4096});
  }
  static constexpr int binding = 7;
  int thread_binding() const { return binding; }
  void bind_thread(int b) const {
    if (log && b == binding) ++log->bound_threads;
  }

 private:
  void record(bool up, std::size_t bytes) const {
    if (!log) return;
    const auto b = static_cast<std::int64_t>(bytes);
    auto& total = up ? log->upload_bytes : log->download_bytes;
    auto& calls = up ? log->upload_calls : log->download_calls;
    auto& largest = up ? log->largest_upload : log->largest_download;
    total += b;
    ++calls;
    std::int64_t cur = largest.load();
    while (b > cur && !largest.compare_exchange_weak(cur, b)) {
    }
  }
};

static_assert(std::is_trivially_copyable_v<device_model>);

}  // namespace edgeplane_test
