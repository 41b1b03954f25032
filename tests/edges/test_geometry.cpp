// The edge tests' distance shortcut (detail::farther_than) skips the square root and the division
// when the answer is clear by a relative margin; it must always give the plain expression's answer.  Points are drawn at distances from 0 to twice the bound, densest
// right at the bound (within 1e-3 and 1e-6 of it, where float rounding decides), at scales from
// 1 mm to 100 m, plus degenerate chords.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>

#include "edgeplane/detail/geometry.hpp"
#include "support/test_backends.hpp"

using namespace edgeplane;
using namespace edgeplane_test;
using detail::point3;

namespace {
point3 random_point(lcg_noise& g, float scale) {
  return {g(scale), g(scale), scale + g(scale * 0.5f)};
}
// A point at distance d from the line through a and b (b != a).
point3 at_distance(lcg_noise& g, point3 a, point3 b, float d) {
  const point3 ab = b - a;
  point3 q = {g(1.f), g(1.f), g(1.f)};
  point3 perp = detail::cross(ab, q);
  const float n = detail::norm(perp);
  if (!(n > 0.f)) perp = {1.f, 0.f, 0.f};
  else perp = (1.f / n) * perp;
  const float s = static_cast<float>(g.uniform01() * 1.4 - 0.2);  // also beyond the ends
  return a + s * ab + d * perp;
}
}  // namespace

TEST_CASE("farther_than gives the plain expression's answer") {
  lcg_noise g(17);
  long cases = 0, near = 0, yes_far = 0, no_far = 0;
  for (const float scale : {0.001f, 0.05f, 1.f, 7.f, 100.f})
    for (int i = 0; i < 40000; ++i) {
      const point3 a = random_point(g, scale);
      point3 b = random_point(g, scale);
      if (i % 500 == 0) b = a;  // a degenerate chord
      const float t = static_cast<float>(g.uniform01() * 0.2), noise = static_cast<float>(g.uniform01() * 0.01 * scale);
      const float bound = t * detail::norm(b - a) + noise;
      double f = g.uniform01() * 2.0;  // distance as a share of the bound
      if (i % 3 == 1) f = 1.0 + g(1e-3f);
      if (i % 3 == 2) f = 1.0 + g(1e-6f);
      near += i % 3 != 0;
      const point3 p = at_distance(g, a, b, static_cast<float>(f * bound));
      const float d = sqrtf(detail::dist2_to_line(p, a, b));
      const bool far = d > t * detail::norm(b - a) + noise;
      CHECK(detail::farther_than(p, a, b, t, noise) == far);
      yes_far += far;
      no_far += !far;
      ++cases;
    }
  CHECK(near > cases / 2);
  CHECK(yes_far > cases / 5);  // both answers occur often
  CHECK(no_far > cases / 5);
}
