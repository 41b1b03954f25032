// edgeplane: the four kinds of 3-D edge, each a policy with a host/device predicate over the two
// opposite neighbour arrays of one direction (see README "Method" for each rule and its repair).
//
// Points are metric camera-frame points (metres).  A straightness test compares a deviation with
// `t * chord + noise_k * sigma(z_c)`: relative to the length it is measured over, so one threshold
// holds at every range, resolution and focal length, plus an allowance for the sensor's noise.
#pragma once
#include <cstdint>

#include "edgeplane/config.hpp"
#include "edgeplane/edges/neighbourhood.hpp"

namespace edgeplane {

/// Bits of the edge map.
enum edge_bits : std::uint8_t {
  edge_jump = 1,
  edge_extrema = 2,
  edge_corner = 4,
  edge_curved = 8,
  edge_invalid = 16,  ///< the pixel has no valid depth
};

namespace edge_type {

/// Jump edge: the step to the nearest neighbour on one side exceeds t_abs + t_quad * z_c^2 metres
/// plus t_ratio times the step on the other side.  The second term keeps a steeply slanted surface
/// (a floor seen at a grazing angle, whose depth steps grow from pixel to pixel) from firing, while
/// a real discontinuity, flat on its near side, still does.  t_ratio = 0 is the thesis's rule.
struct jump {
  float t_abs, t_quad, t_ratio;
  static constexpr std::uint8_t bit = edge_jump;
  EDGEPLANE_HD int reach() const { return 1; }
  EDGEPLANE_HD EDGEPLANE_INLINE bool operator()(const detail::neighbourhood& nb) const {
    const float t = t_abs + t_quad * nb.zc * nb.zc;
    const float dl = nb.nl >= 1 ? fabsf(nb.zl(1) - nb.zc) : -1.f;
    const float dr = nb.nr >= 1 ? fabsf(nb.zr(1) - nb.zc) : -1.f;
    const bool jl = dl > t + t_ratio * (dr > 0.f ? dr : 0.f);
    const bool jr = dr > t + t_ratio * (dl > 0.f ? dl : 0.f);
    return jl || jr;
  }
};

/// Extrema edge: c is nearer than all 2n neighbours by the factor t (z_c < t * z_i), or farther
/// than all of them (z_c > z_i / t).  Read literally (all neighbours deeper than t * z_c) the
/// thesis's rule holds on every flat surface; this is its evident intent.
struct extrema {
  float t;
  int n;
  static constexpr std::uint8_t bit = edge_extrema;
  EDGEPLANE_HD int reach() const { return n; }
  EDGEPLANE_HD EDGEPLANE_INLINE bool operator()(const detail::neighbourhood& nb) const {
    if (nb.nl < n || nb.nr < n) return false;
    bool nearer = true, farther = true;
    for (int k = 1; k <= n; ++k) {
      const float a = nb.zl(k), b = nb.zr(k);
      nearer = nearer && nb.zc < t * a && nb.zc < t * b;
      farther = farther && nb.zc * t > a && nb.zc * t > b;
      if (!nearer && !farther) return false;  // on a surface the nearest neighbours decide
    }
    return nearer || farther;
  }
};

/// Corner edge (a crease between two flat surfaces): both arms of n neighbours are straight (every
/// inner point within t_arm * chord + noise of the line from c to the arm's end), and c itself lies
/// farther than t_bend * |chord| + noise from the chord joining the two arms' centres.  The thesis
/// asks this of every inner-half point, which needs a bend n/2 times the threshold; c alone is the
/// vertex of the V.
struct corner {
  float t_bend, t_arm, noise_k;
  int n;
  detail::noise_sigma sigma;
  static constexpr std::uint8_t bit = edge_corner;
  EDGEPLANE_HD int reach() const { return n; }
  EDGEPLANE_HD EDGEPLANE_INLINE bool operator()(const detail::neighbourhood& nb) const {
    if (nb.nl < n || nb.nr < n) return false;
    const float noise = noise_k * sigma(nb.zc);
    // The cheap test first (one distance): on flat surfaces c lies on the chord and we stop here.
    const int h = n / 2 > 0 ? n / 2 : 1;
    if (!detail::farther_than(nb.center(), nb.left(h), nb.right(h), t_bend, noise)) return false;
    return detail::arm_within(nb, -1, n, t_arm, noise) && detail::arm_within(nb, +1, n, t_arm, noise);
  }
};

/// Curved edge (where a flat surface meets a curved one): exactly one arm is straight within
/// t_straight, and the other bends like an arc: its deviation from its chord at the middle exceeds
/// t_bend * chord + noise, and at a quarter and three quarters of its length it is at least 0.6
/// of that (a circular arc gives 0.75; a kink, i.e. a crease a few pixels away, gives less on one
/// side, so flat pixels near a crease are not marked).
struct curved {
  float t_straight, t_bend, noise_k;
  int n;
  detail::noise_sigma sigma;
  static constexpr std::uint8_t bit = edge_curved;
  EDGEPLANE_HD int reach() const { return n; }
  EDGEPLANE_HD EDGEPLANE_INLINE bool arc_like(const detail::neighbourhood& nb, int s, float noise) const {
    const detail::point3 c = nb.center(), e = nb.side(s, n);
    const int q1 = n / 4 > 0 ? n / 4 : 1, mid = n / 2 > 0 ? n / 2 : 1, q3 = (3 * n) / 4;
    const detail::point3 pm = nb.side(s, mid);
    if (!detail::farther_than(pm, c, e, t_bend, noise)) return false;
    const float dm = sqrtf(detail::dist2_to_line(pm, c, e));
    const float d1 = sqrtf(detail::dist2_to_line(nb.side(s, q1), c, e));
    const float d3 = sqrtf(detail::dist2_to_line(nb.side(s, q3), c, e));
    return d1 >= 0.6f * dm && d3 >= 0.6f * dm;
  }
  EDGEPLANE_HD EDGEPLANE_INLINE bool straight(const detail::neighbourhood& nb, int s, float noise) const {
    return detail::arm_within(nb, s, n, t_straight, noise);
  }
  /// Whether an arc-like side is never straight, so that its own arm need not be scanned: its
  /// midpoint (an inner point of the arm where n >= 2) lies beyond t_bend * chord + noise of the
  /// chord, and so beyond t_straight * chord + noise where t_straight <= t_bend, by the same float
  /// operations (farther_than's distance is dist2_to_line's, its chord norm's; a product with a
  /// non-negative chord and a sum round monotonically).  Every preset has t_cue1 < t_cue2.
  EDGEPLANE_HD bool arc_excludes_straight() const { return n >= 2 && t_straight <= t_bend; }
  // Exactly one arm straight and the other arc-like: at most one side can be the bent one, so test
  // each side's cheap arc shape (3 distances) first and scan the arms only where it holds.
  EDGEPLANE_HD EDGEPLANE_INLINE bool operator()(const detail::neighbourhood& nb) const {
    if (nb.nl < n || nb.nr < n) return false;
    const float noise = noise_k * sigma(nb.zc);
    for (int s = -1; s <= 1; s += 2)
      if (arc_like(nb, s, noise) && straight(nb, -s, noise) && (arc_excludes_straight() || !straight(nb, s, noise)))
        return true;
    return false;
  }
};

}  // namespace edge_type
}  // namespace edgeplane
