// edgeplane: the two opposite neighbour arrays of one pixel in one direction.
#pragma once
#include <cstdint>

#include "edgeplane/config.hpp"
#include "edgeplane/detail/geometry.hpp"
#include "edgeplane/image.hpp"

namespace edgeplane::detail {

inline constexpr int max_arm = 32;  ///< longest neighbour array per side

/// Depths of up to `max_arm` consecutive valid neighbours on each side of pixel (x, y) along
/// (dx, dy); an arm ends at the image border or at the first invalid pixel.
struct neighbourhood {
  projector proj;
  int x, y, dx, dy;
  float zc;
  int nl, nr;  // valid neighbours gathered on the left (-dx,-dy) and right (+dx,+dy) sides
  float zl[max_arm];
  float zr[max_arm];

  EDGEPLANE_HD point3 center() const { return proj(x, y, zc); }
  /// k-th neighbour (k = 1 is the nearest) on the left / right side.
  EDGEPLANE_HD point3 left(int k) const { return proj(x - k * dx, y - k * dy, zl[k - 1]); }
  EDGEPLANE_HD point3 right(int k) const { return proj(x + k * dx, y + k * dy, zr[k - 1]); }
  EDGEPLANE_HD point3 side(int s, int k) const { return s < 0 ? left(k) : right(k); }
  EDGEPLANE_HD int count(int s) const { return s < 0 ? nl : nr; }
};

/// Fills nb with up to `reach` neighbours per side.
EDGEPLANE_HD inline void gather(neighbourhood& nb, image_view<const float> depth, int reach) {
  nb.zc = depth(nb.x, nb.y);
  nb.nl = nb.nr = 0;
  for (int k = 1; k <= reach; ++k) {
    const int u = nb.x - k * nb.dx, v = nb.y - k * nb.dy;
    if (!depth.contains(u, v)) break;
    const float z = depth(u, v);
    if (!(z > 0.f)) break;
    nb.zl[nb.nl++] = z;
  }
  for (int k = 1; k <= reach; ++k) {
    const int u = nb.x + k * nb.dx, v = nb.y + k * nb.dy;
    if (!depth.contains(u, v)) break;
    const float z = depth(u, v);
    if (!(z > 0.f)) break;
    nb.zr[nb.nr++] = z;
  }
}

/// Sets nb up for pixel (x, y) along Direction and gathers `reach` neighbours per side.
template <class Direction>
EDGEPLANE_HD inline void gather_along(neighbourhood& nb, image_view<const float> depth, projector proj, int x, int y,
                                      int reach) {
  nb.proj = proj;
  nb.x = x;
  nb.y = y;
  nb.dx = Direction::dx;
  nb.dy = Direction::dy;
  gather(nb, depth, reach);
}

/// Largest distance of the arm's inner points 1..m-1 on side s from the chord c -> P_m, and the
/// chord's length.
EDGEPLANE_HD inline void arm_deviation(const neighbourhood& nb, int s, int m, float& max_dev, float& chord) {
  const point3 c = nb.center(), e = nb.side(s, m);
  float worst = 0.f;
  for (int k = 1; k < m; ++k) {
    const float d2 = dist2_to_line(nb.side(s, k), c, e);
    worst = d2 > worst ? d2 : worst;
  }
  max_dev = sqrtf(worst);
  chord = norm(e - c);
}

}  // namespace edgeplane::detail
