// Tests of include/edgeplane/labels/label_ops.hpp: relabelling, plane-guided growth, the label
// closing and nearest-neighbour upsampling.
#include <doctest/doctest.h>

#include <algorithm>
#include <cstdint>
#include <vector>

#include "edgeplane/labels/label_ops.hpp"
#include "edgeplane/params.hpp"
#include "support/test_backends.hpp"

using namespace edgeplane;
using namespace edgeplane_test;

namespace {

/// Source of candidate ids for relabel_kernel: a plain array.
struct array_source {
  const std::uint16_t* ids;
  int w;
  std::int32_t operator()(int x, int y) const { return ids[static_cast<std::size_t>(y) * w + x]; }
};

std::size_t at(int w, int x, int y) { return static_cast<std::size_t>(y) * w + x; }

/// One growth step over labels `in` (host vectors in, host vector out).  `caps` holds each plane's
/// own tolerance (metres, index 0 unused); empty = no cap.  `changed` receives the kernel's flag.
template <class B>
std::vector<std::uint16_t> grow_once(const B& b, const std::vector<float>& depth, const std::vector<std::uint16_t>& in,
                                     int w, int h, const std::vector<float>& planes, std::vector<float> caps = {},
                                     std::int32_t* changed = nullptr) {
  const params p = presets::thesis_full();  // grow_k = 3: tolerance 3 sigma(2 m) = 22.5 mm
  if (caps.empty()) caps.assign(planes.size() / 4, 1e9f);
  device_array<float, B> z(b, depth), pl(b, planes), cp(b, caps);
  device_array<std::uint16_t, B> li(b, in), lo(b, in.size(), 0xBEEF);
  device_array<std::int32_t, B> flag(b, 1, 0);
  detail::for_each_pixel(b, w, h,
                   detail::grow_kernel{z.cview(w, h), li.cview(w, h), lo.view(w, h), detail::make_projector(camera(w, h)),
                                       detail::make_noise(p.noise), p.grow_k, pl.data(), cp.data(), flag.data()});
  if (changed) *changed = flag.host()[0];
  return lo.host();
}

template <class B>
std::vector<std::uint16_t> closed(const B& b, const std::vector<std::uint16_t>& in, int w, int h, int r) {
  device_array<std::uint16_t, B> li(b, in), dil(b, in.size(), 0), out(b, in.size(), 0xBEEF);
  close_labels(b, li.cview(w, h), dil.view(w, h), out.view(w, h), r);
  return out.host();
}

}  // namespace

TEST_CASE_TEMPLATE("relabel_kernel maps every pixel through the table", B, EDGEPLANE_TEST_BACKENDS) {
  const int w = 9, h = 8;
  std::vector<std::uint16_t> ids(static_cast<std::size_t>(w) * h);
  for (std::size_t i = 0; i < ids.size(); ++i) ids[i] = static_cast<std::uint16_t>(i % 4);
  const std::vector<std::uint16_t> table = {0, 5, 5, 2};  // candidates 1 and 2 merged, 3 renamed
  for (const B& b : variants<B>()) {
    device_array<std::uint16_t, B> src(b, ids), tab(b, table), out(b, ids.size(), 0xBEEF);
    detail::for_each_pixel(b, w, h,
                           detail::relabel_kernel<array_source>{array_source{src.data(), w}, tab.data(), out.view(w, h)});
    const auto o = out.host();
    for (std::size_t i = 0; i < o.size(); ++i) REQUIRE(o[i] == table[ids[i]]);
  }
}

TEST_CASE_TEMPLATE("grow_kernel: a pixel on the plane joins, one off it does not, growth is one pixel a step", B,
                   EDGEPLANE_TEST_BACKENDS) {
  const int w = 12, h = 8;
  std::vector<float> depth(static_cast<std::size_t>(w) * h, 2.0f);  // the plane z = 2: n = (0, 0, -1), d = 2
  depth[at(w, 6, 2)] = 2.05f;    // 5 cm off the plane (tolerance 22.5 mm)
  depth[at(w, 6, 3)] = 2.015f;   // 15 mm off: within tolerance
  depth[at(w, 6, 5)] = 0.f;      // invalid depth never grows
  std::vector<std::uint16_t> labels(depth.size(), 0);
  for (int y = 0; y < 6; ++y)
    for (int x = 0; x < 6; ++x) labels[at(w, x, y)] = 1;
  const std::vector<float> planes = {0, 0, 0, 0, 0, 0, -1, 2};
  for (const B& b : variants<B>()) {
    CAPTURE(variant_name(b));
    std::int32_t changed = -1;
    const auto out = grow_once(b, depth, labels, w, h, planes, {}, &changed);
    CHECK(changed == 1);
    // A second step from the grown labels grows further; a step that assigns nothing leaves the flag 0.
    const auto out2 = grow_once(b, depth, out, w, h, planes, {}, &changed);
    CHECK(changed == 1);
    CHECK(out2[at(w, 7, 0)] == 1);
    std::vector<std::uint16_t> none(labels.size(), 0);
    CHECK(grow_once(b, depth, none, w, h, planes, {}, &changed) == none);
    CHECK(changed == 0);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        CAPTURE(x);
        CAPTURE(y);
        std::uint16_t want = labels[at(w, x, y)];
        if (x == 6 && y < 6 && y != 2 && y != 5) want = 1;  // the column beside the region, on the plane
        if (x < 6 && y == 6) want = 1;                      // the row below it
        CHECK(out[at(w, x, y)] == want);                    // (6, 6) touches the region only diagonally
      }
  }
}

// Host backends grow by the front (detail::grow_front_kernel): after the first round, only the
// unlabelled neighbours of the pixels the previous round labelled are evaluated, and the output
// buffer (two rounds old) is brought up to date by the row lists.  The result after every round
// must be the per-pixel rounds'.  Three planes grow from seeds until their fronts meet (which
// one takes a pixel depends on the nearest plane and, on ties, the lowest label); noisy depth
// leaves pixels out of every plane's tolerance, and invalid depth and a wall split the image.
TEST_CASE("grow_front_kernel: rounds over the growth front equal full rounds") {
  const int w = 41, h = 90;
  std::vector<float> depth(static_cast<std::size_t>(w) * h, 2.0f);  // the plane z = 2...
  std::uint32_t seed = 12345;
  for (auto& d : depth) {  // ...with noise up to +-30 mm (the tolerance at 2 m is 22.5 mm)
    seed = seed * 1664525u + 1013904223u;
    d += 0.06f * (static_cast<float>(seed >> 8) / 16777216.f - 0.5f);
  }
  for (int x = 0; x < w; ++x) depth[at(w, x, 45)] = 0.f;  // an invalid row: growth stops there...
  depth[at(w, 20, 45)] = 2.0f;                            // ...but for one gap
  for (int y = 60; y < 90; ++y) depth[at(w, 5, y)] = 2.1f;  // a ridge off the plane
  for (int y = 0; y < 30; ++y) depth[at(w, 0, y)] = 0.f;    // invalid at the left border
  std::vector<std::uint16_t> start(depth.size(), 0);
  for (int x = 0; x < 4; ++x) start[at(w, x, 2)] = 1;  // seeds far apart, and two close together
  start[at(w, 30, 80)] = 2;
  start[at(w, 40, 10)] = 3;
  start[at(w, 34, 10)] = 2;
  start[at(w, 20, 89)] = 3;
  // planes 1 and 2: z = 2; plane 3: z = 2.01 (farther from most points, so it loses most ties)
  const std::vector<float> planes = {0, 0, 0, 0, 0, 0, -1, 2, 0, 0, -1, 2, 0, 0, -1, 2.01f};
  const std::vector<float> caps(4, 1e9f);
  const params p = presets::thesis_full();
  std::vector<std::uint16_t> a = start, b1 = start, b2(start.size(), 0xBEEF);  // b1, b2: the two buffers
  const std::size_t hp = static_cast<std::size_t>(h) + 2, n = start.size();
  std::vector<std::int32_t> counts(2 * hp, 0), lists(2 * n, -1);
  std::int32_t flag = 0;
  const cpu b{};
  int rounds_changed = 0, front_sum = 0;
  for (int it = 0; it < 60; ++it) {
    CAPTURE(it);
    std::vector<std::uint16_t> next(a.size());
    const detail::grow_kernel full{make_view<const float>(depth.data(), w, h), make_view<const std::uint16_t>(a.data(), w, h),
                                   make_view(next.data(), w, h), detail::make_projector(camera(w, h)),
                                   detail::make_noise(p.noise), p.grow_k, planes.data(), caps.data(), &flag};
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) full(x, y);
    int changed = 0;
    for (std::size_t i = 0; i < n; ++i) changed += next[i] != a[i];
    rounds_changed += changed > 0;
    a = next;
    std::vector<std::uint16_t>& in = it % 2 == 0 ? b1 : b2;
    std::vector<std::uint16_t>& out = it % 2 == 0 ? b2 : b1;
    const detail::grow_kernel g{make_view<const float>(depth.data(), w, h), make_view<const std::uint16_t>(in.data(), w, h),
                                make_view(out.data(), w, h), detail::make_projector(camera(w, h)),
                                detail::make_noise(p.noise), p.grow_k, planes.data(), caps.data(), &flag};
    const int q = it % 2, r = 1 - q;
    b.for_each_index(h, detail::grow_front_kernel{g, counts.data() + q * hp, lists.data() + q * n, counts.data() + r * hp,
                                                  lists.data() + r * n, it == 0});
    REQUIRE(out == a);
    int listed = 0;  // the lists hold exactly the pixels this round labelled
    for (int y = 0; y < h; ++y) listed += counts[r * hp + static_cast<std::size_t>(y) + 1];
    CHECK(listed == changed);
    front_sum += listed;
  }
  CHECK(rounds_changed > 30);     // growth went on for many rounds
  CHECK(a[at(w, 40, 89)] != 0);   // reached the far corner...
  CHECK(a[at(w, 20, 45)] != 0);  // ...and the one gap in the invalid row
  for (int y = 60; y < 90; ++y) CHECK(a[at(w, 5, y)] == 0);  // but not the ridge
  CHECK(std::count(a.begin(), a.end(), 3) > 0);  // every plane took pixels
  CHECK(std::count(a.begin(), a.end(), 0) > 50);  // and noise left pixels out
  CHECK(front_sum < static_cast<int>(n));         // a front, not the image, each round
}

TEST_CASE_TEMPLATE("grow_kernel: a pixel between two regions takes the nearer plane", B, EDGEPLANE_TEST_BACKENDS) {
  const int w = 9, h = 3;
  // Left region (label 1): the plane z = 2.000; right region (label 2): the plane z = 2.010.  The
  // middle column is unlabelled with depths 2.002 (nearer 1), 2.008 (nearer 2), 2.009 (nearer 2).
  std::vector<float> depth(static_cast<std::size_t>(w) * h);
  std::vector<std::uint16_t> labels(depth.size(), 0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      depth[at(w, x, y)] = x < 4 ? 2.0f : 2.01f;
      labels[at(w, x, y)] = x < 4 ? 1 : x > 4 ? 2 : 0;
    }
  depth[at(w, 4, 0)] = 2.002f;
  depth[at(w, 4, 1)] = 2.008f;
  depth[at(w, 4, 2)] = 2.009f;
  const std::vector<float> planes = {0, 0, 0, 0, 0, 0, -1, 2.0f, 0, 0, -1, 2.01f};
  for (const B& b : variants<B>()) {
    const auto out = grow_once(b, depth, labels, w, h, planes);
    CHECK(out[at(w, 4, 0)] == 1);
    CHECK(out[at(w, 4, 1)] == 2);
    CHECK(out[at(w, 4, 2)] == 2);
    // Swapping which side holds which label must not change the choice of plane.
    std::vector<std::uint16_t> swapped = labels;
    for (auto& l : swapped) l = l == 0 ? 0 : static_cast<std::uint16_t>(3 - l);
    const std::vector<float> planes_sw = {0, 0, 0, 0, 0, 0, -1, 2.01f, 0, 0, -1, 2.0f};
    const auto out2 = grow_once(b, depth, swapped, w, h, planes_sw);
    CHECK(out2[at(w, 4, 0)] == 2);
    CHECK(out2[at(w, 4, 1)] == 1);
  }
}

TEST_CASE_TEMPLATE("grow_kernel: a plane's own cap limits its growth below the noise tolerance", B,
                   EDGEPLANE_TEST_BACKENDS) {
  const int w = 9, h = 1;
  // Label 1 left (plane z = 2.000), label 2 right (plane z = 2.010); the middle pixel at 2.008 is
  // 2 mm from plane 2 and 8 mm from plane 1, both within the 22.5 mm noise tolerance.
  std::vector<float> depth = {2.f, 2.f, 2.f, 2.f, 2.008f, 2.01f, 2.01f, 2.01f, 2.01f};
  const std::vector<std::uint16_t> labels = {1, 1, 1, 1, 0, 2, 2, 2, 2};
  const std::vector<float> planes = {0, 0, 0, 0, 0, 0, -1, 2.0f, 0, 0, -1, 2.01f};
  for (const B& b : variants<B>()) {
    CHECK(grow_once(b, depth, labels, w, h, planes, {0.f, 0.05f, 0.05f})[4] == 2);
    CHECK(grow_once(b, depth, labels, w, h, planes, {0.f, 0.05f, 0.001f})[4] == 1);  // 2 mm > plane 2's cap
    CHECK(grow_once(b, depth, labels, w, h, planes, {0.f, 0.005f, 0.001f})[4] == 0);  // beyond both caps
  }
}

TEST_CASE_TEMPLATE("label closing (r = 1) fills 1-pixel and 2x2 holes, not a 5x5 one, and does not grow regions", B,
                   EDGEPLANE_TEST_BACKENDS) {
  const int w = 30, h = 24;
  std::vector<std::uint16_t> in(static_cast<std::size_t>(w) * h, 0);
  for (int y = 2; y < 20; ++y)
    for (int x = 2; x < 26; ++x) in[at(w, x, y)] = 3;
  std::vector<std::pair<int, int>> filled = {{5, 5}, {10, 5}, {11, 5}, {10, 6}, {11, 6}};  // 1x1 and 2x2 holes
  std::vector<std::pair<int, int>> kept;
  for (int y = 10; y < 15; ++y)
    for (int x = 15; x < 20; ++x) kept.push_back({x, y});  // 5x5 hole
  for (auto [x, y] : filled) in[at(w, x, y)] = 0;
  for (auto [x, y] : kept) in[at(w, x, y)] = 0;
  for (const B& b : variants<B>()) {
    CAPTURE(variant_name(b));
    const auto out = closed(b, in, w, h, 1);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        CAPTURE(x);
        CAPTURE(y);
        const bool inside = x >= 2 && x < 26 && y >= 2 && y < 20;
        const bool big_hole = x >= 15 && x < 20 && y >= 10 && y < 15;
        CHECK(out[at(w, x, y)] == (inside && !big_hole ? 3 : 0));
      }
  }
}

TEST_CASE_TEMPLATE("label closing: a hole on the border of two labels takes the smaller label", B,
                   EDGEPLANE_TEST_BACKENDS) {
  const int w = 10, h = 6;
  std::vector<std::uint16_t> in(static_cast<std::size_t>(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) in[at(w, x, y)] = x < 5 ? 7 : 4;
  in[at(w, 5, 3)] = 0;
  in[at(w, 4, 1)] = 0;
  const B b{};
  const auto out = closed(b, in, w, h, 1);
  CHECK(out[at(w, 5, 3)] == 4);
  CHECK(out[at(w, 4, 1)] == 4);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      if (in[at(w, x, y)] != 0) CHECK(out[at(w, x, y)] == in[at(w, x, y)]);  // labelled pixels keep theirs
}

TEST_CASE_TEMPLATE("upsample_kernel: nearest neighbour 2x, odd last row and column repeat", B,
                   EDGEPLANE_TEST_BACKENDS) {
  const int w = 3, h = 2;
  const std::vector<std::uint16_t> in = {1, 2, 3, 4, 5, 6};
  for (const B& b : variants<B>()) {
    // 6 x 4, 7 x 5: exactly and one more than 2x; 5 x 3: less than 2x (the last source column
    // and row unused); 9 x 6: more than one repeated column.  Each by the per-pixel kernel and by
    // upsample_labels (host backends: by rows).
    for (auto [ow, oh] : {std::pair{6, 4}, std::pair{7, 5}, std::pair{5, 3}, std::pair{9, 6}})
      for (const bool rows : {false, true}) {
        CAPTURE(ow);
        CAPTURE(rows);
        device_array<std::uint16_t, B> src(b, in), out(b, static_cast<std::size_t>(ow) * oh, 0xBEEF);
        if (rows)
          upsample_labels(b, src.cview(w, h), out.view(ow, oh));
        else
          detail::for_each_pixel(b, ow, oh, detail::upsample_kernel{src.cview(w, h), out.view(ow, oh)});
        const auto o = out.host();
        int wrong = 0;
        for (int y = 0; y < oh; ++y)
          for (int x = 0; x < ow; ++x)
            wrong += o[at(ow, x, y)] != in[at(w, std::min(x / 2, w - 1), std::min(y / 2, h - 1))];
        CHECK(wrong == 0);
      }
    // Spot checks written out: the 2x2 block of source pixel (1, 0) and the repeated last column.
    device_array<std::uint16_t, B> src(b, in), out(b, 35, 0);
    detail::for_each_pixel(b, 7, 5, detail::upsample_kernel{src.cview(w, h), out.view(7, 5)});
    const auto o = out.host();
    CHECK(o[at(7, 2, 0)] == 2);
    CHECK(o[at(7, 3, 1)] == 2);
    CHECK(o[at(7, 6, 4)] == 6);
    CHECK(o[at(7, 0, 4)] == 4);
  }
}

TEST_CASE_TEMPLATE("grow_sweep_kernel: a round carries a label along whole rows and columns, never through an "
                   "off-plane wall",
                   B, EDGEPLANE_TEST_BACKENDS) {
  const int w = 40, h = 10;
  // The frame as drawn below, and turned by 180 degrees (the seed in the last row's last pixel):
  // then labels travel right to left and bottom to top, which only the backward half of each
  // sweep does.
  for (const bool turned : {false, true}) {
    CAPTURE(turned);
    const auto at_ = [&](int x, int y) { return turned ? at(w, w - 1 - x, h - 1 - y) : at(w, x, y); };
    std::vector<float> depth(static_cast<std::size_t>(w) * h, 2.0f);  // the plane z = 2
    for (int y = 0; y < h - 1; ++y) depth[at_(20, y)] = 2.05f;          // a wall 5 cm off it, open in the last row
    std::vector<std::uint16_t> labels(depth.size(), 0);
    labels[at_(0, 0)] = 1;
    const std::vector<float> planes = {0, 0, 0, 0, 0, 0, -1, 2};
    const std::vector<float> caps = {0.f, 1e9f};
    const params p = presets::thesis_full();  // tolerance 3 sigma(2 m) = 22.5 mm
    for (const B& b : variants<B>()) {
      CAPTURE(variant_name(b));
      device_array<float, B> z(b, depth), pl(b, planes), cp(b, caps);
      device_array<std::uint16_t, B> lab(b, labels);
      device_array<std::int32_t, B> flag(b, 1, 0);
      device_array<std::int32_t, B> dirty(b, static_cast<std::size_t>(h + w), 1);  // every line swept
      std::vector<std::int32_t> changed;
      std::vector<std::vector<std::uint16_t>> after;
      for (int round = 0; round < 3; ++round) {
        b.for_each_index(h, detail::grow_sweep_kernel<0>{z.cview(w, h), lab.view(w, h), detail::make_projector(camera(w, h)),
                                                         detail::make_noise(p.noise), p.grow_k, pl.data(), cp.data(),
                                                         flag.data(), dirty.data()});
        b.for_each_index(w, detail::grow_sweep_kernel<1>{z.cview(w, h), lab.view(w, h), detail::make_projector(camera(w, h)),
                                                         detail::make_noise(p.noise), p.grow_k, pl.data(), cp.data(),
                                                         flag.data(), dirty.data()});
        dirty = device_array<std::int32_t, B>(b, static_cast<std::size_t>(h + w), 1);
        changed.push_back(flag.host()[0]);
        after.push_back(lab.host());
        flag = device_array<std::int32_t, B>(b, 1, 0);
      }
      CHECK(changed == std::vector<std::int32_t>{1, 1, 0});
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
          CAPTURE(x);
          CAPTURE(y);
          CHECK(after[0][at_(x, y)] == (x < 20 ? 1 : 0));            // row 0, then every column left of the wall
          CHECK(after[1][at_(x, y)] == (x == 20 && y < h - 1 ? 0 : 1));  // through the gap, then up every column
        }
    }
  }
}

namespace {
// A maze for the sweeps: the planes z = 2 (label 1) and z = 2.1 (label 2) of maze_planes, with a
// share `holes` of holes (depth 0), 10 % of pixels on z = 2.1 and 5 % off both planes (2.5), and
// `seeds` seeds at random pixels labelled with their pixel's plane.
const std::vector<float> maze_planes = {0, 0, 0, 0, 0, 0, -1, 2.0f, 0, 0, -1, 2.1f};
const std::vector<float> maze_caps = {0.f, 1e9f, 1e9f};
struct maze {
  std::vector<float> depth;
  std::vector<std::uint16_t> labels;
};
maze make_maze(lcg_noise& rng, int w, int h, double holes, int seeds) {
  const std::size_t n = static_cast<std::size_t>(w) * h;
  maze m{std::vector<float>(n), std::vector<std::uint16_t>(n, 0)};
  for (std::size_t i = 0; i < n; ++i) {
    const double u = rng.uniform01();
    m.depth[i] = u < holes ? 0.f : u < holes + 0.1 ? 2.1f : u < holes + 0.15 ? 2.5f : 2.0f;
  }
  for (int s = 0; s < seeds; ++s) {
    const std::size_t i = rng.next_u32(static_cast<std::uint32_t>(n));
    m.labels[i] = m.depth[i] == 2.1f ? 2 : 1;
  }
  return m;
}

// Each line of `labels` swept by the host form's pixel-by-pixel walk (visit(), forward then
// backward) and, in `dev`, by the device form's chunked passes (device_pass<1>, device_pass<-1>).
template <int Axis>
void sweep_both_forms(const maze& m, int w, int h, std::vector<std::uint16_t>& host, std::vector<std::uint16_t>& dev,
                      std::vector<std::int32_t>& host_flags, std::vector<std::int32_t>& dev_flags) {
  const params p = presets::thesis_full();
  std::int32_t changed = 0;
  const auto z = make_view(static_cast<const float*>(m.depth.data()), w, h);
  const auto kernel = [&](std::vector<std::uint16_t>& labels, std::vector<std::int32_t>& flags) {
    return detail::grow_sweep_kernel<Axis>{z, make_view(labels.data(), w, h), detail::make_projector(camera(w, h)),
                                           detail::make_noise(p.noise), p.grow_k, maze_planes.data(),
                                           maze_caps.data(), &changed, flags.data()};
  };
  const auto a = kernel(host, host_flags), d = kernel(dev, dev_flags);
  const int lines = Axis == 0 ? h : w, len = Axis == 0 ? w : h;
  std::int32_t* crossing_a = host_flags.data() + (Axis == 0 ? h : 0);
  std::int32_t* crossing_d = dev_flags.data() + (Axis == 0 ? h : 0);
  for (int line = 0; line < lines; ++line) {
    std::uint16_t prev = 0;
    for (int t = 0; t < len; ++t) a.visit(line, t, prev, crossing_a);
    prev = 0;
    for (int t = len - 1; t >= 0; --t) a.visit(line, t, prev, crossing_a);
    d.template device_pass<1>(line, len, crossing_d);
    d.template device_pass<-1>(line, len, crossing_d);
  }
}
}  // namespace

// The device form of a sweep (two passes of chunks loaded ahead, grow_sweep_kernel::device_pass)
// labels and flags exactly what the host form's pixel-by-pixel walk does, on rows and columns of
// lengths around the chunk size, in mazes with many seeds.
TEST_CASE("grow_sweep_kernel: the device form's chunked passes equal the host form's walk") {
  lcg_noise rng(31);
  long long labelled = 0;
  for (const auto& [w, h] : {std::pair{1, 1}, {7, 3}, {8, 9}, {9, 16}, {17, 23}, {64, 40}, {100, 7}})
    for (int seed = 0; seed < 4; ++seed) {
      CAPTURE(w);
      CAPTURE(h);
      CAPTURE(seed);
      const maze m = make_maze(rng, w, h, 0.15, 1 + w * h / 20);
      for (int axis = 0; axis < 2; ++axis) {
        CAPTURE(axis);
        std::vector<std::uint16_t> host = m.labels, dev = m.labels;
        std::vector<std::int32_t> host_flags(static_cast<std::size_t>(w + h), 0), dev_flags = host_flags;
        if (axis == 0)
          sweep_both_forms<0>(m, w, h, host, dev, host_flags, dev_flags);
        else
          sweep_both_forms<1>(m, w, h, host, dev, host_flags, dev_flags);
        CHECK(dev == host);
        CHECK(dev_flags == host_flags);
        for (std::size_t i = 0; i < host.size(); ++i) labelled += host[i] != m.labels[i];
      }
    }
  CHECK(labelled > 1000);  // the walks did label pixels
}

// The segmenter keeps the sweeps' line flags from round to round, so that a line is swept again
// only after the other axis labelled a pixel on it.  That must label exactly what sweeping every
// line every round labels: after every round, the same labels and the same `changed` flag.  The
// frames are mazes of holes (depth 0) and pixels off both planes, with seeds of two planes, so
// labels reach most pixels only after turning several corners (many rounds).
TEST_CASE_TEMPLATE("grow_sweep_kernel: sweeping only the lines the other axis labelled gives every round's labels",
                   B, EDGEPLANE_TEST_BACKENDS) {
  const params p = presets::thesis_full();  // tolerance 3 sigma(2 m) = 22.5 mm
  const std::vector<float>& planes = maze_planes;
  const std::vector<float>& caps = maze_caps;
  lcg_noise rng(29);
  int deep = 0;  // frames that took more than 3 rounds
  for (const auto& [w, h] : {std::pair{1, 1}, {1, 9}, {9, 1}, {7, 5}, {33, 17}, {64, 48}, {50, 50}})
    for (int seed = 0; seed < 6; ++seed) {
      CAPTURE(w);
      CAPTURE(h);
      CAPTURE(seed);
      const std::size_t n = static_cast<std::size_t>(w) * h;
      const maze m = make_maze(rng, w, h, 0.2 + 0.05 * seed, 1 + static_cast<int>(n / 400));
      const std::vector<float>& depth = m.depth;
      const std::vector<std::uint16_t>& labels = m.labels;
      for (const B& b : variants<B>()) {
        CAPTURE(variant_name(b));
        device_array<float, B> z(b, depth), pl(b, planes), cp(b, caps);
        device_array<std::uint16_t, B> kept(b, labels), every(b, labels);
        device_array<std::int32_t, B> dirty(b, static_cast<std::size_t>(h + w), 0x01010101);
        int rounds = 0;
        for (bool more = true; more && rounds < 200; ++rounds) {
          std::int32_t changed[2];
          for (int variant = 0; variant < 2; ++variant) {
            device_array<std::int32_t, B> flag(b, 1, 0);
            device_array<std::int32_t, B> all(b, static_cast<std::size_t>(h + w), 1);
            std::int32_t* d = variant == 0 ? dirty.data() : all.data();
            auto lab = (variant == 0 ? kept : every).view(w, h);
            b.for_each_index(h, detail::grow_sweep_kernel<0>{z.cview(w, h), lab, detail::make_projector(camera(w, h)),
                                                             detail::make_noise(p.noise), p.grow_k, pl.data(),
                                                             cp.data(), flag.data(), d});
            if (variant == 1) all = device_array<std::int32_t, B>(b, static_cast<std::size_t>(h + w), 1);
            d = variant == 0 ? dirty.data() : all.data();
            b.for_each_index(w, detail::grow_sweep_kernel<1>{z.cview(w, h), lab, detail::make_projector(camera(w, h)),
                                                             detail::make_noise(p.noise), p.grow_k, pl.data(),
                                                             cp.data(), flag.data(), d});
            changed[variant] = flag.host()[0];
          }
          CAPTURE(rounds);
          REQUIRE(kept.host() == every.host());
          REQUIRE(changed[0] == changed[1]);
          more = changed[1] != 0;
        }
        CHECK(rounds < 200);
        deep += rounds > 3;
      }
    }
  CHECK(deep >= 20);  // the frames do exercise the late rounds
}
