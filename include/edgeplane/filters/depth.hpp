// edgeplane: depth preprocessing.  Conversion to metres, the closing filter that fills pepper
// holes, and the optional 2x downscale.  Working depth images are float metres, 0 = invalid.
#pragma once
#include <cmath>
#include <cstdint>

#include "edgeplane/config.hpp"
#include "edgeplane/detail/geometry.hpp"
#include "edgeplane/image.hpp"

namespace edgeplane {
namespace detail {

/// Converts raw depth (uint16 units or float metres) to float metres; 0, NaN, infinities,
/// negatives and values outside [min_depth, max_depth] become 0 (invalid).
template <class In>
struct convert_depth_kernel {
  static constexpr bool even_work = true;  // see detail::even_work_v
  image_view<const In> in;
  image_view<float> out;
  float scale;  // metres per unit
  float min_depth, max_depth;
  EDGEPLANE_HD void operator()(int x, int y) const {
    const float z = static_cast<float>(in(x, y)) * scale;
    out(x, y) = ((z >= min_depth) & (z <= max_depth) & (z > 0.f)) ? z : 0.f;  // NaN fails every comparison
  }
};

/// Dilation half of the hole-filling closing: the largest valid depth in the (2r+1)^2 window.
struct depth_dilate_kernel {
  image_view<const float> in;
  image_view<float> out;
  int r;
  EDGEPLANE_HD void operator()(int x, int y) const {
    float m = in(x, y);
    if (m <= 0.f) {  // only invalid pixels need the dilation; valid ones keep their depth
      for (int dy = -r; dy <= r; ++dy)
        for (int dx = -r; dx <= r; ++dx)
          if (in.contains(x + dx, y + dy)) {
            const float v = in(x + dx, y + dy);
            m = v > m ? v : m;
          }
    }
    out(x, y) = m;
  }
};

/// Erosion half: an originally invalid pixel takes the smallest dilated depth of its window, or
/// stays invalid when the window still holds an invalid pixel (the hole was wider than the filter).
/// Valid pixels are never changed (the closing fills holes; it does not move depth edges).  `out`
/// may be `original` itself: a pixel reads only its own original depth, and its window in
/// `dilated`.
struct depth_erode_kernel {
  image_view<const float> original;
  image_view<const float> dilated;
  image_view<float> out;
  int r;
  EDGEPLANE_HD void operator()(int x, int y) const {
    const float z = original(x, y);
    if (z > 0.f) {
      out(x, y) = z;
      return;
    }
    float m = 3.4e38f;
    for (int dy = -r; dy <= r; ++dy)
      for (int dx = -r; dx <= r; ++dx)
        if (dilated.contains(x + dx, y + dy)) {
          const float v = dilated(x + dx, y + dy);
          if (v <= 0.f) {
            out(x, y) = 0.f;
            return;
          }
          m = v < m ? v : m;
        }
    out(x, y) = m;
  }
};

/// Host form of the closing's halves, one work item per row: chunks of the row accumulate the
/// window one shift at a time, each a pass over the chunk (vectorizable), taps outside the image
/// skipped as the per-pixel kernels skip them.  Dilation: the largest tap, kept where the pixel
/// is invalid.  Erosion: the smallest dilated tap where the pixel was invalid, 0 where that is
/// <= 0 (the window held an invalid pixel: depth is never negative), the original depth
/// elsewhere.  Either order of a maximum or minimum of finite non-negative depths gives the same
/// float.  `out` may be `in` (erosion: a row reads only its own original depth).
template <bool Dilate>
struct depth_rows_kernel {
  static constexpr bool even_work = true;  // see detail::even_work_v
  image_view<const float> in;       // the depth before the closing
  image_view<const float> dilated;  // the dilation's output (erosion only)
  image_view<float> out;
  int r;
  EDGEPLANE_HOST_CLONES void operator()(std::int64_t row) const {
    const int y = static_cast<int>(row), w = in.width;
    const image_view<const float> taps = Dilate ? in : dilated;
    const float* c = &in(0, y);
    float* o = &out(0, y);
    constexpr int chunk = 256, block = 32;
    float m[chunk];
    // Only pixels without valid depth change (either half gives a valid pixel its own depth), so
    // the window is accumulated only over stretches of 32-pixel blocks that hold one (at most a
    // chunk long); the other blocks are copied, or left alone in place.
    for (int xa = 0; xa < w;) {
      const auto clean = [&](int x0) {  // block x0 .. x0 + block - 1 (within the row) all valid
        const int x1 = x0 + block < w ? x0 + block : w;
        unsigned holes = 0;
        for (int x = x0; x < x1; ++x) holes |= static_cast<unsigned>(!(c[x] > 0.f));
        return holes == 0;
      };
      if (clean(xa)) {
        const int xb = xa + block < w ? xa + block : w;
        if (Dilate || o != c)
          for (int x = xa; x < xb; ++x) o[x] = c[x];
        xa = xb;
        continue;
      }
      int xb = xa + block < w ? xa + block : w;
      while (xb < w && xb - xa + block <= chunk && !clean(xb)) xb = xb + block < w ? xb + block : w;
      for (int x = xa; x < xb; ++x) m[x - xa] = Dilate ? c[x] : 3.4e38f;
      for_each_window_shift(taps, y, r, [&](const float* t, int dx, int x0, int x1) {
        const int lo = x0 > xa ? x0 : xa, hi = x1 < xb ? x1 : xb;
        for (int x = lo; x < hi; ++x) {
          const float v = t[x + dx];
          if constexpr (Dilate)
            m[x - xa] = v > m[x - xa] ? v : m[x - xa];
          else
            m[x - xa] = v < m[x - xa] ? v : m[x - xa];
        }
      });
      for (int x = xa; x < xb; ++x) {  // (in place too: a valid pixel is rewritten with its own depth)
        const float z = c[x], v = m[x - xa];
        o[x] = z > 0.f ? z : (Dilate ? v : (v > 0.f ? v : 0.f));
      }
      xa = xb;
    }
  }
};

/// 2x downscale: the mean of the valid pixels of each 2x2 block that lie within 2% of the
/// block's nearest valid depth (so a block straddling a depth edge takes the near surface, never
/// a depth between the two surfaces).  Odd last rows/columns are dropped.
struct downscale_kernel {
  image_view<const float> in;
  image_view<float> out;
  EDGEPLANE_HD void operator()(int x, int y) const {
    float v[4] = {in(2 * x, 2 * y), in(2 * x + 1, 2 * y), in(2 * x, 2 * y + 1), in(2 * x + 1, 2 * y + 1)};
    float mn = 3.4e38f;
    for (float z : v)
      if (z > 0.f && z < mn) mn = z;
    if (mn == 3.4e38f) {
      out(x, y) = 0.f;
      return;
    }
    float s = 0.f;
    int n = 0;
    for (float z : v)
      if (z > 0.f && z <= mn * 1.02f) {
        s += z;
        ++n;
      }
    out(x, y) = n > 0 ? s / static_cast<float>(n) : 0.f;  // no tap taken (a NaN or negative tolerance): 0
  }
};

/// downscale_kernel by rows (host backends): the same operations without branches (selects by
/// bits over values computed either way: g++ turns `?:` into branches for AVX2), so that the row
/// loop vectorizes.  The smallest valid depth of each 2x2 block (a depth that is not > 0, or not
/// below the running minimum, leaves it), then the mean of the valid depths within 2 % of it,
/// summed in the block's order (a skipped depth adds +0, which
/// leaves the non-negative sum as it is).
struct downscale_rows_kernel {
  image_view<const float> in;
  image_view<float> out;
  EDGEPLANE_HOST_CLONES void operator()(std::int64_t row) const {
    const int y = static_cast<int>(row), w = out.width;
    const float* r0 = &in(0, 2 * y);
    const float* r1 = &in(0, 2 * y + 1);
    float* o = &out(0, y);
    constexpr float none = 3.4e38f;
    for (int x = 0; x < w; ++x) {
      const float a = r0[2 * x], b = r0[2 * x + 1], c = r1[2 * x], d = r1[2 * x + 1];
      float mn = none;
      mn = select_f((a > 0.f) & (a < mn), a, mn);
      mn = select_f((b > 0.f) & (b < mn), b, mn);
      mn = select_f((c > 0.f) & (c < mn), c, mn);
      mn = select_f((d > 0.f) & (d < mn), d, mn);
      const float lim = mn * 1.02f;
      const bool ta = (a > 0.f) & (a <= lim), tb = (b > 0.f) & (b <= lim), tc = (c > 0.f) & (c <= lim),
                 td = (d > 0.f) & (d <= lim);
      float s = 0.f;
      s += select_f(ta, a, 0.f);
      s += select_f(tb, b, 0.f);
      s += select_f(tc, c, 0.f);
      s += select_f(td, d, 0.f);
      const float n = select_f(ta, 1.f, 0.f) + select_f(tb, 1.f, 0.f) + select_f(tc, 1.f, 0.f) +
                      select_f(td, 1.f, 0.f);  // exact
      o[x] = select_f(mn == none, 0.f, s / n);  // no valid depth: 0 (not the division's NaN)
    }
  }
};

/// Edge-preserving smoothing: the mean of the valid depths in the (2r+1)^2 window that lie within
/// k * sigma(z_c) of the centre depth (a box filter truncated in range), so noise is averaged out
/// on surfaces while depth steps larger than the noise are kept.  Invalid pixels stay invalid.
struct smooth_kernel {
  image_view<const float> in;
  image_view<float> out;
  int r;
  float k, s0, s2;
  EDGEPLANE_HD void operator()(int x, int y) const {
    const float zc = in(x, y);
    if (!(zc > 0.f)) {
      out(x, y) = 0.f;
      return;
    }
    const float tol = k * (s0 + s2 * zc * zc);
    float s = 0.f;
    int n = 0;
    if (x >= r && y >= r && x < in.width - r && y < in.height - r) {  // the window is inside: no checks
      for (int dy = -r; dy <= r; ++dy) {
        const float* row = &in(x - r, y + dy);
        for (int j = 0; j <= 2 * r; ++j) {
          const float z = row[j];
          const bool take = z > 0.f && fabsf(z - zc) <= tol;
          s += take ? z : 0.f;  // the same sum, in the same order, as the checked loop below
          n += take ? 1 : 0;
        }
      }
      out(x, y) = n > 0 ? s / static_cast<float>(n) : 0.f;  // no tap taken (a NaN or negative tolerance): 0
      return;
    }
    for (int dy = -r; dy <= r; ++dy)
      for (int dx = -r; dx <= r; ++dx)
        if (in.contains(x + dx, y + dy)) {
          const float z = in(x + dx, y + dy);
          if (z > 0.f && fabsf(z - zc) <= tol) {
            s += z;
            ++n;
          }
        }
    out(x, y) = n > 0 ? s / static_cast<float>(n) : 0.f;  // no tap taken (a NaN or negative tolerance): 0
  }
  /// Host runs of Lanes pixels (see window_runs), c[0..Lanes-1] into o[0..Lanes-1] (rows pitch
  /// elements apart, their windows readable): the lanes advance together through the window, each
  /// lane's sum in the same order as above (bit-identical), which breaks the one-add-after-another
  /// chain of a single pixel and lets the compiler use SIMD.  A zero tap (outside the image, in
  /// window_runs' border copies) adds +0 and no count, as operator() skips it.
  template <int Lanes>
  EDGEPLANE_HD EDGEPLANE_INLINE void lanes_from(const float* c, std::ptrdiff_t pitch, float* o) const {
    float zc[Lanes], tol[Lanes], sum[Lanes], cnt[Lanes];  // counts as floats: exact, and one vector type
    for (int l = 0; l < Lanes; ++l) {
      zc[l] = c[l];
      tol[l] = k * (s0 + s2 * zc[l] * zc[l]);
      sum[l] = 0.f;
      cnt[l] = 0.f;
    }
    unsigned wide = 0;  // some valid centre's tolerance not below its depth (as bits: a bool's
    EDGEPLANE_VECTOR_LOOP  // &= became a branch per lane)
    for (int l = 0; l < Lanes; ++l) wide |= static_cast<unsigned>((zc[l] > 0.f) & !(tol[l] < zc[l]));
    // Where a valid centre's tolerance is below its depth, a tap's own test z > 0 decides nothing:
    // for z <= 0 the rounded z - zc is at most -zc (rounding is monotonic and -zc is a float), so
    // |z - zc| >= zc > tol already rejects it, and a NaN tap fails both.  Lanes with an invalid
    // centre give 0 whatever they sum.  So runs where every lane is so (all but absurd noise
    // parameters) leave that comparison out; the decisions are the same.
    if (!wide)
      sum_window<Lanes, false>(c, pitch, zc, tol, sum, cnt);
    else
      sum_window<Lanes, true>(c, pitch, zc, tol, sum, cnt);
    // an invalid centre, or no tap taken (cnt 0: the division's NaN is not selected), gives 0
    for (int l = 0; l < Lanes; ++l) o[l] = select_f((zc[l] > 0.f) & (cnt[l] > 0.f), sum[l] / cnt[l], 0.f);
  }
  template <int Lanes, bool CheckTap>
  EDGEPLANE_HD EDGEPLANE_INLINE void sum_window(const float* c, std::ptrdiff_t pitch, const float* zc, const float* tol,
                                                float* sum, float* cnt) const {
    for (int dy = -r; dy <= r; ++dy) {
      const float* row = c + dy * pitch - r;
      for (int j = 0; j <= 2 * r; ++j)
        for (int l = 0; l < Lanes; ++l) {
          const float z = row[j + l];
          // z or +0 (adding +0 leaves a sum of non-negative depths as it is), selected by bits:
          // g++ turns `take ? z : 0.f` into branches for AVX2 and SSE targets (only the AVX-512
          // clone stayed vector), which made this loop scalar and data-dependent
          const bool near = fabsf(z - zc[l]) <= tol[l];
          const bool take = CheckTap ? (z > 0.f) & near : near;
          sum[l] += select_f(take, z, 0.f);
          cnt[l] += select_f(take, 1.f, 0.f);
        }
    }
  }
};

}  // namespace detail

/// Edge-preserving smoothing (see detail::smooth_kernel) of `in` into `out` (same size, distinct).
template <class Backend>
void smooth_depth(const Backend& b, image_view<const float> in, image_view<float> out, int r, float k,
                  float sigma0, float sigma2) {
  detail::check_same_size(in, out, "depth", "smoothed depth");
  detail::for_each_pixel_run<detail::window_runs<detail::smooth_kernel>::template kernel>(
      b, in.width, in.height, detail::smooth_kernel{in, out, r, k, sigma0, sigma2});
}

/// Converts raw uint16 depth (scale = metres per unit) or float metres (scale 1) into a working
/// depth image (float metres, 0 = invalid).  Views in the backend's memory; asynchronous on
/// device backends.
template <class Backend, class In>
void convert_depth(const Backend& b, image_view<const In> in, float scale, float min_depth, float max_depth,
                   image_view<float> out) {
  detail::check_view(in, "depth");
  detail::check_view(out, "converted depth");
  detail::check_same_size(in, out, "depth", "converted depth");
  detail::require(std::isfinite(scale) && scale > 0.f, "depth scale must be positive and finite (got " +
                                                           std::to_string(scale) + " metres per unit)");
  detail::for_each_pixel(b, in.width, in.height, detail::convert_depth_kernel<In>{in, out, scale, min_depth, max_depth});
}

/// The closing filter (dilate, then erode, square window of half-size r) restricted to invalid
/// pixels: fills pepper holes narrower than the window and leaves valid depth untouched.
/// `scratch` and `out` must be the size of the image (`out` may be `depth` itself).
template <class Backend>
void close_depth(const Backend& b, image_view<float> depth, image_view<float> scratch, image_view<float> out, int r) {
  detail::check_same_size(depth, scratch, "depth", "scratch");
  detail::check_same_size(depth, out, "depth", "output");
  if constexpr (Backend::host_accessible) {  // host: by rows
    b.for_each_index(depth.height, detail::depth_rows_kernel<true>{depth, depth, scratch, r});
    b.for_each_index(depth.height, detail::depth_rows_kernel<false>{depth, scratch, out, r});
  } else {
    detail::for_each_pixel(b, depth.width, depth.height, detail::depth_dilate_kernel{depth, scratch, r});
    detail::for_each_pixel(b, depth.width, depth.height, detail::depth_erode_kernel{depth, scratch, out, r});
  }
}

/// 2x downscale of a working depth image into out (width/2 x height/2).
template <class Backend>
void downscale_depth(const Backend& b, image_view<const float> in, image_view<float> out) {
  detail::require(out.width == in.width / 2 && out.height == in.height / 2,
                  "downscale output must be half the input size");
  if (out.width <= 0 || out.height <= 0) return;
  if constexpr (Backend::host_accessible)
    b.for_each_index(out.height, detail::downscale_rows_kernel{in, out});
  else
    detail::for_each_pixel(b, out.width, out.height, detail::downscale_kernel{in, out});
}

}  // namespace edgeplane
