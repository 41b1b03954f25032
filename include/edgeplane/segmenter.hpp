// edgeplane: the reusable plane segmenter.  Owns its scratch memory (allocated on the first frame
// and whenever a larger frame arrives; never per frame otherwise) and runs every stage on its
// backend.
#pragma once
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <string>
#include <type_traits>
#include <vector>

#include "edgeplane/backend/buffer.hpp"
#include "edgeplane/backend/cpu.hpp"
#include "edgeplane/camera.hpp"
#include "edgeplane/edges/detect_edges.hpp"
#include "edgeplane/filters/depth.hpp"
#include "edgeplane/image.hpp"
#include "edgeplane/labels/label_ops.hpp"
#include "edgeplane/labels/union_find.hpp"
#include "edgeplane/params.hpp"
#include "edgeplane/planes/plane_stats.hpp"
#include "edgeplane/planes/validate.hpp"
#include "edgeplane/segments/line_segments.hpp"

namespace edgeplane {

/// One segmented plane, in the camera frame (x right, y down, z forward), metres.
struct plane {
  std::uint16_t id = 0;                 ///< its value in the label image
  std::array<float, 3> normal{};        ///< unit normal n, pointing toward the camera
  float d = 0.f;                        ///< n . X + d = 0 (metres, d >= 0)
  std::array<float, 3> centroid{};      ///< metres
  std::int64_t pixels = 0;              ///< labelled pixels in the output label image
  std::int64_t points = 0;              ///< of those, pixels with valid depth (used for the fit)
  std::array<float, 3> eigenvalues{};   ///< PCA eigenvalues l1 >= l2 >= l3 (m^2); sqrt(l3) = RMS residual
  std::array<int, 4> bbox{};            ///< min x, min y, max x, max y (pixels of the output image)
};

/// Per-stage wall-clock times of one frame in milliseconds (each stage synchronizes the backend).
struct stage_times {
  double preprocess = 0, edges = 0, segments = 0, candidates = 0, validation = 0, merge = 0, finalize = 0,
         total = 0;
};

struct segmentation_result {
  std::vector<plane> planes;
  stage_times times;
  int candidates = 0;        ///< connected groups of line segments of at least t_size pixels, including
                             ///< the pieces of failed candidates split during validation
  int valid_candidates = 0;  ///< of those, the ones that passed validation
};

namespace detail {
struct count_roots_kernel {
  const std::int32_t* parent;
  std::int32_t* count;
  EDGEPLANE_HD void operator()(std::int64_t i) const {
    const std::int32_t r = parent[i];
    if (r >= 0) atomic_add(count + r, 1);
  }
};
/// Throws edgeplane::error unless a frame's depth view, depth scale and intrinsics can be segmented.
template <class In>
void check_frame(image_view<const In> depth, float scale, const intrinsics& k) {
  check_view(depth, "depth");
  check_intrinsics(k);
  require(std::isfinite(scale) && scale > 0.f, "depth scale must be positive and finite (got " + std::to_string(scale) + ")");
  require(depth.pixels() < (std::int64_t(1) << 31), "image too large");
}
/// Throws edgeplane::error unless a batch has one label image per frame.
inline void check_batch_counts(std::size_t frames, std::size_t labels) {
  require(frames == labels,
          "segment_batch: " + std::to_string(frames) + " frames but " + std::to_string(labels) + " label images");
}
struct flag_candidates_kernel {
  const std::int32_t* parent;
  const std::int32_t* count;
  std::int32_t t_size;
  std::int32_t* flags;
  EDGEPLANE_HD void operator()(std::int64_t i) const {
    flags[i] = (parent[i] == static_cast<std::int32_t>(i) && count[i] >= t_size) ? 1 : 0;
  }
};
/// cand[i] = 1-based index of i's root among the kept roots for pixels of kept components, 0 for
/// all other pixels.
struct write_candidates_kernel {
  const std::int32_t* parent;
  const std::int32_t* flags;
  const std::int32_t* scan;
  std::int32_t* cand;
  EDGEPLANE_HD void operator()(std::int64_t i) const {
    const std::int32_t r = parent[i];
    cand[i] = r >= 0 && flags[r] ? scan[r] : 0;
  }
};
/// write_candidates_kernel on host backends, one work item per `span` elements, where the
/// numbering left scan[r] = 0 at the roots of components not kept (and scan[0] written), and the
/// union-find is counted by runs (uf_count_runs_kernel: an element's root is uf_head_root's,
/// parent[0] readable): uf_head_root's two reads without its branch, one table read per element
/// and no branch (the per-element form's two branches, on inactive elements and on dropped
/// components, which interleave with the kept ones, took twice the time).  uf_head_root itself
/// keeps its branch: made branch-free, with its mask taken from the root, it slowed this pass and
/// write_members (the candidates stage +0.085 ms, validation +0.06 on TUM, one core).
struct write_candidates_span_kernel {
  const std::int32_t* parent;
  const std::int32_t* scan;  // a root's number, 0 where its component is not kept
  std::int32_t* cand;
  std::int64_t n;
  int span;
  EDGEPLANE_HOST_CLONES void operator()(std::int64_t item) const {
    const std::int64_t i0 = item * span, i1 = i0 + span < n ? i0 + span : n;
    const std::int32_t* __restrict p = parent;
    const std::int32_t* __restrict ids = scan;
    std::int32_t* __restrict out = cand;
    for (std::int64_t i = i0; i < i1; ++i) {
      const std::int32_t h = p[i], inactive = h >> 31;  // -1 where h < 0 (C++20: arithmetic shift)
      const std::int32_t r = p[h & ~inactive] & ~inactive;  // (an inactive element reads p[0], ids[0], gets 0)
      out[i] = ids[r] & ~inactive;
    }
  }
};
/// A split round's ids over a rectangle of the candidate image (`cand`, a view of it), whose
/// pixel (x, y) is element y * cand.width + x of the union-find: pixels of kept components get
/// offset + the 1-based index of their root among the kept roots; all others keep their value, so
/// a split candidate's pixels that no piece took (its rim and its dropped components) keep its
/// id.  A retired id counts as none everywhere after: its status keeps it out of the merge table,
/// the failed flags and the refits, as 0 is.  `parent` flat or counted by runs (uf_head_root).
struct write_members_kernel {
  const std::int32_t* parent;
  const std::int32_t* flags;
  const std::int32_t* scan;
  std::int32_t offset;
  image_view<std::int32_t> cand;
  EDGEPLANE_HD void operator()(int x, int y) const {
    const std::int32_t r = uf_head_root(parent, static_cast<std::int64_t>(y) * cand.width + x);
    if (r >= 0 && flags[r]) cand(x, y) = offset + scan[r];
  }
};
/// write_members_kernel on host backends, one work item per row of its rectangle, over the
/// row's span of eroded pixels (eroded_rows_kernel's eroded_spans), the only ones of kept pieces.
struct write_members_rows {
  write_members_kernel k;
  const std::int32_t* spans;
  void operator()(std::int64_t row) const {
    const int y = static_cast<int>(row);
    for (int x = spans[2 * y]; x < spans[2 * y + 1]; ++x) k(x, y);
  }
};
/// Labels from a candidate-id image through a table (host backends' sums of a split round's
/// pieces): pixel (x, y) gets table[cand(x, y)] (ids 0 .. the table's last).  No lanes<L> of its
/// own: moments_kernel's per-lane fallback is the same gather.  (Looking the id up once where 8
/// pixels hold one, after a test that they do, made the pass slower per pixel than
/// candidate_image_labels' by about a tenth of a pixel's sums.)
struct candidate_table_labels {
  image_view<const std::int32_t> cand;
  const std::int32_t* table;
  /// When not null: the labels of row y lie in columns [col0 + spans[2 (y - row0)], col0 + spans[2 (y - row0) + 1])
  /// (the host moments read only those: has_column_spans).
  const std::int32_t* spans = nullptr;
  int row0 = 0, col0 = 0;
  EDGEPLANE_HD std::int32_t operator()(int x, int y) const { return table[cand(x, y)]; }
  EDGEPLANE_HD void columns(int y, int& x0, int& x1) const {
    if (!spans) return;
    x0 = col0 + spans[2 * (y - row0)];
    x1 = col0 + spans[2 * (y - row0) + 1];
  }
};
/// The rectangle [x0, x1] x [y0, y1] of view v as a view of its own (same pitch).
template <class T>
image_view<T> sub_view(image_view<T> v, int x0, int y0, int x1, int y1) {
  return image_view<T>{v.data + static_cast<std::ptrdiff_t>(y0) * v.pitch + x0, x1 - x0 + 1, y1 - y0 + 1, v.pitch};
}
}  // namespace detail

template <class Backend = cpu>
class segmenter {
 public:
  explicit segmenter(params p = presets::thesis_full(), Backend b = Backend{}) : p_(p), b_(b) {
    validate(p_);
    rebind();
  }

  const params& parameters() const { return p_; }
  /// Replaces the thresholds (validated; throws edgeplane::error).
  void set_parameters(const params& p) {
    validate(p);
    p_ = p;
  }
  const Backend& backend() const { return b_; }

  /// Segments a uint16 depth image (metres_per_unit: e.g. 0.001 for millimetres).  `depth` and
  /// `labels` are HOST memory of the same size; labels receives 0 (no plane) or the plane id.
  /// Synchronous.  Throws edgeplane::error on unusable arguments.
  segmentation_result segment(image_view<const std::uint16_t> depth, float metres_per_unit, const intrinsics& k,
                              image_view<std::uint16_t> labels) {
    segmentation_result r;
    segment(depth, metres_per_unit, k, labels, r);
    return r;
  }
  /// Float depth in metres (0, NaN or infinity = invalid).
  segmentation_result segment(image_view<const float> depth, const intrinsics& k, image_view<std::uint16_t> labels) {
    segmentation_result r;
    segment(depth, 1.f, k, labels, r);
    return r;
  }
  /// As above, reusing `out` (its vector keeps its capacity: no allocation in steady state).
  template <class In>
  void segment(image_view<const In> depth, float scale, const intrinsics& k, image_view<std::uint16_t> labels,
               segmentation_result& out) {
    static_assert(std::is_same_v<In, std::uint16_t> || std::is_same_v<In, float>, "uint16 or float depth");
    run(depth, scale, k, labels, out, false);
  }

  /// As segment(), but `depth` and `labels` are in the BACKEND's memory (device pointers for
  /// edgeplane::cuda, any pitch): the frame is neither uploaded nor are its labels downloaded,
  /// only the few per-plane numbers cross to the host.  Returns when the labels are written.
  /// For host backends this is segment().
  template <class In>
  void segment_on_backend(image_view<const In> depth, float scale, const intrinsics& k,
                          image_view<std::uint16_t> labels, segmentation_result& out) {
    static_assert(std::is_same_v<In, std::uint16_t> || std::is_same_v<In, float>, "uint16 or float depth");
    run(depth, scale, k, labels, out, true);
  }

  /// Offline throughput: segments frames[i] (one camera: intrinsics k for all) into labels[i]
  /// (host memory) with this segmenter, results[i] receiving each frame's planes and times.
  /// Throws edgeplane::error before any work when the counts differ; a frame whose arguments are
  /// unusable throws when its turn comes (the frames before it are done).
  template <class In>
  void segment_batch(const std::vector<image_view<const In>>& frames, float scale, const intrinsics& k,
                     const std::vector<image_view<std::uint16_t>>& labels, std::vector<segmentation_result>& results) {
    detail::check_batch_counts(frames.size(), labels.size());
    results.resize(frames.size());
    for (std::size_t i = 0; i < frames.size(); ++i) segment(frames[i], scale, k, labels[i], results[i]);
  }

  /// The edge map (edge_bits) and the closed edge mask of the last frame, at processing resolution,
  /// in the backend's memory.
  image_view<const std::uint8_t> edge_map() const { return view(edges_.data(), pw_, ph_); }
  image_view<const std::uint8_t> edge_mask() const { return view(mask_.data(), pw_, ph_); }
  /// Bytes of scratch memory held in the backend's memory.
  std::size_t scratch_bytes() const {
    return raw_in_.capacity_bytes() + z_a_.capacity_bytes() + z_b_.capacity_bytes() +
           z_proc_.capacity_bytes() + z_smooth_.capacity_bytes() + edges_.capacity_bytes() + mask_.capacity_bytes() + runs_.capacity_bytes() + cov_l_.capacity_bytes() +
           cov_r_.capacity_bytes() + parent_.capacity_bytes() + count_.capacity_bytes() + flags_.capacity_bytes() +
           scan_.capacity_bytes() + cand_.capacity_bytes() + failed_.capacity_bytes() + moments_.capacity_bytes() + bbox_.capacity_bytes() + table_.capacity_bytes() +
           planes_.capacity_bytes() + tol_.capacity_bytes() + refit_planes_.capacity_bytes() + refit_tol_.capacity_bytes() + flag_.capacity_bytes() + grow_counts_.capacity_bytes() + sweep_dirty_.capacity_bytes() + lab_a_.capacity_bytes() + lab_b_.capacity_bytes() + lab_c_.capacity_bytes() +
           lab_full_.capacity_bytes() + origin_.capacity_bytes();
  }

 private:
  template <class T>
  static image_view<T> view(T* p, int w, int h) {
    return image_view<T>{p, w, h, w};
  }

  void rebind() {
    raw_in_.set_backend(b_);
    z_a_.set_backend(b_);
    z_b_.set_backend(b_);
    z_proc_.set_backend(b_);
    z_smooth_.set_backend(b_);
    edges_.set_backend(b_);
    mask_.set_backend(b_);
    runs_.set_backend(b_);
    cov_l_.set_backend(b_);
    cov_r_.set_backend(b_);
    parent_.set_backend(b_);
    count_.set_backend(b_);
    flags_.set_backend(b_);
    scan_.set_backend(b_);
    cand_.set_backend(b_);
    failed_.set_backend(b_);
    moments_.set_backend(b_);
    bbox_.set_backend(b_);
    table_.set_backend(b_);
    planes_.set_backend(b_);
    tol_.set_backend(b_);
    refit_planes_.set_backend(b_);
    refit_tol_.set_backend(b_);
    flag_.set_backend(b_);
    grow_counts_.set_backend(b_);
    sweep_dirty_.set_backend(b_);
    lab_a_.set_backend(b_);
    lab_b_.set_backend(b_);
    lab_c_.set_backend(b_);
    lab_full_.set_backend(b_);
    origin_.set_backend(b_);
  }

  using clock = std::chrono::steady_clock;
  static double ms_since(clock::time_point& t) {
    const auto now = clock::now();
    const double ms = std::chrono::duration<double, std::milli>(now - t).count();
    t = now;
    return ms;
  }

  // Downloads the moment blocks of labels first+1..n and fits each (host); the blocks and fits of
  // labels 1..first stay as they are.
  // (planes = false: the moments are first-order only, and only counts, boxes and centroids are set)
  void download_fits(std::int32_t n, std::vector<plane_fit>& fits, std::int32_t first = 0, bool planes = true) {
    host_moments_.resize(static_cast<std::size_t>(n + 1) * moment_slots);
    host_bbox_.resize(static_cast<std::size_t>(n + 1) * 4);
    const std::size_t m0 = static_cast<std::size_t>(first + 1) * moment_slots, b0 = static_cast<std::size_t>(first + 1) * 4;
    b_.copy_to_host(host_moments_.data() + m0, moments_.data() + m0, (host_moments_.size() - m0) * sizeof(std::uint64_t));
    b_.copy_to_host(host_bbox_.data() + b0, bbox_.data() + b0, (host_bbox_.size() - b0) * sizeof(std::int32_t));
    fits.resize(static_cast<std::size_t>(n));
    for (std::int32_t c = first + 1; c <= n; ++c)
      fits[c - 1] = (planes ? fit_plane : centroid_fit)(host_moments_.data() + static_cast<std::size_t>(c) * moment_slots,
                                                        host_bbox_.data() + static_cast<std::size_t>(c) * 4);
  }

  // The connected components (into parent_) of the n elements, their roots flagged (flags_) where
  // they have at least min_size elements and numbered 1, 2, ... in raster order of the roots
  // (scan_); returns how many.  Host backends count the components by the row pass's runs
  // (uf_count_runs_kernel), which flattens only the runs' first elements: parent_ is then read
  // through detail::uf_head_root.
  // (spans: host backends, the rows' column spans of the active elements, unite_components')
  template <class Active, class Adjacency>
  std::int32_t components(std::int64_t n, Active active, std::int64_t work_items, Adjacency adj,
                          std::int32_t min_size, const std::int32_t* spans = nullptr) {
    if constexpr (Backend::host_accessible) {
      static_assert(detail::has_grid_joins<Adjacency>, "host components are counted by the row pass's runs");
      std::uint16_t* right_bits = nullptr;  // the row pass's right joins, for the vertical unions
      if constexpr (detail::has_join_lanes<Adjacency>) {
        right_bits_.resize(static_cast<std::size_t>(detail::join_blocks(adj.grid_width())) * adj.grid_height());
        right_bits = right_bits_.data();
      }
      // the runs' lengths in count_, their first elements listed per row in flags_
      row_heads_.resize(static_cast<std::size_t>(adj.grid_height()));
      const detail::row_runs runs{count_.data(), flags_.data(), row_heads_.data()};
      detail::unite_components(b_, n, active, work_items, adj, parent_.data(), right_bits, runs, spans);
      return number_runs(adj.grid_width(), adj.grid_height(), runs, min_size);
    } else {
      connected_components(b_, n, active, work_items, adj, parent_.data());
      return flag_components(n, min_size);
    }
  }

  // Host backends: counts the components of the w x h grid by the row pass's runs (into count_ at
  // the roots), flags (flags_) the roots of those of at least min_size elements and numbers them
  // 1, 2, ... in raster order of their roots (scan_); returns how many.  flags_ and scan_ are
  // written at the roots only (the only entries anyone reads: every reader indexes them by a root;
  // scan_ is 0 at the roots not kept, which write_candidates_span_kernel relies on).  A row's list
  // of roots (in flags_) lies in its own elements, the only ones its roots' entries can overwrite,
  // so it is copied out first.
  // (runs: the row pass's, whose heads lie in flags_ and lengths in count_)
  std::int32_t number_runs(int w, int h, detail::row_runs runs, std::int32_t min_size) {
    b_.for_each_index(h, detail::uf_count_runs_kernel{parent_.data(), runs, w});
    std::int32_t* flags = flags_.data();
    std::int32_t* scan = scan_.data();
    const std::int32_t* count = runs.len;
    std::int32_t k = 0;
    kept_roots_.clear();
    row_list_.resize(static_cast<std::size_t>(w));
    if (static_cast<std::int64_t>(w) * h > 0) scan[0] = 0;  // (write_candidates_span_kernel reads it for inactive elements; a root 0 sets its own)
    for (int y = 0; y < h; ++y) {
      const std::int32_t m = runs.nheads[y];
      const std::int32_t* list = runs.heads + static_cast<std::int64_t>(y) * w;
      std::copy(list, list + m, row_list_.begin());
      for (std::int32_t j = 0; j < m; ++j) {
        const std::int32_t r = row_list_[static_cast<std::size_t>(j)];
        const std::int32_t keep = count[r] >= min_size ? 1 : 0;
        k += keep;
        flags[r] = keep;
        scan[r] = keep ? k : 0;  // the inclusive scan of the flags at kept roots (0 at the others)
        if (keep) kept_roots_.push_back(r);
      }
    }
    return k;
  }

  // Device backends: flags (flags_) the roots of the flattened union-find's components of at
  // least min_size elements and numbers them 1, 2, ... in raster order of their roots (scan_);
  // returns how many.
  std::int32_t flag_components(std::int64_t n, std::int32_t min_size) {
    b_.memset(count_.data(), 0, sizeof(std::int32_t) * n);
    b_.for_each_index(n, detail::count_roots_kernel{parent_.data(), count_.data()});
    b_.for_each_index(n, detail::flag_candidates_kernel{parent_.data(), count_.data(), min_size, flags_.data()});
    b_.inclusive_scan(flags_.data(), n, scan_.data());
    std::int32_t k = 0;  // the scan's last element is the number of components kept
    b_.copy_to_host(&k, scan_.data() + (n - 1), sizeof(std::int32_t));
    return k;
  }

  // Fits candidates first+1..num from their pixels; those of 1..first keep their fits (a split
  // round writes its new ids only over pixels of retired candidates, so the others are unchanged).
  // Candidates first+1..num lie in rows [row_begin, row_end) (row_end < 0: to the last).
  void refit_candidates(image_view<const float> z, const intrinsics& kp, std::int32_t num, std::int32_t first = 0,
                        int row_begin = 0, int row_end = -1) {
    moments_.resize(static_cast<std::size_t>(num + 1) * moment_slots);
    bbox_.resize(static_cast<std::size_t>(num + 1) * 4);
    accumulate_moments(b_, z, kp, detail::candidate_image_labels{view(cand_.data(), pw_, ph_), first}, num,
                       moments_.data(), bbox_.data(), row_begin, row_end);
    download_fits(num, fits_, first);
  }

  // Host backends, a split round: each piece's candidate (read at its root before the ids are
  // written; a piece lies in one candidate), with cand the whole candidate image, [x0, x1] x
  // [y0, y1] the round's rectangle, kept_roots_ its union-find's kept roots in order.
  void split_parents(image_view<const std::int32_t> cand, int x0, int y0, int x1, std::int32_t added) {
    const int rw = x1 - x0 + 1;
    piece_of_.resize(static_cast<std::size_t>(added) + 1);
    piece_size_.resize(static_cast<std::size_t>(added) + 1);
    for (std::int32_t k = 1; k <= added; ++k) {
      const std::int32_t r = kept_roots_[static_cast<std::size_t>(k - 1)];
      piece_of_[static_cast<std::size_t>(k)] = cand(x0 + r % rw, y0 + r / rw);
      piece_size_[static_cast<std::size_t>(k)] = count_.data()[r];
    }
  }

  // Host backends, a split round over the w x h rectangle at (x0, y0): the columns of each of its
  // rows that the erosion reads (scan_spans_, in the rectangle's columns; returned), those of the
  // failed candidates' boxes (host_failed_, host_bbox_) that cover the row and, after the first
  // round (after_round, whose rectangle was at (last_x0, last_y0)), within that round's eroded
  // columns (eroded_spans_): its pieces, the only candidates that can have failed since, lie there.
  std::int32_t* split_scan_spans(std::int32_t num_cand, int x0, int y0, int w, int h, bool after_round, int last_x0,
                                 int last_y0) {
    scan_spans_.assign(2 * static_cast<std::size_t>(h), 0);
    std::int32_t* sc = scan_spans_.data();
    for (int y = 0; y < h; ++y) sc[2 * y] = w;  // (empty)
    for (int c = 0; c < num_cand; ++c)
      if (host_failed_[c + 1]) {
        const std::int32_t* bb = host_bbox_.data() + static_cast<std::size_t>(c + 1) * 4;
        for (int y = bb[1] - y0; y <= bb[3] - y0; ++y) {
          sc[2 * y] = std::min(sc[2 * y], bb[0] - x0);
          sc[2 * y + 1] = std::max(sc[2 * y + 1], bb[2] - x0 + 1);
        }
      }
    if (after_round)
      for (int y = 0; y < h; ++y) {
        const int py = y + y0 - last_y0;  // the row in the last rectangle, whose columns start at last_x0
        const bool in = py >= 0 && 2 * static_cast<std::size_t>(py) < eroded_spans_.size();
        const std::int32_t* e = eroded_spans_.data() + 2 * static_cast<std::size_t>(in ? py : 0);
        sc[2 * y] = std::max(sc[2 * y], in ? e[0] + last_x0 - x0 : w);
        sc[2 * y + 1] = std::min(sc[2 * y + 1], in ? e[1] + last_x0 - x0 : 0);
      }
    return sc;
  }

  // Host backends: the moment blocks, boxes and fits of a split round's pieces, candidates
  // num_cand+1 .. num_cand+added, after their ids are written (split_parents before that), in rows
  // [y0, y1] and, of row y, columns x0 + [failed_spans_[2 (y - y0)], failed_spans_[2 (y - y0) + 1]) (the
  // failed candidates' pixels).  Where a split candidate's largest piece outweighs the pixels of it that no piece took
  // (its rim and dropped components, which keep its id), that piece is not summed: its sums are
  // the candidate's less those of the rest and of its other pieces (integers: exactly the piece's
  // own sums), so a candidate that loses only its rim costs the sums of its rim.  That piece's box
  // is its candidate's (a box around its pixels, which is all a box serves for: the next round's
  // rectangle).
  void split_refit(image_view<const float> z, const intrinsics& kp, image_view<const std::int32_t> cand, int x0,
                   int y0, int y1, std::int32_t num_cand, std::int32_t added) {
    const std::size_t slots = moment_slots;
    const std::int32_t total = num_cand + added;
    largest_.assign(static_cast<std::size_t>(num_cand) + 1, 0);      // candidate -> its largest piece
    rest_size_.assign(static_cast<std::size_t>(num_cand) + 1, 0);   // its pixels that no piece took
    for (std::int32_t k = 1; k <= added; ++k) {
      const std::int32_t c = piece_of_[static_cast<std::size_t>(k)];
      std::int32_t& big = largest_[static_cast<std::size_t>(c)];
      if (big == 0) rest_size_[static_cast<std::size_t>(c)] = static_cast<std::int64_t>(host_moments_[static_cast<std::size_t>(c) * slots + 10]);
      rest_size_[static_cast<std::size_t>(c)] -= piece_size_[static_cast<std::size_t>(k)];
      if (big == 0 || piece_size_[static_cast<std::size_t>(k)] > piece_size_[static_cast<std::size_t>(big)]) big = k;
    }
    // labels: piece k -> k unless derived (0), a derived piece's candidate -> added + 1, ...
    label_table_.assign(static_cast<std::size_t>(total) + 1, 0);
    for (std::int32_t k = 1; k <= added; ++k) label_table_[static_cast<std::size_t>(num_cand + k)] = k;
    std::int32_t labels = added;
    for (std::int32_t c = 1; c <= num_cand; ++c) {
      const std::int32_t big = largest_[static_cast<std::size_t>(c)];
      if (big != 0 && rest_size_[static_cast<std::size_t>(c)] < piece_size_[static_cast<std::size_t>(big)]) {
        label_table_[static_cast<std::size_t>(num_cand + big)] = 0;
        label_table_[static_cast<std::size_t>(c)] = ++labels;
      } else {
        largest_[static_cast<std::size_t>(c)] = 0;  // summed directly
      }
    }
    moments_.resize(static_cast<std::size_t>(labels + 1) * slots);
    bbox_.resize(static_cast<std::size_t>(labels + 1) * 4);
    accumulate_moments(b_, z, kp, detail::candidate_table_labels{cand, label_table_.data(), failed_spans_.data(), y0, x0},
                       labels, moments_.data(), bbox_.data(), y0, y1 + 1);
    const std::uint64_t* m = moments_.data();
    const std::int32_t* bb = bbox_.data();
    host_moments_.resize(static_cast<std::size_t>(total + 1) * slots);
    host_bbox_.resize(static_cast<std::size_t>(total + 1) * 4);
    for (std::int32_t k = 1; k <= added; ++k) {
      std::uint64_t* dst = host_moments_.data() + static_cast<std::size_t>(num_cand + k) * slots;
      std::int32_t* box = host_bbox_.data() + static_cast<std::size_t>(num_cand + k) * 4;
      const std::int32_t c = piece_of_[static_cast<std::size_t>(k)];
      if (largest_[static_cast<std::size_t>(c)] != k) {
        std::copy_n(m + static_cast<std::size_t>(k) * slots, slots, dst);
        std::copy_n(bb + static_cast<std::size_t>(k) * 4, 4, box);
        continue;
      }
      // the candidate's sums less its rest's and its other pieces' (wrapping uint64: exact)
      const std::uint64_t* whole = host_moments_.data() + static_cast<std::size_t>(c) * slots;
      const std::uint64_t* rest = m + static_cast<std::size_t>(label_table_[static_cast<std::size_t>(c)]) * slots;
      for (std::size_t j = 0; j < slots; ++j) dst[j] = whole[j] - rest[j];
      for (std::int32_t o = 1; o <= added; ++o)
        if (o != k && piece_of_[static_cast<std::size_t>(o)] == c)
          for (std::size_t j = 0; j < slots; ++j) dst[j] -= m[static_cast<std::size_t>(o) * slots + j];
      std::copy_n(host_bbox_.data() + static_cast<std::size_t>(c) * 4, 4, box);
    }
    fits_.resize(static_cast<std::size_t>(total));
    for (std::int32_t k = num_cand + 1; k <= total; ++k)
      fits_[static_cast<std::size_t>(k - 1)] = fit_plane(host_moments_.data() + static_cast<std::size_t>(k) * slots,
                                                         host_bbox_.data() + static_cast<std::size_t>(k) * 4);
#if defined(EDGEPLANE_VERIFY_SPLIT_SUMS)
    // (tests) the pieces summed directly give the very same blocks, in boxes within theirs
    verify_moments_.assign(host_moments_.begin(), host_moments_.end());
    verify_bbox_.assign(host_bbox_.begin(), host_bbox_.end());
    verify_fits_.assign(fits_.begin(), fits_.end());
    refit_candidates(z, kp, total, num_cand, y0, y1 + 1);  // the pieces' blocks summed from their ids
    for (std::int32_t k = num_cand + 1; k <= total; ++k) {
      const std::uint64_t* direct = moments_.data() + static_cast<std::size_t>(k) * slots;
      const std::uint64_t* got = verify_moments_.data() + static_cast<std::size_t>(k) * slots;
      const std::int32_t* box = bbox_.data() + static_cast<std::size_t>(k) * 4;
      const std::int32_t* got_box = verify_bbox_.data() + static_cast<std::size_t>(k) * 4;
      detail::require(std::equal(direct, direct + slots, got) && got_box[0] <= box[0] && got_box[1] <= box[1] &&
                          got_box[2] >= box[2] && got_box[3] >= box[3],
                      "split_refit: candidate " + std::to_string(k) + "'s sums differ from its direct sums");
      if (largest_[static_cast<std::size_t>(piece_of_[static_cast<std::size_t>(k - num_cand)])] == k - num_cand)
        ++verified_derived_pieces;
    }
    host_moments_.swap(verify_moments_);  // go on with what the segmenter computed
    host_bbox_.swap(verify_bbox_);
    fits_.swap(verify_fits_);
#endif
  }
#if defined(EDGEPLANE_VERIFY_SPLIT_SUMS)
  std::vector<std::uint64_t> verify_moments_;
  std::vector<std::int32_t> verify_bbox_;
  std::vector<plane_fit> verify_fits_;

 public:
  /// (tests, with EDGEPLANE_VERIFY_SPLIT_SUMS) split pieces whose sums were derived by
  /// subtraction and checked against their direct sums
  std::int64_t verified_derived_pieces = 0;

 private:
#endif

  template <class In>
  void run(image_view<const In> depth_in, float scale, const intrinsics& k, image_view<std::uint16_t> labels_out,
           segmentation_result& out, bool on_backend) {
    auto t0 = clock::now(), t = t0;
    out.planes.clear();
    out.times = {};
    out.candidates = out.valid_candidates = 0;
    detail::check_frame(depth_in, scale, k);
    detail::check_view(labels_out, "labels");
    detail::check_same_size(depth_in, labels_out, "depth", "labels");
    const int w = depth_in.width, h = depth_in.height;
    if (w == 0 || h == 0) return;
    const std::int64_t n_full = static_cast<std::int64_t>(w) * h;

    // ---- 1. preprocessing ----------------------------------------------------------------------
    const bool down = p_.downscale && w >= 2 && h >= 2;
    pw_ = down ? w / 2 : w;
    ph_ = down ? h / 2 : h;
    const std::int64_t n = static_cast<std::int64_t>(pw_) * ph_;
    const intrinsics kp = down ? scaled(k, 2) : k;
    z_a_.resize(n_full);
    z_b_.resize(n_full);
    image_view<const In> src = depth_in;
    if (!Backend::host_accessible && !on_backend) {
      raw_in_.resize(n_full * sizeof(In));
      In* dst = reinterpret_cast<In*>(raw_in_.data());
      if (depth_in.pitch == w)  // dense: one copy
        b_.copy_from_host(dst, depth_in.data, sizeof(In) * n_full);
      else
        for (int y = 0; y < h; ++y)
          b_.copy_from_host(dst + static_cast<std::int64_t>(y) * w, &depth_in(0, y), sizeof(In) * w);
      src = image_view<const In>{dst, w, h, w};
    }
    const auto za = view(z_a_.data(), w, h), zb = view(z_b_.data(), w, h);
    // Deeper than the exact fixed-point statistics hold (hundreds of metres for real cameras) is
    // invalid, like depth beyond max_depth.
    const float max_depth = std::min(p_.max_depth, fixed_point_max_depth(k, w, h));
    convert_depth(b_, src, scale, p_.min_depth, max_depth, za);
    image_view<float> z_full = za;
    if (p_.depth_closing_radius > 0) {
      close_depth(b_, za, zb, za, p_.depth_closing_radius);  // in place: the erosion writes holes only
    }
    image_view<float> z = z_full;
    if (down) {
      z_proc_.resize(n);
      z = view(z_proc_.data(), pw_, ph_);
      downscale_depth(b_, z_full, z);
    }
    if (p_.smooth_radius > 0) {  // smooth into the buffer z does not occupy
      z_smooth_.resize(n);
      const auto zs = view(z_smooth_.data(), pw_, ph_);
      smooth_depth(b_, z, zs, p_.smooth_radius, p_.smooth_k, p_.noise.sigma0, p_.noise.sigma2);
      z = zs;
    }
    b_.synchronize();
    out.times.preprocess = ms_since(t);

    // ---- 2. edges ------------------------------------------------------------------------------
    edges_.resize(n);
    mask_.resize(n);
    cov_l_.resize(n);
    const auto edges = view(edges_.data(), pw_, ph_), mask = view(mask_.data(), pw_, ph_),
               scratch8 = view(cov_l_.data(), pw_, ph_);
    if constexpr (detail::row_lanes<Backend> > 1) runs_.resize(edge_scratch_bytes(pw_, ph_, p_));
    detect_edges(b_, z, kp, p_, edges, runs_.data());
    close_edges(b_, edges, scratch8, mask, p_.edge_closing_radius);
    b_.synchronize();
    out.times.edges = ms_since(t);

    // ---- 3. line segments ----------------------------------------------------------------------
    cov_r_.resize(n);
    const auto cov_l = view(cov_l_.data(), pw_, ph_), cov_r = view(cov_r_.data(), pw_, ph_);
    extract_segments<direction::left_diagonal>(b_, z, mask, kp, p_, cov_l);
    extract_segments<direction::right_diagonal>(b_, z, mask, kp, p_, cov_r);
    b_.synchronize();
    out.times.segments = ms_since(t);

    // ---- 4. candidates: union-find of touching and crossing runs --------------------------------
    parent_.resize(n);
    count_.resize(n);
    flags_.resize(n);
    scan_.resize(n);
    cand_.resize(n);
    const auto cand = view(cand_.data(), pw_, ph_);
    const float slope_inv_f = p_.adjacency_slope / std::min(std::abs(kp.fx), std::abs(kp.fy));
    const detail::covered_active covered{cov_l_.data(), cov_r_.data()};
    std::int32_t num_cand =
        components(n, covered, n,
                   detail::grid4_adjacency<detail::covered_active>{z, covered, p_.t_je, p_.t_je_quad, slope_inv_f},
                   p_.t_size);
    // each pixel's candidate id (0 for pixels of no kept component)
    if constexpr (Backend::host_accessible) {
      constexpr int span = 4096;
      b_.for_each_index((n + span - 1) / span,
                        detail::write_candidates_span_kernel{parent_.data(), scan_.data(), cand_.data(), n, span});
    } else {
      b_.for_each_index(n, detail::write_candidates_kernel{parent_.data(), flags_.data(), scan_.data(), cand_.data()});
    }
    out.candidates = num_cand;
    b_.synchronize();
    out.times.candidates = ms_since(t);

    // ---- 5. validation, splitting candidates that fail -----------------------------------------
    // status: 1 = plane, 0 = failed (may be split), 2 = retired (replaced by its pieces)
    refit_candidates(z, kp, num_cand);
    status_.assign(static_cast<std::size_t>(num_cand), 0);
    for (int c = 0; c < num_cand; ++c) status_[c] = is_plane(fits_[c], p_) ? 1 : 0;
    int last_x0 = 0, last_y0 = 0;  // (host backends) the last split round's rectangle's corner
    for (int round = 1; round <= p_.split_rounds; ++round) {
      host_failed_.assign(static_cast<std::size_t>(num_cand + 1), 0);
      // The failed candidates' pixels all lie in the union [x0, x1] x [y0, y1] of their bounding
      // boxes: the round works on that rectangle only.
      int x0 = pw_, y0 = ph_, x1 = -1, y1 = -1;
      for (int c = 0; c < num_cand; ++c)
        if (status_[c] == 0) {
          host_failed_[c + 1] = 1;
          status_[c] = 2;
          const std::int32_t* bb = host_bbox_.data() + static_cast<std::size_t>(c + 1) * 4;
          x0 = std::min(x0, bb[0]);
          y0 = std::min(y0, bb[1]);
          x1 = std::max(x1, bb[2]);
          y1 = std::max(y1, bb[3]);
        }
      if (x1 < x0 || y1 < y0) break;  // none failed
      failed_.resize(host_failed_.size());
      b_.copy_from_host(failed_.data(), host_failed_.data(), host_failed_.size());
      // The failed candidates eroded (detail::eroded_failed_active, computed separably into the
      // free coverage buffer, dense over the rectangle), then split by the union-find, whose
      // elements are the rectangle's pixels in raster order (so roots, and the new ids, come in
      // the raster order of the whole image).  A pixel whose erosion window is one failed
      // candidate has that window inside the candidate's box, so the rectangle changes nothing.
      const auto cand_r = detail::sub_view(cand, x0, y0, x1, y1);
      const auto z_r = detail::sub_view(image_view<const float>(z), x0, y0, x1, y1);
      const std::int64_t n_r = static_cast<std::int64_t>(cand_r.width) * cand_r.height;
      // Host backends: the passes after the erosion read each row's span of failed (the refit)
      // or eroded pixels (the union-find, the ids) only, not the whole rectangle; the erosion
      // itself looks at the columns of the failed candidates' boxes that cover the row and, after
      // the first round, at the last round's eroded columns (the only pixels its pieces have).
      std::int32_t *failed_spans = nullptr, *eroded_spans = nullptr, *scan_spans = nullptr;
      if constexpr (Backend::host_accessible) {
        scan_spans = split_scan_spans(num_cand, x0, y0, cand_r.width, cand_r.height, round > 1, last_x0, last_y0);
        failed_spans_.resize(2 * static_cast<std::size_t>(cand_r.height));
        eroded_spans_.resize(2 * static_cast<std::size_t>(cand_r.height));
        failed_spans = failed_spans_.data();
        eroded_spans = eroded_spans_.data();
        last_x0 = x0;
        last_y0 = y0;
      }
      erode_failed(b_, image_view<const std::int32_t>(cand_r), failed_.data(), round * p_.split_erode,
                   view(cov_l_.data(), cand_r.width, cand_r.height), failed_spans, eroded_spans, scan_spans);
      const detail::mask_bit_active eroded{cov_l_.data(), 2};
      const std::int32_t added =
          components(n_r, eroded, n_r,
                     detail::grid4_adjacency<detail::mask_bit_active>{z_r, eroded, p_.t_je, p_.t_je_quad, slope_inv_f},
                     p_.t_size, eroded_spans);
      const detail::write_members_kernel members{parent_.data(), flags_.data(), scan_.data(), num_cand, cand_r};
      if constexpr (Backend::host_accessible) {
        split_parents(image_view<const std::int32_t>(cand), x0, y0, x1, added);
        if (added > 0) b_.for_each_index(cand_r.height, detail::write_members_rows{members, eroded_spans});
      } else {
        detail::for_each_pixel(b_, cand_r.width, cand_r.height, members);
      }
      if (added == 0) break;
      if constexpr (Backend::host_accessible) {
        split_refit(z, kp, image_view<const std::int32_t>(cand), x0, y0, y1, num_cand, added);
      } else
        refit_candidates(z, kp, num_cand + added, num_cand, y0, y1 + 1);
      num_cand += added;
      for (int c = num_cand - added; c < num_cand; ++c) status_.push_back(is_plane(fits_[c], p_) ? 1 : 0);
    }
    out.candidates = num_cand;
    keep_.assign(static_cast<std::size_t>(num_cand), 0);
    for (int c = 0; c < num_cand; ++c) keep_[c] = status_[c] == 1 ? 1 : 0;
    out.valid_candidates = static_cast<int>(std::count(keep_.begin(), keep_.end(), 1));
    b_.synchronize();
    out.times.validation = ms_since(t);

    // ---- 6. merging ----------------------------------------------------------------------------
    merge_groups(fits_, keep_, p_, group_, merge_parent_);
    const std::vector<int>& group = group_;
    int num_planes = 0;
    for (int g : group) num_planes = std::max(num_planes, g + 1);
    num_planes = std::min(num_planes, 65535);
    host_table_.assign(static_cast<std::size_t>(num_cand + 1), 0);
    group_moments_.assign(static_cast<std::size_t>(num_planes + 1) * moment_slots, 0);
    for (int c = 0; c < num_cand; ++c) {
      if (group[c] < 0 || group[c] >= num_planes) continue;
      host_table_[c + 1] = static_cast<std::uint16_t>(group[c] + 1);
      add_moments(group_moments_.data() + static_cast<std::size_t>(group[c] + 1) * moment_slots,
                  host_moments_.data() + static_cast<std::size_t>(c + 1) * moment_slots);
    }
    host_planes_.assign(static_cast<std::size_t>(num_planes + 1) * 4, 0.f);
    host_tol_.assign(static_cast<std::size_t>(num_planes + 1), 0.f);
    group_fits_.resize(static_cast<std::size_t>(num_planes));
    auto set_planes = [&](const std::uint64_t* moments) {
      for (int g = 1; g <= num_planes; ++g) {
        const plane_fit f = fit_plane(moments + static_cast<std::size_t>(g) * moment_slots);
        if (f.points < 3) continue;  // keep the previous fit of a plane that lost its inliers
        group_fits_[g - 1] = f;
        for (int j = 0; j < 3; ++j) host_planes_[4 * g + j] = static_cast<float>(f.normal(j));
        host_planes_[4 * g + 3] = static_cast<float>(f.d);
        host_tol_[g] = static_cast<float>(std::max(2.5 * std::sqrt(f.eigenvalues(2)), 1e-3));
      }
    };
    set_planes(group_moments_.data());
    table_.resize(host_table_.size());
    planes_.resize(host_planes_.size());
    tol_.resize(host_tol_.size());
    b_.copy_from_host(table_.data(), host_table_.data(), host_table_.size() * sizeof(std::uint16_t));
    // The plane image (each pixel's merged plane, 0 for none): the refit passes read it, and the
    // final labels (stage 7) start from it.
    lab_a_.resize(n);
    detail::for_each_pixel(b_, pw_, ph_,
                           detail::relabel_kernel<detail::candidate_image_labels>{
                               detail::candidate_image_labels{cand}, table_.data(), view(lab_a_.data(), pw_, ph_)});
    const image_view<const std::uint16_t> plane_image = view(lab_a_.data(), pw_, ph_);
    // Robust refit: twice, keep only the candidate pixels within 2.5 RMS residuals of their plane
    // (the rim of a neighbouring face that a candidate picks up at a crease biases the fit).  Each
    // pass sums only the pixels whose membership changed (detail::inlier_change_labels: label g
    // for those that joined plane g, g + num_planes for those that left it) and corrects the
    // previous sums, integers, so the result is exactly the sums of the pass's inliers.  The first
    // pass starts from the sums of the plane's candidates (every pixel of theirs counted in).
    // Those sums are the candidates' pixels in `cand` (a split round writes only over pixels of
    // retired candidates); should slot 10 (pixels) disagree with slot 0 (points) afterwards, as it
    // must not, the first pass's inliers are summed directly instead.
    constexpr int refit_passes = 2;
    const std::size_t slots = static_cast<std::size_t>(num_planes + 1) * moment_slots;
    host_moments_.assign(group_moments_.begin(), group_moments_.end());
    for (int pass = 0; pass < refit_passes && num_planes > 0; ++pass) {
      // planes_ and tol_ hold the previous pass's planes; this pass's go to refit_planes_, refit_tol_
      refit_planes_.resize(host_planes_.size());
      refit_tol_.resize(host_tol_.size());
      b_.copy_from_host(refit_planes_.data(), host_planes_.data(), host_planes_.size() * sizeof(float));
      b_.copy_from_host(refit_tol_.data(), host_tol_.data(), host_tol_.size() * sizeof(float));
      const std::int32_t changes = 2 * num_planes;
      moments_.resize(static_cast<std::size_t>(changes + 1) * moment_slots);
      bbox_.resize(static_cast<std::size_t>(changes + 1) * 4);
      const float* before_planes = pass == 0 ? refit_planes_.data() : planes_.data();
      const float* before_tol = pass == 0 ? refit_tol_.data() : tol_.data();
      accumulate_moments(b_, z, kp,
                         detail::inlier_change_labels{plane_image, before_planes, before_tol,
                                                      refit_planes_.data(), refit_tol_.data(), num_planes, z,
                                                      detail::make_projector(kp), pass == 0},
                         changes, moments_.data(), bbox_.data());
      change_moments_.resize(static_cast<std::size_t>(changes + 1) * moment_slots);
      b_.copy_to_host(change_moments_.data(), moments_.data(), change_moments_.size() * sizeof(std::uint64_t));
      bool consistent = true;
      for (std::size_t i = moment_slots; i < slots; ++i)
        host_moments_[i] += change_moments_[i] - change_moments_[i + slots - moment_slots];
      for (std::size_t i = moment_slots; i < slots && pass == 0; i += moment_slots)
        consistent = consistent && host_moments_[i + 10] == host_moments_[i];
      if (!consistent) {
        moments_.resize(slots);
        accumulate_moments(b_, z, kp,
                           detail::inlier_labels{plane_image, refit_planes_.data(), refit_tol_.data(), z,
                                                 detail::make_projector(kp)},
                           num_planes, moments_.data(), bbox_.data());
        b_.copy_to_host(host_moments_.data(), moments_.data(), slots * sizeof(std::uint64_t));
      }
      std::swap(planes_, refit_planes_);  // the next pass compares with this one's planes
      std::swap(tol_, refit_tol_);
      set_planes(host_moments_.data());
    }
    b_.copy_from_host(planes_.data(), host_planes_.data(), host_planes_.size() * sizeof(float));
    b_.copy_from_host(tol_.data(), host_tol_.data(), host_tol_.size() * sizeof(float));
    b_.synchronize();
    out.times.merge = ms_since(t);

    // ---- 7. final labels: the plane image, plane-guided growth, closing, upsampling -----------
    lab_b_.resize(n);
    auto la = view(lab_a_.data(), pw_, ph_), lb = view(lab_b_.data(), pw_, ph_);
    const detail::projector proj = detail::make_projector(kp);
    const detail::noise_sigma sigma = detail::make_noise(p_.noise);
    // Growth stops early once a round assigns nothing (the flag is read every 4 rounds, so a device
    // backend synchronizes rarely).
    flag_.resize(1);
    b_.memset(flag_.data(), 0, sizeof(std::int32_t));
    if (p_.grow_sweeps) {
      // rows, then columns: a line is swept again only when the other axis labelled a pixel on it
      sweep_dirty_.resize(static_cast<std::size_t>(ph_) + pw_);
      b_.memset(sweep_dirty_.data(), 0xff, sweep_dirty_.size() * sizeof(std::int32_t));
      for (int it = 0; it < p_.grow_iterations && num_planes > 0; ++it) {
        b_.for_each_index(ph_, detail::grow_sweep_kernel<0>{z, la, proj, sigma, p_.grow_k, planes_.data(),
                                                            tol_.data(), flag_.data(), sweep_dirty_.data()});
        b_.for_each_index(pw_, detail::grow_sweep_kernel<1>{z, la, proj, sigma, p_.grow_k, planes_.data(),
                                                            tol_.data(), flag_.data(), sweep_dirty_.data()});
        std::int32_t changed = 0;
        b_.copy_to_host(&changed, flag_.data(), sizeof(std::int32_t));
        if (!changed) break;
        b_.memset(flag_.data(), 0, sizeof(std::int32_t));
      }
    } else {
      // host backends: per round, each row's count and list of the pixels it labelled (two sets,
      // alternating; detail::grow_front_kernel).  The lists borrow the union-find's parent and
      // count buffers, free from the candidates' last use until the regions' components.
      [[maybe_unused]] const std::size_t hp = static_cast<std::size_t>(ph_) + 2;
      if constexpr (Backend::host_accessible) {
        grow_counts_.resize(2 * hp);
        b_.memset(grow_counts_.data(), 0, 2 * hp * sizeof(std::int32_t));
      }
      for (int it = 0; it < p_.grow_iterations && num_planes > 0; ++it) {
        const detail::grow_kernel g{z, la, lb, proj, sigma, p_.grow_k, planes_.data(), tol_.data(), flag_.data()};
        if constexpr (Backend::host_accessible) {  // only the growth front is evaluated
          std::int32_t* counts = grow_counts_.data();
          std::int32_t* lists[2] = {parent_.data(), count_.data()};
          const int p = it % 2, q = 1 - p;
          b_.for_each_index(ph_, detail::grow_front_kernel{g, counts + p * hp, lists[p], counts + q * hp, lists[q],
                                                           it == 0});
        } else {
          detail::for_each_pixel(b_, pw_, ph_, g);
        }
        std::swap(la, lb);
        if (it % 4 == 3) {
          std::int32_t changed = 0;
          b_.copy_to_host(&changed, flag_.data(), sizeof(std::int32_t));
          if (!changed) break;
          b_.memset(flag_.data(), 0, sizeof(std::int32_t));
        }
      }
    }
    // Where the closing's labels are the final ones (no regions to split, no upsampling) and the
    // caller's label image is in the backend's memory, the closing writes them there: no copy.
    const bool closing = p_.label_closing_radius > 0 && num_planes > 0;
    const bool closed_out = closing && !p_.split_regions && !down && (Backend::host_accessible || on_backend);
    if (closing) {
      image_view<std::uint16_t> lc = labels_out;
      if (!closed_out) {
        lab_c_.resize(n);
        lc = view(lab_c_.data(), pw_, ph_);
      }
      close_labels(b_, image_view<const std::uint16_t>(la), lb, lc, p_.label_closing_radius);
      la = lc;
    }
    // Disconnected regions of one plane (a floor seen on both sides of a table, coplanar box
    // faces) become planes of their own, each with its plane's equation; regions smaller than
    // min_region_pixels are dropped.
    region_origin_.clear();
    if (p_.split_regions && num_planes > 0) {
      const std::uint16_t* lbl = la.data;
      const std::int32_t min_px = p_.min_region_pixels > 0 ? p_.min_region_pixels : p_.t_size;
      const std::int32_t regions = std::min<std::int32_t>(
          components(n, detail::nonzero_label_active{lbl}, n,
                     detail::same_label_adjacency{image_view<const std::uint16_t>(la)}, min_px),
          65535);
      origin_.resize(static_cast<std::size_t>(regions) + 1);
      b_.memset(origin_.data(), 0, sizeof(std::uint16_t) * (static_cast<std::size_t>(regions) + 1));
      b_.for_each_index(n, detail::region_relabel_kernel{parent_.data(), flags_.data(), scan_.data(), lbl, regions,
                                                         lb.data, origin_.data()});
      std::swap(la, lb);
      region_origin_.resize(static_cast<std::size_t>(regions) + 1);
      b_.copy_to_host(region_origin_.data(), origin_.data(), region_origin_.size() * sizeof(std::uint16_t));
      num_planes = regions;
    }
    // Upsampled labels are the final ones: where the caller's label image is in the backend's
    // memory, the upsampling writes them there (no copy), as the closing does above.
    image_view<std::uint16_t> final_labels = la;
    const bool labels_there = closed_out || (down && (Backend::host_accessible || on_backend));
    if (down) {
      if (!labels_there) lab_full_.resize(n_full);
      final_labels = labels_there ? labels_out : view(lab_full_.data(), w, h);
      upsample_labels(b_, image_view<const std::uint16_t>(la), final_labels);
    }
    // final statistics at output resolution: counts, centroids and boxes, which need only the
    // first-order sums (the planes' equations and eigenvalues are the validated candidates')
    moments_.resize(static_cast<std::size_t>(num_planes + 1) * moment_slots);
    bbox_.resize(static_cast<std::size_t>(num_planes + 1) * 4);
    accumulate_first_moments(b_, image_view<const float>(z_full), k, detail::image_labels{final_labels}, num_planes,
                             moments_.data(), bbox_.data());
    download_fits(num_planes, fits_, 0, false);
    for (int g = 1; g <= num_planes; ++g) {
      // The plane equation and eigenvalues come from the validated candidates (before growth and
      // closing, whose rim pixels would bias the fit); extent, centroid and counts from the labels.
      const plane_fit& f = fits_[g - 1];
      const plane_fit& c = group_fits_[region_origin_.empty() ? g - 1 : region_origin_[g] - 1];
      plane pl;
      pl.id = static_cast<std::uint16_t>(g);
      for (int j = 0; j < 3; ++j) {
        pl.normal[j] = static_cast<float>(c.normal(j));
        pl.centroid[j] = static_cast<float>(f.points > 0 ? f.centroid(j) : c.centroid(j));
        pl.eigenvalues[j] = static_cast<float>(c.eigenvalues(j));
      }
      pl.d = static_cast<float>(c.d);
      pl.pixels = f.pixels;
      pl.points = f.points;
      pl.bbox = f.bbox;
      out.planes.push_back(pl);
    }
    auto copy_out = [&](void* to, const void* from, std::size_t bytes) {
      if (on_backend)
        b_.copy(to, from, bytes);
      else
        b_.copy_to_host(to, from, bytes);
    };
    if (!labels_there) {
      if (labels_out.pitch == w)  // dense: one copy
        copy_out(labels_out.data, final_labels.data, sizeof(std::uint16_t) * n_full);
      else
        for (int y = 0; y < h; ++y)
          copy_out(&labels_out(0, y), final_labels.data + static_cast<std::int64_t>(y) * w, sizeof(std::uint16_t) * w);
    }
    b_.synchronize();
    out.times.finalize = ms_since(t);
    out.times.total = std::chrono::duration<double, std::milli>(clock::now() - t0).count();
  }

  params p_;
  Backend b_;
  int pw_ = 0, ph_ = 0;
  buffer<unsigned char, Backend> raw_in_;
  buffer<float, Backend> z_a_, z_b_, z_proc_, z_smooth_;
  buffer<std::uint8_t, Backend> edges_, mask_, cov_l_, cov_r_, runs_;
  buffer<std::int32_t, Backend> parent_, count_, flags_, scan_, cand_;
  buffer<std::uint8_t, Backend> failed_;
  buffer<std::uint64_t, Backend> moments_;
  buffer<std::int32_t, Backend> bbox_;
  buffer<std::uint16_t, Backend> table_;
  buffer<float, Backend> planes_, tol_, refit_planes_, refit_tol_;
  buffer<std::int32_t, Backend> flag_, grow_counts_, sweep_dirty_;
  buffer<std::uint16_t, Backend> lab_a_, lab_b_, lab_c_, lab_full_, origin_;
  // host scratch, reused across frames
  std::vector<std::uint64_t> host_moments_, group_moments_, change_moments_;
  std::vector<std::int32_t> host_bbox_;
  std::vector<plane_fit> fits_, group_fits_;
  std::vector<char> keep_, status_;
  std::vector<int> group_, merge_parent_;
  std::vector<std::uint8_t> host_failed_;
  std::vector<std::int32_t> row_heads_;  // runs, then roots, listed per row (host backends' numbering)
  std::vector<std::int32_t> row_list_;   // one row's roots (host backends' numbering)
  std::vector<std::int32_t> kept_roots_;   // the kept roots in order (host backends' numbering)
  std::vector<std::int32_t> piece_of_, largest_, label_table_;  // split rounds' tables (host backends)
  // split rounds' row spans (host backends), in the columns of the round's rectangle: of the
  // failed and the eroded pixels (the refit adds the rectangle's x0), and the columns the erosion
  // looks at
  std::vector<std::int32_t> failed_spans_, eroded_spans_, scan_spans_;
  std::vector<std::int64_t> piece_size_, rest_size_;
  std::vector<std::uint16_t> right_bits_;  // host backends' union-find: right joins per block of 16
  std::vector<std::uint16_t> host_table_, region_origin_;
  std::vector<float> host_planes_, host_tol_;
};

}  // namespace edgeplane
