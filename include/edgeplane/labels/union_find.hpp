// edgeplane: lock-free parallel union-find (ECL-CC: Jaiganesh and Burtscher, HPDC 2018), written
// once for host threads and CUDA devices.
//
// parent[i] == -1: element i takes no part; parent[i] == i: i is a root.  unite() hooks the larger
// of two roots onto the smaller with a compare-and-swap, so parents only ever decrease and every
// component ends up rooted at its smallest element, whatever the order of the unions: the result
// is deterministic across threads and backends.
//
// Why the races are harmless:
// - find() halves paths with plain (relaxed atomic) stores of a grandparent into parent[x].  Any
//   value stored there is an ancestor of x at some moment, and ancestors stay in x's set, so the
//   store never changes which set x is in; a lost update only leaves a longer path.
// - unite() changes a root only by CAS(parent[r], r, s) with s < r.  If another thread hooked r
//   first, the CAS fails and the loop retries from the new root; no hook is lost, and since every
//   hook points to a smaller index, no cycle can form.
// - flatten() runs after all unions (a separate launch).  It must NOT halve paths: a halving write
//   to parent[x] could land after x's own flatten stored its root and leave x pointing at a
//   non-root.  So it walks to the root with loads only and writes parent[i] alone; a concurrent
//   reader of parent[i] sees either i's old parent or its root, both of which lead to the root.
#pragma once
#include <bit>
#include <cmath>
#include <cstdint>

#include "edgeplane/backend/atomic.hpp"
#include "edgeplane/config.hpp"
#include "edgeplane/detail/swar.hpp"
#include "edgeplane/image.hpp"

namespace edgeplane {
namespace detail {

/// The index of the lowest set bit of u (u != 0), in host and device code alike (nvcc warned
/// about __builtin_ctz, a host function, in the host/device union-find kernels).
EDGEPLANE_HD EDGEPLANE_INLINE int lowest_bit(unsigned u) {
#if defined(__CUDA_ARCH__)
  return __ffs(static_cast<int>(u)) - 1;
#else
  return __builtin_ctz(u);
#endif
}

EDGEPLANE_HD inline std::int32_t uf_find(std::int32_t* parent, std::int32_t x) {
  std::int32_t p = atomic_load(parent + x);
  while (p != x) {
    const std::int32_t gp = atomic_load(parent + p);
    if (gp != p) atomic_store(parent + x, gp);  // path halving
    x = p;
    p = gp;
  }
  return x;
}

EDGEPLANE_HD inline void uf_unite(std::int32_t* parent, std::int32_t a, std::int32_t b) {
  a = uf_find(parent, a);
  b = uf_find(parent, b);
  while (a != b) {
    if (a < b) {
      const std::int32_t t = a;
      a = b;
      b = t;
    }
    // hook the larger root a onto the smaller b
    const std::int32_t old = atomic_cas(parent + a, a, b);
    if (old == a) return;
    a = uf_find(parent, old);
    b = uf_find(parent, b);
  }
}

/// parent[i] = active(i) ? i : -1.
template <class Active>
struct uf_init_kernel {
  Active active;
  std::int32_t* parent;
  EDGEPLANE_HD void operator()(std::int64_t i) const {
    parent[i] = active(i) ? static_cast<std::int32_t>(i) : -1;
  }
};

/// For pixel (x, y), unites the pairs a grid adjacency policy names (at most 4).
template <class Adjacency>
struct uf_union_grid_kernel {
  Adjacency adj;
  std::int32_t* parent;
  EDGEPLANE_HD void operator()(int x, int y) const {
    std::int32_t a[4], b[4];
    const int n = adj(x, y, a, b);
    for (int k = 0; k < n; ++k) uf_unite(parent, a[k], b[k]);
  }
};

/// Grid adjacency policies (one work item per pixel of a dense image, called as adj(x, y, a, b))
/// say so with grid_width() and grid_height(); other policies are called as adj(i, a, b).
template <class Adjacency>
inline constexpr bool is_grid_adjacency = requires(const Adjacency& a) {
  a.grid_width();
  a.grid_height();
};
/// Grid adjacencies whose pairs are exactly (x, y)-(x + 1, y) where joins_right(x, y) and
/// (x, y)-(x, y + 1) where joins_down(x, y), each implying that both elements are active: host
/// backends then link horizontal runs without atomics (uf_init_runs_kernel) and unite only
/// vertically.
template <class Adjacency>
inline constexpr bool has_grid_joins = is_grid_adjacency<Adjacency> && requires(const Adjacency& a) {
  a.joins_right(0, 0);
  a.joins_down(0, 0);
};

/// Grid-join adjacencies that also give joins_right / joins_down for L pixels of a row at once as
/// bits (right_lanes<L>(x, y): needs x + L < width; down_lanes<L>(x, y): x + L <= width and
/// y + 1 < height), computed without branches so that host row passes vectorize them.
template <class Adjacency>
inline constexpr bool has_join_lanes = has_grid_joins<Adjacency> && requires(const Adjacency& a) {
  a.template right_lanes<16>(0, 0);
  a.template down_lanes<16>(0, 0);
};

/// Blocks of 16 pixels per row whose right joins the host row passes keep (uf_init_runs_kernel's
/// right_bits): those from x = 0, 16, ... with x + 16 < w.
EDGEPLANE_HD EDGEPLANE_INLINE int join_blocks(int w) { return w > 16 ? (w - 1) / 16 : 0; }

/// Row y's span [spans[2y], spans[2y + 1]) widened to whole blocks of 16 on the left: x = the
/// first column of the block holding its first pixel, x_end = its end (both 0 where it is empty).
EDGEPLANE_HD EDGEPLANE_INLINE void span_from_block(const std::int32_t* spans, int y, int& x, int& x_end) {
  x_end = spans[2 * y] < spans[2 * y + 1] ? spans[2 * y + 1] : 0;
  x = x_end > 0 ? spans[2 * y] / 16 * 16 : 0;
}

/// The host row pass's record of its runs (uf_init_runs_kernel), for counting the components by
/// runs (uf_count_runs_kernel): len[h] = the number of elements of the run whose first element is
/// h (other entries untouched); row y's runs' first elements, in order, at heads[y * w + k] for
/// k < nheads[y] (w: the grid's width).  The three are given together or not at all.
struct row_runs {
  std::int32_t* len = nullptr;
  std::int32_t* heads = nullptr;
  std::int32_t* nheads = nullptr;
};

/// Host row pass of connected_components for adjacencies with has_grid_joins (one work item per
/// row; rows are independent): parent[i] = -1 for inactive elements, else the first element of
/// its run of horizontally joined pixels, which is the run's smallest element and its root so far.
template <class Active, class Adjacency, bool Spans = false>
struct uf_init_runs_kernel {
  Active active;
  Adjacency adj;
  std::int32_t* parent;
  /// When not null (adjacencies with has_join_lanes): row y's right joins of the 16 pixels from
  /// x, right_lanes<16>(x, y), kept at right_bits[y * join_blocks(w) + x / 16] for every block
  /// the lanes loop covers (x + 16 < w), for the vertical unions to read.
  std::uint16_t* right_bits = nullptr;
  /// Where given (runs.len not null): each run's length and row y's list of its runs' first
  /// elements (row_runs), for uf_count_runs_kernel.
  row_runs runs{};
  /// (Spans) row y's active pixels all lie in columns [spans[2y], spans[2y + 1]) (empty where
  /// the second is not above the first); the row pass reads only from the 16-pixel block holding
  /// the first of them to the last, and marks the rest inactive without testing them.  (A
  /// template flag: the pass without spans compiles as it did before them.)
  const std::int32_t* spans = nullptr;
  EDGEPLANE_HOST_CLONES EDGEPLANE_HD void operator()(std::int64_t row) const {
    const int y = static_cast<int>(row), w = adj.grid_width();
    const std::int64_t o = static_cast<std::int64_t>(y) * w;
    std::int32_t* const len = runs.len;
    std::int32_t* const heads = len ? runs.heads + o : nullptr;
    std::int32_t m = 0;  // runs listed
    std::int32_t start = -1, last = -1;  // the current run's first element, the last active one
    // a new run from element `first`; the previous run, if any, ended at element `end`
    const auto begin_run = [&](std::int32_t first, std::int32_t end) {
      if (len) {
        if (start >= 0) len[start] = end - start + 1;
        heads[m++] = first;
      }
      start = first;
    };
    bool joined = false;  // the previous pixel joins this one
    int x = 0, x_end = w;
    if constexpr (Spans) {  // the block of the span's first pixel .. its end; to its left, inactive
      span_from_block(spans, y, x, x_end);
      for (int i = 0; i < x; ++i) parent[o + i] = -1;
    }
    if constexpr (has_join_lanes<Adjacency>) {  // 16 pixels' activity and right joins as bits first
      constexpr int L = 16;
      std::uint16_t* const kept = right_bits ? right_bits + static_cast<std::int64_t>(y) * join_blocks(w) : nullptr;
      if (Spans && kept)
        for (int b = 0; b < x / L; ++b) kept[b] = 0;  // (blocks left of a span: no joins)
      for (; x + L < w && (!Spans || x < x_end); x += L) {
        unsigned act = 0;
        for (int l = 0; l < L; ++l) act |= static_cast<unsigned>(active(o + x + l)) << l;
        const unsigned right = adj.template right_lanes<L>(x, y);
        if (kept) kept[x / L] = static_cast<std::uint16_t>(right);
        // The runs starting in the block: active lanes that the lane to their left does not
        // join (a join implies both lanes active).  Each active lane's parent is the last start
        // at or before it, or the run carried in from the previous block: without branches, a
        // leading-zero count per lane (vector code where the target has one).
        const std::int32_t base = static_cast<std::int32_t>(o + x);
        const unsigned starts = act & ~((right << 1) | static_cast<unsigned>(joined));
        std::int32_t* const out = parent + o + x;
        for (int l = 0; l < L; ++l) {
          const unsigned upto = starts & ((2u << l) - 1u);
          const int hb = 31 - std::countl_zero(upto);  // the last start at or before lane l (-1: none)
          const std::int32_t p = hb >= 0 ? base + hb : start;
          out[l] = (act >> l) & 1u ? p : -1;
        }
        for (unsigned u = starts; u != 0; u &= u - 1u) {  // each new run, after the block's active lanes before it
          const int sl = lowest_bit(u);
          const unsigned before = act & ((1u << sl) - 1u);
          begin_run(base + sl, before ? base + 31 - std::countl_zero(before) : last);
        }
        if (act != 0) last = base + 31 - std::countl_zero(act);
        joined = (right >> (L - 1)) & 1u;
      }
      if (Spans && kept)
        for (int b = x / L; b < join_blocks(w); ++b) kept[b] = 0;  // (blocks right of a span)
    }
    for (; x < x_end; ++x) {
      const std::int64_t i = o + x;
      if (!active(i)) {
        parent[i] = -1;
        joined = false;
        continue;
      }
      if (!joined) begin_run(static_cast<std::int32_t>(i), last);
      parent[i] = start;
      last = static_cast<std::int32_t>(i);
      joined = adj.joins_right(x, y);
    }
    if constexpr (Spans)
      for (; x < w; ++x) parent[o + x] = -1;  // right of a span
    if (len) {
      if (start >= 0) len[start] = last - start + 1;
      runs.nheads[y] = m;
    }
  }
};
/// Then the vertical unions, one work item per row.  Host lanes skip a pair (x, y)-(x, y + 1)
/// whose left neighbours' pair joins and both join it horizontally: it is already connected through
/// them (a square of joins), so a run lying on a run is united once per block of 16 pixels, not
/// once per pixel.  The components, and so their roots (each its smallest element), are the same.
template <class Adjacency, bool Spans = false>
struct uf_union_down_kernel {
  Adjacency adj;
  std::int32_t* parent;
  const std::uint16_t* right_bits = nullptr;  // uf_init_runs_kernel's, when it kept them
  const std::int32_t* spans = nullptr;         // uf_init_runs_kernel's, when it had them
  EDGEPLANE_HOST_CLONES EDGEPLANE_HD void operator()(std::int64_t row) const {
    const int y = static_cast<int>(row), w = adj.grid_width();
    const std::int64_t o = static_cast<std::int64_t>(y) * w;
    int x = 0, x_end = w;
    if constexpr (Spans) span_from_block(spans, y, x, x_end);  // only row y's active pixels join down
    if constexpr (has_join_lanes<Adjacency>) {  // 16 pixels' joins as bits, then the unions needed
      constexpr int L = 16;
      if (y + 1 >= adj.grid_height()) return;  // no pixel joins down
      unsigned carry = 0;  // the previous block's last pixel is a square's left side (none left of a span)
      const int blocks = join_blocks(w);
      const std::uint16_t* const kept = right_bits ? right_bits + static_cast<std::int64_t>(y) * blocks : nullptr;
      for (; x + L < w && (!Spans || x < x_end); x += L) {
        const unsigned down = adj.template down_lanes<L>(x, y);
        // pixels whose pair, and the pairs to their right on both rows, all join
        unsigned right0, right1;
        if (kept) {  // rows y and y + 1
          right0 = kept[x / L];
          right1 = kept[blocks + x / L];
        } else {
          right0 = adj.template right_lanes<L>(x, y);
          right1 = adj.template right_lanes<L>(x, y + 1);
        }
        const unsigned square = down & right0 & right1;
        for (unsigned u = down & ~((square << 1) | carry); u != 0; u &= u - 1) {
          const std::int32_t i = static_cast<std::int32_t>(o + x + lowest_bit(u));
          uf_unite(parent, i, i + w);
        }
        carry = (square >> (L - 1)) & 1u;
      }
    }
    for (; x < x_end; ++x)
      if (adj.joins_down(x, y)) uf_unite(parent, static_cast<std::int32_t>(o + x), static_cast<std::int32_t>(o + x + w));
  }
};

/// For work item i, unites the pairs the adjacency policy names (at most 4).
template <class Adjacency>
struct uf_union_kernel {
  Adjacency adj;
  std::int32_t* parent;
  EDGEPLANE_HD void operator()(std::int64_t i) const {
    std::int32_t a[4], b[4];
    const int n = adj(i, a, b);
    for (int k = 0; k < n; ++k) uf_unite(parent, a[k], b[k]);
  }
};

/// Root of x by loads only (no path halving).
EDGEPLANE_HD inline std::int32_t uf_root(const std::int32_t* parent, std::int32_t x) {
  std::int32_t p = atomic_load(parent + x);
  while (p != x) {
    x = p;
    p = atomic_load(parent + x);
  }
  return x;
}

/// parent[i] = root of i (after all unions; see the note at the top on why this does not halve).
struct uf_flatten_kernel {
  std::int32_t* parent;
  EDGEPLANE_HD void operator()(std::int64_t i) const {
    if (atomic_load(parent + i) >= 0) atomic_store(parent + i, uf_root(parent, static_cast<std::int32_t>(i)));
  }
};

/// Host backends: the components' sizes from the row pass's runs (row_runs), one work item per
/// row, once all unions are done.  Each run's first element h takes its root (parent[h] = root,
/// as uf_flatten_kernel does for every element) and adds its run's length len[h] to len[root]; a
/// root keeps its own run's length there, so len[r] ends as the size of r's component at every
/// root r (other entries: their runs' lengths).  A run whose first element's parent is the one the
/// previous walk started from takes that walk's root (the roots are final), and runs of one root
/// in a row add once.  Row y's list ends holding its roots (the runs whose first element is its
/// own parent), in order, and nheads[y] their number.  The other elements are not flattened:
/// every active element's parent is a run's first element (its own, or an ancestor that path
/// halving stored), so once this has run, parent[parent[i]] is i's root (uf_head_root).
struct uf_count_runs_kernel {
  std::int32_t* parent;
  row_runs runs;
  int w;
  EDGEPLANE_HD void operator()(std::int64_t row) const {
    std::int32_t* const list = runs.heads + row * w;
    std::int32_t* const len = runs.len;
    const std::int32_t m = runs.nheads[row];
    std::int32_t listed = 0, walked = -1, walked_root = -1, cur = -1, sum = 0;
    for (std::int32_t j = 0; j < m; ++j) {
      const std::int32_t h = list[j], p = atomic_load(parent + h);
      if (p == h) {  // a root: its length stays (only other rows' runs add to it)
        list[listed++] = h;
        continue;
      }
      if (p != walked) {
        walked = p;
        walked_root = uf_root(parent, h);
      }
      atomic_store(parent + h, walked_root);
      if (walked_root != cur) {
        if (cur >= 0) atomic_add(len + cur, sum);
        cur = walked_root;
        sum = 0;
      }
      sum += len[h];  // (not a root: no other row adds to it)
    }
    if (cur >= 0) atomic_add(len + cur, sum);
    runs.nheads[row] = listed;
  }
};
/// i's root (or -1 where i is inactive) where parent is flat (every element's parent its root) or
/// counted by uf_count_runs_kernel (every parent a root or a run's first element, which points to
/// its root).
EDGEPLANE_HD EDGEPLANE_INLINE std::int32_t uf_head_root(const std::int32_t* parent, std::int64_t i) {
  const std::int32_t r = parent[i];
  return r >= 0 ? parent[r] : r;
}

/// Active elements: a nonzero byte in either of two masks (the two diagonal coverages).
struct covered_active {
  const std::uint8_t* a;
  const std::uint8_t* b;
  EDGEPLANE_HD bool operator()(std::int64_t i) const {
    const std::uint8_t* c = b != nullptr ? b : a;  // loop-invariant: the test itself does not branch
    return (a[i] | c[i]) != 0;
  }
};

/// Pixels of failed candidates (failed[cand[i]] != 0) whose whole (2r+1)^2 window lies in the same
/// candidate: the failed regions eroded by r, so that narrow bridges through gaps in the edge map
/// break and the pieces can be validated on their own.
struct eroded_failed_active {
  image_view<const std::int32_t> cand;
  const std::uint8_t* failed;
  int r;
  EDGEPLANE_HD bool operator()(std::int64_t i) const {
    const int x = static_cast<int>(i % cand.width), y = static_cast<int>(i / cand.width);
    const std::int32_t c = cand(x, y);
    if (c <= 0 || !failed[c]) return false;
    for (int dy = -r; dy <= r; ++dy)
      for (int dx = -r; dx <= r; ++dx)
        if (!cand.contains(x + dx, y + dy) || cand(x + dx, y + dy) != c) return false;
    return true;
  }
};

/// eroded_failed_active on host backends, one work item per row, written as bit 1 of a byte mask
/// (bit 0 is scratch; the item writes only its own row and reads only `cand`, so rows run
/// concurrently).  Row y's runs of one value: a run [a, b) of a failed value at least 2r + 1 long
/// can hold full windows; over it, bit 0 marks the columns whose rows y - r .. y + r all hold the
/// value (compared row by row in lanes, stopping once no column is left), and bit 1 the centres of
/// 2r + 1 consecutive such columns.  Work: the row's scan, plus up to 2r compares per pixel of
/// failed runs only (a column's walk for every pixel, as a separable form does, took a cache line
/// per pixel or ran scalar over narrow blocks).
struct eroded_rows_kernel {
  image_view<const std::int32_t> cand;
  const std::uint8_t* failed;
  image_view<std::uint8_t> mask;
  int r;
  /// When not null: the columns [a, b) from row y's first pixel of a failed candidate to its last,
  /// at failed_spans[2y], [2y + 1], and from its first eroded pixel to its last at
  /// eroded_spans[2y], [2y + 1] (a = w, b = 0 where there are none).
  std::int32_t* failed_spans = nullptr;
  std::int32_t* eroded_spans = nullptr;
  /// When not null: row y's pixels of failed candidates all lie in columns [scan_spans[2y],
  /// scan_spans[2y + 1]), the only ones whose runs are looked at.
  const std::int32_t* scan_spans = nullptr;
  EDGEPLANE_HD void operator()(std::int64_t row) const {
    const int y = static_cast<int>(row), w = cand.width, full = 2 * r + 1;
    std::uint8_t* mr = &mask(0, y);
    for (int x = 0; x < w; ++x) mr[x] = 0;
    int fa = w, fb = 0, ea = w, eb = 0;
    const bool windows = y >= r && y + r < cand.height;  // a window of this row lies inside the image
    if (!windows && !failed_spans) return;
    const std::int32_t* cr = &cand(0, y);
    const int scan_end = scan_spans ? scan_spans[2 * y + 1] : w;
    for (int a = scan_spans ? scan_spans[2 * y] : 0; a < scan_end;) {
      const std::int32_t c = cr[a];
      int b = a + 1;
      for (;;) {  // the run's end: 16 lanes compared at a time
        if (b + 16 > w) {
          while (b < w && cr[b] == c) ++b;
          break;
        }
        unsigned differ = 0;
        for (int l = 0; l < 16; ++l) differ |= static_cast<unsigned>(cr[b + l] != c) << l;
        if (differ != 0) {
          b += lowest_bit(differ);
          break;
        }
        b += 16;
      }
      const bool of_failed = c > 0 && failed[c];
      if (of_failed) {
        fa = fa < a ? fa : a;
        fb = b;
      }
      if (of_failed && windows && b - a >= full) {
        const int m = b - a;
        std::uint8_t* v = mr + a;
        for (int l = 0; l < m; ++l) v[l] = 1;
        for (int k = 1; k <= r; ++k) {
          const std::int32_t* up = &cand(a, y - k);
          const std::int32_t* dn = &cand(a, y + k);
          unsigned any = 0;
          EDGEPLANE_VECTOR_LOOP
          for (int l = 0; l < m; ++l) {
            const std::uint8_t on = static_cast<std::uint8_t>(v[l] & (up[l] == c) & (dn[l] == c));
            v[l] = on;
            any |= on;
          }
          if (!any) break;
        }
        // bit 1 at the centres of 2r + 1 consecutive such columns: over each stretch [a', b') of
        // them (v is 0 or 1 here; stretches found 8 bytes at a time), the columns a' + r .. b' - 1 - r.
        // (A counter of consecutive columns, pixel by pixel, took most of the pass where a
        // large candidate failed.)
        for (int l = 0; l < m;) {
          while (l + 8 <= m && swar::load(v + l) == 0) l += 8;
          while (l < m && v[l] == 0) ++l;
          const int first = l;
          while (l + 8 <= m && swar::load(v + l) == swar::ones8) l += 8;
          while (l < m && v[l] != 0) ++l;
          for (int q = first + r; q < l - r; ++q) v[q] = 3;
          if (first + r < l - r) {
            ea = ea < a + first + r ? ea : a + first + r;
            eb = a + l - r;
          }
        }
      }
      a = b;
    }
    if (failed_spans) {
      failed_spans[2 * y] = fa;
      failed_spans[2 * y + 1] = fb;
      eroded_spans[2 * y] = ea;
      eroded_spans[2 * y + 1] = eb;
    }
  }
};

/// erode_failed on device backends, one work item per pixel: bit 1 (value 2) where
/// eroded_failed_active holds, else 0 (the host's row pass uses bit 0 as scratch, which nothing
/// reads).  The window is read only for pixels of failed candidates and stops at the first pixel
/// that differs.  (Passes that walk a row or a column per work item keep only a few hundred GPU
/// threads busy: the earlier separable passes took 0.2 ms a call at 512x424 on an H200.)
struct eroded_pixel_kernel {
  eroded_failed_active eroded;
  image_view<std::uint8_t> mask;
  EDGEPLANE_HD void operator()(int x, int y) const {
    mask(x, y) = eroded(static_cast<std::int64_t>(y) * eroded.cand.width + x) ? std::uint8_t(2) : std::uint8_t(0);
  }
};

/// Active where a byte mask has the given bit.
struct mask_bit_active {
  const std::uint8_t* mask;
  std::uint8_t bit;
  EDGEPLANE_HD bool operator()(std::int64_t i) const { return (mask[i] & bit) != 0; }
};

/// Every element active.
struct all_active {
  EDGEPLANE_HD bool operator()(std::int64_t) const { return true; }
};

/// The union pairs of pixel (x, y) of a grid adjacency's dense w x h elements: with its right
/// neighbour where adj.joins_right(x, y), with its lower one where adj.joins_down(x, y) (each
/// false outside the grid); returns how many (at most 2).
template <class Adjacency>
EDGEPLANE_HD EDGEPLANE_INLINE int grid4_joins(const Adjacency& adj, int x, int y, std::int32_t* a, std::int32_t* b) {
  const int w = adj.grid_width();
  const std::int64_t i = static_cast<std::int64_t>(y) * w + x;
  int n = 0;
  if (adj.joins_right(x, y)) {
    a[n] = static_cast<std::int32_t>(i);
    b[n++] = static_cast<std::int32_t>(i + 1);
  }
  if (adj.joins_down(x, y)) {
    a[n] = static_cast<std::int32_t>(i);
    b[n++] = static_cast<std::int32_t>(i + w);
  }
  return n;
}

/// 4-connectivity on an image: pixel i is joined to its right and lower neighbours when both are
/// active and their depths differ by no more than t_je + t_je_quad z^2 + slope * z * inv_f (the
/// last term: `slope` pixel footprints, which admits surfaces seen at grazing angles), so a gap in
/// the edge map does not join surfaces at different depths.  The elements (and `active`) are the
/// dense w x h pixels of `depth`'s size; `depth` itself may be a view with any pitch (a
/// rectangle of a larger image).
template <class Active>
struct grid4_adjacency {
  image_view<const float> depth;
  Active active;
  float t_je, t_je_quad, slope_inv_f;
  EDGEPLANE_HD bool compatible(float za, float zb) const {
    const float z = za < zb ? za : zb;
    return fabsf(za - zb) <= t_je + t_je_quad * z * z + slope_inv_f * z;
  }
  EDGEPLANE_HD int grid_width() const { return depth.width; }
  EDGEPLANE_HD int grid_height() const { return depth.height; }
  /// (x, y) joins (x + 1, y) / (x, y + 1)
  EDGEPLANE_HD EDGEPLANE_INLINE bool joins_right(int x, int y) const {
    const std::int64_t i = static_cast<std::int64_t>(y) * depth.width + x;  // dense elements
    return x + 1 < depth.width && active(i) && active(i + 1) && compatible(depth(x, y), depth(x + 1, y));
  }
  EDGEPLANE_HD EDGEPLANE_INLINE bool joins_down(int x, int y) const {
    const std::int64_t i = static_cast<std::int64_t>(y) * depth.width + x;
    return y + 1 < depth.height && active(i) && active(i + depth.width) && compatible(depth(x, y), depth(x, y + 1));
  }
  /// Bits l where joins_right(x + l, y) (x + L < width) / joins_down(x + l, y) (x + L <= width,
  /// y + 1 < height): the same tests and float operations, without branches.
  template <int L>
  EDGEPLANE_HD EDGEPLANE_INLINE unsigned right_lanes(int x, int y) const {
    const std::int64_t i = static_cast<std::int64_t>(y) * depth.width + x;
    const float* z = &depth(x, y);
    unsigned bits = 0;
    for (int l = 0; l < L; ++l)
      bits |= static_cast<unsigned>(active(i + l) & active(i + l + 1) & compatible(z[l], z[l + 1])) << l;
    return bits;
  }
  template <int L>
  EDGEPLANE_HD EDGEPLANE_INLINE unsigned down_lanes(int x, int y) const {
    const std::int64_t i = static_cast<std::int64_t>(y) * depth.width + x;
    const float* z0 = &depth(x, y);
    const float* z1 = &depth(x, y + 1);
    unsigned bits = 0;
    for (int l = 0; l < L; ++l)
      bits |= static_cast<unsigned>(active(i + l) & active(i + l + depth.width) & compatible(z0[l], z1[l])) << l;
    return bits;
  }
  EDGEPLANE_HD int operator()(int x, int y, std::int32_t* a, std::int32_t* b) const {
    return grid4_joins(*this, x, y, a, b);
  }
};

/// An explicit list of pairs: work item i unites first[i] and second[i].
struct pair_list_adjacency {
  const std::int32_t* first;
  const std::int32_t* second;
  EDGEPLANE_HD int operator()(std::int64_t i, std::int32_t* a, std::int32_t* b) const {
    a[0] = first[i];
    b[0] = second[i];
    return 1;
  }
};

}  // namespace detail

/// Marks (bit 1 of `mask`, a byte image of cand's size in the backend's memory) the pixels that
/// detail::eroded_failed_active(cand, failed, r) names: pixels of failed candidates whose whole
/// (2r+1)^2 window lies in the same candidate (r >= 0, else edgeplane::error).  Host backends: a
/// work item per row (detail::eroded_rows_kernel; other bits of `mask` are scratch); device
/// backends: a work item per pixel (detail::eroded_pixel_kernel).  Asynchronous on device backends.
/// `failed_spans`, `eroded_spans` (host backends only, 2 * cand.height entries each, or null):
/// each row's columns [a, b) from its first pixel of a failed candidate to its last, and from its
/// first marked pixel to its last (a = width, b = 0 where there are none): bounds for the passes
/// that follow (unite_components' spans; candidate_table_labels' column spans for the moments).  `scan_spans` (host backends
/// only, or null): each row's pixels of failed candidates lie in columns [scan_spans[2y],
/// scan_spans[2y + 1]), the only ones read in the row itself.
template <class Backend>
void erode_failed(const Backend& b, image_view<const std::int32_t> cand, const std::uint8_t* failed, int r,
                  image_view<std::uint8_t> mask, std::int32_t* failed_spans = nullptr,
                  std::int32_t* eroded_spans = nullptr, const std::int32_t* scan_spans = nullptr) {
  detail::check_same_size(cand, mask, "candidates", "mask");
  detail::require(r >= 0, "erode_failed: the erosion radius must be >= 0 (got " + std::to_string(r) + ")");
  detail::require((failed_spans == nullptr) == (eroded_spans == nullptr),
                  "erode_failed: give both row span buffers or neither");
  if constexpr (!Backend::host_accessible) {
    detail::require(failed_spans == nullptr && scan_spans == nullptr,
                    "erode_failed: row spans are for host backends only");
    detail::for_each_pixel(b, cand.width, cand.height,
                           detail::eroded_pixel_kernel{detail::eroded_failed_active{cand, failed, r}, mask});
    return;
  }
  b.for_each_index(cand.height,
                   detail::eroded_rows_kernel{cand, failed, mask, r, failed_spans, eroded_spans, scan_spans});
}

namespace detail {
/// connected_components without its last pass: `parent` ends as a forest whose roots are each
/// component's smallest element, not yet flattened (uf_root(parent, i) is i's root).  For callers
/// that flatten within their next pass.
/// `right_bits` (optional, host backends): scratch of join_blocks(width) * height entries, in which
/// the row pass keeps each block's right joins for the vertical unions (which otherwise compute
/// them again, twice); used only by adjacencies with has_join_lanes.  `runs` (optional, host
/// backends and adjacencies with has_grid_joins only): the row pass records its runs there
/// (row_runs), so that the components can be counted by uf_count_runs_kernel.  `spans` (optional, host backends,
/// grid adjacencies): each row's active pixels lie in columns [spans[2y], spans[2y + 1]), and
/// the row passes read only those (uf_init_runs_kernel::spans).
template <class Backend, class Active, class Adjacency>
void unite_components(const Backend& b, std::int64_t n, Active active, std::int64_t work_items, Adjacency adj,
                      std::int32_t* parent, std::uint16_t* right_bits = nullptr, row_runs runs = {},
                      const std::int32_t* spans = nullptr) {
  require(n >= 0 && n < (std::int64_t(1) << 31), "union-find supports up to 2^31 - 1 elements");
  if constexpr (Backend::host_accessible && has_grid_joins<Adjacency>) {
    require(work_items == n && static_cast<std::int64_t>(adj.grid_width()) * adj.grid_height() == n,
            "connected_components: a grid adjacency needs one work item per pixel of its image");
    if constexpr (!has_join_lanes<Adjacency>) right_bits = nullptr;
    if (spans) {
      b.for_each_index(adj.grid_height(),
                       uf_init_runs_kernel<Active, Adjacency, true>{active, adj, parent, right_bits, runs, spans});
      b.for_each_index(adj.grid_height(), uf_union_down_kernel<Adjacency, true>{adj, parent, right_bits, spans});
    } else {
      b.for_each_index(adj.grid_height(),
                       uf_init_runs_kernel<Active, Adjacency>{active, adj, parent, right_bits, runs});
      b.for_each_index(adj.grid_height(), uf_union_down_kernel<Adjacency>{adj, parent, right_bits});
    }
    return;
  }
  require(runs.len == nullptr, "unite_components: row runs are recorded on host backends with grid-join adjacencies only");
  b.for_each_index(n, uf_init_kernel<Active>{active, parent});
  if constexpr (is_grid_adjacency<Adjacency>) {
    require(work_items == n && static_cast<std::int64_t>(adj.grid_width()) * adj.grid_height() == n,
            "connected_components: a grid adjacency needs one work item per pixel of its image");
    for_each_pixel(b, adj.grid_width(), adj.grid_height(), uf_union_grid_kernel<Adjacency>{adj, parent});
  } else {
    b.for_each_index(work_items, uf_union_kernel<Adjacency>{adj, parent});
  }
}
}  // namespace detail

/// Connected components with the lock-free union-find: `parent` (n elements, backend memory) ends
/// with each active element's root, the smallest element of its component, and -1 for inactive
/// ones.  `work_items` is the number of adjacency work items.  Synchronous semantics between the
/// three launches come from the backend's stream order.  A grid adjacency (detail::is_grid_adjacency)
/// runs one work item per pixel of its image, so `work_items` must be n, its pixel count.
template <class Backend, class Active, class Adjacency>
void connected_components(const Backend& b, std::int64_t n, Active active, std::int64_t work_items, Adjacency adj,
                          std::int32_t* parent) {
  detail::unite_components(b, n, active, work_items, adj, parent);
  b.for_each_index(n, detail::uf_flatten_kernel{parent});
}

}  // namespace edgeplane
