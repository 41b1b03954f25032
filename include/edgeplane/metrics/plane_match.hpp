// edgeplane: plane precision / recall at IoU >= 0.5, mean IoU and mean normal angle of the matched
// pairs (EVALUATION.md).  Host only, no I/O.
#pragma once
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "edgeplane/image.hpp"
#include "edgeplane/metrics/overlap_table.hpp"
#include "edgeplane/metrics/plane_equation.hpp"

namespace edgeplane::metrics {

/// Plane precision / recall of one image.  Ratios with a zero denominator are NaN; the counts are
/// there to pool a set (sum matches, segments and gt_planes over the images).
struct plane_match_result {
  int matches = 0;    ///< (segment, GT plane) pairs with IoU >= 0.5, one-to-one
  int segments = 0;   ///< segments taking part (non-zero ids with scored pixels, fragments left out)
  int gt_planes = 0;  ///< GT planes (non-zero GT ids with scored pixels)
  double precision = std::numeric_limits<double>::quiet_NaN();  ///< matches / segments
  double recall = std::numeric_limits<double>::quiet_NaN();     ///< matches / gt_planes
  double mean_iou = std::numeric_limits<double>::quiet_NaN();   ///< mean IoU of the matches
  int angle_pairs = 0;                                          ///< matches whose two plane equations were both given
  double mean_angle_deg = std::numeric_limits<double>::quiet_NaN();  ///< degrees, [0, 90]
  std::vector<segment_match> matched;                                ///< the matches, best IoU first
};

namespace detail {
struct iou_candidate {
  int i = 0, j = 0;             // overlap_table row / column
  std::int64_t overlap = 0;     // O(m, n)
  std::int64_t union_size = 0;  // P_m + P_n - O(m, n)
};
/// Best IoU first, compared exactly (O_a / U_a > O_b / U_b as O_a U_b > O_b U_a); ties by
/// ascending segment id, then GT id.
struct iou_greater {
  bool operator()(const iou_candidate& a, const iou_candidate& b) const {
    const std::int64_t lhs = a.overlap * b.union_size, rhs = b.overlap * a.union_size;
    if (lhs != rhs) return lhs > rhs;
    if (a.i != b.i) return a.i < b.i;
    return a.j < b.j;
  }
};
}  // namespace detail

/// Precision / recall from an overlap table: a segment and a GT plane match when IoU =
/// O / (P_m + P_n - O) >= 0.5 on scored pixels (compared exactly), one-to-one, best IoU first.
/// Segments excluded by the small-fragment rule take no part.  The angles come from the plane
/// equations, looked up by id (either span may be empty or partial).  Throws edgeplane::error on
/// bad plane equations.
inline plane_match_result plane_precision_recall(const overlap_table& t,
                                                 std::span<const plane_equation> pred_planes = {},
                                                 std::span<const plane_equation> gt_planes = {}) {
  const detail::plane_lookup pred_lookup(pred_planes, "pred_planes"), gt_lookup(gt_planes, "gt_planes");
  const int ns = t.segments(), ng = t.gt_planes();
  plane_match_result r;
  r.gt_planes = ng;
  std::vector<detail::iou_candidate> candidates;
  for (int i = 1; i <= ns; ++i) {
    if (t.excluded_from_region_metrics(i)) continue;
    ++r.segments;
    for (int j = 1; j <= ng; ++j) {
      const std::int64_t o = t.overlap(i, j);
      const std::int64_t u = t.segment_size[static_cast<std::size_t>(i)] + t.gt_size[static_cast<std::size_t>(j)] - o;
      if (o > 0 && 2 * o >= u) candidates.push_back({i, j, o, u});
    }
  }
  std::sort(candidates.begin(), candidates.end(), detail::iou_greater{});
  std::vector<char> seg_used(static_cast<std::size_t>(ns) + 1, 0), gt_used(static_cast<std::size_t>(ng) + 1, 0);
  double iou_sum = 0;
  detail::angle_mean angles;
  for (const detail::iou_candidate& c : candidates) {
    if (seg_used[static_cast<std::size_t>(c.i)] != 0 || gt_used[static_cast<std::size_t>(c.j)] != 0) continue;
    seg_used[static_cast<std::size_t>(c.i)] = 1;
    gt_used[static_cast<std::size_t>(c.j)] = 1;
    const std::uint16_t seg_id = t.segment_ids[static_cast<std::size_t>(c.i) - 1];
    const std::uint16_t gt_id = t.gt_ids[static_cast<std::size_t>(c.j) - 1];
    r.matched.push_back({seg_id, gt_id, c.overlap});
    iou_sum += static_cast<double>(c.overlap) / static_cast<double>(c.union_size);
    angles.add(pred_lookup, seg_id, gt_lookup, gt_id);
  }
  r.matches = static_cast<int>(r.matched.size());
  if (r.segments > 0) r.precision = static_cast<double>(r.matches) / r.segments;
  if (r.gt_planes > 0) r.recall = static_cast<double>(r.matches) / r.gt_planes;
  if (r.matches > 0) r.mean_iou = iou_sum / r.matches;
  r.angle_pairs = angles.pairs;
  r.mean_angle_deg = angles.mean();
  return r;
}

/// Precision / recall of a predicted label image against a GT label image on the scored pixels
/// (`scored` != 0); host images of the same size.  See the overload above.
inline plane_match_result plane_precision_recall(image_view<const std::uint16_t> pred,
                                                 image_view<const std::uint16_t> gt,
                                                 image_view<const std::uint8_t> scored,
                                                 std::span<const plane_equation> pred_planes = {},
                                                 std::span<const plane_equation> gt_planes = {}) {
  return plane_precision_recall(make_overlap_table(pred, gt, scored), pred_planes, gt_planes);
}

}  // namespace edgeplane::metrics
