// edgeplane: the "scored" pixel masks of the evaluation (docs: EVALUATION.md).  Host only, no I/O.
#pragma once
#include <cstdint>

#include "edgeplane/error.hpp"
#include "edgeplane/image.hpp"

namespace edgeplane::metrics {

/// Smallest ABW ground-truth value that is a plane: ABW GT values below 10 are not scored.
inline constexpr std::uint16_t abw_first_plane_label = 10;

namespace detail {
template <class T>
void scored_mask_from_ignore_impl(image_view<const T> ignore, image_view<std::uint8_t> scored) {
  edgeplane::detail::check_view(ignore, "ignore");
  edgeplane::detail::check_view(scored, "scored");
  edgeplane::detail::check_same_size(ignore, scored, "ignore", "scored");
  for (int y = 0; y < ignore.height; ++y)
    for (int x = 0; x < ignore.width; ++x) scored(x, y) = ignore(x, y) == 0 ? 1 : 0;
}
}  // namespace detail

/// Synthetic sets: a pixel is scored when its `_ignore.png` value is 0.  Writes 1 (scored) or 0
/// into `scored`, a host image the caller owns, the size of `ignore`.  Throws edgeplane::error when
/// the views are unusable or their sizes differ.
inline void scored_mask_from_ignore(image_view<const std::uint8_t> ignore, image_view<std::uint8_t> scored) {
  detail::scored_mask_from_ignore_impl(ignore, scored);
}
/// As above, for a 16-bit ignore image.
inline void scored_mask_from_ignore(image_view<const std::uint16_t> ignore, image_view<std::uint8_t> scored) {
  detail::scored_mask_from_ignore_impl(ignore, scored);
}

/// ABW: a pixel is scored when its GT label is >= 10.  Writes 1 (scored) or 0 into `scored`, a host
/// image the caller owns, the size of `gt`.  Throws edgeplane::error when the views are unusable or
/// their sizes differ.
inline void scored_mask_from_abw_gt(image_view<const std::uint16_t> gt, image_view<std::uint8_t> scored) {
  edgeplane::detail::check_view(gt, "gt");
  edgeplane::detail::check_view(scored, "scored");
  edgeplane::detail::check_same_size(gt, scored, "gt", "scored");
  for (int y = 0; y < gt.height; ++y)
    for (int x = 0; x < gt.width; ++x) scored(x, y) = gt(x, y) >= abw_first_plane_label ? 1 : 0;
}

}  // namespace edgeplane::metrics
