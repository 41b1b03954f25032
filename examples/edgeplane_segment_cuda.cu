// edgeplane_segment with the CUDA backend: the same program (edgeplane_segment.cpp), compiled by
// nvcc with EDGEPLANE_WITH_CUDA, so that it also accepts --backend cuda.  Built as
// edgeplane_segment_cuda when CMake finds a CUDA compiler; the plain edgeplane_segment stays a
// host-compiler-only build.
#define EDGEPLANE_WITH_CUDA 1
#include "edgeplane_segment.cpp"
