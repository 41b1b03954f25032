// edgeplane: per-label statistics as reductions.  Moments are accumulated in 64-bit integers of a
// fixed-point unit (0.1 mm): integer sums are exact whatever the order of the additions, so the
// statistics, and every decision taken on them, are identical across threads and backends.
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "edgeplane/backend/atomic.hpp"
#include "edgeplane/camera.hpp"
#include "edgeplane/config.hpp"
#include "edgeplane/detail/geometry.hpp"
#include "edgeplane/error.hpp"
#include "edgeplane/image.hpp"

namespace edgeplane {

/// Per-label accumulator layout (backend memory): moment_slots uint64 per label, then 4 int32
/// (bounding box min x, min y, max x, max y) per label in a separate array.
inline constexpr int moment_slots = 11;  // points, x, y, z, xx, xy, xz, yy, yz, zz, labelled pixels
inline constexpr double fixed_per_metre = 1e4;

/// The largest depth (metres) whose points the fixed-point moments of a w x h image hold exactly
/// under intrinsics k.  One label may cover every pixel, so w * h squared coordinates, in units of
/// 1 / fixed_per_metre, must stay below 2^62; a point at depth z has coordinates up to
/// z * max(1, |u - cx| / |fx|, |v - cy| / |fy|).  For a 640x480 Kinect frame this is about 360 m;
/// for absurd intrinsics (a focal length of a thousandth of a pixel) it is tiny.  The segmenter
/// treats deeper pixels as invalid, so such frames give a well-defined (usually empty) result.
inline float fixed_point_max_depth(const intrinsics& k, int w, int h) {
  const double u = std::max(std::abs(double(k.cx)), std::abs(double(w - 1) - k.cx));
  const double v = std::max(std::abs(double(k.cy)), std::abs(double(h - 1) - k.cy));
  const double spread = std::max({1.0, u / std::abs(double(k.fx)), v / std::abs(double(k.fy))});
  const double n = std::max(1.0, double(w) * double(h));
  const double max_units = std::sqrt(4.0e18 / n) * (1.0 - 1e-6) - 2.0;  // float rounding, llrint half a unit
  const double z = max_units / fixed_per_metre / spread;
  return std::isfinite(z) ? static_cast<float>(std::min(z, 1.0e6)) : 0.f;
}

namespace detail {

/// Labels from a candidate-id image (int32, 0 = none); ids up to `above` count as none (a split
/// round refits only the candidates it added).
struct candidate_image_labels {
  image_view<const std::int32_t> cand;
  std::int32_t above = 0;
  EDGEPLANE_HD std::int32_t operator()(int x, int y) const {
    const std::int32_t c = cand(x, y);
    return c > above ? c : 0;
  }
  /// out[l] = (*this)(x + l, y) for l < L (host lanes of moments_kernel), as vector operations.
  template <int L>
  EDGEPLANE_HD EDGEPLANE_INLINE void lanes(int x, int y, std::int32_t* out) const {
    const std::int32_t* cr = &cand(x, y);
    EDGEPLANE_VECTOR_LOOP
    for (int l = 0; l < L; ++l) out[l] = cr[l] & -static_cast<std::int32_t>(cr[l] > above);
  }
};

/// A plane's equation and inlier tolerance (planes: nx, ny, nz, d per plane), held in registers.
struct plane_tolerance {
  float n0, n1, n2, d, tol;
  EDGEPLANE_HD EDGEPLANE_INLINE static plane_tolerance of(const float* planes, const float* tol, std::int32_t g) {
    const float* q = planes + 4 * g;
    return {q[0], q[1], q[2], q[3], tol[g]};
  }
  /// plane_distance(planes, g, p) <= tol[g], with plane_distance's operations
  EDGEPLANE_HD EDGEPLANE_INLINE bool holds(point3 p) const { return fabsf(n0 * p.x + n1 * p.y + n2 * p.z + d) <= tol; }
};

/// The host lanes of the inlier label sources: out[l] = decide(g, p, on, valid) for pixels x + l
/// (l < L) of row y, where g is the pixel's plane (the plane image: its candidate's merged plane,
/// table[cand], 0 for none), p its point, on whether it has a plane and valid whether its depth is.
/// Where the L pixels belong to one plane or to none (most runs: planes meet at edge pixels), its
/// coefficients are loaded once and the lanes decide in vector registers (decide's plane
/// coefficients are then loop invariants); where none has a plane, out is 0 without a decision;
/// elsewhere each lane loads its own, without branches (a lane without a plane reads entry 0 of
/// the tables, which always exists, and is off).  decide must give 0 for lanes that are off.  It
/// takes the plane's coefficients as load(g) returns them, loaded once per run in the one-plane
/// case (g++ kept their loads inside the vector loop otherwise).
template <int L, class Load, class Decide>
EDGEPLANE_HD EDGEPLANE_INLINE void inlier_lanes(image_view<const std::uint16_t> plane, image_view<const float> depth,
                                                projector proj, int x, int y, std::int32_t* out, Load load,
                                                Decide decide) {
  std::int32_t g[L];  // widened from one copy of the L labels, as image_labels::lanes does (calling
                      // it here made g++ emit other code, and the refit 1-4 % slower)
  {
    std::uint16_t v[L];
    std::memcpy(v, &plane(x, y), sizeof v);
    for (int l = 0; l < L; ++l) g[l] = v[l];
  }
  std::int32_t g0 = g[0];  // the largest plane, and whether every other lane has it or none
  EDGEPLANE_VECTOR_LOOP
  for (int l = 0; l < L; ++l) g0 = g[l] > g0 ? g[l] : g0;
  if (g0 == 0) {
    for (int l = 0; l < L; ++l) out[l] = 0;
    return;
  }
  std::int32_t others = 0;
  EDGEPLANE_VECTOR_LOOP
  for (int l = 0; l < L; ++l) others |= (g[l] != g0) & (g[l] != 0);
  const float* zr = &depth(x, y);
  if (others) {
    for (int l = 0; l < L; ++l) {
      const float z = zr[l];
      out[l] = decide(g[l], load(g[l]), proj(x + l, y, z), g[l] != 0, z > 0.f);
    }
    return;
  }
  const auto coefficients = load(g0);
  EDGEPLANE_VECTOR_LOOP  // (completely unrolled first, g++ 12 left this loop scalar)
  for (int l = 0; l < L; ++l) {
    const float z = zr[l];
    out[l] = decide(g0, coefficients, proj(x + l, y, z), g[l] != 0, z > 0.f);
  }
}

/// Inliers of merged candidates: pixel i counts for its plane g = plane(i) (the merged plane of its
/// candidate, 0 for none) only when its point lies within tol[g] metres of that plane (planes: nx,
/// ny, nz, d per plane, index 0 unused).  Used to refit planes without the rim pixels a candidate
/// picks up at creases.
struct inlier_labels {
  image_view<const std::uint16_t> plane;
  const float* planes;
  const float* tol;
  image_view<const float> depth;
  projector proj;
  EDGEPLANE_HD std::int32_t operator()(int x, int y) const {
    const std::int32_t g = plane(x, y);
    const float z = depth(x, y);
    if (g == 0 || !(z > 0.f)) return 0;
    const point3 p = proj(x, y, z);
    return plane_distance(planes, g, p) <= tol[g] ? g : 0;
  }
  /// out[l] = (*this)(x + l, y) for l < L (host lanes of moments_kernel; inlier_lanes).
  template <int L>
  EDGEPLANE_HD EDGEPLANE_INLINE void lanes(int x, int y, std::int32_t* out) const {
    inlier_lanes<L>(
        plane, depth, proj, x, y, out, [&](std::int32_t g) { return plane_tolerance::of(planes, tol, g); },
        [](std::int32_t g, const plane_tolerance& q, point3 p, bool on, bool valid) {
          return g & -static_cast<std::int32_t>(on & valid & q.holds(p));  // by bits: with ?: g++ branched per lane
        });
  }
};

/// The pixels whose inlier_labels membership differs between two plane sets (the robust refit's
/// passes: `before_*` the previous pass's planes and tolerances, `planes` and `tol` this pass's):
/// g where the pixel is an inlier of its plane g = plane(i) now and was not, g + num_planes where
/// it was and is no longer, 0 elsewhere.  The moments of these labels turn the previous pass's
/// sums into this pass's exactly (integer sums; wrapping): new[g] = old[g] + m[g] - m[g +
/// num_planes], so a pass reads every pixel but sums only the few that changed.  Each membership
/// is decided with inlier_labels' operations, so it is the one that pass computed.  With
/// before_all, every pixel of plane g counts as having been in (the sums of the plane's
/// candidates, which also count the pixels without valid depth, in slot 10 only): the labels are
/// then g + num_planes for the pixels that are not inliers now, 0 elsewhere.
struct inlier_change_labels {
  image_view<const std::uint16_t> plane;
  const float* before_planes;
  const float* before_tol;
  const float* planes;
  const float* tol;
  std::int32_t num_planes;
  image_view<const float> depth;
  projector proj;
  bool before_all = false;
  EDGEPLANE_HD std::int32_t operator()(int x, int y) const {
    const std::int32_t g = plane(x, y);
    if (g == 0) return 0;
    const float z = depth(x, y);
    if (!(z > 0.f)) return before_all ? g + num_planes : 0;
    const point3 p = proj(x, y, z);
    const bool was = before_all || plane_distance(before_planes, g, p) <= before_tol[g];
    const bool is = plane_distance(planes, g, p) <= tol[g];
    return was == is ? 0 : is ? g : g + num_planes;
  }
  /// out[l] = (*this)(x + l, y) for l < L (host lanes of moments_kernel; inlier_lanes).
  template <int L>
  EDGEPLANE_HD EDGEPLANE_INLINE void lanes(int x, int y, std::int32_t* out) const {
    struct now_and_before {
      plane_tolerance now, before;
    };
    const std::int32_t gone = num_planes;
    if (before_all) {  // every pixel of a plane was in: no previous plane to test
      inlier_lanes<L>(
          plane, depth, proj, x, y, out, [&](std::int32_t g) { return plane_tolerance::of(planes, tol, g); },
          [gone](std::int32_t g, const plane_tolerance& q, point3 p, bool on, bool valid) {
            return (g + gone) & -static_cast<std::int32_t>(on & !(valid & q.holds(p)));
          });
      return;
    }
    inlier_lanes<L>(
        plane, depth, proj, x, y, out,
        [&](std::int32_t g) {
          return now_and_before{plane_tolerance::of(planes, tol, g), plane_tolerance::of(before_planes, before_tol, g)};
        },
        [gone](std::int32_t g, const now_and_before& q, point3 p, bool on, bool valid) {
          const bool is = on & valid & q.now.holds(p), was = on & valid & q.before.holds(p);
          return (g & -static_cast<std::int32_t>(is & !was)) | ((g + gone) & -static_cast<std::int32_t>(was & !is));
        });
  }
  /// Few pixels change membership: lanes<L>, and whether any of the L labels is not 0 (the host
  /// moments then skip L pixels at once; has_sparse_lanes).
  template <int L>
  EDGEPLANE_HD EDGEPLANE_INLINE bool sparse_lanes(int x, int y, std::int32_t* out) const {
    lanes<L>(x, y, out);
    std::int32_t any = 0;
    EDGEPLANE_VECTOR_LOOP
    for (int l = 0; l < L; ++l) any |= out[l];
    return any != 0;
  }
};

/// Pixels the host moments test at once for a sparse label source (runs of 16 left the merge stage
/// 4-10 % slower, of 64 10-18 %).
inline constexpr int sparse_run = 32;
/// Whether a label source has sparse_lanes<sparse_run>(x, y, out): its labels are mostly 0, and
/// the host moments test sparse_run of them at once before looking at each.
template <class Labels, class = void>
inline constexpr bool has_sparse_lanes = false;
template <class Labels>
inline constexpr bool has_sparse_lanes<
    Labels,
    std::enable_if_t<std::is_same_v<decltype(std::declval<const Labels&>().template sparse_lanes<sparse_run>(0, 0, nullptr)), bool>>> =
    true;

/// Whether a label source has columns(y, x0, x1): it narrows [x0, x1) (the whole row on entry) to
/// the columns of row y that can hold its labels, the only ones the host moments read.
template <class Labels, class = void>
inline constexpr bool has_column_spans = false;
template <class Labels>
inline constexpr bool has_column_spans<
    Labels, std::void_t<decltype(std::declval<const Labels&>().columns(0, std::declval<int&>(), std::declval<int&>()))>> =
    true;

/// Whether a label source has lanes<L>(x, y, out) (the host's moments lanes use it).
template <class Labels, class = void>
inline constexpr bool has_label_lanes = false;
template <class Labels>
inline constexpr bool has_label_lanes<Labels, decltype(std::declval<const Labels&>().template lanes<8>(0, 0, nullptr))> = true;

/// Labels from a label image (0 = none).
struct image_labels {
  image_view<const std::uint16_t> labels;
  EDGEPLANE_HD std::int32_t operator()(int x, int y) const { return labels(x, y); }
  /// out[l] = (*this)(x + l, y) for l < L (host lanes of moments_kernel): the L labels read in
  /// one copy, then widened (read one by one, g++ assembled them through 2-byte stack stores that
  /// the next wider load had to wait for).
  template <int L>
  EDGEPLANE_HD EDGEPLANE_INLINE void lanes(int x, int y, std::int32_t* out) const {
    std::uint16_t v[L];
    std::memcpy(v, &labels(x, y), sizeof v);
    for (int l = 0; l < L; ++l) out[l] = v[l];
  }
};

/// llrint(double(v) * fixed_per_metre): the fixed-point coordinate of v metres.  On the host it is
/// computed without the library call (which g++ does not inline, and which keeps the loop scalar):
/// adding 1.5 * 2^52 rounds s = v * 1e4 to an integer in the current rounding mode, exactly as
/// llrint does, and for |s| < 2^51 the sum's bit pattern minus that of 1.5 * 2^52 is the integer.
/// fixed_point_max_depth keeps every coordinate far below 2^51 units (2^31 at most); the two
/// operations stay separate (the library compiles with -ffp-contract=off).
EDGEPLANE_HD EDGEPLANE_INLINE std::int64_t to_fixed(float v) {
#if defined(__CUDA_ARCH__)
  return static_cast<std::int64_t>(llrint(static_cast<double>(v) * fixed_per_metre));
#else
  const double r = static_cast<double>(v) * fixed_per_metre + 0x1.8p52;
  std::uint64_t bits;
  std::memcpy(&bits, &r, sizeof bits);
  return static_cast<std::int64_t>(bits - 0x4338000000000000ull);
#endif
}

/// The product of two fixed-point coordinates (as their uint64 two's complement bits), modulo
/// 2^64.  fixed_point_max_depth keeps every coordinate within +-2^31, so the product of their low
/// 32 bits as signed integers is the exact product: one 32 x 32 -> 64-bit multiply, which vector
/// units have (a full 64-bit multiply they have not, or only slowly).
EDGEPLANE_HD EDGEPLANE_INLINE std::uint64_t mul_fixed(std::uint64_t a, std::uint64_t b) {
  return static_cast<std::uint64_t>(static_cast<std::int64_t>(static_cast<std::int32_t>(a)) *
                                    static_cast<std::int32_t>(b));
}

/// One work item per `block` rows (rows row0 .. row_end - 1): accumulates the moments of the
/// pixels of one label locally and hands them on when another label begins.  Unlabelled pixels
/// (label 0) between pixels of one label do not end its run: a plane's scattered outliers or holes
/// then cost no hand-over.  The bounding box is that of the label's pixels in the run.  Device
/// backends add each run's sums to the label's counters with atomics (a row holds few labels, so
/// few atomics).  Host backends keep the sums of the last few labels of the work item in a small
/// table and add them to the counters when an entry is evicted and at the item's end: a block of
/// rows sees the same few labels over and over, and on two cores the label's counters would
/// otherwise move between the cores' caches at every run.  Sums are kept as uint64 (two's
/// complement: wrapping, so the order of additions cannot matter, and the totals fit an int64 by
/// fixed_point_max_depth).  On the host, runs of 8 pixels whose labels are the current one or 0
/// are summed lane by lane (vectorizable), a stretch of such blocks at a time (sum_stretch).
/// Second = false leaves the second-order slots (4..9) at 0: the sums of a centroid and counts.
template <class Labels, bool Second = true>
struct moments_kernel {
  image_view<const float> depth;
  Labels label_of;
  projector proj;
  std::int32_t num_labels;
  std::uint64_t* moments;  // (num_labels + 1) * moment_slots; slot block of label L at L * moment_slots
  std::int32_t* bbox;      // (num_labels + 1) * 4
  int row0 = 0;            // work item k covers rows row0 + k * block .. (before row_end)
  int row_end = 0;
  int block = 1;

  static constexpr int lanes = 8;

  // adds sums s and box [x0, x1] x [y0, y1] of label l to its counters
  EDGEPLANE_HD void publish(std::int32_t l, const std::uint64_t* s, int x0, int y0, int x1, int y1) const {
    if (l <= 0 || l > num_labels) return;
    std::uint64_t* m = moments + static_cast<std::int64_t>(l) * moment_slots;
    for (int k = 0; k < moment_slots; ++k)
      if (s[k] != 0) atomic_add(m + k, s[k]);
    std::int32_t* bb = bbox + static_cast<std::int64_t>(l) * 4;
    atomic_min(bb + 0, x0);
    atomic_min(bb + 1, y0);
    atomic_max(bb + 2, x1);
    atomic_max(bb + 3, y1);
  }
  // hand-over to the counters at once (device backends)
  struct direct {
    const moments_kernel* k;
    EDGEPLANE_HD explicit direct(const moments_kernel* kernel) : k(kernel) {}
    EDGEPLANE_HD void operator()(std::int32_t l, const std::uint64_t* s, int x0, int x1, int y) const {
      k->publish(l, s, x0, y, x1, y);
    }
    EDGEPLANE_HD void drain() {}
  };
  // hand-over to a table of the work item's last `entries` labels (host backends)
  struct table {
    static constexpr int entries = 8;
    const moments_kernel* k;
    std::int32_t label[entries];
    std::uint64_t sums[entries][moment_slots];
    int box[entries][4];
    int used = 0, next = 0;
    explicit table(const moments_kernel* kernel) : k(kernel) {}
    void operator()(std::int32_t l, const std::uint64_t* s, int x0, int x1, int y) {
      if (l <= 0 || l > k->num_labels) return;
      int e = 0;
      while (e < used && label[e] != l) ++e;
      if (e == used) {
        if (used < entries) {
          ++used;
        } else {  // evict the entries in turn
          e = next;
          next = (next + 1) % entries;
          k->publish(label[e], sums[e], box[e][0], box[e][1], box[e][2], box[e][3]);
        }
        label[e] = l;
        for (int j = 0; j < moment_slots; ++j) sums[e][j] = 0;
        box[e][0] = x0;
        box[e][1] = y;
        box[e][2] = x1;
        box[e][3] = y;
      }
      for (int j = 0; j < moment_slots; ++j) sums[e][j] += s[j];
      box[e][0] = x0 < box[e][0] ? x0 : box[e][0];
      box[e][1] = y < box[e][1] ? y : box[e][1];
      box[e][2] = x1 > box[e][2] ? x1 : box[e][2];
      box[e][3] = y > box[e][3] ? y : box[e][3];
    }
    void drain() {
      for (int e = 0; e < used; ++e) k->publish(label[e], sums[e], box[e][0], box[e][1], box[e][2], box[e][3]);
      used = 0;
    }
  };

  // pixel (x, y) of label l > 0 into the sums s
  EDGEPLANE_HD EDGEPLANE_INLINE void add(std::uint64_t* s, int x, int y) const {
    s[10] += 1;
    const float z = depth(x, y);
    if (!(z > 0.f)) return;
    const point3 p = proj(x, y, z);
    const auto px = static_cast<std::uint64_t>(to_fixed(p.x)), py = static_cast<std::uint64_t>(to_fixed(p.y)),
               pz = static_cast<std::uint64_t>(to_fixed(p.z));
    s[0] += 1;
    s[1] += px;
    s[2] += py;
    s[3] += pz;
    if constexpr (!Second) return;
    s[4] += mul_fixed(px, px);
    s[5] += mul_fixed(px, py);
    s[6] += mul_fixed(px, pz);
    s[7] += mul_fixed(py, py);
    s[8] += mul_fixed(py, pz);
    s[9] += mul_fixed(pz, pz);
  }

  // pixel x of label l of the scalar path: a label other than 0 and the current one hands over
  // the current run (its pixels span x0 .. x1) and starts its own
  template <class Out>
  EDGEPLANE_HD EDGEPLANE_INLINE void step(Out& flush, std::uint64_t* s, std::int32_t& cur, int& x0, int& x1,
                                          std::int32_t l, int x, int y) const {
    if (l == 0) return;
    if (l != cur) {
      flush(cur, s, x0, x1, y);
      for (int k = 0; k < moment_slots; ++k) s[k] = 0;
      cur = l;
      x0 = x;
    }
    x1 = x;
    if (l > 0) add(s, x, y);
  }

  EDGEPLANE_HOST_CLONES EDGEPLANE_HD void operator()(std::int64_t item) const {
    const int y0 = row0 + static_cast<int>(item) * block, y1 = y0 + block < row_end ? y0 + block : row_end;
#if !defined(__CUDA_ARCH__)
    table out(this);
#else
    direct out(this);
#endif
    for (int y = y0; y < y1; ++y) row(y, out);
    out.drain();
  }

  /// Pixels [xa, xb) of row y, one at a time (device backends' work item: see moments_spans_kernel).
  template <class Out>
  EDGEPLANE_HD void span(int y, int xa, int xb, Out& flush) const {
    std::uint64_t s[moment_slots] = {};
    std::int32_t cur = 0;
    int x0 = 0, x1 = 0;
    for (int x = xa; x < xb; ++x) step(flush, s, cur, x0, x1, label_of(x, y), x, y);
    flush(cur, s, x0, x1, y);
  }

#if !defined(__CUDA_ARCH__)
  // Host lanes of the row pass: the labels of pixels x .. x + lanes - 1 of row y.
  EDGEPLANE_INLINE void load_lanes(int x, int y, std::int32_t* lab) const {
    if constexpr (has_label_lanes<Labels>) {
      label_of.template lanes<lanes>(x, y, lab);
    } else {
      for (int l = 0; l < lanes; ++l) lab[l] = label_of(x + l, y);
    }
  }
  static EDGEPLANE_INLINE bool labelled(const std::int32_t* lab) {
    unsigned any = 0;
    for (int l = 0; l < lanes; ++l) any |= static_cast<unsigned>(lab[l] != 0);
    return any != 0;
  }
  // every pixel of label cur or unlabelled
  static EDGEPLANE_INLINE bool of_run(const std::int32_t* lab, std::int32_t cur) {
    bool same = true;
    for (int l = 0; l < lanes; ++l) same &= (lab[l] == cur) | (lab[l] == 0);
    return same;
  }
  // From block x (labels lab, of label cur or unlabelled, one labelled at least) on, while the
  // blocks are so: their pixels of label cur summed lane by lane (vectorizable) into lane sums
  // local to this stretch, which the compiler keeps in registers (no call, no other path inside),
  // then added to s (slots 0..9; slot 10 counts the labelled pixels); x1 = the last labelled
  // pixel.  Returns the first block not taken (or the row's last whole block's end).
  // (w: the end of the row's columns to read)
  EDGEPLANE_INLINE int sum_stretch(int x, int y, std::int32_t cur, std::int32_t* lab, int& x1,
                                   std::uint64_t* s, int w) const {
    std::uint64_t a[10][lanes] = {};
    std::uint64_t count = 0;
    for (;;) {
      const float* zr = &depth(x, y);
      for (int l = 0; l < lanes; ++l) {
        const float z = zr[l];
        const std::uint64_t on = static_cast<std::uint64_t>(lab[l] == cur);
        const std::uint64_t m = static_cast<std::uint64_t>(0) - (on & static_cast<std::uint64_t>(z > 0.f));
        const point3 p = proj(x + l, y, z);
        const std::uint64_t px = static_cast<std::uint64_t>(to_fixed(p.x)) & m,
                            py = static_cast<std::uint64_t>(to_fixed(p.y)) & m,
                            pz = static_cast<std::uint64_t>(to_fixed(p.z)) & m;
        count += on;
        a[0][l] += m & 1u;
        a[1][l] += px;
        a[2][l] += py;
        a[3][l] += pz;
        if constexpr (Second) {
          a[4][l] += mul_fixed(px, px);
          a[5][l] += mul_fixed(px, py);
          a[6][l] += mul_fixed(px, pz);
          a[7][l] += mul_fixed(py, py);
          a[8][l] += mul_fixed(py, pz);
          a[9][l] += mul_fixed(pz, pz);
        }
      }
      for (int l = lanes - 1; l >= 0; --l)
        if (lab[l] != 0) {
          x1 = x + l;
          break;
        }
      x += lanes;
      if (x + lanes > w) break;
      load_lanes(x, y, lab);
      if (!labelled(lab) || !of_run(lab, cur)) break;
    }
    for (int k = 0; k < 10; ++k)
      for (int l = 0; l < lanes; ++l) s[k] += a[k][l];
    s[10] += count;
    return x;
  }
#endif

  template <class Out>
  EDGEPLANE_HD EDGEPLANE_INLINE void row(int y, Out& flush) const {
    int x = 0, w = depth.width;  // (w: the end of the columns read)
#if !defined(__CUDA_ARCH__)
    if constexpr (has_column_spans<Labels>) label_of.columns(y, x, w);
#endif
    std::uint64_t s[moment_slots] = {};
    std::int32_t cur = 0;
    int x0 = 0, x1 = 0;
#if !defined(__CUDA_ARCH__)
    if constexpr (has_sparse_lanes<Labels>) {  // runs without a label skipped at once
      constexpr int S = sparse_run;
      for (; x + S <= w; x += S) {
        std::int32_t lab[S];
        if (!label_of.template sparse_lanes<S>(x, y, lab)) continue;
        for (int l = 0; l < S; ++l) step(flush, s, cur, x0, x1, lab[l], x + l, y);
      }
    }
    for (; x + lanes <= w;) {
      std::int32_t lab[lanes];
      load_lanes(x, y, lab);
      if (!labelled(lab)) {
        x += lanes;
        continue;
      }
      if (of_run(lab, cur)) {
        x = sum_stretch(x, y, cur, lab, x1, s, w);
        continue;
      }
      for (int l = 0; l < lanes; ++l) step(flush, s, cur, x0, x1, lab[l], x + l, y);
      x += lanes;
    }
#endif
    for (; x < w; ++x) step(flush, s, cur, x0, x1, label_of(x, y), x, y);
    flush(cur, s, x0, x1, y);
  }
};

/// The moments on device backends: one work item per span of `width` pixels of a row, each
/// handing its runs' sums to the counters at once (moments_kernel::direct).  Sums are exact
/// integers and boxes minima and maxima, so any split of the rows gives the same totals.  (A work
/// item per row kept a GPU's few hundred threads walking 512 pixels each: 0.3 ms a call at
/// 512x424 on an H200, five or more calls a frame.)
template <class Labels, bool Second = true>
struct moments_spans_kernel {
  static constexpr int width = 32;
  moments_kernel<Labels, Second> m;
  int spans;  // per row
  EDGEPLANE_HD void operator()(std::int64_t item) const {
    const int y = m.row0 + static_cast<int>(item / spans), xa = static_cast<int>(item % spans) * width;
    const int xb = xa + width < m.depth.width ? xa + width : m.depth.width;
    typename moments_kernel<Labels, Second>::direct out(&m);
    m.span(y, xa, xb, out);
  }
};

struct bbox_init_kernel {
  std::int32_t* bbox;
  EDGEPLANE_HD void operator()(std::int64_t i) const {
    bbox[4 * i + 0] = 0x7fffffff;
    bbox[4 * i + 1] = 0x7fffffff;
    bbox[4 * i + 2] = -1;
    bbox[4 * i + 3] = -1;
  }
};

}  // namespace detail

/// Least-squares plane of a set of points, from its moments.
struct plane_fit {
  std::int64_t points = 0;   ///< valid 3-D points
  std::int64_t pixels = 0;   ///< labelled pixels (includes pixels without valid depth)
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();  ///< metres
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();    ///< unit, pointing toward the camera
  double d = 0;                                        ///< n . X + d = 0, d >= 0
  Eigen::Vector3d eigenvalues = Eigen::Vector3d::Zero();  ///< l1 >= l2 >= l3 (m^2)
  std::array<int, 4> bbox{0, 0, -1, -1};                  ///< min x, min y, max x, max y (pixels)
};

/// The counts, bounding box and centroid of one label from its moment block (host memory), which
/// need only the first-order slots (accumulate_first_moments); normal, d and eigenvalues stay 0.
/// The centroid is set from 3 points on (fit_plane's, exactly).
inline plane_fit centroid_fit(const std::uint64_t* m, const std::int32_t* bb = nullptr) {
  plane_fit f;
  auto v = [&](int k) { return static_cast<double>(static_cast<std::int64_t>(m[k])); };
  f.points = static_cast<std::int64_t>(m[0]);
  f.pixels = static_cast<std::int64_t>(m[10]);
  if (bb) f.bbox = {bb[0], bb[1], bb[2], bb[3]};
  if (f.points < 3) return f;
  const double n = v(0), s = 1.0 / fixed_per_metre;
  f.centroid = Eigen::Vector3d(v(1) / n, v(2) / n, v(3) / n) * s;
  return f;
}

/// Fits the plane of one label from its moment block (host memory).
inline plane_fit fit_plane(const std::uint64_t* m, const std::int32_t* bb = nullptr) {
  plane_fit f = centroid_fit(m, bb);
  if (f.points < 3) return f;
  auto v = [&](int k) { return static_cast<double>(static_cast<std::int64_t>(m[k])); };
  const double n = v(0), s = 1.0 / fixed_per_metre;
  const Eigen::Vector3d mean(v(1) / n, v(2) / n, v(3) / n);
  Eigen::Matrix3d c;
  c(0, 0) = v(4) / n - mean.x() * mean.x();
  c(0, 1) = c(1, 0) = v(5) / n - mean.x() * mean.y();
  c(0, 2) = c(2, 0) = v(6) / n - mean.x() * mean.z();
  c(1, 1) = v(7) / n - mean.y() * mean.y();
  c(1, 2) = c(2, 1) = v(8) / n - mean.y() * mean.z();
  c(2, 2) = v(9) / n - mean.z() * mean.z();
  c *= s * s;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(c);
  // ascending eigenvalues
  f.eigenvalues = Eigen::Vector3d(es.eigenvalues()(2), es.eigenvalues()(1), std::max(0.0, es.eigenvalues()(0)));
  f.normal = es.eigenvectors().col(0).normalized();
  if (f.normal.dot(f.centroid) > 0) f.normal = -f.normal;
  f.d = -f.normal.dot(f.centroid);
  return f;
}

/// Accumulates the moments and bounding boxes of labels 1..num_labels (label_of(x, y) gives
/// pixel (x, y)'s label) into backend buffers `moments` ((num_labels + 1) * moment_slots) and `bbox`
/// ((num_labels + 1) * 4), which this call clears first.  Only rows [row_begin, row_end) are read
/// (row_end < 0: to the last row): for labels known to lie in those rows (host backends: and, for
/// label sources with has_column_spans, only their columns of each row).  Asynchronous on device
/// backends.  Precondition: valid depths are at most fixed_point_max_depth(k, w, h) (the
/// segmenter's depth conversion ensures it), so that the fixed-point sums are exact.
namespace detail {
template <bool Second, class Backend, class Labels>
void accumulate_moments(const Backend& b, image_view<const float> depth, const intrinsics& k, Labels label_of,
                        std::int32_t num_labels, std::uint64_t* moments, std::int32_t* bbox, int row_begin,
                        int row_end) {
  if (row_end < 0 || row_end > depth.height) row_end = depth.height;
  if (row_begin < 0) row_begin = 0;
  b.memset(moments, 0, sizeof(std::uint64_t) * moment_slots * (num_labels + 1));
  b.for_each_index(num_labels + 1, detail::bbox_init_kernel{bbox});
  if (row_end > row_begin) {
    // host backends: blocks of rows (each hands its labels' sums over once), still 64 or more
    // work items where there are that many rows (the CPU backend runs fewer items serially)
    const int rows = row_end - row_begin;
    const int block = Backend::host_accessible && rows >= 128 ? rows / 64 : 1;
    const moments_kernel<Labels, Second> m{depth, label_of, make_projector(k), num_labels, moments, bbox,
                                           row_begin, row_end, block};
    if constexpr (Backend::host_accessible) {
      b.for_each_index((rows + block - 1) / block, m);
    } else {  // device: spans of 32 pixels (moments_spans_kernel)
      constexpr int width = moments_spans_kernel<Labels, Second>::width;
      const int spans = (depth.width + width - 1) / width;
      b.for_each_index(static_cast<std::int64_t>(rows) * spans, moments_spans_kernel<Labels, Second>{m, spans});
    }
  }
}
}  // namespace detail

template <class Backend, class Labels>
void accumulate_moments(const Backend& b, image_view<const float> depth, const intrinsics& k, Labels label_of,
                        std::int32_t num_labels, std::uint64_t* moments, std::int32_t* bbox, int row_begin = 0,
                        int row_end = -1) {
  detail::accumulate_moments<true>(b, depth, k, label_of, num_labels, moments, bbox, row_begin, row_end);
}

/// accumulate_moments without the second-order sums: slots 0..3 and 10 and the boxes as it gives
/// them, slots 4..9 left 0.  For the counts, centroids and boxes of labels (centroid_fit), at
/// about two thirds of the work (no products).
template <class Backend, class Labels>
void accumulate_first_moments(const Backend& b, image_view<const float> depth, const intrinsics& k, Labels label_of,
                              std::int32_t num_labels, std::uint64_t* moments, std::int32_t* bbox, int row_begin = 0,
                              int row_end = -1) {
  detail::accumulate_moments<false>(b, depth, k, label_of, num_labels, moments, bbox, row_begin, row_end);
}

}  // namespace edgeplane
