// Tests of include/edgeplane/edges/edge_types.hpp: each edge type's predicate on ray-cast 1-D
// depth profiles (steps, spikes, slanted planes, creases, arcs) in each of the four directions,
// applied over the image by the per-(direction, type) kernel detect_edge<Direction>.
//
// For a profile along D, the type's bit must be set exactly at the pixels known by construction
// and nowhere else along D, and never along the perpendicular direction (which sees a straight
// line of constant depth).
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "edgeplane/edges/detect_edges.hpp"
#include "edges/profiles.hpp"
#include "support/test_backends.hpp"

using namespace edgeplane;
using namespace edgeplane_test;

namespace {

template <class D>
struct perpendicular;
template <>
struct perpendicular<direction::horizontal> {
  using type = direction::vertical;
};
template <>
struct perpendicular<direction::vertical> {
  using type = direction::horizontal;
};
template <>
struct perpendicular<direction::left_diagonal> {
  using type = direction::right_diagonal;
};
template <>
struct perpendicular<direction::right_diagonal> {
  using type = direction::left_diagonal;
};

template <class F>
void for_each_direction(F&& f) {
  f(direction::horizontal{}, "horizontal");
  f(direction::vertical{}, "vertical");
  f(direction::left_diagonal{}, "left_diagonal");
  f(direction::right_diagonal{}, "right_diagonal");
}

/// Runs detect_edge<D> for one type over a cleared edge map; returns the map.
template <class D, class B, class T>
std::vector<std::uint8_t> run_kernel(const B& b, const profile& p, const T& type) {
  device_array<float, B> z(b, p.z);
  device_array<std::uint8_t, B> e(b, p.z.size(), 0);
  detect_edge<D>(b, z.cview(p.w, p.h), p.k, type, e.view(p.w, p.h));
  return e.host();
}

/// Steps along D between pixel profile coordinates s and s0 (|D|^2 = 1 or 2 profile units a step).
template <class D>
double steps(int s, int s0) {
  return static_cast<double>(s - s0) / (D::dx * D::dx + D::dy * D::dy);
}

/// Checks type T along D on profile p: expect(x, y) returns 1 (bit required), 0 (bit forbidden) or
/// -1 (either).  Also checks that the perpendicular direction never fires.  Returns the number of
/// pixels where the bit was required.
template <class D, class B, class T, class Expect>
int check_profile(const B& b, const profile& p, const T& type, Expect expect) {
  const auto e = run_kernel<D>(b, p, type);
  int required = 0;
  for (int y = 0; y < p.h; ++y)
    for (int x = 0; x < p.w; ++x) {
      const int want = expect(x, y);
      if (want < 0) continue;
      const bool got = (e[static_cast<std::size_t>(y) * p.w + x] & T::bit) != 0;
      required += want;
      if (got != (want == 1)) {
        CAPTURE(x);
        CAPTURE(y);
        CAPTURE(p.s(x, y));
        CHECK(got == (want == 1));
      }
    }
  const auto ep = run_kernel<typename perpendicular<D>::type>(b, p, type);
  int perp_hits = 0;
  for (auto v : ep) perp_hits += (v & T::bit) ? 1 : 0;
  CHECK(perp_hits == 0);
  return required;
}

/// The lateral size (metres) of one step along D at depth z (one pixel footprint times |D|).
template <class D>
double step_length(double z) {
  return z / 365.0 * std::sqrt(double(D::dx * D::dx + D::dy * D::dy));
}

/// Default thresholds; the edge-type policies as the detector builds them.
detail::edge_set defaults() { return detail::make_edge_set(presets::thesis_full()); }

}  // namespace

TEST_CASE_TEMPLATE("jump: a depth step is a jump edge on both sides of the step, nowhere else", B,
                   EDGEPLANE_TEST_BACKENDS) {
  const B b{};
  for_each_direction([&](auto dir, const char* name) {
    using D = decltype(dir);
    CAPTURE(name);
    const int s0 = mid_s<D>();
    for (double far : {2.5, 2.07}) {  // 0.5 m and 7 cm (just above t_je = 6 cm)
      CAPTURE(far);
      const profile p = make_profile<D>([&](int s, double) { return s < s0 ? 2.0 : far; });
      // A pixel is on the step when one of its two D-neighbours lies on the other side of s0.
      const int required = check_profile<D>(b, p, defaults().jump, [&](int x, int y) {
        const int s = p.s(x, y), st = D::dx * D::dx + D::dy * D::dy;
        const bool left = x - D::dx >= 0 && x - D::dx < p.w && y - D::dy >= 0 && ((s - st < s0) != (s < s0));
        const bool right = x + D::dx >= 0 && x + D::dx < p.w && y + D::dy < p.h && ((s + st < s0) != (s < s0));
        return (left || right) ? 1 : 0;
      });
      CHECK(required >= 2 * std::min(p.w, p.h));
    }
    // A 5 cm step is below t_je: no jump edge at all.
    const profile small = make_profile<D>([&](int s, double) { return s < s0 ? 2.0 : 2.05; });
    check_profile<D>(b, small, defaults().jump, [](int, int) { return 0; });
  });
}

TEST_CASE_TEMPLATE("jump: a slanted plane seen at a grazing angle is not a jump edge (t_je_ratio)", B,
                   EDGEPLANE_TEST_BACKENDS) {
  const B b{};
  for_each_direction([&](auto dir, const char* name) {
    using D = decltype(dir);
    CAPTURE(name);
    // z = 2 + 6 xi: about 80 degrees from fronto-parallel; neighbouring depths differ by up to ~0.3 m.
    const profile p = make_profile<D>([](int, double rho) { return line_depth(rho, 0.0, 2.0, 6.0); });
    float biggest_step = 0.f;
    for (int y = 0; y < p.h; ++y)
      for (int x = 0; x < p.w; ++x)
        if (p.full_arms(x, y, 1)) biggest_step = std::max(biggest_step, std::abs(p.at(x + D::dx, y + D::dy) - p.at(x, y)));
    REQUIRE(biggest_step > 0.1f);  // the thesis rule (t_je alone) would fire here
    const auto interior = [&](int x, int y) { return p.full_arms(x, y, 1) ? 0 : -1; };
    check_profile<D>(b, p, defaults().jump, interior);
    // With t_je_ratio = 0 (the thesis's rule) the same plane is full of jump edges: the test can fail.
    auto thesis = defaults().jump;
    thesis.t_ratio = 0.f;
    const auto e = run_kernel<D>(b, p, thesis);
    int hits = 0;
    for (auto v : e) hits += v & edge_jump ? 1 : 0;
    CHECK(hits > 10);
  });
}

TEST_CASE_TEMPLATE("extrema: a spike or a dip is an extrema edge; flat and slanted planes never are", B,
                   EDGEPLANE_TEST_BACKENDS) {
  const B b{};
  const auto ex = defaults().extrema;
  for_each_direction([&](auto dir, const char* name) {
    using D = decltype(dir);
    CAPTURE(name);
    const int s0 = mid_s<D>();
    for (double dz : {-0.05, +0.05}) {  // 2.5 % nearer / farther than the 2 m background; below t_je
      CAPTURE(dz);
      const profile p = make_profile<D>([&](int s, double) { return s == s0 ? 2.0 + dz : 2.0; });
      const int required = check_profile<D>(b, p, ex, [&](int x, int y) {
        if (p.s(x, y) != s0) return 0;
        return p.full_arms(x, y, ex.n) ? 1 : 0;  // a spike at the border has too few neighbours
      });
      CHECK(required >= 5);
    }
    // A 1 % spike is within t_ee = 0.98: not an extremum.
    const profile weak = make_profile<D>([&](int s, double) { return s == s0 ? 1.98 : 2.0; });
    check_profile<D>(b, weak, ex, [](int, int) { return 0; });
    for (double m : {0.0, 0.7, 6.0}) {  // fronto-parallel, 35 degrees, grazing
      CAPTURE(m);
      const profile plane = make_profile<D>([&](int, double rho) { return line_depth(rho, 0.0, 2.0, m); });
      check_profile<D>(b, plane, ex, [](int, int) { return 0; });
    }
  });
}

TEST_CASE_TEMPLATE("corner: a roof or a V is a corner edge at the crease, not a few pixels away", B,
                   EDGEPLANE_TEST_BACKENDS) {
  const B b{};
  const auto co = defaults().corner;
  for_each_direction([&](auto dir, const char* name) {
    using D = decltype(dir);
    CAPTURE(name);
    const int s0 = mid_s<D>();
    const double rho0 = blank_profile<D>().rho(s0);
    for (double z0 : {1.0, 2.0})
      for (double m : {0.5, 1.0})  // faces at +-27 and +-45 degrees: a 127 or 90 degree crease
        for (int ridge : {0, 1}) {
          CAPTURE(z0);
          CAPTURE(m);
          CAPTURE(ridge);
          const profile p = make_profile<D>(crease{s0, z0, ridge ? -m : m, ridge ? m : -m, rho0});
          const int required = check_profile<D>(b, p, co, [&](int x, int y) {
            const double k = steps<D>(p.s(x, y), s0);
            if (k == 0) return p.full_arms(x, y, co.n) ? 1 : 0;
            return std::abs(k) >= 3 ? 0 : -1;  // the band around the crease is at most 2 steps wide
          });
          CHECK(required >= 5);
        }
    // Planes (fronto-parallel, slanted, grazing) have no corner anywhere.
    for (double m : {0.0, 0.7, 6.0}) {
      const profile plane = make_profile<D>([&](int, double rho) { return line_depth(rho, 0.0, 2.0, m); });
      check_profile<D>(b, plane, co, [](int, int) { return 0; });
    }
  });
}

TEST_CASE_TEMPLATE("corner: a crease gentler than t_coe is not a corner (the threshold is used)", B,
                   EDGEPLANE_TEST_BACKENDS) {
  const B b{};
  using D = direction::horizontal;
  const int s0 = mid_s<D>();
  const profile p = make_profile<D>(crease{s0, 2.0, -0.05, 0.05, blank_profile<D>().rho(s0)});  // 174 degrees
  check_profile<D>(b, p, defaults().corner, [](int, int) { return 0; });
}

TEST_CASE_TEMPLATE("curved: a flat region joining a circular arc is a curved edge at the junction", B,
                   EDGEPLANE_TEST_BACKENDS) {
  // The synthetic arc is noise-free, so the noise allowance is switched off (noise_k = 0) and the
  // rule's geometry is tested alone.  (With presets::thesis_full() the allowance 2 sigma(z) is larger
  // than the sagitta any arc visible over n_cue = 8 pixels can have; see the report.)
  const B b{};
  params p0 = presets::thesis_full();
  p0.noise_k = 0.f;
  const auto cu = detail::make_edge_set(p0).curved;
  for_each_direction([&](auto dir, const char* name) {
    using D = decltype(dir);
    CAPTURE(name);
    const int s0 = mid_s<D>();
    const double rho0 = blank_profile<D>().rho(s0);
    for (double z0 : {1.0, 2.0}) {
      CAPTURE(z0);
      // Radius 12 steps along D: the 8-neighbour arm spans about 40 degrees of arc.
      const profile p = make_profile<D>(flat_to_arc{s0, z0, 12 * step_length<D>(z0), rho0});
      const int required = check_profile<D>(b, p, cu, [&](int x, int y) {
        const double k = steps<D>(p.s(x, y), s0);
        if (k == 0) return p.full_arms(x, y, cu.n) && p.at(x + 8 * D::dx, y + 8 * D::dy) > 0.f ? 1 : 0;
        return std::abs(k) >= 4 ? 0 : -1;
      });
      CHECK(required >= 5);
    }
    // Inside an arc (both arms bent alike) there is no curved edge: a cylinder's crest, 12 steps
    // radius, seen head-on.  (Each arm alone is arc-like here, so this needs the straight-arm test.)
    {
      const double R = 12 * step_length<D>(1.0), zc = 1.0 + R;
      const profile crest = make_profile<D>([&](int, double rho) {
        const double a = rho * rho + 1, bq = -2 * zc, c = zc * zc - R * R, disc = bq * bq - 4 * a * c;
        return disc < 0 ? 0.0 : (-bq - std::sqrt(disc)) / (2 * a);
      });
      const int s_mid = mid_s<D>();
      int bent_both = 0;
      check_profile<D>(b, crest, cu, [&](int x, int y) {
        if (std::abs(steps<D>(crest.s(x, y), s_mid)) > 1 || !crest.full_arms(x, y, cu.n)) return -1;
        ++bent_both;
        return 0;
      });
      CHECK(bent_both > 0);
    }
    // Creases are not curved edges (the arc-likeness test rejects a kink), nor are planes.
    for (int ridge : {0, 1}) {
      const profile roof = make_profile<D>(crease{s0, 2.0, ridge ? -1.0 : 1.0, ridge ? 1.0 : -1.0, rho0});
      check_profile<D>(b, roof, cu, [](int, int) { return 0; });
    }
    for (double m : {0.0, 0.7, 6.0}) {
      const profile plane = make_profile<D>([&](int, double rho) { return line_depth(rho, 0.0, 2.0, m); });
      check_profile<D>(b, plane, cu, [](int, int) { return 0; });
    }
  });
}

TEST_CASE("curved: where t_cue1 <= t_cue2 an arc-like side is never straight (arc_excludes_straight), and only there") {
  // The curved test skips the bent side's own arm scan when arc_excludes_straight(): random
  // one-row profiles (each side a circular arc or a kink on a slanted line, plus noise), every
  // side checked.
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  const detail::projector proj{1.f / 365.f, 1.f / 365.f, 20.f, 0.f};
  struct thresholds {
    float t_straight, t_bend;
  };
  for (int n : {1, 2, 5, 8}) {
    CAPTURE(n);
    const int w = 2 * n + 1;
    std::vector<float> row(static_cast<std::size_t>(w));
    for (thresholds t : {thresholds{0.02f, 0.08f}, thresholds{0.08f, 0.08f}, thresholds{0.3f, 0.08f}}) {
      CAPTURE(t.t_straight);
      for (float noise_k : {0.f, 0.5f}) {
        const edge_type::curved cu{t.t_straight, t.t_bend, noise_k, n, detail::noise_sigma{0.0005f, 0.0002f}};
        CHECK(cu.arc_excludes_straight() == (n >= 2 && t.t_straight <= t.t_bend));
        int arcs = 0, arcs_straight = 0;
        for (int trial = 0; trial < 3000; ++trial) {
          // depths 2-3 m, slopes up to 45 degrees; each side a circular arc bending either way
          // (radius 1-3 arm lengths) or a kink; noise up to 0.3 mm
          const float z0 = 2.5f + 0.5f * u(rng), p = z0 / 365.f, slope = u(rng), noise = 0.00015f * (u(rng) + 1.f);
          float radius[2], sign[2], kink[2];
          for (int side = 0; side < 2; ++side) {
            radius[side] = static_cast<float>(n) * p * (2.f + u(rng));
            sign[side] = u(rng) > 0.f ? 1.f : -1.f;
            kink[side] = u(rng) > 0.5f ? u(rng) : 0.f;  // slope change of a kink (0: an arc)
          }
          for (int k = -n; k <= n; ++k) {
            const int side = k < 0 ? 0 : 1;
            const float x = static_cast<float>(k) * p, r = radius[side];
            const float shape = kink[side] != 0.f ? kink[side] * std::fabs(x) : sign[side] * (r - std::sqrt(r * r - x * x));
            row[static_cast<std::size_t>(k + n)] = z0 + slope * x + shape + noise * u(rng);
          }
          detail::neighbourhood nb;
          detail::gather_along<direction::horizontal>(nb, image_view<const float>{row.data(), w, 1, w}, proj, n, 0, n);
          REQUIRE(nb.nl == n);
          REQUIRE(nb.nr == n);
          const float nz = cu.noise_k * cu.sigma(nb.zc);
          for (int s = -1; s <= 1; s += 2) {
            if (!cu.arc_like(nb, s, nz)) continue;
            ++arcs;
            arcs_straight += cu.straight(nb, s, nz) ? 1 : 0;
          }
        }
        if (n < 2) continue;  // (an arm of one neighbour has no inner point: arc-like nowhere)
        CHECK(arcs > 100);
        if (cu.arc_excludes_straight())
          CHECK(arcs_straight == 0);
        else
          CHECK(arcs_straight > 0);  // a looser straight limit admits arc-like sides: the scan is needed
      }
    }
  }
}

TEST_CASE_TEMPLATE("a flat plane with 1 mm noise has no edge of any type with presets::thesis_full()", B,
                   EDGEPLANE_TEST_BACKENDS) {
  const int w = 64, h = 48;
  const auto k = camera(w, h);
  for (const B& b : variants<B>()) {
    CAPTURE(variant_name(b));
    for (double d : {1.0, 2.0, 4.0}) {
      CAPTURE(d);
      auto z = plane_image(k, w, h, normalized({0.35, -0.3, -1.0}), d);  // tilted about 25 degrees
      lcg_noise noise(static_cast<std::uint64_t>(d * 10));
      for (auto& v : z) v += noise(0.001f);
      device_array<float, B> zd(b, z);
      device_array<std::uint8_t, B> e(b, z.size(), 0xff);
      detect_edges(b, zd.cview(w, h), k, presets::thesis_full(), e.view(w, h));
      int hits = 0;
      for (auto v : e.host()) hits += v != 0 ? 1 : 0;
      CHECK(hits == 0);
    }
  }
}
