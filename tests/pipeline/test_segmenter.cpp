// End-to-end tests of edgeplane::segmenter on scenes rendered in code (tests/support/scenes.hpp),
// checked against the planes they were built from.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <vector>

#include "edgeplane/edgeplane.hpp"
#include "support/device_model.hpp"
#include "support/scenes.hpp"

using namespace edgeplane;
using edgeplane::test::rendered;

namespace {

struct run_output {
  std::vector<std::uint16_t> labels;
  segmentation_result result;
};

template <class Backend = cpu>
run_output segment_float(const rendered& r, const params& p = presets::thesis_full(), Backend b = {}) {
  run_output o;
  o.labels.assign(r.depth.size(), 0xffff);
  segmenter<Backend> seg(p, b);
  o.result = seg.segment(make_view(r.depth.data(), r.width, r.height), r.k,
                         make_view(o.labels.data(), r.width, r.height));
  return o;
}

const plane* find_plane(const segmentation_result& res, int id) {
  for (const auto& p : res.planes)
    if (p.id == id) return &p;
  return nullptr;
}

double angle_deg(const std::array<float, 3>& a, const std::array<double, 4>& b) {
  const double c = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  return std::acos(std::min(1.0, std::max(-1.0, c))) * 180.0 / 3.141592653589793;
}

/// Every ground-truth plane with at least `min_pixels` visible pixels must be found: the label
/// covering most of it covers >= 70 % of it, >= 90 % of that label's pixels with ground truth lie
/// on it, and its plane is within 2 degrees and 1 cm of the truth.  Returns how many were checked.
int check_known_planes(const test::scene& s, const test::camera_pose& pose, const rendered& r,
                       const run_output& o, int min_pixels) {
  std::map<int, std::map<int, int>> overlap;  // gt -> label -> pixels
  std::map<int, int> gt_size, label_size_on_gt;
  for (std::size_t i = 0; i < r.gt.size(); ++i) {
    if (r.depth[i] <= 0.f) continue;
    gt_size[r.gt[i]]++;
    overlap[r.gt[i]][o.labels[i]]++;
    if (o.labels[i] != 0 && r.gt[i] != 0) label_size_on_gt[o.labels[i]]++;
  }
  int checked = 0;
  for (const auto& [id, size] : gt_size) {
    if (id <= 0 || size < min_pixels) continue;
    ++checked;
    CAPTURE(id);
    CAPTURE(size);
    int best = 0, best_px = 0;
    for (const auto& [l, px] : overlap[id])
      if (l != 0 && px > best_px) {
        best = l;
        best_px = px;
      }
    REQUIRE(best != 0);
    CHECK(best_px >= 0.7 * size);
    CHECK(best_px >= 0.9 * label_size_on_gt[best]);
    const plane* pl = find_plane(o.result, best);
    REQUIRE(pl != nullptr);
    const auto truth = test::plane_in_camera(s, pose, id);
    CHECK(angle_deg(pl->normal, truth) < 2.0);
    CHECK(std::abs(pl->d - truth[3]) < 0.01);
  }
  return checked;
}

}  // namespace

TEST_CASE("segmenter: room corner with a box on the floor") {
  const auto s = test::room_with_box();
  const auto pose = test::room_camera();
  const rendered r = test::render(s, pose, 512, 424, test::kinect2_intrinsics(), {0.001, 0.0005, 0.0, 7});
  const run_output o = segment_float(r);
  // four ground-truth planes exceed 3000 px from this view: floor, two walls, the box's front
  CHECK(check_known_planes(s, pose, r, o, 3000) == 4);
}

// The table top's 3 cm front face lies within the corner arms of the top's edge, so its pixels
// join the top candidate: this checks that the robust refit and the residual-capped growth keep
// the top's plane within 1 cm and its label pure.
TEST_CASE("segmenter: table top, floor and wall") {
  const auto s = test::table_scene();
  const auto pose = test::table_camera();
  const rendered r = test::render(s, pose, 512, 424, test::kinect2_intrinsics(), {0.001, 0.0005, 0.0, 3});
  const run_output o = segment_float(r);
  CHECK(check_known_planes(s, pose, r, o, 5000) >= 3);
}

TEST_CASE("segmenter: stairs give one plane per tread and riser") {
  const auto s = test::stairs_scene();
  const auto pose = test::stairs_camera();
  const rendered r = test::render(s, pose, 512, 424, test::kinect2_intrinsics(), {0.001, 0.0005, 0.0, 5});
  const run_output o = segment_float(r);
  CHECK(check_known_planes(s, pose, r, o, 4000) >= 6);
}

TEST_CASE("segmenter: a cylinder does not become a plane") {
  const auto s = test::cylinder_scene();
  const auto pose = test::cylinder_camera();
  const rendered r = test::render(s, pose, 512, 424, test::kinect2_intrinsics(), {0.001, 0.0005, 0.0, 11});
  const run_output o = segment_float(r);
  std::size_t side = 0, side_labelled = 0;
  std::map<int, std::size_t> label_px, label_on_side;
  for (std::size_t i = 0; i < r.gt.size(); ++i) {
    if (o.labels[i]) label_px[o.labels[i]]++;
    if (r.gt[i] != -1) continue;
    ++side;
    if (o.labels[i] != 0) {
      ++side_labelled;
      label_on_side[o.labels[i]]++;
    }
  }
  REQUIRE(side > 20000);
  CHECK(side_labelled < 0.05 * side);
  for (const auto& [l, px] : label_on_side) CHECK(px < 0.2 * label_px[l]);
  CHECK(check_known_planes(s, pose, r, o, 5000) >= 2);  // the floor and the wall are still found
}

namespace {
/// Whether every nonzero label of a w x h image forms one 4-connected region.
bool every_label_connected(const std::vector<std::uint16_t>& labels, int w, int h) {
  std::vector<char> seen(labels.size(), 0);
  std::map<int, int> regions;
  std::vector<int> stack;
  for (int i = 0; i < w * h; ++i) {
    if (!labels[i] || seen[i]) continue;
    ++regions[labels[i]];
    stack.assign(1, i);
    seen[i] = 1;
    while (!stack.empty()) {
      const int j = stack.back();
      stack.pop_back();
      const int x = j % w, y = j / w;
      const int nb[4][2] = {{x - 1, y}, {x + 1, y}, {x, y - 1}, {x, y + 1}};
      for (const auto& q : nb) {
        if (q[0] < 0 || q[1] < 0 || q[0] >= w || q[1] >= h) continue;
        const int k = q[1] * w + q[0];
        if (!seen[k] && labels[k] == labels[j]) {
          seen[k] = 1;
          stack.push_back(k);
        }
      }
    }
  }
  for (const auto& [l, n] : regions)
    if (n != 1) return false;
  return true;
}
}  // namespace

// A pillar in front of a wall splits the wall's image into a left and a right part: by default
// (the thesis's coplanar merging) they are one plane; with split_regions each part is a plane of
// its own with the wall's equation, and every label is one connected region.
TEST_CASE("segmenter: split_regions gives each disconnected part of a plane its own id") {
  test::scene s;
  s.planes.push_back({Eigen::Vector3d(0, 0, 1), 0.0, 1});
  s.planes.push_back({Eigen::Vector3d(1, 0, 0), -3.5, 2});
  s.boxes.push_back({Eigen::Vector3d(2.0, -0.2, 0.0), Eigen::Vector3d(2.3, 0.2, 6.0), 10});
  const auto pose = test::look_at({0.0, 0.0, 1.2}, {3.5, 0.0, 1.0});
  const rendered r = test::render(s, pose, 256, 212, test::kinect2_intrinsics(256, 212), {0.001, 0.0005, 0.0, 13});
  const auto truth = test::plane_in_camera(s, pose, 2);
  auto wall_labels = [&](const run_output& o) {
    std::map<int, int> px;  // label -> wall pixels
    int wall = 0;
    for (std::size_t i = 0; i < r.gt.size(); ++i)
      if (r.gt[i] == 2 && r.depth[i] > 0.f) {
        ++wall;
        if (o.labels[i]) px[o.labels[i]]++;
      }
    std::map<int, double> share;
    for (const auto& [l, n] : px)
      if (n >= 0.2 * wall) share[l] = static_cast<double>(n) / wall;
    return share;
  };
  params p = presets::thesis_half();
  p.downscale = false;
  const run_output merged = segment_float(r, p);
  const auto m = wall_labels(merged);
  REQUIRE(m.size() == 1);
  CHECK(m.begin()->second > 0.9);
  CHECK_FALSE(every_label_connected(merged.labels, r.width, r.height));

  p.split_regions = true;
  const run_output split = segment_float(r, p);
  const auto sp = wall_labels(split);
  REQUIRE(sp.size() == 2);
  double total = 0;
  for (const auto& [l, share] : sp) {
    total += share;
    const plane* pl = find_plane(split.result, l);
    REQUIRE(pl != nullptr);
    CHECK(angle_deg(pl->normal, truth) < 2.0);
    CHECK(std::abs(pl->d - truth[3]) < 0.01);
  }
  CHECK(total > 0.9);
  CHECK(every_label_connected(split.labels, r.width, r.height));
  CHECK(split.result.planes.size() == merged.result.planes.size() + 1);
  // pixel counts stay consistent with the relabelled image
  for (const auto& pl : split.result.planes)
    CHECK(pl.pixels == std::count(split.labels.begin(), split.labels.end(), pl.id));
}

TEST_CASE("segmenter: a fronto-parallel wall is one plane facing the camera") {
  rendered r;
  r.width = 160;
  r.height = 120;
  r.k = test::kinect2_intrinsics(160, 120);
  r.depth.assign(160 * 120, 2.0f);
  r.gt.assign(160 * 120, 1);
  params p = presets::thesis_full();
  const run_output o = segment_float(r, p);
  REQUIRE(o.result.planes.size() == 1);
  const plane& pl = o.result.planes[0];
  CHECK(pl.normal[2] == doctest::Approx(-1.0).epsilon(1e-4));
  CHECK(pl.d == doctest::Approx(2.0).epsilon(1e-3));
  CHECK(pl.pixels == 160 * 120);
  CHECK(pl.bbox == std::array<int, 4>{0, 0, 159, 119});
  for (auto l : o.labels) CHECK_EQ(l, pl.id);
}

TEST_CASE("segmenter: uint16 and float inputs agree, serial and parallel agree, reuse is stable") {
  const auto s = test::room_with_box();
  const rendered r = test::render(s, test::room_camera(), 256, 212, test::kinect2_intrinsics(256, 212),
                                  {0.001, 0.0005, 0.02, 9});
  const auto mm = r.depth_mm();
  params p = presets::thesis_half();
  p.downscale = false;
  std::vector<std::uint16_t> a(mm.size()), b(mm.size()), c(mm.size());
  segmenter<cpu> par(p);
  segmenter<cpu> ser(p, cpu{cpu::mode::serial});
  const auto ra = par.segment(make_view(mm.data(), r.width, r.height), 0.001f, r.k, make_view(a.data(), r.width, r.height));
  const std::size_t bytes = par.scratch_bytes();
  const auto rb = par.segment(make_view(mm.data(), r.width, r.height), 0.001f, r.k, make_view(b.data(), r.width, r.height));
  CHECK(par.scratch_bytes() == bytes);  // nothing re-allocated for a frame of the same size
  ser.segment(make_view(mm.data(), r.width, r.height), 0.001f, r.k, make_view(c.data(), r.width, r.height));
  CHECK(ra.planes.size() >= 3);
  CHECK(a == b);
  CHECK(a == c);
  // float metres with the same values give the same labels
  std::vector<float> f(mm.size());
  for (std::size_t i = 0; i < mm.size(); ++i) f[i] = mm[i] * 0.001f;
  std::vector<std::uint16_t> d(mm.size());
  par.segment(make_view(static_cast<const float*>(f.data()), r.width, r.height), r.k,
              make_view(d.data(), r.width, r.height));
  CHECK(a == d);
}

TEST_CASE("segmenter: half-scale processing returns full-size labels") {
  const auto s = test::room_with_box();
  const auto pose = test::room_camera();
  const rendered r = test::render(s, pose, 512, 424, test::kinect2_intrinsics(), {0.001, 0.0005, 0.0, 7});
  const run_output o = segment_float(r, presets::thesis_half());
  CHECK(check_known_planes(s, pose, r, o, 3000) == 4);
}

TEST_CASE("segmenter: degenerate data gives a well-defined empty result") {
  segmenter<cpu> seg;
  const intrinsics k{365.f, 365.f, 10.f, 10.f};
  SUBCASE("all invalid") {
    std::vector<std::uint16_t> z(64 * 48, 0), l(64 * 48, 7);
    const auto res = seg.segment(make_view(static_cast<const std::uint16_t*>(z.data()), 64, 48), 0.001f, k,
                                 make_view(l.data(), 64, 48));
    CHECK(res.planes.empty());
    for (auto v : l) CHECK_EQ(v, 0);
  }
  SUBCASE("NaN, infinities and negatives") {
    std::vector<float> z(64 * 48);
    for (std::size_t i = 0; i < z.size(); ++i)
      z[i] = i % 3 == 0 ? std::numeric_limits<float>::quiet_NaN()
                        : (i % 3 == 1 ? std::numeric_limits<float>::infinity() : -1.f);
    std::vector<std::uint16_t> l(z.size(), 7);
    const auto res = seg.segment(make_view(static_cast<const float*>(z.data()), 64, 48), k, make_view(l.data(), 64, 48));
    CHECK(res.planes.empty());
    for (auto v : l) CHECK_EQ(v, 0);
  }
  SUBCASE("tiny and line images") {
    for (auto [w, h] : {std::pair{1, 1}, std::pair{1, 50}, std::pair{50, 1}, std::pair{2, 2}, std::pair{0, 0}}) {
      std::vector<float> z(static_cast<std::size_t>(w) * h + 1, 1.5f);
      std::vector<std::uint16_t> l(z.size(), 7);
      const auto res = seg.segment(make_view(static_cast<const float*>(z.data()), w, h), k, make_view(l.data(), w, h));
      CHECK(res.planes.empty());
      for (int i = 0; i < w * h; ++i) CHECK_EQ(l[i], 0);
    }
  }
  SUBCASE("a single valid pixel") {
    std::vector<float> z(40 * 30, 0.f);
    z[400] = 2.f;
    std::vector<std::uint16_t> l(z.size(), 7);
    CHECK(seg.segment(make_view(static_cast<const float*>(z.data()), 40, 30), k, make_view(l.data(), 40, 30)).planes.empty());
  }
}

namespace {
// The final labels written straight into the caller's image on the CPU (by the closing, or by the
// upsampling of a downscaled frame's labels), the plane statistics read there: checked against
// the device path, whose labels go through its own buffer.
void check_labels_in_callers_image(const params& p) {
  const auto s = test::room_with_box();
  const rendered r = test::render(s, test::look_at({0.1, -1.2, 1.3}, {2.6, 0.8, 0.4}), 160, 128,
                                  test::kinect2_intrinsics(160, 128), {0.001, 0.0005, 0.01, 41ull});
  const std::vector<std::uint16_t> mm = r.depth_mm();
  const int w = r.width, h = r.height;
  // Reference: the device path (support/device_model.hpp: host memory that the segmenter treats
  // as a device's), whose closing writes its own buffer, then downloaded; it gives the CPU
  // backend's labels (test_device_path.cpp).
  std::vector<std::uint16_t> want(mm.size(), 0xffff);
  segmenter<edgeplane_test::device_model> ref(p);
  const segmentation_result want_res =
      ref.segment(make_view(static_cast<const std::uint16_t*>(mm.data()), w, h), 0.001f, r.k, make_view(want.data(), w, h));
  REQUIRE(want_res.planes.size() >= 3);
  auto same_planes = [&](const segmentation_result& got) {
    REQUIRE(got.planes.size() == want_res.planes.size());
    for (std::size_t i = 0; i < got.planes.size(); ++i) {
      CHECK(got.planes[i].pixels == want_res.planes[i].pixels);
      CHECK(got.planes[i].points == want_res.planes[i].points);
      CHECK(got.planes[i].bbox == want_res.planes[i].bbox);
      CHECK(got.planes[i].centroid == want_res.planes[i].centroid);
    }
  };
  segmenter<cpu> seg(p);
  SUBCASE("pitched rows, padding untouched") {
    const int pitch = w + 7;
    std::vector<std::uint16_t> out(static_cast<std::size_t>(pitch) * h, 0xbeef);
    const auto res = seg.segment(make_view(static_cast<const std::uint16_t*>(mm.data()), w, h), 0.001f, r.k,
                                 make_view(out.data(), w, h, pitch));
    same_planes(res);
    int differ = 0, padding = 0;
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) differ += out[static_cast<std::size_t>(y) * pitch + x] != want[static_cast<std::size_t>(y) * w + x];
      for (int x = w; x < pitch; ++x) padding += out[static_cast<std::size_t>(y) * pitch + x] != 0xbeef;
    }
    CHECK(differ == 0);
    CHECK(padding == 0);
  }
  SUBCASE("the labels over the depth they came from (one buffer in and out)") {
    std::vector<std::uint16_t> buf = mm;
    const auto res = seg.segment(make_view(static_cast<const std::uint16_t*>(buf.data()), w, h), 0.001f, r.k,
                                 make_view(buf.data(), w, h));
    same_planes(res);
    CHECK(buf == want);
  }
  SUBCASE("a segmenter reused: the second frame's labels do not depend on the first's image") {
    std::vector<std::uint16_t> first(mm.size(), 0), second(mm.size(), 0x5555);
    std::vector<std::uint16_t> blank(mm.size(), 0);
    seg.segment(make_view(static_cast<const std::uint16_t*>(mm.data()), w, h), 0.001f, r.k, make_view(first.data(), w, h));
    CHECK(first == want);
    // an all-invalid frame into another image: no planes, every label 0 (no closing runs then)
    const auto none = seg.segment(make_view(static_cast<const std::uint16_t*>(blank.data()), w, h), 0.001f, r.k,
                                  make_view(second.data(), w, h));
    CHECK(none.planes.empty());
    CHECK(std::all_of(second.begin(), second.end(), [](std::uint16_t v) { return v == 0; }));
    CHECK(first == want);  // the first frame's image is not written again
  }
}
}  // namespace

TEST_CASE("segmenter: the closing's labels written into the caller's image: pitched, in the depth's own buffer") {
  // thesis_full closes the labels and neither splits regions nor downscales: the closing writes
  // the final labels.
  const params p = presets::thesis_full();
  REQUIRE(p.label_closing_radius > 0);
  REQUIRE(!p.split_regions);
  REQUIRE(!p.downscale);
  check_labels_in_callers_image(p);
}

TEST_CASE("segmenter: the upsampled labels written into the caller's image: pitched, in the depth's own buffer") {
  const params p = presets::thesis_half();  // downscaled: the upsampling writes the final labels
  REQUIRE(p.downscale);
  check_labels_in_callers_image(p);
}

TEST_CASE("segmenter: segment_on_backend and segment_batch give what segment gives") {
  const auto s = test::room_with_box();
  std::vector<rendered> frames;
  for (int i = 0; i < 3; ++i)  // one camera, moving
    frames.push_back(test::render(s, test::look_at({0.1 * i, -1.2, 1.3}, {2.6, 0.9 - 0.1 * i, 0.4}), 192, 160,
                                  test::kinect2_intrinsics(192, 160), {0.001, 0.0005, 0.01, 30ull + i}));
  const params p = presets::thesis_half();
  std::vector<std::vector<std::uint16_t>> mm, want;
  std::vector<std::size_t> want_planes;
  for (const auto& r : frames) {
    mm.push_back(r.depth_mm());
    want.emplace_back(mm.back().size());
    segmenter<cpu> fresh(p);
    want_planes.push_back(fresh.segment(make_view(static_cast<const std::uint16_t*>(mm.back().data()), r.width, r.height),
                                        0.001f, r.k, make_view(want.back().data(), r.width, r.height))
                              .planes.size());
    CHECK(want_planes.back() >= 2);
  }
  segmenter<cpu> seg(p);
  SUBCASE("backend memory, pitched rows") {
    const rendered& r = frames[1];
    const int pitch = r.width + 5;
    std::vector<std::uint16_t> in(static_cast<std::size_t>(pitch) * r.height, 0), out(in.size(), 0xbeef);
    for (int y = 0; y < r.height; ++y)
      std::copy_n(mm[1].begin() + static_cast<std::ptrdiff_t>(y) * r.width, r.width, in.begin() + static_cast<std::ptrdiff_t>(y) * pitch);
    segmentation_result res;
    seg.segment_on_backend(make_view(static_cast<const std::uint16_t*>(in.data()), r.width, r.height, pitch), 0.001f, r.k,
                           make_view(out.data(), r.width, r.height, pitch), res);
    CHECK(res.planes.size() == want_planes[1]);
    int differ = 0;
    for (int y = 0; y < r.height; ++y) {
      for (int x = 0; x < r.width; ++x) differ += out[static_cast<std::size_t>(y) * pitch + x] != want[1][static_cast<std::size_t>(y) * r.width + x];
      CHECK(out[static_cast<std::size_t>(y) * pitch + r.width] == 0xbeef);  // padding untouched
    }
    CHECK(differ == 0);
  }
  SUBCASE("a batch of frames of different sizes") {
    std::vector<image_view<const std::uint16_t>> in;
    std::vector<std::vector<std::uint16_t>> out;
    std::vector<image_view<std::uint16_t>> out_views;
    for (std::size_t i = 0; i < frames.size(); ++i) {
      in.push_back(make_view(static_cast<const std::uint16_t*>(mm[i].data()), frames[i].width, frames[i].height));
      out.emplace_back(mm[i].size(), 0xbeef);
    }
    for (std::size_t i = 0; i < frames.size(); ++i) out_views.push_back(make_view(out[i].data(), frames[i].width, frames[i].height));
    std::vector<segmentation_result> results;
    seg.segment_batch(in, 0.001f, frames[0].k, out_views, results);
    REQUIRE(results.size() == frames.size());
    for (std::size_t i = 0; i < frames.size(); ++i) {
      CHECK(out[i] == want[i]);
      CHECK(results[i].planes.size() == want_planes[i]);
    }
    out_views.pop_back();
    CHECK_THROWS_AS(seg.segment_batch(in, 0.001f, frames[0].k, out_views, results), edgeplane::error);
  }
}

TEST_CASE("segmenter: depth beyond what the fixed-point statistics hold is invalid, not an overflow") {
  // A wall at 2 m, 160 x 120.
  std::vector<float> z(160 * 120, 2.0f);
  std::vector<std::uint16_t> l(z.size(), 7);
  const auto zv = make_view(static_cast<const float*>(z.data()), 160, 120);
  params p = presets::thesis_full();
  p.max_depth = 1000.f;  // far beyond: normal frames are unaffected
  segmenter<cpu> seg(p);
  CHECK(seg.segment(zv, test::kinect2_intrinsics(160, 120), make_view(l.data(), 160, 120)).planes.size() == 1);
  // A denormal focal length would put lateral coordinates at 1e40 m: every pixel is invalid (the
  // fuzzer found the int64 sums of squares overflowing here), so the frame has no planes.
  const auto res = seg.segment(zv, intrinsics{7.8e-41f, 269.f, 80.f, 60.f}, make_view(l.data(), 160, 120));
  CHECK(res.planes.empty());
  CHECK(std::all_of(l.begin(), l.end(), [](std::uint16_t v) { return v == 0; }));
}

TEST_CASE("segmenter: unusable arguments throw edgeplane::error") {
  segmenter<cpu> seg;
  std::vector<float> z(32 * 32, 1.f);
  std::vector<std::uint16_t> l(32 * 32);
  const auto zv = make_view(static_cast<const float*>(z.data()), 32, 32);
  const intrinsics k{300.f, 300.f, 16.f, 16.f};
  CHECK_THROWS_AS(seg.segment(zv, k, make_view(l.data(), 16, 32)), edgeplane::error);  // size mismatch
  CHECK_THROWS_AS(seg.segment(zv, intrinsics{0.f, 300.f, 16.f, 16.f}, make_view(l.data(), 32, 32)), edgeplane::error);
  CHECK_THROWS_AS(seg.segment(zv, intrinsics{std::nanf(""), 300.f, 16.f, 16.f}, make_view(l.data(), 32, 32)),
                  edgeplane::error);
  CHECK_THROWS_AS(seg.segment(image_view<const float>{nullptr, 32, 32, 32}, k, make_view(l.data(), 32, 32)),
                  edgeplane::error);
  CHECK_THROWS_AS(seg.segment(image_view<const float>{z.data(), 32, 32, 16}, k, make_view(l.data(), 32, 32)),
                  edgeplane::error);  // pitch < width
  std::vector<std::uint16_t> raw(32 * 32, 1000);
  CHECK_THROWS_AS(seg.segment(make_view(static_cast<const std::uint16_t*>(raw.data()), 32, 32), -1.f, k,
                              make_view(l.data(), 32, 32)),
                  edgeplane::error);  // negative depth scale
  params bad = presets::thesis_full();
  bad.t_je = -1.f;
  CHECK_THROWS_AS(segmenter<cpu>{bad}, edgeplane::error);
  try {
    seg.segment(zv, k, make_view(l.data(), 16, 32));
  } catch (const edgeplane::error& e) {
    CHECK(std::string(e.what()).find("16x32") != std::string::npos);  // the message carries the values
  }
}
