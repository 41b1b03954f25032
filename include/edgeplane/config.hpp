// edgeplane: configuration macros shared by every header.
#pragma once

#if defined(__CUDACC__)
#define EDGEPLANE_HD __host__ __device__
#define EDGEPLANE_DEVICE_COMPILE 1
#else
#define EDGEPLANE_HD
#endif

// Forces inlining of the small predicates inside hot kernels, so that a pixel's shared terms (its
// 3-D point, its noise allowance) are computed once for every test and direction.
#if defined(__CUDACC__)
#define EDGEPLANE_INLINE __forceinline__
#elif defined(__GNUC__) || defined(__clang__)
#define EDGEPLANE_INLINE inline __attribute__((always_inline))
#else
#define EDGEPLANE_INLINE inline
#endif

// Device code asserts only in debug builds (never in release kernels).
#if !defined(NDEBUG) && !defined(__CUDA_ARCH__)
#include <cassert>
#define EDGEPLANE_ASSERT(x) assert(x)
#else
#define EDGEPLANE_ASSERT(x) ((void)0)
#endif

namespace edgeplane::detail {
/// Pixels per work item of the row kernels (smoothing, edges): runs of 16 on host backends (SIMD
/// lanes and independent chains for a core), 1 on device backends (a thread per pixel).
template <class Backend>
inline constexpr int row_lanes = Backend::host_accessible ? 16 : 1;
}  // namespace edgeplane::detail
