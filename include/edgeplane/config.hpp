// edgeplane: configuration macros shared by every header.
#pragma once
#include <cstdint>
#include <type_traits>

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
// Keeps a rarely taken path out of the hot kernel that calls it (its code would crowd the kernel).
#if defined(__CUDACC__)
#define EDGEPLANE_NOINLINE __noinline__
#elif defined(__GNUC__) || defined(__clang__)
#define EDGEPLANE_NOINLINE __attribute__((noinline))
#else
#define EDGEPLANE_NOINLINE
#endif

// Unrolls the loop that follows in device code (which keeps small per-thread arrays in registers
// only when every index is a constant); nothing in host code, whose compilers (nvcc's host pass
// included) would warn about an unknown pragma.
#if defined(__CUDA_ARCH__)
#define EDGEPLANE_UNROLL _Pragma("unroll")
#else
#define EDGEPLANE_UNROLL
#endif

// Keeps g++ from unrolling the short constant-count host loop that follows completely before its
// loop vectorizer sees it: unrolled first, an 8-lane loop is left to the straight-line (SLP)
// vectorizer, which may judge it unprofitable and leave it scalar.  Nothing elsewhere, nvcc
// included (its front end warns about the pragma even in the host pass).
#if defined(__GNUC__) && !defined(__clang__) && !defined(__CUDACC__)
#define EDGEPLANE_VECTOR_LOOP _Pragma("GCC unroll 1")
#else
#define EDGEPLANE_VECTOR_LOOP
#endif

// Host kernels whose inner loops are SIMD over pixels (the edge pass, smoothing, the depth
// closing, moments, growth, the union-find's row passes) are compiled three times on x86-64 ELF
// systems, for x86-64-v4 (AVX-512), x86-64-v3 (AVX2) and the baseline, and the loader picks the
// widest the CPU runs (GCC/Clang target_clones).  The results are those of the baseline: the
// library compiles with -ffp-contract=off (no fused multiply-add under any target), and every
// other float operation is the same IEEE operation at any vector width.  Off under nvcc, when the
// compiler already targets AVX-512 (-march=native on such a machine), or with
// EDGEPLANE_NO_TARGET_CLONES.
#if !defined(__CUDACC__) && !defined(EDGEPLANE_NO_TARGET_CLONES) && defined(__x86_64__) && defined(__ELF__) && \
    !defined(__AVX512F__) && ((defined(__clang__) && __clang_major__ >= 14) || (!defined(__clang__) && defined(__GNUC__) && __GNUC__ >= 11))
#define EDGEPLANE_HOST_CLONES __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define EDGEPLANE_HOST_CLONES
#endif

// The host edge kernel (about 59 KB of code per clone) starts on a 4 KB boundary.  Where it
// happened to start within a page, which any change elsewhere in a program moves, changed the
// edge pass by up to 18 % with identical instructions (benchmarks/RESULTS.md, session 30, item
// 89); fixed, the kernel runs as fast in every program compiled alike.  GCC host code only:
// Clang refuses an alignment on a function with target_clones (and the effect was measured with
// GCC only).
#if !defined(__CUDACC__) && defined(__GNUC__) && !defined(__clang__)
#define EDGEPLANE_PAGE_ALIGNED __attribute__((aligned(4096)))
#else
#define EDGEPLANE_PAGE_ALIGNED
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

/// The CPU backend runs fewer work items than this serially (below it, waking a second thread
/// costs more than it saves); host kernels that choose their block size keep this many blocks
/// where the data allows.
inline constexpr std::int64_t host_parallel_items = 64;

/// Whether a kernel declares `static constexpr bool even_work = true`: its work items cost about
/// the same (rows of a cheap pass, blocks sized to equal work), so the CPU backend hands each
/// thread a few contiguous runs of them instead of letting TBB split the range item by item.
template <class F>
inline constexpr bool even_work_v = requires { requires F::even_work; };

/// f(x, y) for every pixel of row `row`: host backends' work item of for_each_pixel.
template <class F>
struct pixel_rows {
  static constexpr bool even_work = even_work_v<F>;
  F f;
  int w;
  EDGEPLANE_HD void operator()(std::int64_t row) const {
    const int y = static_cast<int>(row);
    for (int x = 0; x < w; ++x) f(x, y);
  }
};
/// f(x, y) for pixel i of a w-wide image: device backends' work item of for_each_pixel.
template <class F>
struct pixel_flat {
  F f;
  int w;
  EDGEPLANE_HD void operator()(std::int64_t i) const {
    const int j = static_cast<int>(i);  // images hold fewer than 2^31 pixels (the segmenter checks)
    f(j % w, j / w);
  }
};

/// Calls f(x, y) for every pixel of a w x h image, in any order and concurrently.  Host backends
/// run one work item per row with the x loop inside (no division per pixel, and the loop is open
/// to the compiler's vectorizer); device backends run a thread per pixel.
template <class Backend, class F>
void for_each_pixel(const Backend& b, int w, int h, const F& f) {
  if (w <= 0 || h <= 0) return;
  if constexpr (Backend::host_accessible)
    b.for_each_index(h, pixel_rows<F>{f, w});
  else
    b.for_each_index(static_cast<std::int64_t>(w) * h, pixel_flat<F>{f, w});
}

/// Runs a per-pixel kernel px(x, y) over a w x h image: on device backends one work item per pixel;
/// on host backends RowKernel<row_lanes>{px, chunks}, one work item per run of row_lanes pixels of
/// a row (chunks = runs per row), which must compute what px computes.
template <template <int> class RowKernel, class Backend, class Pixel>
void for_each_pixel_run(const Backend& b, int w, int h, const Pixel& px) {
  constexpr int lanes = row_lanes<Backend>;
  if constexpr (lanes == 1) {
    for_each_pixel(b, w, h, px);
  } else {
    const int chunks = (w + lanes - 1) / lanes;
    b.for_each_index(static_cast<std::int64_t>(chunks) * h, RowKernel<lanes>{px, chunks});
  }
}

/// Host row kernels of a windowed pixel kernel (the smoothing): px.lanes_from<Lanes>(c, pitch, o)
/// computes the run of Lanes pixels whose first pixel is c (rows pitch elements apart, windows
/// readable) into o, and must give exactly what px(x, y) gives, treating a zero tap as one that
/// px(x, y) skips (outside the image: a tap that changes nothing).  Runs whose windows lie inside
/// the image read it in place; border runs (inside a row) read a copy of their window with zeros
/// outside the image (for px.r up to max_tile_r); the rest run px(x, y) per pixel.  Use as
/// for_each_pixel_run<window_runs<Px>::template kernel>.
inline constexpr int max_tile_r = 8;

template <class Px>
struct window_runs {
  template <int Lanes>
  EDGEPLANE_HD EDGEPLANE_INLINE static void run(const Px& px, int chunks, std::int64_t item) {
    const int y = static_cast<int>(item / chunks), x0 = static_cast<int>(item % chunks) * Lanes;
    const int w = px.out.width, h = px.out.height, r = px.r;
    if (x0 < r || x0 + Lanes > w - r || y < r || y >= h - r) {
      if (x0 + Lanes <= w && r <= max_tile_r) {  // rows y - r .. y + r, columns x0 - r .. x0 + Lanes - 1 + r
        using T = std::remove_cv_t<std::remove_reference_t<decltype(px.in(0, 0))>>;
        constexpr int tp = Lanes + 2 * max_tile_r;
        T tile[(2 * max_tile_r + 1) * tp];
        for (int dy = -r; dy <= r; ++dy) {
          const int v = y + dy;
          for (int j = 0; j < Lanes + 2 * r; ++j) {
            const int u = x0 - r + j;
            tile[(dy + r) * tp + j] = (v >= 0 && v < px.in.height && u >= 0 && u < px.in.width) ? px.in(u, v) : T{};
          }
        }
        px.template lanes_from<Lanes>(tile + r * tp + r, tp, &px.out(x0, y));
        return;
      }
      const int x1 = x0 + Lanes < w ? x0 + Lanes : w;
      for (int x = x0; x < x1; ++x) px(x, y);
      return;
    }
    px.template lanes_from<Lanes>(&px.in(x0, y), px.in.pitch, &px.out(x0, y));
  }
  template <int Lanes>
  struct kernel {
    Px px;
    int chunks;
    EDGEPLANE_HOST_CLONES EDGEPLANE_HD void operator()(std::int64_t item) const { run<Lanes>(px, chunks, item); }
  };
};
}  // namespace edgeplane::detail
