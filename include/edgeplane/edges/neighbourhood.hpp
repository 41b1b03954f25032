// edgeplane: the two opposite neighbour arrays of one pixel in one direction.
#pragma once
#include <cstdint>

#include "edgeplane/config.hpp"
#include "edgeplane/detail/geometry.hpp"
#include "edgeplane/image.hpp"

namespace edgeplane::detail {

/// The two opposite neighbour arrays of pixel (x, y) along (dx, dy), read in place from the depth
/// image: side arrays end at the image border or at the first invalid pixel, and hold at most
/// `reach` neighbours (nl, nr).  Neighbour k (k = 1 is the nearest) is read only when k <= nl
/// (left) or k <= nr (right).
struct neighbourhood {
  projector proj;
  int x, y, dx, dy;
  float zc;
  int nl, nr;             // valid neighbours on the left (-dx,-dy) and right (+dx,+dy) sides
  const float* c;         // the centre pixel in the depth image
  std::ptrdiff_t step;    // elements from one neighbour to the next along (dx, dy)

  EDGEPLANE_HD EDGEPLANE_INLINE float zl(int k) const { return c[-k * step]; }
  EDGEPLANE_HD EDGEPLANE_INLINE float zr(int k) const { return c[k * step]; }
  EDGEPLANE_HD EDGEPLANE_INLINE point3 center() const { return proj(x, y, zc); }
  /// k-th neighbour (k = 1 is the nearest) on the left / right side.
  EDGEPLANE_HD EDGEPLANE_INLINE point3 left(int k) const { return proj(x - k * dx, y - k * dy, zl(k)); }
  EDGEPLANE_HD EDGEPLANE_INLINE point3 right(int k) const { return proj(x + k * dx, y + k * dy, zr(k)); }
  EDGEPLANE_HD EDGEPLANE_INLINE point3 side(int s, int k) const { return s < 0 ? left(k) : right(k); }
  EDGEPLANE_HD EDGEPLANE_INLINE int count(int s) const { return s < 0 ? nl : nr; }
};

/// Counts up to `reach` valid neighbours per side.  `interior`: the caller knows that every pixel
/// within `reach` of (x, y) (a square window) is inside the image and valid, so nothing is read.
EDGEPLANE_HD EDGEPLANE_INLINE void gather(neighbourhood& nb, image_view<const float> depth, int reach, bool interior = false) {
  nb.c = &depth(nb.x, nb.y);
  nb.step = static_cast<std::ptrdiff_t>(nb.dy) * depth.pitch + nb.dx;
  nb.zc = *nb.c;
  if (interior) {
    nb.nl = nb.nr = reach;
    return;
  }
  nb.nl = nb.nr = 0;
  for (int k = 1; k <= reach; ++k) {
    const int u = nb.x - k * nb.dx, v = nb.y - k * nb.dy;
    if (!depth.contains(u, v) || !(depth(u, v) > 0.f)) break;
    ++nb.nl;
  }
  for (int k = 1; k <= reach; ++k) {
    const int u = nb.x + k * nb.dx, v = nb.y + k * nb.dy;
    if (!depth.contains(u, v) || !(depth(u, v) > 0.f)) break;
    ++nb.nr;
  }
}

/// Sets nb up for pixel (x, y) along Direction and counts up to `reach` neighbours per side.
template <class Direction>
EDGEPLANE_HD EDGEPLANE_INLINE void gather_along(neighbourhood& nb, image_view<const float> depth, projector proj, int x, int y,
                                      int reach, bool interior = false) {
  nb.proj = proj;
  nb.x = x;
  nb.y = y;
  nb.dx = Direction::dx;
  nb.dy = Direction::dy;
  gather(nb, depth, reach, interior);
}

/// Whether the arm's inner points 1..m-1 on side s all lie within t * chord + noise of the chord
/// c -> P_m: the same decision as comparing their largest distance with that bound (sqrtf is
/// monotonic, so the largest distance exceeds it exactly when one point's does), but the scan stops
/// at the first point beyond it.
EDGEPLANE_HD EDGEPLANE_INLINE bool arm_within(const neighbourhood& nb, int s, int m, float t, float noise) {
  const point3 c = nb.center(), e = nb.side(s, m);
  const float bound = t * norm(e - c) + noise;
  for (int k = 1; k < m; ++k)
    if (sqrtf(dist2_to_line(nb.side(s, k), c, e)) > bound) return false;
  return true;
}

}  // namespace edgeplane::detail
