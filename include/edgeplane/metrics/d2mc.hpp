// edgeplane: D2MC (data-to-model coverage) of EVALUATION.md.  Host only, no I/O.
#pragma once
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "edgeplane/image.hpp"
#include "edgeplane/metrics/hungarian.hpp"
#include "edgeplane/metrics/overlap_table.hpp"

namespace edgeplane::metrics {

/// The D2MC figure and the matching it rests on (the SSIM rendering reuses the matching).
struct d2mc_result {
  /// (O(0,0) + sum of O over matched pairs) / (number of scored pixels); 1 is perfect.  NaN when
  /// no pixel is scored.
  double d2mc = std::numeric_limits<double>::quiet_NaN();
  std::vector<segment_match> matches;  ///< ascending segment id; zero-overlap pairs dropped
  /// Per overlap_table row (index 0 unused): the matched column (GT index, >= 1) or 0 if unmatched.
  std::vector<int> segment_to_gt;
};

/// D2MC from an overlap table: non-zero segments (all of them: the region-metric exclusion rule
/// does not apply here) are matched one-to-one to GT planes by maximum total overlap with the
/// Hungarian method; pairs with zero overlap are dropped; 0 is matched to 0 only.
inline d2mc_result d2mc_matching(const overlap_table& t) {
  const int rows = t.segments(), cols = t.gt_planes();
  std::vector<std::int64_t> w(static_cast<std::size_t>(rows) * static_cast<std::size_t>(cols));
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < cols; ++j)
      w[static_cast<std::size_t>(i) * static_cast<std::size_t>(cols) + static_cast<std::size_t>(j)] =
          t.overlap(i + 1, j + 1);
  const std::vector<int> assignment = max_weight_assignment(w, rows, cols);

  d2mc_result r;
  r.segment_to_gt.assign(static_cast<std::size_t>(rows) + 1, 0);
  std::int64_t covered = t.counts.empty() ? 0 : t.overlap(0, 0);
  for (int i = 0; i < rows; ++i) {
    const int j = assignment[static_cast<std::size_t>(i)];
    if (j < 0) continue;
    const std::int64_t o = t.overlap(i + 1, j + 1);
    if (o <= 0) continue;
    covered += o;
    r.segment_to_gt[static_cast<std::size_t>(i) + 1] = j + 1;
    r.matches.push_back({t.segment_ids[static_cast<std::size_t>(i)], t.gt_ids[static_cast<std::size_t>(j)], o});
  }
  if (t.scored > 0) r.d2mc = static_cast<double>(covered) / static_cast<double>(t.scored);
  return r;
}

/// D2MC of a predicted label image against a GT label image on the scored pixels (`scored` != 0).
/// Host images of the same size; throws edgeplane::error otherwise.  NaN when nothing is scored.
inline double d2mc(image_view<const std::uint16_t> pred, image_view<const std::uint16_t> gt,
                   image_view<const std::uint8_t> scored) {
  return d2mc_matching(make_overlap_table(pred, gt, scored)).d2mc;
}

}  // namespace edgeplane::metrics
