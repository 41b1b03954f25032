// edgeplane: umbrella header for CUDA users: the whole library plus the CUDA backend
// (edgeplane::cuda).  Needs nvcc; link edgeplane::cuda.  CPU-only code includes edgeplane.hpp.
#pragma once

#if !defined(__CUDACC__)
#error "edgeplane/edgeplane.cuh needs a CUDA compiler (nvcc): compile this translation unit as CUDA and link edgeplane::cuda. The CPU library is edgeplane/edgeplane.hpp."
#endif

#include "edgeplane/edgeplane.hpp"
#include "edgeplane/backend/cuda.cuh"
