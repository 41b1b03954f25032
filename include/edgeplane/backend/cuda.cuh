// edgeplane: the CUDA backend.  Runs the same named functors as edgeplane::cpu, on a CUDA stream,
// with Thrust.  Needs nvcc (this is a .cuh); link edgeplane::cuda, which adds the CUDA runtime and
// the flags the kernels need (-std=c++20 --expt-relaxed-constexpr for CUDA sources).  Users need
// no --extended-lambda: every kernel is a named functor.
#pragma once

#if !defined(__CUDACC__)
#error "edgeplane/backend/cuda.cuh needs a CUDA compiler (nvcc): compile this translation unit as CUDA and link edgeplane::cuda. The CPU library is edgeplane/edgeplane.hpp."
#endif

#include <cuda_runtime_api.h>
#include <thrust/for_each.h>
#include <thrust/iterator/counting_iterator.h>
#include <thrust/scan.h>
#include <thrust/system/cuda/error.h>
#include <thrust/system/cuda/execution_policy.h>
#include <thrust/system_error.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <type_traits>

#include "edgeplane/config.hpp"
#include "edgeplane/error.hpp"

namespace edgeplane {
namespace detail {

/// The message of a failed CUDA call: "edgeplane: CUDA <what> failed: <name>: <description>".
inline std::string cuda_error_message(cudaError_t e, const char* what) {
  return std::string("edgeplane: CUDA ") + what + " failed: " + cudaGetErrorName(e) + ": " + cudaGetErrorString(e);
}

/// Throws edgeplane::backend_error when `e` is an error.  The runtime's last-error state is cleared
/// first, so that a non-sticky failure (an allocation that did not fit, a bad argument) is not
/// reported again by the next kernel launch; sticky errors (a kernel fault) stay and are reported
/// by every later call.
inline void cuda_check(cudaError_t e, const char* what) {
  if (e == cudaSuccess) return;
  (void)cudaGetLastError();
  throw backend_error(cuda_error_message(e, what));
}

/// Thrust reports CUDA failures as thrust::system_error; edgeplane's callers catch backend_error.
[[noreturn]] inline void rethrow_thrust(const thrust::system_error& e, const char* what) {
  (void)cudaGetLastError();
  if (e.code().category() == thrust::cuda_category()) {
    const auto ce = static_cast<cudaError_t>(e.code().value());
    throw backend_error(cuda_error_message(ce, what) + " (" + e.what() + ")");
  }
  throw backend_error(std::string("edgeplane: CUDA ") + what + " failed: " + e.what());
}

/// Thrust's temporary storage (the scan's tile states) from the stream-ordered allocator, on the
/// backend's stream: no cudaMalloc/cudaFree (which synchronizes the device) per call, so a
/// segmenter's frame allocates nothing the device must wait for.  Needs memory-pool support
/// (cudaDevAttrMemoryPoolsSupported; every Linux GPU since Pascal, Jetson Orin included).
struct stream_temporary_allocator {
  using value_type = char;
  cudaStream_t stream;
  char* allocate(std::ptrdiff_t bytes) const {
    void* p = nullptr;
    cuda_check(cudaMallocAsync(&p, static_cast<std::size_t>(bytes > 0 ? bytes : 1), stream),
               "cudaMallocAsync (temporary storage)");
    return static_cast<char*>(p);
  }
  // Called from Thrust's destructors: must not throw.  A failure here leaves only a sticky error,
  // which the next checked call (the synchronize at the latest) reports.
  void deallocate(char* p, std::size_t) const noexcept { (void)cudaFreeAsync(p, stream); }
};

}  // namespace detail

/// CUDA backend: runs kernels on `stream` (nullptr = the legacy default stream) of the device that
/// is current when each call is made; keep the same device current for a backend's whole life.
///
/// Memory it hands out (allocate, and every buffer of a segmenter<cuda>) is DEVICE memory
/// (cudaMalloc; never managed), not readable from the host.  Calls are asynchronous on the stream
/// unless documented otherwise: for_each_index, inclusive_scan, copy, memset and copy_from_host
/// return before the work is done; synchronize() and copy_to_host() wait for it.  Failures of any
/// CUDA call throw edgeplane::backend_error carrying the error's name and description (an error
/// of an earlier asynchronous kernel surfaces at the next call that synchronizes).
///
/// A value type (trivially copyable, as cheap to copy as its stream handle): a segmenter and
/// its buffers each hold a copy.  It owns nothing; the caller owns the stream.
struct cuda {
  cudaStream_t stream = nullptr;

  static constexpr bool host_accessible = false;

  /// Calls f(i) on the device for i in [0, n) (any order, concurrently).  f is a trivially
  /// copyable functor with an EDGEPLANE_HD operator()(std::int64_t) const; every pointer it holds
  /// is device memory.  Asynchronous.
  template <class F>
  void for_each_index(std::int64_t n, F f) const {
    static_assert(std::is_trivially_copyable_v<F>, "edgeplane kernels are trivially copyable functors");
    if (n <= 0) return;
    try {
      thrust::for_each_n(thrust::cuda::par_nosync.on(stream), thrust::counting_iterator<std::int64_t>(0), n, f);
    } catch (const thrust::system_error& e) {
      detail::rethrow_thrust(e, "kernel launch (thrust::for_each_n)");
    }
  }

  /// out[i] = in[0] + ... + in[i] (inclusive prefix sum).  Device pointers; in == out allowed.
  /// Asynchronous.
  template <class T>
  void inclusive_scan(const T* in, std::int64_t n, T* out) const {
    if (n <= 0) return;
    const detail::stream_temporary_allocator alloc{stream};
    try {
      thrust::inclusive_scan(thrust::cuda::par_nosync(alloc).on(stream), in, in + n, out);
    } catch (const thrust::system_error& e) {
      detail::rethrow_thrust(e, "scan (thrust::inclusive_scan)");
    }
  }

  /// Waits for all work queued on the stream; throws backend_error if any of it failed.
  void synchronize() const { detail::cuda_check(cudaStreamSynchronize(stream), "cudaStreamSynchronize"); }

  /// `bytes` of device memory (cudaMalloc; 256-byte aligned).  Synchronous with the host.
  void* allocate(std::size_t bytes) const {
    void* p = nullptr;
    detail::cuda_check(cudaMalloc(&p, bytes == 0 ? 1 : bytes),
                       ("cudaMalloc of " + std::to_string(bytes) + " bytes").c_str());
    return p;
  }
  /// Frees memory from allocate() (cudaFree waits for the device first).  Never throws: errors
  /// (e.g. during shutdown, after the runtime is unloaded) are dropped.
  void deallocate(void* p) const noexcept {
    if (p) (void)cudaFree(p);
  }

  /// Page-locked host memory (cudaMallocHost): uploads from it and downloads into it run
  /// asynchronously and overlap with other streams' work.  edgeplane::pipeline holds its frames
  /// in flight there.  Synchronous with the host.
  void* allocate_host(std::size_t bytes) const {
    void* p = nullptr;
    detail::cuda_check(cudaMallocHost(&p, bytes == 0 ? 1 : bytes),
                       ("cudaMallocHost of " + std::to_string(bytes) + " bytes").c_str());
    return p;
  }
  /// Frees memory from allocate_host().  Never throws.
  void deallocate_host(void* p) const noexcept {
    if (p) (void)cudaFreeHost(p);
  }
  /// The device current on the calling thread; bind_thread() makes it current on another one:
  /// edgeplane::pipeline's lane threads run on the device current where the pipeline was built.
  int thread_binding() const {
    int device = 0;
    detail::cuda_check(cudaGetDevice(&device), "cudaGetDevice");
    return device;
  }
  void bind_thread(int device) const { detail::cuda_check(cudaSetDevice(device), "cudaSetDevice"); }

  /// Device -> host.  Complete when it returns (waits for the stream: the host may read dst).
  void copy_to_host(void* dst, const void* src, std::size_t bytes) const {
    if (bytes == 0) return;
    detail::cuda_check(cudaMemcpyAsync(dst, src, bytes, cudaMemcpyDeviceToHost, stream), "cudaMemcpyAsync (to host)");
    synchronize();
  }
  /// Host -> device, ordered on the stream.  From pageable memory the call returns once the source
  /// has been staged (the caller may reuse it); from pinned memory it may return earlier, so keep
  /// a pinned source unchanged until the next synchronize.
  void copy_from_host(void* dst, const void* src, std::size_t bytes) const {
    if (bytes == 0) return;
    detail::cuda_check(cudaMemcpyAsync(dst, src, bytes, cudaMemcpyHostToDevice, stream),
                       "cudaMemcpyAsync (from host)");
  }
  /// Device -> device.  Asynchronous.
  void copy(void* dst, const void* src, std::size_t bytes) const {
    if (bytes == 0) return;
    detail::cuda_check(cudaMemcpyAsync(dst, src, bytes, cudaMemcpyDeviceToDevice, stream), "cudaMemcpyAsync");
  }
  /// Sets `bytes` of device memory to the byte `value`.  Asynchronous.
  void memset(void* dst, int value, std::size_t bytes) const {
    if (bytes == 0) return;
    detail::cuda_check(cudaMemsetAsync(dst, value, bytes, stream), "cudaMemsetAsync");
  }
};

static_assert(std::is_trivially_copyable_v<cuda>);

}  // namespace edgeplane
