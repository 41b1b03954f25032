// edgeplane: configuration macros shared by every header.
#pragma once

#if defined(__CUDACC__)
#define EDGEPLANE_HD __host__ __device__
#define EDGEPLANE_DEVICE_COMPILE 1
#else
#define EDGEPLANE_HD
#endif

// Device code asserts only in debug builds (never in release kernels).
#if !defined(NDEBUG) && !defined(__CUDA_ARCH__)
#include <cassert>
#define EDGEPLANE_ASSERT(x) assert(x)
#else
#define EDGEPLANE_ASSERT(x) ((void)0)
#endif
