// Tests of include/edgeplane/planes/validate.hpp (is_plane, should_merge, merge_groups) on fits of
// synthetic surfaces, and of the threshold checks of include/edgeplane/params.hpp that validation
// relies on (validate(), preset()).
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "edgeplane/params.hpp"
#include "edgeplane/planes/validate.hpp"
#include "support/test_backends.hpp"

using namespace edgeplane;
using namespace edgeplane_test;

namespace {

/// Fits of labels 1..num of a depth image, through the backend's moment accumulation.
template <class B>
std::vector<plane_fit> fits(const B& b, const std::vector<float>& depth, const std::vector<std::uint16_t>& labels,
                            int w, int h, int num) {
  device_array<float, B> z(b, depth);
  device_array<std::uint16_t, B> l(b, labels);
  device_array<std::uint64_t, B> m(b, static_cast<std::size_t>(num + 1) * moment_slots, 0);
  device_array<std::int32_t, B> bb(b, static_cast<std::size_t>(num + 1) * 4, 0);
  accumulate_moments(b, z.cview(w, h), camera(w, h), detail::image_labels{l.cview(w, h)}, num, m.data(), bb.data());
  const auto mh = m.host();
  std::vector<plane_fit> out;
  for (int i = 1; i <= num; ++i) out.push_back(fit_plane(mh.data() + i * moment_slots));
  return out;
}

/// Left half of the image labelled 1, right half 2; depth from plane (n1, d1) on the left and
/// (n2, d2) on the right.
template <class B>
std::pair<plane_fit, plane_fit> halves(const B& b, vec3 n1, double d1, vec3 n2, double d2) {
  const int w = 64, h = 48;
  const auto k = camera(w, h);
  std::vector<float> depth(static_cast<std::size_t>(w) * h);
  std::vector<std::uint16_t> labels(depth.size());
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const bool left = x < w / 2;
      depth[static_cast<std::size_t>(y) * w + x] = plane_depth(k, x, y, left ? n1 : n2, left ? d1 : d2);
      labels[static_cast<std::size_t>(y) * w + x] = left ? 1 : 2;
    }
  const auto f = fits(b, depth, labels, w, h, 2);
  return {f[0], f[1]};
}

plane_fit hand_fit(double nx, double nz, double cx, double cz) {
  plane_fit f;
  f.points = 5000;
  f.normal = Eigen::Vector3d(nx, 0, nz).normalized();
  f.centroid = Eigen::Vector3d(cx, 0, cz);
  f.d = -f.normal.dot(f.centroid);
  return f;
}

}  // namespace

TEST_CASE_TEMPLATE("is_plane: a noisy plane passes; a cylinder patch of radius 0.3 m fails", B,
                   EDGEPLANE_TEST_BACKENDS) {
  const B b{};
  const params p = presets::thesis_full();
  {  // 64 x 48 plane at about 2 m with +-5 mm uniform noise (sigma 2.9 mm; the model allows 3 x 7.5 mm)
    const int w = 64, h = 48;
    auto depth = plane_image(camera(w, h), w, h, normalized({0.3, -0.4, -1.0}), 2.0);
    lcg_noise noise(21);
    for (auto& z : depth) z += noise(0.005f);
    const auto f = fits(b, depth, std::vector<std::uint16_t>(depth.size(), 1), w, h, 1)[0];
    CHECK(is_plane(f, p));
    params big = p;
    big.t_size = w * h + 1;  // one point too few
    CHECK_FALSE(is_plane(f, big));
  }
  {  // A vertical cylinder, radius 0.3 m, axis 1.6 m away: the image sees about +-47 degrees of it.
    const int w = 120, h = 90;
    const auto k = camera(w, h);
    const double R = 0.3, zc = 1.6;
    std::vector<float> depth(static_cast<std::size_t>(w) * h, 0.f);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const double rx = (x - k.cx) / k.fx;  // (t rx)^2 + (t - zc)^2 = R^2, nearer root
        const double a = rx * rx + 1, bq = -2 * zc, c = zc * zc - R * R, disc = bq * bq - 4 * a * c;
        if (disc >= 0) depth[static_cast<std::size_t>(y) * w + x] = static_cast<float>((-bq - std::sqrt(disc)) / (2 * a));
      }
    const auto f = fits(b, depth, std::vector<std::uint16_t>(depth.size(), 1), w, h, 1)[0];
    REQUIRE(f.points == w * h);
    CHECK_FALSE(is_plane(f, p));
    // Each of the two tests rejects it on its own.
    params curvature_only = p;
    curvature_only.t_residual = 0.f;
    CHECK_FALSE(is_plane(f, curvature_only));
    params residual_only = p;
    residual_only.t_cu = 1.f;
    CHECK_FALSE(is_plane(f, residual_only));
    // With both relaxed, the same fit passes: the rejection above came from the shape.
    params lax = residual_only;
    lax.t_residual = 0.f;
    CHECK(is_plane(f, lax));
  }
}

// A region whose in-plane spread is isotropic (a square seen head-on: l1 == l2 exactly in the
// fixed-point moments) is a perfect plane; the thesis's strict l1 > l2 would reject it.
TEST_CASE_TEMPLATE("is_plane: a square fronto-parallel plane (l1 == l2) is a plane", B, EDGEPLANE_TEST_BACKENDS) {
  const B b{};
  const int w = 64, h = 64;
  const auto depth = plane_image(camera(w, h), w, h, {0, 0, -1}, 2.0);
  const auto f = fits(b, depth, std::vector<std::uint16_t>(depth.size(), 1), w, h, 1)[0];
  CHECK(f.eigenvalues(0) == f.eigenvalues(1));  // the premise: exactly isotropic
  CHECK(is_plane(f, presets::thesis_full()));
}

TEST_CASE_TEMPLATE("should_merge: coplanar pieces merge; parallel offset (5 cm) and perpendicular ones do not", B,
                   EDGEPLANE_TEST_BACKENDS) {
  const B b{};
  const params p = presets::thesis_full();
  const vec3 n = normalized({0.2, -0.3, -1.0});
  {
    const auto [a, c] = halves(b, n, 2.0, n, 2.0);
    CHECK(should_merge(a, c, p));
    CHECK(should_merge(c, a, p));
  }
  {
    const auto [a, c] = halves(b, n, 2.0, n, 2.05);
    CHECK_FALSE(should_merge(a, c, p));
    CHECK_FALSE(should_merge(c, a, p));
  }
  {
    const auto [a, c] = halves(b, normalized({1, 0, -1}), 1.5, normalized({-1, 0, -1}), 1.5);
    CHECK_FALSE(should_merge(a, c, p));
    CHECK_FALSE(should_merge(c, a, p));
  }
  {  // tilted by 2 degrees (|n1 x n2| = 0.035 > t_par = 0.03), both 2 m from the camera: not parallel
    const auto [a, c] = halves(b, normalized({0, 0, -1}), 2.0, normalized({std::tan(0.035), 0, -1}), 2.0);
    CHECK_FALSE(should_merge(a, c, p));
  }
}

TEST_CASE("merge_groups: grouping is transitive, groups are numbered by first member, keep flags are honoured") {
  const params p = presets::thesis_full();
  // A, B, C: normals 0.02 rad apart in turn (A-B and B-C parallel within t_par = 0.03; A-C not),
  // side by side on one gently bending surface.  D: perpendicular.  E: the next piece after C
  // (0.02 rad from C, 0.06 rad from A).
  const plane_fit A = hand_fit(std::sin(-0.02), -std::cos(0.02), -0.3, 2.0);
  const plane_fit B = hand_fit(0, -1, 0.0, 2.0);
  const plane_fit C = hand_fit(std::sin(0.02), -std::cos(0.02), 0.3, 2.0);
  const plane_fit D = hand_fit(-1, -1, 0.0, 2.5);
  const plane_fit E = hand_fit(std::sin(0.04), -std::cos(0.04), 0.6, 2.0);
  REQUIRE(should_merge(A, B, p));
  REQUIRE(should_merge(B, C, p));
  REQUIRE_FALSE(should_merge(A, C, p));
  using G = std::vector<int>;
  CHECK(merge_groups({A, B, C}, {1, 1, 1}, p) == G{0, 0, 0});  // A-C joined through B
  CHECK(merge_groups({C, A, B}, {1, 1, 1}, p) == G{0, 0, 0});
  CHECK(merge_groups({D, A, B, C}, {1, 1, 1, 1}, p) == G{0, 1, 1, 1});
  CHECK(merge_groups({A, D, C}, {1, 1, 1}, p) == G{0, 1, 2});
  // Without B (not kept), A and C stay apart and B gets no group, wherever B stands in the list.
  CHECK(merge_groups({A, B, C}, {1, 0, 1}, p) == G{0, -1, 1});
  CHECK(merge_groups({A, C, B}, {1, 1, 0}, p) == G{0, 1, -1});
  CHECK(merge_groups({B, A, C}, {0, 1, 1}, p) == G{-1, 0, 1});
  CHECK(merge_groups({A, B, C, E}, {1, 0, 1, 1}, p) == G{0, -1, 1, 1});  // C-E merge, A stays apart
  CHECK(merge_groups({A, B, C, E}, {1, 1, 1, 1}, p) == G{0, 0, 0, 0});
  CHECK(merge_groups({}, {}, p).empty());
  // The overload writing into caller-owned vectors gives the same groups and reuses them.
  std::vector<int> group(17, 5), parent;
  merge_groups({D, A, B, C}, {1, 1, 1, 1}, p, group, parent);
  CHECK(group == G{0, 1, 1, 1});
  merge_groups({A, C, B}, {1, 1, 0}, p, group, parent);
  CHECK(group == G{0, 1, -1});
}

TEST_CASE("params: validate() accepts the presets and throws edgeplane::error naming a bad threshold") {
  for (const auto& name : presets::preset_names()) {
    CAPTURE(name);
    CHECK_NOTHROW(validate(preset(name)));
  }
  const float qnan = std::numeric_limits<float>::quiet_NaN();
  struct bad_case {
    const char* name;
    std::function<void(params&)> set;
  };
  const std::vector<bad_case> cases = {
      {"t_je", [](params& q) { q.t_je = -0.01f; }},
      {"t_je", [](params& q) { q.t_je = 0.f; }},
      {"n_coe", [](params& q) { q.n_coe = 0; }},
      {"n_coe", [](params& q) { q.n_coe = 33; }},  // longer than the neighbour arrays
      {"t_line", [=](params& q) { q.t_line = qnan; }},
      {"t_ee", [](params& q) { q.t_ee = 1.f; }},
      {"n_ee", [](params& q) { q.n_ee = 0; }},
      {"max_depth", [](params& q) { q.max_depth = q.min_depth; }},
      {"min_depth", [](params& q) { q.min_depth = -1.f; }},
      {"t_size", [](params& q) { q.t_size = 2; }},
      {"max_run_splits", [](params& q) { q.max_run_splits = 8; }},
      {"t_cu", [=](params& q) { q.t_cu = std::numeric_limits<float>::infinity(); }},
      {"noise.sigma0", [](params& q) { q.noise.sigma0 = -0.001f; }},
      {"t_residual", [=](params& q) { q.t_residual = qnan; }},
      {"smooth_radius", [](params& q) { q.smooth_radius = -1; }},
      {"t_je_ratio", [](params& q) { q.t_je_ratio = -1.f; }},
  };
  for (const auto& c : cases) {
    CAPTURE(c.name);
    params q = presets::thesis_full();
    c.set(q);
    std::string what;
    try {
      validate(q);
    } catch (const edgeplane::error& e) {
      what = e.what();
    }
    CHECK(what.find(std::string("parameter ") + c.name + " ") != std::string::npos);
  }
}

TEST_CASE("params: preset() finds every listed name and throws listing them for an unknown one") {
  CHECK(preset("thesis_half").downscale);
  CHECK_FALSE(preset("thesis_full").downscale);
  CHECK(preset("kinect360").t_je_quad > 0.f);
  std::string what;
  try {
    (void)preset("nope");
  } catch (const edgeplane::error& e) {
    what = e.what();
  }
  CHECK(what.find("nope") != std::string::npos);
  for (const auto& name : presets::preset_names()) {
    CAPTURE(name);
    CHECK(what.find(name) != std::string::npos);
  }
  CHECK_THROWS_AS((void)preset(""), edgeplane::error);
}
