// edgeplane: every figure of EVALUATION.md for one predicted label image at once.  Host only, no
// I/O.  The parts live in d2mc.hpp, ssim.hpp, segcomp.hpp and plane_match.hpp.
#pragma once
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <utility>
#include <vector>

#include "edgeplane/image.hpp"
#include "edgeplane/metrics/d2mc.hpp"
#include "edgeplane/metrics/hungarian.hpp"
#include "edgeplane/metrics/overlap_table.hpp"
#include "edgeplane/metrics/plane_equation.hpp"
#include "edgeplane/metrics/plane_match.hpp"
#include "edgeplane/metrics/scored_mask.hpp"
#include "edgeplane/metrics/segcomp.hpp"
#include "edgeplane/metrics/ssim.hpp"

namespace edgeplane::metrics {

/// All the figures of one image.
struct report {
  double d2mc = std::numeric_limits<double>::quiet_NaN();  ///< 1 is perfect; NaN when nothing is scored
  double ssim = std::numeric_limits<double>::quiet_NaN();  ///< thesis SSIM; NaN below 11x11 after downsampling
  segcomp_counts segcomp;                                  ///< at the tolerance given
  plane_match_result planes;                               ///< precision / recall at IoU >= 0.5
  std::vector<segment_match> d2mc_matches;                 ///< the D2MC (Hungarian) matching
  std::int64_t scored_pixels = 0;
};

/// Evaluate a predicted label image `pred` (0 = no plane) against the GT label image `gt` on the
/// pixels where `scored` is non-zero (build it with scored_mask_from_ignore() or
/// scored_mask_from_abw_gt()); host images of the same size.  `pred_planes` / `gt_planes` give
/// plane equations by id for the angle metrics (may be empty).  Throws edgeplane::error on unusable
/// views, sizes that differ, a SegComp tolerance outside (0.5, 1] or bad plane equations.
inline report evaluate(image_view<const std::uint16_t> pred, image_view<const std::uint16_t> gt,
                       image_view<const std::uint8_t> scored, std::span<const plane_equation> pred_planes = {},
                       std::span<const plane_equation> gt_planes = {},
                       double segcomp_tolerance = segcomp_default_tolerance) {
  const overlap_table t = make_overlap_table(pred, gt, scored);
  report r;
  r.scored_pixels = t.scored;
  r.segcomp = segcomp(t, segcomp_tolerance, pred_planes, gt_planes);
  r.planes = plane_precision_recall(t, pred_planes, gt_planes);
  d2mc_result m = d2mc_matching(t);
  r.d2mc = m.d2mc;
  const std::size_t n = static_cast<std::size_t>(pred.width) * static_cast<std::size_t>(pred.height);
  std::vector<std::uint8_t> a(n), b(n);
  render_labels_for_ssim(t, m, pred, gt, scored, make_view(a.data(), pred.width, pred.height),
                         make_view(b.data(), pred.width, pred.height));
  r.ssim = ssim(make_view(static_cast<const std::uint8_t*>(a.data()), pred.width, pred.height),
                make_view(static_cast<const std::uint8_t*>(b.data()), pred.width, pred.height));
  r.d2mc_matches = std::move(m.matches);
  return r;
}

}  // namespace edgeplane::metrics
