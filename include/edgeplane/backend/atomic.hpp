// edgeplane: the few atomic operations kernels need, for host threads and for CUDA devices.
// Algorithm code calls these and never branches on the backend itself.
#pragma once
#include <cstdint>

#include "edgeplane/config.hpp"

#if !defined(__CUDA_ARCH__)
#include <atomic>
#endif

namespace edgeplane::detail {

EDGEPLANE_HD inline std::int32_t atomic_load(const std::int32_t* p) {
#if defined(__CUDA_ARCH__)
  return *reinterpret_cast<const volatile std::int32_t*>(p);
#else
  return std::atomic_ref<std::int32_t>(*const_cast<std::int32_t*>(p)).load(std::memory_order_relaxed);
#endif
}

EDGEPLANE_HD inline void atomic_store(std::int32_t* p, std::int32_t v) {
#if defined(__CUDA_ARCH__)
  *reinterpret_cast<volatile std::int32_t*>(p) = v;
#else
  std::atomic_ref<std::int32_t>(*p).store(v, std::memory_order_relaxed);
#endif
}

/// Compare-and-swap; returns the value found at *p (== expected on success).
EDGEPLANE_HD inline std::int32_t atomic_cas(std::int32_t* p, std::int32_t expected, std::int32_t desired) {
#if defined(__CUDA_ARCH__)
  return atomicCAS(reinterpret_cast<int*>(p), expected, desired);
#else
  std::atomic_ref<std::int32_t>(*p).compare_exchange_strong(expected, desired, std::memory_order_acq_rel,
                                                            std::memory_order_acquire);
  return expected;
#endif
}

EDGEPLANE_HD inline void atomic_add(std::int32_t* p, std::int32_t v) {
#if defined(__CUDA_ARCH__)
  atomicAdd(reinterpret_cast<int*>(p), v);
#else
  std::atomic_ref<std::int32_t>(*p).fetch_add(v, std::memory_order_relaxed);
#endif
}

/// Wrapping 64-bit add (unsigned arithmetic: overflow is defined, and integer sums are exact and
/// independent of the order of the additions, hence deterministic across threads and backends).
EDGEPLANE_HD inline void atomic_add(std::uint64_t* p, std::uint64_t v) {
#if defined(__CUDA_ARCH__)
  atomicAdd(reinterpret_cast<unsigned long long*>(p), static_cast<unsigned long long>(v));
#else
  std::atomic_ref<std::uint64_t>(*p).fetch_add(v, std::memory_order_relaxed);
#endif
}

EDGEPLANE_HD inline void atomic_min(std::int32_t* p, std::int32_t v) {
#if defined(__CUDA_ARCH__)
  atomicMin(reinterpret_cast<int*>(p), v);
#else
  std::atomic_ref<std::int32_t> a(*p);
  std::int32_t cur = a.load(std::memory_order_relaxed);
  while (v < cur && !a.compare_exchange_weak(cur, v, std::memory_order_relaxed)) {
  }
#endif
}

EDGEPLANE_HD inline void atomic_max(std::int32_t* p, std::int32_t v) {
#if defined(__CUDA_ARCH__)
  atomicMax(reinterpret_cast<int*>(p), v);
#else
  std::atomic_ref<std::int32_t> a(*p);
  std::int32_t cur = a.load(std::memory_order_relaxed);
  while (v > cur && !a.compare_exchange_weak(cur, v, std::memory_order_relaxed)) {
  }
#endif
}

}  // namespace edgeplane::detail
