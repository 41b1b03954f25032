// Tests of include/edgeplane/planes/plane_stats.hpp: moments of synthetic planes, the plane fit,
// bounding boxes, and the determinism of the fixed-point sums.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "edgeplane/planes/plane_stats.hpp"
#include "edgeplane/segmenter.hpp"
#include "support/test_backends.hpp"

using namespace edgeplane;
using namespace edgeplane_test;

namespace {

struct moments_result {
  std::vector<std::uint64_t> m;
  std::vector<std::int32_t> bbox;
  plane_fit fit(int label) const { return fit_plane(m.data() + label * moment_slots, bbox.data() + 4 * label); }
};

template <class B>
moments_result moments(const B& b, const std::vector<float>& depth, const std::vector<std::uint16_t>& labels, int w,
                       int h, int num_labels) {
  device_array<float, B> z(b, depth);
  device_array<std::uint16_t, B> l(b, labels);
  device_array<std::uint64_t, B> m(b, static_cast<std::size_t>(num_labels + 1) * moment_slots, 12345);
  device_array<std::int32_t, B> bb(b, static_cast<std::size_t>(num_labels + 1) * 4, 12345);  // cleared by the call
  accumulate_moments(b, z.cview(w, h), camera(w, h), detail::image_labels{l.cview(w, h)}, num_labels, m.data(),
                     bb.data());
  return {m.host(), bb.host()};
}

double angle_deg(const Eigen::Vector3d& a, vec3 b) {
  const double c = a.dot(Eigen::Vector3d(b.x, b.y, b.z)) / a.norm();
  return std::acos(std::min(1.0, std::max(-1.0, c))) * 180.0 / 3.14159265358979;
}

// The plane image of candidate ids under a merge table (what the segmenter's relabel writes).
std::vector<std::uint16_t> planes_of(const std::vector<std::int32_t>& cand, const std::vector<std::uint16_t>& table) {
  std::vector<std::uint16_t> out(cand.size());
  for (std::size_t i = 0; i < cand.size(); ++i) out[i] = cand[i] > 0 ? table[static_cast<std::size_t>(cand[i])] : 0;
  return out;
}
}  // namespace

TEST_CASE_TEMPLATE("fit_plane: the moments of a ray-cast plane give its normal (0.1 deg) and d (1 mm)", B,
                   EDGEPLANE_TEST_BACKENDS) {
  const int w = 64, h = 48;
  struct plane_case {
    vec3 n;
    double d;
  };
  // Normals given toward the camera (d > 0) and away from it (d < 0): the fit always turns them
  // toward the camera.
  const plane_case cases[] = {{normalized({0.0, 0.0, -1.0}), 2.0},
                              {normalized({0.3, -0.2, -1.0}), 1.5},
                              {normalized({-0.5, 0.6, -1.0}), 3.0},
                              {normalized({0.2, 0.9, 0.4}), -1.2}};  // a floor-like plane, normal given away
  for (const B& b : variants<B>()) {
    CAPTURE(variant_name(b));
    for (const auto& c : cases) {
      CAPTURE(c.d);
      const auto depth = plane_image(camera(w, h), w, h, c.n, c.d);
      int valid = 0;
      for (float z : depth) valid += z > 0.f ? 1 : 0;
      REQUIRE(valid > w * h / 2);
      const std::vector<std::uint16_t> labels(depth.size(), 1);
      const plane_fit f = moments(b, depth, labels, w, h, 1).fit(1);
      const vec3 toward = c.d >= 0 ? c.n : vec3{-c.n.x, -c.n.y, -c.n.z};
      CHECK(angle_deg(f.normal, toward) < 0.1);
      CHECK(std::abs(f.d - std::abs(c.d)) < 0.001);
      CHECK(f.d >= 0);
      CHECK(f.normal.dot(f.centroid) < 0);  // pointing toward the camera
      CHECK(std::abs(f.normal.norm() - 1.0) < 1e-9);
      CHECK(f.points == valid);
      CHECK(f.pixels == w * h);
      CHECK(f.eigenvalues(0) >= f.eigenvalues(1));
      CHECK(f.eigenvalues(1) >= f.eigenvalues(2));
      CHECK(std::sqrt(f.eigenvalues(2)) < 0.0005);  // flat: residual below the 0.1 mm quantum scale
    }
  }
}

TEST_CASE_TEMPLATE("accumulate_moments: two labels, invalid pixels, unlabelled pixels and bounding boxes", B,
                   EDGEPLANE_TEST_BACKENDS) {
  const int w = 40, h = 30;
  const auto k = camera(w, h);
  const vec3 n1 = normalized({0.2, 0.1, -1.0}), n2 = normalized({-0.6, 0.0, -1.0});
  std::vector<float> depth(static_cast<std::size_t>(w) * h);
  std::vector<std::uint16_t> labels(depth.size(), 0);
  int pts1 = 0, px1 = 0, pts2 = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      // Label 1: an L shape (x 3..14, y 4..25, minus x > 8 for y > 12); label 2: a diamond around (28, 15).
      const bool l1 = x >= 3 && x <= 14 && y >= 4 && y <= 25 && !(x > 8 && y > 12);
      const bool l2 = std::abs(x - 28) + std::abs(y - 15) <= 7;
      depth[i] = plane_depth(k, x, y, l2 ? n2 : n1, l2 ? 2.5 : 1.8);
      if ((x + 2 * y) % 11 == 0) depth[i] = 0.f;  // scattered invalid pixels
      labels[i] = l1 ? 1 : l2 ? 2 : 0;
      if (l1) {
        ++px1;
        pts1 += depth[i] > 0.f ? 1 : 0;
      }
      if (l2) pts2 += depth[i] > 0.f ? 1 : 0;
    }
  for (const B& b : variants<B>()) {
    CAPTURE(variant_name(b));
    const auto r = moments(b, depth, labels, w, h, 2);
    for (int s = 0; s < moment_slots; ++s) CHECK(r.m[s] == 0);  // label 0 is not accumulated
    const plane_fit f1 = r.fit(1), f2 = r.fit(2);
    CHECK(f1.points == pts1);
    CHECK(f1.pixels == px1);
    CHECK(f1.points < f1.pixels);
    CHECK(f2.points == pts2);
    CHECK(f1.bbox == std::array<int, 4>{3, 4, 14, 25});
    CHECK(f2.bbox == std::array<int, 4>{21, 8, 35, 22});
    CHECK(angle_deg(f1.normal, n1) < 0.1);
    CHECK(angle_deg(f2.normal, n2) < 0.1);
    CHECK(std::abs(f1.d - 1.8) < 0.001);
    CHECK(std::abs(f2.d - 2.5) < 0.001);
  }
}

TEST_CASE_TEMPLATE("accumulate_moments: a row range reads only its rows, with the whole image's coordinates", B,
                   EDGEPLANE_TEST_BACKENDS) {
  // Two tilted planes; rows [9, 23) hold all of label 2 and part of label 1.  The range must give
  // exactly the slots and boxes of the whole image with the labels outside the range erased (so
  // the points keep their pixel coordinates: a range that shifted them would move the centroid).
  const int w = 41, h = 30, y0 = 9, y1 = 23;
  const auto k = camera(w, h);
  const vec3 n1 = normalized({0.2, 0.1, -1.0}), n2 = normalized({-0.6, 0.0, -1.0});
  std::vector<float> depth(static_cast<std::size_t>(w) * h);
  std::vector<std::uint16_t> labels(depth.size(), 0), cut(depth.size(), 0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      const bool l2 = std::abs(x - 28) + std::abs(y - 15) <= 6;  // rows 9..21
      depth[i] = plane_depth(k, x, y, l2 ? n2 : n1, l2 ? 2.5 : 1.8);
      if ((x + 3 * y) % 13 == 0) depth[i] = 0.f;
      labels[i] = l2 ? 2 : (x < 20 ? 1 : 0);
      cut[i] = y >= y0 && y < y1 ? labels[i] : 0;
    }
  for (const B& b : variants<B>()) {
    CAPTURE(variant_name(b));
    device_array<float, B> z(b, depth);
    device_array<std::uint16_t, B> l(b, labels);
    auto run = [&](int rb, int re) {
      device_array<std::uint64_t, B> m(b, 3 * moment_slots, 777);
      device_array<std::int32_t, B> bb(b, 12, 777);
      accumulate_moments(b, z.cview(w, h), k, detail::image_labels{l.cview(w, h)}, 2, m.data(), bb.data(), rb, re);
      return moments_result{m.host(), bb.host()};
    };
    const moments_result want = moments(b, depth, cut, w, h, 2), all = moments(b, depth, labels, w, h, 2);
    const moments_result got = run(y0, y1);
    CHECK(got.m == want.m);
    CHECK(got.bbox == want.bbox);
    CHECK(got.fit(1).bbox == std::array<int, 4>{0, y0, 19, y1 - 1});
    CHECK(got.fit(2).pixels == all.fit(2).pixels);
    CHECK((got.fit(2).centroid - all.fit(2).centroid).norm() < 1e-12);  // label 2 whole: the same points
    CHECK(run(0, -1).m == all.m);                                         // the default: every row
    CHECK(run(-3, h + 5).m == all.m);                                     // clamped to the image
    const moments_result none = run(5, 5);                                // an empty range: nothing
    CHECK(std::all_of(none.m.begin(), none.m.end(), [](std::uint64_t v) { return v == 0; }));
  }
}

TEST_CASE_TEMPLATE("accumulate_moments: fixed-point sums are identical between serial and parallel runs", B,
                   EDGEPLANE_TEST_BACKENDS) {
  const int w = 160, h = 120, num = 7;  // more than 64 rows: the parallel path really runs in parallel
  auto depth = plane_image(camera(w, h), w, h, normalized({0.1, -0.3, -1.0}), 2.2);
  lcg_noise noise(9);
  for (auto& z : depth) z += noise(0.004f);
  std::vector<std::uint16_t> labels(depth.size());
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      labels[static_cast<std::size_t>(y) * w + x] = static_cast<std::uint16_t>((x / 7 + y / 5 + x * y % 3) % (num + 1));
  const auto vs = variants<B>();
  const auto ref = moments(vs.back(), depth, labels, w, h, num);
  for (const B& b : vs)
    for (int rep = 0; rep < 5; ++rep) {
      CAPTURE(variant_name(b));
      const auto r = moments(b, depth, labels, w, h, num);
      CHECK(r.m == ref.m);
      CHECK(r.bbox == ref.bbox);
    }
  // And the sums are those of a plain serial loop over the fixed-point coordinates.
  const auto proj = detail::make_projector(camera(w, h));
  std::int64_t sx = 0, szz = 0, cnt = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      if (labels[static_cast<std::size_t>(y) * w + x] == 3) {
        const auto p = proj(x, y, depth[static_cast<std::size_t>(y) * w + x]);
        const auto px = static_cast<std::int64_t>(std::llrint(double(p.x) * fixed_per_metre));
        const auto pz = static_cast<std::int64_t>(std::llrint(double(p.z) * fixed_per_metre));
        sx += px;
        szz += pz * pz;
        ++cnt;
      }
  CHECK(static_cast<std::int64_t>(ref.m[3 * moment_slots + 0]) == cnt);
  CHECK(static_cast<std::int64_t>(ref.m[3 * moment_slots + 1]) == sx);
  CHECK(static_cast<std::int64_t>(ref.m[3 * moment_slots + 9]) == szz);
}

TEST_CASE_TEMPLATE("inlier_labels: the refit ignores a candidate's off-plane rim; candidate_image_labels agrees", B,
                   EDGEPLANE_TEST_BACKENDS) {
  const int w = 48, h = 36;
  const auto k = camera(w, h);
  const vec3 n = normalized({0.25, -0.15, -1.0});
  auto depth = plane_image(k, w, h, n, 2.0);
  std::vector<std::int32_t> cand(depth.size(), 0);
  int inliers = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      if (x >= 40) continue;                  // not in any candidate
      cand[i] = y < 18 ? 1 : 2;               // two candidates, merged into plane 1 by the table
      if (x >= 36) depth[i] += 0.04f;         // a rim 4 cm off the plane (a crease's other face)
      else ++inliers;
    }
  const std::vector<std::uint16_t> table = {0, 1, 1};
  const std::vector<float> planes = {0, 0, 0, 0, float(n.x), float(n.y), float(n.z), 2.0f};
  const std::vector<float> tol = {0.f, 0.01f};
  for (const B& b : variants<B>()) {
    CAPTURE(variant_name(b));
    device_array<float, B> z(b, depth), pl(b, planes), tl(b, tol);
    device_array<std::int32_t, B> c(b, cand);
    device_array<std::uint16_t, B> of_plane(b, planes_of(cand, table));
    device_array<std::uint64_t, B> m(b, 2 * moment_slots, 0);
    device_array<std::int32_t, B> bb(b, 8, 0);
    accumulate_moments(b, z.cview(w, h), k,
                       detail::inlier_labels{of_plane.cview(w, h), pl.data(), tl.data(), z.cview(w, h),
                                             detail::make_projector(k)},
                       1, m.data(), bb.data());
    const auto mh = m.host();
    const plane_fit f = fit_plane(mh.data() + moment_slots, bb.host().data() + 4);
    CHECK(f.points == inliers);
    CHECK(f.bbox == std::array<int, 4>{0, 0, 35, h - 1});
    CHECK(angle_deg(f.normal, n) < 0.1);
    CHECK(std::abs(f.d - 2.0) < 0.001);
    // Candidate ids straight from the image: two labels, rim included.
    device_array<std::uint64_t, B> m2(b, 3 * moment_slots, 0);
    device_array<std::int32_t, B> bb2(b, 12, 0);
    accumulate_moments(b, z.cview(w, h), k, detail::candidate_image_labels{c.cview(w, h)}, 2, m2.data(), bb2.data());
    const auto m2h = m2.host();
    CHECK(fit_plane(m2h.data() + moment_slots).points == 40 * 18);
    CHECK(fit_plane(m2h.data() + 2 * moment_slots).points == 40 * 18);
  }
}

TEST_CASE("fixed_point_max_depth: hundreds of metres for real cameras, nothing for absurd intrinsics") {
  // Kinect v1 at 640x480: coordinates stay within depth (|u - cx| < fx), so the bound is the depth's:
  // sqrt(4e18 / 307200) units of 0.1 mm = 361 m.
  const float kinect = fixed_point_max_depth(intrinsics{525.f, 525.f, 319.5f, 239.5f}, 640, 480);
  CHECK(kinect == doctest::Approx(360.8).epsilon(0.01));
  // A wide lens spreads the lateral coordinates: twice |u - cx| / fx halves the bound.
  const float wide = fixed_point_max_depth(intrinsics{160.f, 160.f, 319.5f, 239.5f}, 640, 480);
  CHECK(wide == doctest::Approx(kinect * 160.0 / 320.0).epsilon(0.01));
  // The same camera at twice the resolution: four times the pixels, half the bound.
  CHECK(fixed_point_max_depth(intrinsics{1050.f, 1050.f, 639.5f, 479.5f}, 1280, 960) ==
        doctest::Approx(kinect / 2).epsilon(0.01));
  // A denormal focal length (found by the fuzzer: the sums of squares overflowed int64).
  CHECK(fixed_point_max_depth(intrinsics{7.8e-41f, 269.f, 60.f, 48.f}, 64, 48) < 1e-30f);
  // At the bound, one label covering the whole image: every sum of squares fits in 2^62.
  for (const intrinsics k : {intrinsics{525.f, 525.f, 319.5f, 239.5f}, intrinsics{50.f, 60.f, -100.f, 700.f}}) {
    const int w = 640, h = 480;
    const double z = fixed_point_max_depth(k, w, h);
    const double u = std::max(std::abs(double(k.cx)), std::abs(w - 1 - double(k.cx)));
    const double v = std::max(std::abs(double(k.cy)), std::abs(h - 1 - double(k.cy)));
    const double coord = std::max({z, u * z / k.fx, v * z / k.fy}) * fixed_per_metre + 0.5;
    CHECK(double(w) * h * coord * coord <= std::ldexp(1.0, 62));
  }
}

TEST_CASE_TEMPLATE("accumulate_moments: long runs (the host's 8-pixel lanes) give every slot and box of a plain loop", B,
                   EDGEPLANE_TEST_BACKENDS) {
  // Runs of one label far longer than 8 pixels, starting and ending at every offset of a chunk,
  // with unlabelled pixels and invalid depth inside runs, negative coordinates (left of and above the centre) and a
  // width that is not a multiple of 8; candidate_image_labels with `above` drops the low ids.
  // 300 rows: host backends take blocks of 4 rows, and 13 labels overflow the table of a block's
  // last 8 labels, whose entries are then handed over early.
  const int dims[2][3] = {{157, 23, 5}, {157, 300, 13}};
  for (const auto& dim : dims) {
  const int w = dim[0], h = dim[1], num = dim[2];
  CAPTURE(h);
  const auto k = camera(w, h);
  auto depth = plane_image(k, w, h, normalized({0.2, -0.4, -1.0}), 2.6);
  lcg_noise noise(4);
  for (auto& z : depth) z += noise(0.003f);
  std::vector<std::int32_t> cand(depth.size(), 0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      const int run = (x + 3 * y) / (17 + y % 13);  // runs of 17..29 pixels, shifted per row
      cand[i] = (run + y) % (num + 1);              // 0 = no label, also runs of no label
      if ((x * 5 + y) % 23 == 0 || x % 37 == 36) cand[i] = 0;  // unlabelled pixels inside runs, at their ends
      if ((x * 7 + y * 3) % 41 == 0) depth[i] = 0.f;  // a hole inside a run
    }
  const auto proj = detail::make_projector(k);
  for (const std::int32_t above : {0, 2}) {
    CAPTURE(above);
    std::vector<std::int64_t> ref(static_cast<std::size_t>(num + 1) * moment_slots, 0);
    std::vector<std::int32_t> ref_bb;
    for (int l = 0; l <= num; ++l) ref_bb.insert(ref_bb.end(), {0x7fffffff, 0x7fffffff, -1, -1});
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const std::size_t i = static_cast<std::size_t>(y) * w + x;
        const int l = cand[i] > above ? cand[i] : 0;
        if (l == 0) continue;
        std::int64_t* s = ref.data() + static_cast<std::size_t>(l) * moment_slots;
        std::int32_t* bb = ref_bb.data() + 4 * l;
        bb[0] = std::min(bb[0], x);
        bb[1] = std::min(bb[1], y);
        bb[2] = std::max(bb[2], x);
        bb[3] = std::max(bb[3], y);
        s[10] += 1;
        if (!(depth[i] > 0.f)) continue;
        const auto p = proj(x, y, depth[i]);
        const std::int64_t q[3] = {std::llrint(double(p.x) * fixed_per_metre), std::llrint(double(p.y) * fixed_per_metre),
                                   std::llrint(double(p.z) * fixed_per_metre)};
        s[0] += 1;
        for (int j = 0; j < 3; ++j) s[1 + j] += q[j];
        s[4] += q[0] * q[0];
        s[5] += q[0] * q[1];
        s[6] += q[0] * q[2];
        s[7] += q[1] * q[1];
        s[8] += q[1] * q[2];
        s[9] += q[2] * q[2];
      }
    bool neg_x = false, neg_y = false;  // some sums of coordinates are negative
    for (int l = 1; l <= num; ++l) {
      neg_x |= ref[static_cast<std::size_t>(l) * moment_slots + 1] < 0;
      neg_y |= ref[static_cast<std::size_t>(l) * moment_slots + 2] < 0;
    }
    if (above == 0) {
      CHECK(neg_x);
      CHECK(neg_y);
    }
    for (const B& b : variants<B>()) {
      CAPTURE(variant_name(b));
      device_array<float, B> z(b, depth);
      device_array<std::int32_t, B> c(b, cand);
      device_array<std::uint64_t, B> m(b, static_cast<std::size_t>(num + 1) * moment_slots, 777);
      device_array<std::int32_t, B> bb(b, static_cast<std::size_t>(num + 1) * 4, 777);
      accumulate_moments(b, z.cview(w, h), k, detail::candidate_image_labels{c.cview(w, h), above}, num, m.data(),
                         bb.data());
      const auto got = m.host();
      const auto got_bb = bb.host();
      for (int l = 1; l <= num; ++l) {
        CAPTURE(l);
        for (int j = 0; j < moment_slots; ++j) {
          CAPTURE(j);
          CHECK(static_cast<std::int64_t>(got[static_cast<std::size_t>(l) * moment_slots + j]) ==
                ref[static_cast<std::size_t>(l) * moment_slots + j]);
        }
        for (int j = 0; j < 4; ++j) CHECK(got_bb[4 * l + j] == ref_bb[4 * l + j]);
      }
      // first-order only: the same counts, sums of coordinates and boxes, no products (0); a
      // centroid_fit of them is fit_plane's of the full sums, bit for bit, in every field it sets
      device_array<std::uint64_t, B> m1(b, static_cast<std::size_t>(num + 1) * moment_slots, 777);
      device_array<std::int32_t, B> bb1(b, static_cast<std::size_t>(num + 1) * 4, 777);
      accumulate_first_moments(b, z.cview(w, h), k, detail::candidate_image_labels{c.cview(w, h), above}, num,
                               m1.data(), bb1.data());
      const auto got1 = m1.host();
      const auto got1_bb = bb1.host();
      int fitted = 0;
      for (int l = 1; l <= num; ++l) {
        CAPTURE(l);
        for (int j = 0; j < moment_slots; ++j) {
          CAPTURE(j);
          const std::int64_t want = j >= 4 && j <= 9 ? 0 : ref[static_cast<std::size_t>(l) * moment_slots + j];
          CHECK(static_cast<std::int64_t>(got1[static_cast<std::size_t>(l) * moment_slots + j]) == want);
        }
        for (int j = 0; j < 4; ++j) CHECK(got1_bb[4 * l + j] == ref_bb[4 * l + j]);
        const plane_fit full = fit_plane(got.data() + static_cast<std::size_t>(l) * moment_slots, got_bb.data() + 4 * l);
        const plane_fit first = centroid_fit(got1.data() + static_cast<std::size_t>(l) * moment_slots,
                                             got1_bb.data() + 4 * l);
        CHECK(first.points == full.points);
        CHECK(first.pixels == full.pixels);
        CHECK(first.bbox == full.bbox);
        for (int j = 0; j < 3; ++j) CHECK(first.centroid(j) == full.centroid(j));
        if (full.points >= 3) {
          CHECK(first.centroid.norm() > 0.5);  // (a plane 2.6 m away)
          ++fitted;
        }
      }
      CHECK(fitted >= num - 2);
    }
  }
}
}

TEST_CASE("image_labels::lanes: 8 labels at once equal the per-pixel labels, all 16 bits, in a pitched image") {
  static_assert(detail::has_label_lanes<detail::image_labels>);
  const int w = 29, h = 5, pitch = 37;
  lcg_noise noise(3);
  std::vector<std::uint16_t> img(static_cast<std::size_t>(pitch) * h);
  for (auto& v : img) v = static_cast<std::uint16_t>(noise.next_u32(65536));  // labels above 32767 too
  const detail::image_labels lab{image_view<const std::uint16_t>{img.data(), w, h, pitch}};
  int mismatches = 0, high = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x + 8 <= w; ++x) {
      std::int32_t out[8];
      lab.lanes<8>(x, y, out);
      for (int l = 0; l < 8; ++l) {
        mismatches += out[l] != static_cast<std::int32_t>(img[static_cast<std::size_t>(y) * pitch + x + l]);
        high += out[l] > 32767;
      }
    }
  CHECK(mismatches == 0);
  CHECK(high > 0);
}

TEST_CASE("candidate_image_labels::lanes: 8 labels at once equal the per-pixel labels, for every threshold") {
  static_assert(detail::has_label_lanes<detail::candidate_image_labels>);
  const int w = 27, h = 4;
  lcg_noise noise(5);
  std::vector<std::int32_t> cand(static_cast<std::size_t>(w) * h);
  for (auto& c : cand) c = static_cast<std::int32_t>(noise.next_u32(9)) - 1;  // ids -1..7, 0 = none
  for (const std::int32_t above : {0, 1, 3, 6, 7}) {
    CAPTURE(above);
    const detail::candidate_image_labels lab{make_view<const std::int32_t>(cand.data(), w, h), above};
    int mismatches = 0, kept = 0, at_threshold = 0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x + 8 <= w; ++x) {
        std::int32_t out[8];
        lab.lanes<8>(x, y, out);
        for (int l = 0; l < 8; ++l) {
          const std::int32_t c = cand[static_cast<std::size_t>(y) * w + x + l];
          const std::int32_t want = c > above ? c : 0;  // the definition, not lab(x, y)
          mismatches += out[l] != want;
          kept += want != 0;
          at_threshold += c == above;
        }
      }
    CHECK(mismatches == 0);
    CHECK(at_threshold > 0);  // ids equal to the threshold occur: they tell > from >=
    if (above < 7) CHECK(kept > 0);
  }
}

namespace {
// A noisy plane (depth n . X = d plus noise of up to +-amp) with holes (x + hole_step * y a
// multiple of hole_period) under candidate ids 0..4 in diagonal bands of `band` columns.
struct candidate_scene {
  std::vector<float> depth;
  std::vector<std::int32_t> cand;
};
candidate_scene noisy_candidates(const intrinsics& k, int w, int h, vec3 n, double d, unsigned seed, float amp,
                                 int slope, int band, int hole_step, int hole_period) {
  candidate_scene s{plane_image(k, w, h, n, d), {}};
  s.cand.assign(s.depth.size(), 0);
  lcg_noise noise(seed);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      s.cand[i] = ((x + slope * y) / band) % 5;
      s.depth[i] += noise(amp);
      if ((x + y * hole_step) % hole_period == 0) s.depth[i] = 0.f;
    }
  return s;
}
// Lanes of 8 and of 16 from every start column of every row that differ from the per-pixel
// labels (and, for a sparse source, runs of 32 whose labels or "any label" answer are wrong).
template <class Labels>
int lane_mismatches(const Labels& lab, int w, int h) {
  int mismatches = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x + 8 <= w; ++x) {
      std::int32_t out[8];
      lab.template lanes<8>(x, y, out);
      for (int l = 0; l < 8; ++l) mismatches += out[l] != lab(x + l, y);
      if (x + 16 > w) continue;
      std::int32_t wide[16];
      lab.template lanes<16>(x, y, wide);
      for (int l = 0; l < 16; ++l) mismatches += wide[l] != lab(x + l, y);
      if constexpr (detail::has_sparse_lanes<Labels>) {
        if (x + 32 > w) continue;
        std::int32_t sparse[32];
        bool any32 = false;
        for (int l = 0; l < 32; ++l) any32 = any32 || lab(x + l, y) != 0;
        mismatches += lab.template sparse_lanes<32>(x, y, sparse) != any32;
        for (int l = 0; l < 32; ++l) mismatches += sparse[l] != lab(x + l, y);
      }
    }
  return mismatches;
}
}  // namespace

TEST_CASE("inlier_labels::lanes: 8 labels at once equal the per-pixel labels, and the moments those of the label image") {
  // Long runs of candidates (one plane looked up per run), candidates of no plane (table 0),
  // pixels off their plane and holes; every start column, so runs cross lane boundaries.
  const int w = 141, h = 19;
  const auto k = camera(w, h);
  const vec3 n = normalized({0.1, 0.3, -1.0});
  // ids 0..4; noise puts some pixels beyond the 1 cm tolerance
  auto [depth, cand] = noisy_candidates(k, w, h, n, 2.4, 11, 0.006f, 2, 23, 5, 37);
  const std::vector<std::uint16_t> table = {0, 1, 0, 2, 1};  // candidate 2 belongs to no plane
  const std::vector<float> planes = {0, 0, 0, 0, float(n.x), float(n.y), float(n.z), 2.4f,
                                     float(n.x), float(n.y), float(n.z), 2.41f};
  std::vector<float> tol = {0.f, 0.01f, 0.008f};
  const auto proj = detail::make_projector(k);
  // Plane 2's tolerance is exactly the distance of one of its pixels (the first valid pixel of
  // candidate 3 in row 0, past the first lane run), so that pixel tells "<=" from "<".
  {
    int bx = -1;
    for (int x = 8; x + 8 < w && bx < 0; ++x)
      if (cand[static_cast<std::size_t>(x)] == 3 && depth[static_cast<std::size_t>(x)] > 0.f) bx = x;
    REQUIRE(bx >= 0);
    tol[2] = detail::plane_distance(planes.data(), 2, proj(bx, 0, depth[static_cast<std::size_t>(bx)]));
  }
  const auto of_plane = planes_of(cand, table);
  const detail::inlier_labels lab{make_view<const std::uint16_t>(of_plane.data(), w, h), planes.data(), tol.data(),
                                  make_view<const float>(depth.data(), w, h), proj};
  static_assert(detail::has_label_lanes<detail::inlier_labels>);
  int kept = 0, dropped = 0;
  CHECK(lane_mismatches(lab, w, h) == 0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::int32_t want = lab(x, y);
      kept += want > 0;
      dropped += want == 0 && cand[static_cast<std::size_t>(y) * w + x] != 0;
    }
  CHECK(kept > 1000);
  CHECK(dropped > 500);  // off-plane pixels, holes and candidate 2 (distinct pixels; 719 here): not vacuous
  // The moments through the lanes equal those of the image of per-pixel labels.
  std::vector<std::uint16_t> labels(depth.size());
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) labels[static_cast<std::size_t>(y) * w + x] = static_cast<std::uint16_t>(lab(x, y));
  const cpu b{};
  std::vector<std::uint64_t> m1(3 * moment_slots), m2(3 * moment_slots);
  std::vector<std::int32_t> b1(12), b2(12);
  accumulate_moments(b, make_view<const float>(depth.data(), w, h), k, lab, 2, m1.data(), b1.data());
  accumulate_moments(b, make_view<const float>(depth.data(), w, h), k,
                     detail::image_labels{make_view<const std::uint16_t>(labels.data(), w, h)}, 2, m2.data(), b2.data());
  CHECK(m1 == m2);
  CHECK(b1 == b2);
}

TEST_CASE_TEMPLATE("inlier_change_labels: the moments of the pixels that joined and left turn one pass's sums into the next's",
                   B, EDGEPLANE_TEST_BACKENDS) {
  // Candidates of two planes (and one of none) on a noisy plane with holes; two plane sets whose
  // tolerances and offsets differ, so that pixels join and leave each plane between them.
  const int w = 141, h = 23;
  const auto k = camera(w, h);
  const vec3 n = normalized({0.1, 0.3, -1.0});
  const auto [depth, cand] = noisy_candidates(k, w, h, n, 2.4, 5, 0.008f, 3, 19, 7, 41);
  const std::vector<std::uint16_t> table = {0, 1, 0, 2, 1};  // candidate 2 belongs to no plane
  const std::vector<float> planes_a = {0, 0, 0, 0, float(n.x), float(n.y), float(n.z), 2.4f,
                                       float(n.x), float(n.y), float(n.z), 2.405f};
  const std::vector<float> planes_b = {0, 0, 0, 0, float(n.x), float(n.y), float(n.z), 2.402f,
                                       float(n.x), float(n.y), float(n.z), 2.4f};
  const std::vector<float> tol_a = {0.f, 0.01f, 0.006f}, tol_b = {0.f, 0.007f, 0.009f};
  const auto proj = detail::make_projector(k);
  const int np = 2;
  const auto of_plane = planes_of(cand, table);
  static_assert(detail::has_sparse_lanes<detail::inlier_change_labels>);
  static_assert(!detail::has_sparse_lanes<detail::inlier_labels>);
  // Lane form against the per-pixel form, both modes, on the host.
  for (const bool all : {false, true}) {
    CAPTURE(all);
    const detail::inlier_change_labels lab{make_view<const std::uint16_t>(of_plane.data(), w, h),
                                           planes_a.data(), tol_a.data(), planes_b.data(), tol_b.data(), np,
                                           make_view<const float>(depth.data(), w, h), proj, all};
    int joined = 0, left = 0;
    CHECK(lane_mismatches(lab, w, h) == 0);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const std::int32_t want = lab(x, y);
        joined += want >= 1 && want <= np;
        left += want > np;
      }
    CHECK(left > 100);
    if (all) CHECK(joined == 0);
    else CHECK(joined > 100);
  }
  for (const B& b : variants<B>()) {
    CAPTURE(variant_name(b));
    device_array<float, B> z(b, depth), pa(b, planes_a), pb(b, planes_b), ta(b, tol_a), tb(b, tol_b);
    device_array<std::uint16_t, B> op(b, of_plane);
    const std::size_t slots = (np + 1) * moment_slots;
    auto sums = [&](const auto& labels, int num) {
      device_array<std::uint64_t, B> m(b, static_cast<std::size_t>(num + 1) * moment_slots, 7);
      device_array<std::int32_t, B> bb(b, static_cast<std::size_t>(num + 1) * 4, 7);
      accumulate_moments(b, z.cview(w, h), k, labels, num, m.data(), bb.data());
      return m.host();
    };
    auto inliers = [&](const device_array<float, B>& pl, const device_array<float, B>& tl) {
      return sums(detail::inlier_labels{op.cview(w, h), pl.data(), tl.data(), z.cview(w, h), proj}, np);
    };
    auto change = [&](bool all) {
      return sums(detail::inlier_change_labels{op.cview(w, h), pa.data(), ta.data(), pb.data(), tb.data(), np,
                                               z.cview(w, h), proj, all},
                  2 * np);
    };
    auto corrected = [&](std::vector<std::uint64_t> base, const std::vector<std::uint64_t>& d) {
      for (std::size_t i = moment_slots; i < slots; ++i) base[i] += d[i] - d[i + slots - moment_slots];
      return base;
    };
    const auto in_a = inliers(pa, ta), in_b = inliers(pb, tb);
    REQUIRE(in_a != in_b);
    // From the inliers under planes A to those under B.
    auto from_a = corrected(in_a, change(false));
    CHECK(std::equal(from_a.begin() + moment_slots, from_a.end(), in_b.begin() + moment_slots));
    // From every candidate pixel of each plane (the candidates' sums: pixels without depth in slot 10).
    auto from_all = corrected(sums(detail::image_labels{op.cview(w, h)}, np), change(true));
    CHECK(std::equal(from_all.begin() + moment_slots, from_all.end(), in_b.begin() + moment_slots));
  }
}

TEST_CASE("accumulate_moments: a label source's column spans (has_column_spans) bound the columns read in each row") {
  // The segmenter's split rounds sum their pieces through candidate_table_labels with each row's
  // span of failed pixels.  Here the spans are random (empty ones too) and labelled pixels lie
  // outside them, which must not be read: the sums and boxes are those of the label image cut to
  // the spans and to the row range, summed without spans.  The spans count from a column offset, as
  // the segmenter's count from its round's rectangle.
  static_assert(detail::has_column_spans<detail::candidate_table_labels>);
  static_assert(!detail::has_column_spans<detail::candidate_image_labels>);
  const int w = 157, h = 300, num = 13, y0 = 5, y1 = h - 3, x_off = 11;
  const auto k = camera(w, h);
  auto depth = plane_image(k, w, h, normalized({0.2, -0.4, -1.0}), 2.6);
  lcg_noise noise(9);
  for (auto& z : depth) z += noise(0.003f);
  std::vector<std::int32_t> cand(depth.size(), 0), table(num + 1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      cand[i] = ((x + 3 * y) / (17 + y % 13) + y) % (num + 1);  // runs of 17..29 pixels
      if ((x * 7 + y * 3) % 41 == 0) depth[i] = 0.f;
    }
  for (int l = 0; l <= num; ++l) table[static_cast<std::size_t>(l)] = l % 4 == 3 ? 0 : l;  // some ids count as none
  std::vector<std::int32_t> spans(2 * static_cast<std::size_t>(y1 - y0));
  std::vector<std::int32_t> cut(cand.size(), 0);  // the labels the spans keep
  int outside = 0;
  for (int y = y0; y < y1; ++y) {
    const int a = x_off + static_cast<int>(noise.next_u32((w - x_off) / 2 + 1)),
              b = (y % 9 == 0) ? a : a + static_cast<int>(noise.next_u32(w - a + 1));
    spans[2 * static_cast<std::size_t>(y - y0)] = a - x_off;  // spans count from column x_off (col0)
    spans[2 * static_cast<std::size_t>(y - y0) + 1] = b - x_off;
    for (int x = 0; x < w; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      const std::int32_t l = table[static_cast<std::size_t>(cand[i])];
      if (x >= a && x < b)
        cut[i] = l;
      else
        outside += l != 0 ? 1 : 0;
    }
  }
  REQUIRE(outside > 1000);  // labelled pixels the spans leave out
  for (const cpu::mode m : {cpu::mode::serial, cpu::mode::parallel}) {
    const cpu b{m};
    std::vector<std::uint64_t> want(static_cast<std::size_t>(num + 1) * moment_slots, 1), got(want.size(), 2);
    std::vector<std::int32_t> want_bb(static_cast<std::size_t>(num + 1) * 4, 1), got_bb(want_bb.size(), 2);
    accumulate_moments(b, make_view<const float>(depth.data(), w, h), k,
                       detail::candidate_image_labels{make_view<const std::int32_t>(cut.data(), w, h), 0}, num,
                       want.data(), want_bb.data());
    accumulate_moments(b, make_view<const float>(depth.data(), w, h), k,
                       detail::candidate_table_labels{make_view<const std::int32_t>(cand.data(), w, h), table.data(),
                                                      spans.data(), y0, x_off},
                       num, got.data(), got_bb.data(), y0, y1);
    CHECK(got == want);
    CHECK(got_bb == want_bb);
    int summed = 0;
    for (int l = 1; l <= num; ++l) summed += want[static_cast<std::size_t>(l) * moment_slots + 10] > 0 ? 1 : 0;
    CHECK(summed >= 8);  // not vacuous
  }
}
