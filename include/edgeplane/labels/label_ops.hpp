// edgeplane: operations on label images: relabelling through a table, plane-guided growth into
// unlabelled pixels, the final closing, and nearest-neighbour upsampling.
#pragma once
#include <cstdint>

#include "edgeplane/backend/atomic.hpp"
#include "edgeplane/config.hpp"
#include "edgeplane/detail/geometry.hpp"
#include "edgeplane/image.hpp"
#include "edgeplane/labels/union_find.hpp"

namespace edgeplane::detail {

/// labels(i) = table[source(i)] (source gives 1-based candidate ids; table[0] = 0).
template <class Source>
struct relabel_kernel {
  static constexpr bool even_work = true;  // see detail::even_work_v
  Source source;
  const std::uint16_t* table;
  image_view<std::uint16_t> labels;
  EDGEPLANE_HD void operator()(int x, int y) const { labels(x, y) = table[source(x, y)]; }
};

/// One step of plane-guided growth: an unlabelled pixel with valid depth takes the label of the
/// 4-neighbour whose plane (n . X + d = 0, `planes` holds nx, ny, nz, d per label, label 0 unused)
/// is nearest to its point, if that distance is within k * sigma(z) and within the plane's own
/// tolerance cap[l] (2.5 RMS residuals of its fit; a pessimistic noise model must not let a plane
/// swallow the rim of a neighbouring face).  Reads `in`, writes `out`.
struct grow_kernel {
  image_view<const float> depth;
  image_view<const std::uint16_t> in;
  image_view<std::uint16_t> out;
  projector proj;
  noise_sigma sigma;
  float k;
  const float* planes;
  const float* cap;
  std::int32_t* changed;  // set to 1 when any pixel is assigned (relaxed atomic store)
  EDGEPLANE_HD void operator()(int x, int y) const {
    const std::uint16_t cur = in(x, y);
    const float z = depth(x, y);
    if (cur != 0 || !(z > 0.f)) {
      out(x, y) = cur;
      return;
    }
    const point3 p = proj(x, y, z);
    const float tol = k * sigma(z);
    std::uint16_t best = 0;
    float best_d = tol;
    const int nx[4] = {x - 1, x + 1, x, x};
    const int ny[4] = {y, y, y - 1, y + 1};
    for (int j = 0; j < 4; ++j) {
      if (!in.contains(nx[j], ny[j])) continue;
      const std::uint16_t l = in(nx[j], ny[j]);
      if (l == 0 || l == best) continue;
      const float d = plane_distance(planes, l, p);
      if (d > cap[l]) continue;
      if (d <= best_d && (d < best_d || best == 0 || l < best)) {
        best_d = d;
        best = l;
      }
    }
    out(x, y) = best;
    // stored only while unset: a store per labelled pixel from every core made the flag's cache
    // line move between the cores at each one
    if (best != 0 && atomic_load(changed) == 0) atomic_store(changed, 1);
  }
};

/// Host form of a grow_kernel round, one work item per row y, that touches only the growth front.
/// A pixel can change in round k only if one of its 4-neighbours changed in round k - 1: else
/// its neighbourhood is the one round k - 1 saw, and the same inputs give the same (empty)
/// answer.  So round k evaluates only the unlabelled neighbours of the pixels round k - 1
/// labelled, which each row lists: row y's list (the x of every pixel it labelled) at
/// xs_prev + y * w, its length at n_prev[y + 1] (n_prev[0] and n_prev[h + 1] are 0).  The output
/// buffer holds the state of two rounds before (the buffers alternate), so a row first copies in
/// its pixels that the previous round labelled; then out(x, y) != 0 marks a pixel this round
/// already labelled or one labelled before, and a pixel is listed once.  The first round
/// (`first`) gives every pixel grow_kernel's answer (evaluating only the pixels that can take a
/// label) and writes whole rows.  A row writes only its own pixels and list, and reads the
/// previous round's buffer and lists: race-free, and the result after every round is
/// grow_kernel's over all pixels.
struct grow_front_kernel {
  grow_kernel px;
  const std::int32_t* n_prev;
  const std::int32_t* xs_prev;
  std::int32_t* n_cur;
  std::int32_t* xs_cur;
  bool first;
  EDGEPLANE_HOST_CLONES EDGEPLANE_HD void operator()(std::int64_t row) const {
    const int y = static_cast<int>(row), w = px.in.width, h = px.in.height;
    std::int32_t* list = xs_cur + static_cast<std::int64_t>(y) * w;
    std::int32_t m = 0;
    std::uint16_t* o = &px.out(0, y);
    const std::uint16_t* mid = &px.in(0, y);
    // grow_kernel at x, listing the pixel when it took a label (grow_kernel writes out(x, y) either
    // way: the input's label, or a new one where the input had none)
    const auto evaluate = [&](int x) {
      px(x, y);
      if (o[x] != mid[x]) list[m++] = x;
    };
    if (!first) {
      const std::int32_t* own = xs_prev + static_cast<std::int64_t>(y) * w;
      const std::int32_t n_own = n_prev[y + 1];
      for (std::int32_t i = 0; i < n_own; ++i) o[own[i]] = mid[own[i]];
      auto visit = [&](int x) {
        if (o[x] == 0) evaluate(x);  // (else labelled before, or by this round already)
      };
      for (int v = y - 1; v <= y + 1; v += 2) {
        if (v < 0 || v >= h) continue;
        const std::int32_t* other = xs_prev + static_cast<std::int64_t>(v) * w;
        for (std::int32_t i = 0, e = n_prev[v + 1]; i < e; ++i) visit(other[i]);
      }
      for (std::int32_t i = 0; i < n_own; ++i) {
        const int x = own[i];
        if (x > 0) visit(x - 1);
        if (x + 1 < w) visit(x + 1);
      }
      n_cur[y + 1] = m;
      return;
    }
    int x = 0;
#if !defined(__CUDA_ARCH__)
    // Runs of 16 pixels (with both neighbouring rows and columns inside the image): a pixel that
    // is labelled, invalid, or has no labelled 4-neighbour cannot take a label, and grow_kernel
    // writes its input unchanged.  So each run is copied, and grow_kernel evaluates only the
    // others (none in most runs, about 2 of the 16 in the rest on the kinect2 and TUM frames).
    constexpr int lanes = 16;
    if (y >= 1 && y + 1 < h) {
      const std::uint16_t *up = &px.in(0, y - 1), *down = &px.in(0, y + 1);
      const float* z = &px.depth(0, y);
      x = 1;
      evaluate(0);
      // pixel i of the row is unlabelled, valid and has a labelled 4-neighbour (0 or 1)
      const auto can_take = [&](int i) {
        return static_cast<unsigned>((mid[i] == 0) & (z[i] > 0.f) & ((up[i] | down[i] | mid[i - 1] | mid[i + 1]) != 0));
      };
      for (; x + lanes < w; x += lanes) {
        unsigned open = 0;
        for (int l = 0; l < lanes; ++l) open |= can_take(x + l);
        for (int l = 0; l < lanes; ++l) o[x + l] = mid[x + l];
        if (!open) continue;
        // the lane mask only for runs that have one (the OR above vectorizes; packing the lanes'
        // bits does not, and most runs have none)
        unsigned need = 0;
        for (int l = 0; l < lanes; ++l) need |= can_take(x + l) << l;
        for (; need != 0; need &= need - 1) evaluate(x + lowest_bit(need));
      }
    }
#endif
    for (; x < w; ++x) evaluate(x);
    n_cur[y + 1] = m;
  }
};

/// Sweep form of plane-guided growth: work item i walks one whole row (Axis 0) or column (Axis 1)
/// forward, then backward, in place; an unlabelled pixel with valid depth takes the label of the
/// pixel just before it on the walk when its point lies within k * sigma(z) and cap[l] of that
/// label's plane.  One sweep carries a label across a whole row, where a round of grow_kernel
/// moves it one pixel.  Each item reads and writes only its own row or column: race-free, and the
/// result does not depend on scheduling.
///
/// dirty[0, height) flags the rows and dirty[height, height + width) the columns (nonzero: sweep
/// it).  A line whose flag is 0 is skipped, and a swept line's flag is cleared; every pixel a
/// sweep labels flags the line of the other axis through it.  Skipping changes nothing: a sweep
/// reads only its own line's labels and depths, and sweeping a line again when none of them
/// changed labels nothing (a pixel still unlabelled after both passes would see, in each pass,
/// the neighbour label it saw before: the neighbour it follows in the forward pass could only
/// have changed in the backward pass by taking this pixel's label, which stayed 0).  So a round
/// sweeps only the rows that the previous round's columns labelled pixels in, and the columns
/// that its own rows did; late rounds, which label a few pixels, sweep a few lines.  All flags
/// must be nonzero before the first round.
template <int Axis>
struct grow_sweep_kernel {
  image_view<const float> depth;
  image_view<std::uint16_t> labels;
  projector proj;
  noise_sigma sigma;
  float k;
  const float* planes;
  const float* cap;
  std::int32_t* changed;
  std::int32_t* dirty;  // rows, then columns (see above)
  EDGEPLANE_HD bool try_take(int x, int y, std::uint16_t l) const {
    const float z = depth(x, y);
    if (l == 0 || !(z > 0.f)) return false;
    const point3 p = proj(x, y, z);
    const float d = plane_distance(planes, l, p);
    return d <= k * sigma(z) && d <= cap[l];
  }
  /// Pixel t of the line: takes `prev` if it may; `prev` becomes its label.  True if it took one.
  EDGEPLANE_HD EDGEPLANE_INLINE bool visit(int line, int t, std::uint16_t& prev, std::int32_t* crossing) const {
    const int x = Axis == 0 ? t : line, y = Axis == 0 ? line : t;
    std::uint16_t cur = labels(x, y);
    const bool took = cur == 0 && try_take(x, y, prev);
    if (took) {
      cur = prev;
      labels(x, y) = cur;
      atomic_store(crossing + t, 1);
    }
    prev = cur;
    return took;
  }
  EDGEPLANE_HD void operator()(std::int64_t i) const {
    const int n = Axis == 0 ? labels.width : labels.height;
    const int line = static_cast<int>(i);
    std::int32_t* self = dirty + (Axis == 0 ? 0 : labels.height) + line;
    if (atomic_load(self) == 0) return;  // nothing on it changed since its last sweep
    atomic_store(self, 0);
    std::int32_t* crossing = dirty + (Axis == 0 ? labels.height : 0);  // the other axis's flags
    // Two loops, forward then backward.  Not one loop over a direction variable
    // (for (t = pass ? n - 1 : 0; t >= 0 && t < n; t += step)): nvcc 13.0 compiled that form so
    // that the backward pass never ran on an H200 (the labels equalled a forward-only sweep's), a
    // difference from the CPU backend that tests/cuda caught.
    bool any = false;
#if defined(__CUDA_ARCH__)
    // Device: the line in chunks whose depths and labels are loaded together before the walk
    // through them, so that a thread waits for memory once a chunk rather than once a pixel (this
    // thread alone writes the line, so the values it loaded stay current but for its own writes,
    // which the walk carries in lab[]).
    any = device_pass<1>(line, n, crossing);
    any |= device_pass<-1>(line, n, crossing);
#else
    std::uint16_t prev = 0;
    for (int t = 0; t < n; ++t) any |= visit(line, t, prev, crossing);
    prev = 0;
    for (int t = n - 1; t >= 0; --t) any |= visit(line, t, prev, crossing);
#endif
    if (any) atomic_store(changed, 1);
  }
  /// One pass of the walk (Step 1: forward, -1: backward), chunk by chunk; the labels it writes
  /// and the flags it sets are visit()'s, pixel for pixel (host-callable, for the tests).  What a
  /// pixel's test needs that does not depend on the label it is offered (its point and its
  /// tolerance k sigma(z)) is computed as its chunk is loaded, and the plane and cap of the label
  /// being carried are held in registers until the label changes, so that the walk's chain from
  /// one pixel to the next is only the distance to that plane and two comparisons.  The float
  /// operations are try_take()'s, in its order.
  template <int Step>
  EDGEPLANE_HD bool device_pass(int line, int n, std::int32_t* crossing) const {
    constexpr int chunk = 8;
    bool any = false;
    std::uint16_t prev = 0, held = 0;  // held: the label whose plane and cap are in q, q_cap
    float q[4] = {0.f, 0.f, 0.f, 0.f}, q_cap = 0.f;
    for (int c = 0; c < n; c += chunk) {
      point3 pt[chunk];
      float tol[chunk];
      bool valid[chunk];
      std::uint16_t lab[chunk];
      const int m = n - c < chunk ? n - c : chunk;
EDGEPLANE_UNROLL
      for (int j = 0; j < chunk; ++j) {
        const int t = Step > 0 ? c + j : n - 1 - c - j;
        const int x = Axis == 0 ? t : line, y = Axis == 0 ? line : t;
        const float z = j < m ? depth(x, y) : 0.f;
        lab[j] = j < m ? labels(x, y) : std::uint16_t(0);
        valid[j] = z > 0.f;
        pt[j] = proj(x, y, z);
        tol[j] = k * sigma(z);
      }
EDGEPLANE_UNROLL
      for (int j = 0; j < chunk; ++j) {
        if (j >= m) break;
        if (lab[j] == 0 && prev != 0 && valid[j]) {
          if (prev != held) {
            held = prev;
            for (int i = 0; i < 4; ++i) q[i] = planes[4 * held + i];
            q_cap = cap[held];
          }
          const float d = plane_distance(q, 0, pt[j]);
          if (d <= tol[j] && d <= q_cap) {
            const int t = Step > 0 ? c + j : n - 1 - c - j;
            lab[j] = prev;
            labels(Axis == 0 ? t : line, Axis == 0 ? line : t) = prev;
            atomic_store(crossing + t, 1);
            any = true;
          }
        }
        prev = lab[j];
      }
    }
    return any;
  }
};

/// Label closing, dilation half: an unlabelled pixel takes the smallest label in its window.
struct label_dilate_kernel {
  image_view<const std::uint16_t> in;
  image_view<std::uint16_t> out;
  int r;
  EDGEPLANE_HD void operator()(int x, int y) const {
    std::uint16_t v = in(x, y);
    if (v == 0) {
      for (int dy = -r; dy <= r; ++dy)
        for (int dx = -r; dx <= r; ++dx)
          if (in.contains(x + dx, y + dy)) {
            const std::uint16_t l = in(x + dx, y + dy);
            if (l != 0 && (v == 0 || l < v)) v = l;
          }
    }
    out(x, y) = v;
  }
};

/// Label closing, erosion half: a pixel filled by the dilation keeps its label only if every
/// pixel of its window is labelled in the dilated image; original labels are kept.
struct label_erode_kernel {
  image_view<const std::uint16_t> original;
  image_view<const std::uint16_t> dilated;
  image_view<std::uint16_t> out;
  int r;
  EDGEPLANE_HD void operator()(int x, int y) const {
    const std::uint16_t o = original(x, y);
    if (o != 0) {
      out(x, y) = o;
      return;
    }
    std::uint16_t v = dilated(x, y);
    for (int dy = -r; dy <= r && v; ++dy)
      for (int dx = -r; dx <= r; ++dx)
        if (dilated.contains(x + dx, y + dy) && dilated(x + dx, y + dy) == 0) {
          v = 0;
          break;
        }
    out(x, y) = v;
  }
};

/// Host form of the label closing, one work item per row: the output row accumulates the window
/// one shift at a time, each a pass over the row (vectorizable); taps outside the image are
/// skipped, as the per-pixel kernels skip them.  Dilation: the smallest nonzero label of the
/// window where the pixel has none (label - 1 wraps 0 to 0xffff, so the unsigned minimum of
/// label - 1, plus 1, is that label, or 0).  Erosion: a filled pixel keeps its dilated label only
/// where the whole window is labelled in the dilated image; original labels are kept.
template <bool Dilate>
struct label_rows_kernel {
  static constexpr bool even_work = true;  // see detail::even_work_v
  image_view<const std::uint16_t> original;  // the labels before the closing
  image_view<const std::uint16_t> dilated;   // the dilation's output (erosion only)
  image_view<std::uint16_t> out;
  int r;
  EDGEPLANE_HOST_CLONES void operator()(std::int64_t row) const {
    const int y = static_cast<int>(row), w = original.width;
    const image_view<const std::uint16_t> taps = Dilate ? original : dilated;
    std::uint16_t* o = &out(0, y);  // the accumulator: the minimum of label - 1 / all taps set
    for (int x = 0; x < w; ++x) o[x] = 0xffff;
    for_each_window_shift(taps, y, r, [&](const std::uint16_t* t, int dx, int x0, int x1) {
      if constexpr (Dilate)
        for (int x = x0; x < x1; ++x) {
          const std::uint16_t l = static_cast<std::uint16_t>(t[x + dx] - 1);
          o[x] = l < o[x] ? l : o[x];
        }
      else
        for (int x = x0; x < x1; ++x) o[x] = static_cast<std::uint16_t>(o[x] & (t[x + dx] != 0 ? 0xffff : 0));
    });
    const std::uint16_t* c = &original(0, y);
    if constexpr (Dilate) {
      for (int x = 0; x < w; ++x) o[x] = c[x] != 0 ? c[x] : static_cast<std::uint16_t>(o[x] + 1);
    } else {
      const std::uint16_t* d = &dilated(0, y);
      for (int x = 0; x < w; ++x) {  // by bits: g++ made `?:` here a branch for AVX2 (not vectorized)
        const std::uint16_t keep = static_cast<std::uint16_t>(0u - static_cast<unsigned>(c[x] != 0));
        o[x] = static_cast<std::uint16_t>((c[x] & keep) | (d[x] & o[x] & ~keep));
      }
    }
  }
};

/// Splitting planes into connected regions: pixels with a nonzero label take part.
struct nonzero_label_active {
  const std::uint16_t* labels;  // dense (pitch = width)
  EDGEPLANE_HD bool operator()(std::int64_t i) const { return labels[i] != 0; }
};
/// 4-connectivity between pixels of the same nonzero label (a dense label image).
struct same_label_adjacency {
  image_view<const std::uint16_t> labels;
  EDGEPLANE_HD int grid_width() const { return labels.width; }
  EDGEPLANE_HD int grid_height() const { return labels.height; }
  /// (x, y) joins (x + 1, y) / (x, y + 1)
  EDGEPLANE_HD EDGEPLANE_INLINE bool joins_right(int x, int y) const {
    const std::int64_t i = static_cast<std::int64_t>(y) * labels.width + x;
    return x + 1 < labels.width && labels.data[i] != 0 && labels.data[i + 1] == labels.data[i];
  }
  EDGEPLANE_HD EDGEPLANE_INLINE bool joins_down(int x, int y) const {
    const std::int64_t i = static_cast<std::int64_t>(y) * labels.width + x;
    return y + 1 < labels.height && labels.data[i] != 0 && labels.data[i + labels.width] == labels.data[i];
  }
  EDGEPLANE_HD int operator()(int x, int y, std::int32_t* a, std::int32_t* b) const {
    return grid4_joins(*this, x, y, a, b);
  }
};
/// out[i] = the 1-based region id of i's region when kept (flags[root] = 1) and at most
/// max_regions, else 0; the region's root also records its plane's label: origin[id] = labels[i].
/// `parent` flat or counted by runs (uf_head_root).
struct region_relabel_kernel {
  const std::int32_t* parent;
  const std::int32_t* flags;
  const std::int32_t* scan;
  const std::uint16_t* labels;
  std::int32_t max_regions;
  std::uint16_t* out;
  std::uint16_t* origin;
  EDGEPLANE_HD void operator()(std::int64_t i) const {
    const std::int32_t r = uf_head_root(parent, i);
    const bool kept = r >= 0 && flags[r] && scan[r] <= max_regions;
    out[i] = kept ? static_cast<std::uint16_t>(scan[r]) : std::uint16_t(0);
    if (kept && r == static_cast<std::int32_t>(i)) origin[scan[r]] = labels[i];
  }
};

/// upsample_kernel by rows (host backends): each source pixel written to its two output pixels,
/// a copy the compiler vectorizes, instead of a clamped index per pixel.  in is not empty.
struct upsample_rows_kernel {
  image_view<const std::uint16_t> in;
  image_view<std::uint16_t> out;
  EDGEPLANE_HOST_CLONES void operator()(std::int64_t row) const {
    const int y = static_cast<int>(row), w = out.width;
    const int sy = y / 2 < in.height ? y / 2 : in.height - 1;
    const std::uint16_t* s = &in(0, sy);
    std::uint16_t* o = &out(0, y);
    const int pairs = w / 2 < in.width ? w / 2 : in.width;  // output pixels 2i, 2i + 1 from s[i]
    for (int i = 0; i < pairs; ++i) {
      o[2 * i] = s[i];
      o[2 * i + 1] = s[i];
    }
    for (int x = 2 * pairs; x < w; ++x) o[x] = s[x / 2 < in.width ? x / 2 : in.width - 1];
  }
};

/// Nearest-neighbour 2x upsampling (odd last rows/columns repeat the last source pixel).
struct upsample_kernel {
  image_view<const std::uint16_t> in;
  image_view<std::uint16_t> out;
  EDGEPLANE_HD void operator()(int x, int y) const {
    int sx = x / 2, sy = y / 2;
    sx = sx < in.width ? sx : in.width - 1;
    sy = sy < in.height ? sy : in.height - 1;
    out(x, y) = (in.width > 0 && in.height > 0) ? in(sx, sy) : std::uint16_t(0);
  }
};

}  // namespace edgeplane::detail

namespace edgeplane {
/// The final closing of a label image (dilate, then erode, (2r+1)^2 window; see
/// detail::label_dilate_kernel and detail::label_erode_kernel): `dilated` receives the dilation,
/// `out` the closed labels (three distinct images of one size, in the backend's memory).  Host
/// backends run by rows (detail::label_rows_kernel).  Asynchronous on device backends.
/// Nearest-neighbour 2x upsampling of a label image into out (odd last rows and columns repeat
/// the last source pixel; see detail::upsample_kernel).  Asynchronous on device backends.
template <class Backend>
void upsample_labels(const Backend& b, image_view<const std::uint16_t> in, image_view<std::uint16_t> out) {
  if (out.width <= 0 || out.height <= 0) return;
  if constexpr (Backend::host_accessible) {
    if (in.width > 0 && in.height > 0) {
      b.for_each_index(out.height, detail::upsample_rows_kernel{in, out});
      return;
    }
  }
  detail::for_each_pixel(b, out.width, out.height, detail::upsample_kernel{in, out});
}

template <class Backend>
void close_labels(const Backend& b, image_view<const std::uint16_t> labels, image_view<std::uint16_t> dilated,
                  image_view<std::uint16_t> out, int r) {
  detail::check_same_size(labels, dilated, "labels", "dilated labels");
  detail::check_same_size(labels, out, "labels", "closed labels");
  if constexpr (Backend::host_accessible) {
    b.for_each_index(labels.height, detail::label_rows_kernel<true>{labels, labels, dilated, r});
    b.for_each_index(labels.height, detail::label_rows_kernel<false>{labels, dilated, out, r});
  } else {
    detail::for_each_pixel(b, labels.width, labels.height, detail::label_dilate_kernel{labels, dilated, r});
    detail::for_each_pixel(b, labels.width, labels.height, detail::label_erode_kernel{labels, dilated, out, r});
  }
}
}  // namespace edgeplane
