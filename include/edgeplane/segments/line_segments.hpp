// edgeplane: plane-candidate line segments.  One work item walks one diagonal of the image and
// keeps the runs of non-edge pixels that are longer than t_length and straight in 3-D.
#pragma once
#include <algorithm>
#include <cstdint>

#include "edgeplane/camera.hpp"
#include "edgeplane/config.hpp"
#include "edgeplane/detail/geometry.hpp"
#include "edgeplane/detail/swar.hpp"
#include "edgeplane/edges/directions.hpp"
#include "edgeplane/image.hpp"
#include "edgeplane/params.hpp"

namespace edgeplane {
namespace detail {

/// Number of diagonals of a w x h image along a diagonal direction.
EDGEPLANE_HD inline std::int64_t diagonal_count(int w, int h) { return w > 0 && h > 0 ? std::int64_t(w) + h - 1 : 0; }

/// First pixel (top row or outer column) of diagonal k along Direction (dy = 1, dx = +-1).
template <class Direction>
EDGEPLANE_HD inline void diagonal_start(int w, int h, std::int64_t k, int& x, int& y) {
  static_assert(Direction::dy == 1 && (Direction::dx == 1 || Direction::dx == -1), "diagonal directions only");
  if constexpr (Direction::dx == 1) {  // k = x - y + (h - 1)
    const int kk = static_cast<int>(k);
    x = kk - (h - 1) > 0 ? kk - (h - 1) : 0;
    y = (h - 1) - kk > 0 ? (h - 1) - kk : 0;
  } else {  // k = x + y
    const int kk = static_cast<int>(k);
    x = kk < w - 1 ? kk : w - 1;
    y = kk - x;
  }
}

/// The straightness test of one run: every point within t_line * chord + noise_k * sigma(z) of
/// the chord from the run's first to its last point.  Returns the index (0..len-1) of the worst
/// point, or -1 when the run passes.
struct line_test {
  float t_line, noise_k;
  noise_sigma sigma;
  template <class Direction>
  EDGEPLANE_HD int operator()(image_view<const float> depth, projector proj, int x0, int y0, int len,
                              Direction) const {
    const int x1 = x0 + (len - 1) * Direction::dx, y1 = y0 + (len - 1) * Direction::dy;
    const point3 a = proj(x0, y0, depth(x0, y0)), b = proj(x1, y1, depth(x1, y1));
    const float chord = norm(b - a);
    const float chord_tol = t_line * chord;
    int worst = -1;
    float worst_excess = 0.f;
    for (int k = 1; k < len - 1; ++k) {
      const int x = x0 + k * Direction::dx, y = y0 + k * Direction::dy;
      const float z = depth(x, y);
      const float e = excess(proj(x, y, z), z, a, b, chord_tol);
      if (e > worst_excess) {
        worst_excess = e;
        worst = k;
      }
    }
    return worst;
  }

  /// How far point p (depth z) lies beyond its tolerance chord_tol + noise_k * sigma(z) from the
  /// chord a-b (negative: within it); operator() and worst_lanes share these operations.
  EDGEPLANE_HD EDGEPLANE_INLINE float excess(point3 p, float z, point3 a, point3 b, float chord_tol) const {
    const float tol = chord_tol + noise_k * sigma(z);
    return sqrtf(dist2_to_line(p, a, b)) - tol;
  }

  /// operator()'s answer, computed 16 points at a time with the very same float operations (host
  /// backends: one SIMD lane per point, the strided depths gathered).  The worst point is the first
  /// whose excess d - tol equals the largest excess, when that is > 0.  One vector sweep keeps, per
  /// lane, the largest excess and the first point that reached it (a later point replaces it only
  /// when strictly larger); a point with the run's largest excess m lies in a lane whose largest is
  /// m, so the first such point is the smallest of those lanes' first points.  The last, partial
  /// block repeats the last inner point in its spare lanes, which changes neither the largest
  /// excess nor the first point that has it.
  template <class Direction>
  EDGEPLANE_INLINE int worst_lanes(image_view<const float> depth, projector proj, int x0, int y0, int len) const {
    constexpr int lanes = 16;
    const int x1 = x0 + (len - 1) * Direction::dx, y1 = y0 + (len - 1) * Direction::dy;
    const point3 a = proj(x0, y0, depth(x0, y0)), b = proj(x1, y1, depth(x1, y1));
    const float chord_tol = t_line * norm(b - a);
    const std::ptrdiff_t step = depth.pitch * std::ptrdiff_t(Direction::dy) + Direction::dx;
    const float* const z0 = &depth(x0, y0);
    const int last = len - 2;  // the inner points are 1..last
    // point j of the block at k: k + j, or `last` beyond it.  Computed where used, not kept in
    // an array: g++ writes such an array lane by lane, and the vector read that follows would wait
    // for those stores.
    const auto point = [last](int k, int j) { return k + j < last ? k + j : last; };
    const auto gather = [&](int k, float* zl) {
      for (int j = 0; j < lanes; ++j) zl[j] = z0[point(k, j) * step];
    };
    const auto excess_at = [&](int k, float z) {
      return excess(proj(x0 + k * Direction::dx, y0 + k * Direction::dy, z), z, a, b, chord_tol);
    };
    if (last < 1) return -1;
    int at[lanes] = {};
    float zl[lanes], most[lanes] = {};
    // A block whose points all lie surely within their tolerance (num < l2 tol^2 (1 - 1e-4), with
    // num = |(p - a) x (b - a)|^2 and l2 = |b - a|^2: then the excess, num / l2 and its square root
    // rounded, is negative) cannot raise the largest excess above 0, and no point of it can be the
    // worst: it is skipped without the division and square root.  (num and l2 are the very floats
    // the exact path computes; the margin covers the rounding of the other five operations.)
    // Degenerate chords (l2 = 0), tolerances whose square is not a normal float, huge bounds and
    // NaN fail the test and take the exact path.
    const point3 ab = b - a;
    const float l2 = dot(ab, ab);
    for (int k = 1; k <= last; k += lanes) {
      gather(k, zl);
      unsigned doubt = 0;
      for (int j = 0; j < lanes; ++j) {
        const float z = zl[j];
        const int kj = point(k, j);
        const point3 ap = proj(x0 + kj * Direction::dx, y0 + kj * Direction::dy, z) - a;
        const point3 c = cross(ap, ab);
        const float tol = chord_tol + noise_k * sigma(z);
        const float bound = l2 * (tol * tol);
        doubt |= static_cast<unsigned>(!((tol >= 1e-15f) & (bound < 1e30f) & (dot(c, c) < bound * 0.9999f)));
      }
      if (!doubt) continue;
      for (int j = 0; j < lanes; ++j) {
        const int kj = point(k, j);
        const float e = excess_at(kj, zl[j]);
        const bool up = e > most[j];
        most[j] = up ? e : most[j];
        at[j] = up ? kj : at[j];
      }
    }
    float m = 0.f;
    for (int j = 0; j < lanes; ++j) m = most[j] > m ? most[j] : m;
    if (!(m > 0.f)) return -1;
    int worst = last + 1;
    for (int j = 0; j < lanes; ++j) worst = most[j] == m && at[j] < worst ? at[j] : worst;
    return worst;
  }
};

/// Walks diagonal i; marks covered(x, y) = 1 on every pixel of every kept run (`covered` starts
/// all 0: extract_segments clears it).  A run that fails
/// the line test is split at its worst point (that point dropped) and both parts are tested again
/// (at most `max_splits` times per run), so one undetected crease does not lose a whole run.
/// HostLanes (host backends): the line test by line_test::worst_lanes, which gives the same answers.
template <class Direction, bool HostLanes = false>
struct diagonal_runs_kernel {
  image_view<const float> depth;
  image_view<const std::uint8_t> mask;  // 1 = edge or invalid
  image_view<std::uint8_t> covered;
  projector proj;
  int t_length;
  int max_splits;
  line_test test;

  EDGEPLANE_HD void keep(int x0, int y0, int len) const {
    // through a local pointer and step: a byte store may alias anything, so with covered(x, y)
    // the compiler reloaded the view's pointer and pitch for every pixel
    std::uint8_t* const p = &covered(x0, y0);
    const std::ptrdiff_t step = covered.pitch * std::ptrdiff_t(Direction::dy) + Direction::dx;
    for (int k = 0; k < len; ++k) p[k * step] = 1;
  }

  /// Tests run (x0, y0, len) and its split parts.
  EDGEPLANE_HOST_CLONES EDGEPLANE_HD void process(int x0, int y0, int len) const {
    constexpr int stack_size = 16;
    int sx[stack_size], sy[stack_size], sl[stack_size];
    int top = 0, splits = 0;
    sx[top] = x0;
    sy[top] = y0;
    sl[top] = len;
    ++top;
    while (top > 0) {
      --top;
      const int ax = sx[top], ay = sy[top], al = sl[top];
      if (al <= t_length) continue;
      int w;
#if !defined(__CUDA_ARCH__)
      if constexpr (HostLanes)
        w = test.template worst_lanes<Direction>(depth, proj, ax, ay, al);
      else
#endif
        w = test(depth, proj, ax, ay, al, Direction{});
      if (w < 0) {
        keep(ax, ay, al);
        continue;
      }
      if (splits >= max_splits || top + 2 > stack_size) continue;
      ++splits;
      sx[top] = ax;
      sy[top] = ay;
      sl[top] = w;
      ++top;
      sx[top] = ax + (w + 1) * Direction::dx;
      sy[top] = ay + (w + 1) * Direction::dy;
      sl[top] = al - w - 1;
      ++top;
    }
  }

  EDGEPLANE_HD void operator()(std::int64_t i) const {
    int x, y;
    diagonal_start<Direction>(depth.width, depth.height, i, x, y);
    int rx = 0, ry = 0, len = 0;
    while (depth.contains(x, y)) {
      const std::uint8_t m = mask(x, y);
      if (m == 0) {
        if (len == 0) {
          rx = x;
          ry = y;
        }
        ++len;
      } else if (len > 0) {
        process(rx, ry, len);
        len = 0;
      }
      x += Direction::dx;
      y += Direction::dy;
    }
    if (len > 0) process(rx, ry, len);
  }
};

/// The device walk: one work item per pixel, which does something only where a run starts (a
/// pixel off the mask whose predecessor along the diagonal is on the mask or outside the image):
/// it finds the run's end and processes the run.  The same runs as diagonal_runs_kernel's walk, so
/// the same covered pixels (runs do not overlap, and each writes only its own pixels), with as many
/// work items in flight as there are runs rather than diagonals: a GPU walking one diagonal per
/// thread kept a few hundred threads busy, each for a whole diagonal (2.2 ms a pass at 512x424 on
/// an H200).
template <class Direction>
struct run_starts_kernel {
  diagonal_runs_kernel<Direction, false> walk;
  EDGEPLANE_HD void operator()(int x, int y) const {
    if (walk.mask(x, y) != 0) return;
    const int px = x - Direction::dx, py = y - Direction::dy;
    if (walk.depth.contains(px, py) && walk.mask(px, py) == 0) return;  // not the run's first pixel
    int len = 1;
    for (int cx = x + Direction::dx, cy = y + Direction::dy; walk.depth.contains(cx, cy) && walk.mask(cx, cy) == 0;
         cx += Direction::dx, cy += Direction::dy)
      ++len;
    walk.process(x, y, len);
  }
};

/// The host walk: one work item walks L adjacent diagonals together, row by row, so that each row
/// step reads the L lanes' mask bytes from one place (lane j of diagonal k0 + j lies at column
/// xb(y) + j of row y) instead of one cache line per pixel and diagonal, and finds the lanes whose
/// run ends or starts as bits (8 mask bytes at a time where L is a multiple of 8).  A lane's run
/// ends at a mask pixel or where its diagonal leaves the image (lanes outside it read as mask), and
/// goes to walk.process as diagonal_runs_kernel::operator() sends it: the same runs, in another
/// order, each writing only its own pixels of `covered`.
template <class Direction, int L>
struct diagonal_block_runs_kernel {
  static constexpr bool even_work = true;  // see detail::even_work_v
  static_assert(L >= 1 && L <= 32, "one bit per lane in an unsigned");
  diagonal_runs_kernel<Direction, true> walk;
  /// Work item i walks block i % blocks over band i / blocks of `bands` bands of rows (band b:
  /// rows [b h / bands, (b + 1) h / bands)).  A band's item takes the runs that start in its
  /// rows, walking past the band's last row until they end, and leaves those open at its first
  /// row (their pixel on the row above is off the mask) to the band above.  Items run band after
  /// band, so each core walks the rows the row-wise passes before it (which split rows the same
  /// way) left in its cache.
  std::int64_t blocks = 1;
  int bands = 1;

  /// Column of block k0's lane 0 at row y.
  int lane0_x(int k0, int y) const { return Direction::dx == 1 ? k0 - (walk.depth.height - 1) + y : k0 - y; }

  EDGEPLANE_HOST_CLONES void operator()(std::int64_t item) const {
    const int w = walk.depth.width, h = walk.depth.height;
    const std::int64_t block = item % blocks;
    const int band = static_cast<int>(item / blocks);
    const int k0 = static_cast<int>(block * L);
    // the rows where some lane's diagonal is inside the image
    int ylo, yhi;
    if constexpr (Direction::dx == 1) {  // k = x - y + (h - 1)
      ylo = std::max(0, h - 1 - (k0 + L - 1));
      yhi = std::min(h - 1, w + h - 2 - k0);
    } else {  // k = x + y
      ylo = std::max(0, k0 - w + 1);
      yhi = std::min(h - 1, k0 + L - 1);
    }
    const int blo = static_cast<int>(static_cast<std::int64_t>(h) * band / bands);
    const int bhi = static_cast<int>(static_cast<std::int64_t>(h) * (band + 1) / bands);  // first row of the next band
    const int y0 = std::max(ylo, blo);
    if (y0 > yhi || y0 >= bhi) return;
    constexpr unsigned all = L == 32 ? ~0u : (1u << L) - 1u;
    int start[L] = {};   // the first row of each lane's open run
    unsigned open = 0;  // lanes with an open run
    std::uint8_t pad[L];
    const auto end_runs = [&](unsigned ends, int y) {  // runs that ended just before row y
      for (; ends != 0; ends &= ends - 1) {
        const int j = __builtin_ctz(ends);
        walk.process(lane0_x(k0, start[j]) + j, start[j], y - start[j]);
      }
    };
    const auto edge_at = [&](int y) {  // lanes on a mask pixel (or outside the image) at row y
      const int xb = lane0_x(k0, y);
      const std::uint8_t* m = pad;
      if (xb >= 0 && xb + L <= w) {
        m = &walk.mask(xb, y);
      } else {
        for (int j = 0; j < L; ++j) pad[j] = xb + j >= 0 && xb + j < w ? walk.mask(xb + j, y) : 1;
      }
      unsigned edge = 0;
      if constexpr (L % 8 == 0) {
        for (int b = 0; b < L / 8; ++b) edge |= swar::nonzero_bytes(swar::load(m + 8 * b)) << (8 * b);
      } else {
        for (int j = 0; j < L; ++j) edge |= static_cast<unsigned>(m[j] != 0) << j;
      }
      return edge;
    };
    // lanes whose run began above the band: skipped until they meet the mask
    unsigned skip = y0 > 0 ? ~edge_at(y0 - 1) & all : 0u;
    const int yb = std::min(yhi, bhi - 1);
    for (int y = y0; y <= yb; ++y) {
      const unsigned edge = edge_at(y);
      if (const unsigned ends = edge & open) end_runs(ends, y);
      skip &= ~edge;
      for (unsigned starts = ~edge & ~open & ~skip & all; starts != 0; starts &= starts - 1) start[__builtin_ctz(starts)] = y;
      open = ~edge & ~skip & all;
    }
    // past the band: only the runs still open, until they end
    for (int y = yb + 1; y <= yhi && open != 0; ++y) {
      const unsigned edge = edge_at(y);
      if (const unsigned ends = edge & open) end_runs(ends, y);
      open &= ~edge;
    }
    end_runs(open, yhi + 1);
  }
};

}  // namespace detail

/// Extracts the kept diagonal runs along Direction (direction::left_diagonal or right_diagonal):
/// `covered` becomes 1 on their pixels, 0 elsewhere.  `mask` is the closed edge map (1 = edge or
/// invalid).  Views in the backend's memory; asynchronous on device backends.
template <class Direction, class Backend>
void extract_segments(const Backend& b, image_view<const float> depth, image_view<const std::uint8_t> mask,
                      const intrinsics& k, const params& p, image_view<std::uint8_t> covered) {
  detail::check_intrinsics(k);
  detail::check_same_size(depth, mask, "depth", "edge mask");
  detail::check_same_size(depth, covered, "depth", "covered");
  detail::diagonal_runs_kernel<Direction, Backend::host_accessible> f{
      depth, mask, covered, detail::make_projector(k), p.t_length, p.max_run_splits,
      detail::line_test{p.t_line, p.noise_k, detail::make_noise(p.noise)}};
  // cleared first, contiguously (the walks then write only the kept runs' pixels)
  if (covered.pitch == covered.width)
    b.memset(covered.data, 0, static_cast<std::size_t>(covered.width) * covered.height);
  else
    for (int y = 0; y < covered.height; ++y)
      b.memset(covered.data + static_cast<std::ptrdiff_t>(y) * covered.pitch, 0, static_cast<std::size_t>(covered.width));
  const std::int64_t n = detail::diagonal_count(depth.width, depth.height);
  // host: L diagonals over one of two bands of rows a work item, keeping 64 work items or more
  // (the CPU backend runs fewer serially); small images, a diagonal a work item.  Frames of 64
  // rows or more are walked in two bands, the top half's items first: the row passes before this
  // one left each half in the cache of the core that wrote it (segments on two cores: -7 % on
  // kinect2 scene 0, -10 % on the TUM frame; four bands were no better there).  Counting both
  // bands' items, 512x424 takes blocks of 16 diagonals and 256x212 blocks of 8 (the pipeline
  // 3 % and 2 % faster; the walk alone, without the row passes before it, is 12 % slower at
  // 256x212).
  if constexpr (Backend::host_accessible) {
    const int bands = depth.height >= 64 ? 2 : 1;
    const auto blocks = [&](int lanes) { return (n + lanes - 1) / lanes; };
    if (n * bands >= detail::host_parallel_items * 16)
      b.for_each_index(bands * blocks(16), detail::diagonal_block_runs_kernel<Direction, 16>{f, blocks(16), bands});
    else if (n * bands >= detail::host_parallel_items * 8)
      b.for_each_index(bands * blocks(8), detail::diagonal_block_runs_kernel<Direction, 8>{f, blocks(8), bands});
    else if (n * bands >= detail::host_parallel_items * 4)
      b.for_each_index(bands * blocks(4), detail::diagonal_block_runs_kernel<Direction, 4>{f, blocks(4), bands});
    else
      b.for_each_index(n, f);
  } else {
    // device: a work item per pixel, the runs processed in parallel (run_starts_kernel)
    detail::for_each_pixel(b, depth.width, depth.height, detail::run_starts_kernel<Direction>{f});
  }
}

}  // namespace edgeplane
