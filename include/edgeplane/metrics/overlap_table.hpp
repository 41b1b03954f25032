// edgeplane: the overlap table O(m, n) between a predicted label image and a GT label image, on
// scored pixels only, from which every metric of EVALUATION.md is computed.  Host only, no I/O.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "edgeplane/error.hpp"
#include "edgeplane/image.hpp"

namespace edgeplane::metrics {

/// One matched (segment, GT plane) pair, by id.
struct segment_match {
  std::uint16_t segment = 0;  ///< predicted id
  std::uint16_t gt = 0;       ///< GT id
  std::int64_t overlap = 0;   ///< O(segment, gt) > 0, in scored pixels
};

/// Counts of scored pixels per (predicted label, GT label) pair.
///
/// Row index i: 0 is predicted label 0 ("no plane"), i = k + 1 is `segment_ids[k]`.
/// Column index j: 0 is GT label 0, j = k + 1 is `gt_ids[k]`.
/// Only labels with at least one scored pixel get a row or column: a GT plane with no scored pixel
/// does not exist for the metrics, and neither does a segment with none (labelling pixels that
/// are don't-care is never punished).  Memory is (segments + 1) x (GT planes + 1) counts.
struct overlap_table {
  std::vector<std::uint16_t> segment_ids;  ///< non-zero predicted ids on scored pixels, ascending
  std::vector<std::uint16_t> gt_ids;       ///< non-zero GT ids on scored pixels, ascending (the GT planes)
  std::vector<std::int64_t> counts;        ///< O(i, j), row-major, (segments() + 1) x (gt_planes() + 1)
  std::vector<std::int64_t> segment_size;  ///< P_m: row sums (its scored pixels on GT 0 included); [0]: predicted 0
  std::vector<std::int64_t> gt_size;       ///< P_n: column sums (its pixels predicted 0 included); [0]: GT 0
  /// Per row: pixels of the segment that are NOT scored and have GT label 0 (don't-care GT-0
  /// pixels).  Unscored pixels with a non-zero GT label (invalid depth) are not counted.
  std::vector<std::int64_t> segment_dont_care_gt0;
  std::int64_t scored = 0;  ///< number of scored pixels

  int segments() const { return static_cast<int>(segment_ids.size()); }
  int gt_planes() const { return static_cast<int>(gt_ids.size()); }
  std::int64_t overlap(int i, int j) const {
    return counts[static_cast<std::size_t>(i) * (gt_ids.size() + 1) + static_cast<std::size_t>(j)];
  }
  /// The EVALUATION.md rule: a segment whose scored pixels are fewer than its pixels on don't-care
  /// GT-0 pixels (a small plane fragment, say) is left out of the region metrics (SegComp,
  /// precision/recall, IoU, angles).  It still counts for D2MC and SSIM.  `i` >= 1.
  bool excluded_from_region_metrics(int i) const {
    return segment_size[static_cast<std::size_t>(i)] < segment_dont_care_gt0[static_cast<std::size_t>(i)];
  }
};

/// Build the overlap table.  `pred` and `gt` are label images (0 = no plane), `scored` is non-zero
/// on scored pixels; all three are host images of the same size.  Throws edgeplane::error when a
/// view is unusable or the sizes differ.
inline overlap_table make_overlap_table(image_view<const std::uint16_t> pred, image_view<const std::uint16_t> gt,
                                        image_view<const std::uint8_t> scored) {
  using edgeplane::detail::check_same_size;
  using edgeplane::detail::check_view;
  check_view(pred, "pred");
  check_view(gt, "gt");
  check_view(scored, "scored");
  check_same_size(pred, gt, "pred", "gt");
  check_same_size(pred, scored, "pred", "scored");

  constexpr std::size_t n_labels = 65536;
  // Pass 1: which labels occur on scored pixels.  Afterwards: compact index (row/column) per label.
  std::vector<int> seg_index(n_labels, 0), gt_index(n_labels, 0);
  for (int y = 0; y < pred.height; ++y)
    for (int x = 0; x < pred.width; ++x)
      if (scored(x, y) != 0) {
        seg_index[pred(x, y)] = 1;
        gt_index[gt(x, y)] = 1;
      }
  overlap_table t;
  for (std::size_t id = 1; id < n_labels; ++id) {
    if (seg_index[id] != 0) {
      t.segment_ids.push_back(static_cast<std::uint16_t>(id));
      seg_index[id] = static_cast<int>(t.segment_ids.size());
    }
    if (gt_index[id] != 0) {
      t.gt_ids.push_back(static_cast<std::uint16_t>(id));
      gt_index[id] = static_cast<int>(t.gt_ids.size());
    }
  }
  seg_index[0] = 0;
  gt_index[0] = 0;

  // Pass 2: the counts.  A label without a scored pixel has index 0 but is only read for unscored
  // pixels, where it matters only through segment_dont_care_gt0 (kept for real segments only).
  const std::size_t rows = t.segment_ids.size() + 1, cols = t.gt_ids.size() + 1;
  t.counts.assign(rows * cols, 0);
  t.segment_dont_care_gt0.assign(rows, 0);
  for (int y = 0; y < pred.height; ++y)
    for (int x = 0; x < pred.width; ++x) {
      const int i = seg_index[pred(x, y)];
      if (scored(x, y) != 0) {
        ++t.counts[static_cast<std::size_t>(i) * cols + static_cast<std::size_t>(gt_index[gt(x, y)])];
        ++t.scored;
      } else if (gt(x, y) == 0 && i != 0) {
        ++t.segment_dont_care_gt0[static_cast<std::size_t>(i)];
      }
    }
  t.segment_size.assign(rows, 0);
  t.gt_size.assign(cols, 0);
  for (std::size_t i = 0; i < rows; ++i)
    for (std::size_t j = 0; j < cols; ++j) {
      t.segment_size[i] += t.counts[i * cols + j];
      t.gt_size[j] += t.counts[i * cols + j];
    }
  return t;
}

}  // namespace edgeplane::metrics
