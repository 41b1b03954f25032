// edgeplane: SegComp region counts (Hoover et al., "An experimental comparison of range image
// segmentation algorithms", PAMI 1996) as EVALUATION.md defines them.  Host only, no I/O.
#pragma once
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "edgeplane/error.hpp"
#include "edgeplane/image.hpp"
#include "edgeplane/metrics/overlap_table.hpp"
#include "edgeplane/metrics/plane_equation.hpp"

namespace edgeplane::metrics {

/// SegComp's default tolerance.
inline constexpr double segcomp_default_tolerance = 0.8;

/// SegComp counts of one image (average them over a set yourself; pool the angles with
/// mean_angle_deg * angle_pairs).
struct segcomp_counts {
  int correct = 0;      ///< correct detections (one per (segment, GT plane) pair)
  int over = 0;         ///< over-segmentation instances (one per GT plane split in k >= 2 segments)
  int under = 0;        ///< under-segmentation instances (one per segment covering k >= 2 GT planes)
  int missed = 0;       ///< GT planes in no instance
  int noise = 0;        ///< segments in no instance
  int gt_planes = 0;    ///< GT planes (non-zero GT ids with scored pixels)
  int segments = 0;     ///< segments taking part (non-zero ids with scored pixels, fragments left out)
  int excluded = 0;     ///< segments left out by the small-fragment rule (see overlap_table)
  int angle_pairs = 0;  ///< correct detections whose two plane equations were both given
  /// Mean angle (degrees, [0, 90]) between the normals of correctly detected pairs; NaN if none.
  double mean_angle_deg = std::numeric_limits<double>::quiet_NaN();
};

namespace detail {
/// o >= tol * p, with a relative slack of 1e-12 so that a tie in exact arithmetic (O = 0.8 P when
/// 0.8 P is an integer) is not lost to the rounding of 0.8.
inline bool at_least_fraction(std::int64_t o, double tol, std::int64_t p) {
  return static_cast<double>(o) >= tol * static_cast<double>(p) * (1 - 1e-12);
}
}  // namespace detail

/// SegComp at tolerance `tolerance` (0.5 < T <= 1, as in Hoover et al.; above 0.5 each region
/// qualifies for at most one partner, so the instances are well defined) from an overlap table:
/// - correct detection (m, n): O(m,n) >= T P_m and O(m,n) >= T P_n;
/// - over-segmentation of GT n by the segments m1..mk (k >= 2) not yet in an instance with
///   O(mi,n) >= T P_mi, when sum_i O(mi,n) >= T P_n;
/// - under-segmentation of GT n1..nk (k >= 2) not yet in an instance with O(m,ni) >= T P_ni, by
///   segment m, when sum_i O(m,ni) >= T P_m;
/// - missed: a GT plane in none; noise: a segment in none.
/// Correct detections are found first, then over-, then under-segmentations; each region belongs
/// to at most one instance.  Segments excluded by the small-fragment rule take no part (neither
/// in an instance nor as noise); P_n is still the GT plane's full scored size.  The angles come
/// from the plane equations, looked up by id (either span may be empty or partial).  Throws
/// edgeplane::error on a tolerance out of range or bad plane equations.
inline segcomp_counts segcomp(const overlap_table& t, double tolerance = segcomp_default_tolerance,
                              std::span<const plane_equation> pred_planes = {},
                              std::span<const plane_equation> gt_planes = {}) {
  edgeplane::detail::require(tolerance > 0.5 && tolerance <= 1.0,
                             "segcomp: tolerance " + std::to_string(tolerance) + " is not in (0.5, 1]");
  const detail::plane_lookup pred_lookup(pred_planes, "pred_planes"), gt_lookup(gt_planes, "gt_planes");
  using detail::at_least_fraction;
  const int ns = t.segments(), ng = t.gt_planes();
  const std::size_t rows = static_cast<std::size_t>(ns) + 1, cols = static_cast<std::size_t>(ng) + 1;
  // State per row / column (index 0 unused): 0 free, 1 in an instance, 2 excluded segment.
  std::vector<char> seg_used(rows, 0), gt_used(cols, 0);
  segcomp_counts r;
  r.gt_planes = ng;
  for (int i = 1; i <= ns; ++i)
    if (t.excluded_from_region_metrics(i)) {
      seg_used[static_cast<std::size_t>(i)] = 2;
      ++r.excluded;
    }
  r.segments = ns - r.excluded;

  // Correct detections.
  detail::angle_mean angles;
  for (int i = 1; i <= ns; ++i) {
    if (seg_used[static_cast<std::size_t>(i)] != 0) continue;
    for (int j = 1; j <= ng; ++j) {
      if (gt_used[static_cast<std::size_t>(j)] != 0) continue;
      const std::int64_t o = t.overlap(i, j);
      if (o > 0 && at_least_fraction(o, tolerance, t.segment_size[static_cast<std::size_t>(i)]) &&
          at_least_fraction(o, tolerance, t.gt_size[static_cast<std::size_t>(j)])) {
        seg_used[static_cast<std::size_t>(i)] = 1;
        gt_used[static_cast<std::size_t>(j)] = 1;
        ++r.correct;
        angles.add(pred_lookup, t.segment_ids[static_cast<std::size_t>(i) - 1], gt_lookup,
                   t.gt_ids[static_cast<std::size_t>(j) - 1]);
        break;
      }
    }
  }
  // Over-segmentations.
  std::vector<int> members;
  for (int j = 1; j <= ng; ++j) {
    if (gt_used[static_cast<std::size_t>(j)] != 0) continue;
    members.clear();
    std::int64_t sum = 0;
    for (int i = 1; i <= ns; ++i) {
      const std::int64_t o = t.overlap(i, j);
      if (seg_used[static_cast<std::size_t>(i)] == 0 && o > 0 &&
          at_least_fraction(o, tolerance, t.segment_size[static_cast<std::size_t>(i)])) {
        members.push_back(i);
        sum += o;
      }
    }
    if (members.size() >= 2 && at_least_fraction(sum, tolerance, t.gt_size[static_cast<std::size_t>(j)])) {
      gt_used[static_cast<std::size_t>(j)] = 1;
      for (int i : members) seg_used[static_cast<std::size_t>(i)] = 1;
      ++r.over;
    }
  }
  // Under-segmentations.
  for (int i = 1; i <= ns; ++i) {
    if (seg_used[static_cast<std::size_t>(i)] != 0) continue;
    members.clear();
    std::int64_t sum = 0;
    for (int j = 1; j <= ng; ++j) {
      const std::int64_t o = t.overlap(i, j);
      if (gt_used[static_cast<std::size_t>(j)] == 0 && o > 0 &&
          at_least_fraction(o, tolerance, t.gt_size[static_cast<std::size_t>(j)])) {
        members.push_back(j);
        sum += o;
      }
    }
    if (members.size() >= 2 && at_least_fraction(sum, tolerance, t.segment_size[static_cast<std::size_t>(i)])) {
      seg_used[static_cast<std::size_t>(i)] = 1;
      for (int j : members) gt_used[static_cast<std::size_t>(j)] = 1;
      ++r.under;
    }
  }
  for (int j = 1; j <= ng; ++j) r.missed += gt_used[static_cast<std::size_t>(j)] == 0 ? 1 : 0;
  for (int i = 1; i <= ns; ++i) r.noise += seg_used[static_cast<std::size_t>(i)] == 0 ? 1 : 0;
  r.angle_pairs = angles.pairs;
  r.mean_angle_deg = angles.mean();
  return r;
}

/// SegComp of a predicted label image against a GT label image on the scored pixels (`scored` !=
/// 0); host images of the same size.  See the overload above.
inline segcomp_counts segcomp(image_view<const std::uint16_t> pred, image_view<const std::uint16_t> gt,
                              image_view<const std::uint8_t> scored, double tolerance = segcomp_default_tolerance,
                              std::span<const plane_equation> pred_planes = {},
                              std::span<const plane_equation> gt_planes = {}) {
  return segcomp(make_overlap_table(pred, gt, scored), tolerance, pred_planes, gt_planes);
}

}  // namespace edgeplane::metrics
