// Tests of include/edgeplane/filters/depth.hpp: conversion to metres, the hole-filling closing,
// the 2x downscale and the edge-preserving smoothing.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

#include "edgeplane/filters/depth.hpp"
#include "support/test_backends.hpp"

using namespace edgeplane;
using namespace edgeplane_test;

namespace {
constexpr float nan_f = std::numeric_limits<float>::quiet_NaN();
constexpr float inf_f = std::numeric_limits<float>::infinity();

/// A slanted plane (valid everywhere) with the given pixels set to 0.
std::vector<float> plane_with_holes(int w, int h, const std::vector<std::pair<int, int>>& holes) {
  auto z = plane_image(camera(w, h), w, h, normalized({0.2, -0.1, -1.0}), 2.0);
  for (auto [x, y] : holes) z[static_cast<std::size_t>(y) * w + x] = 0.f;
  return z;
}

template <class B>
std::vector<float> closed(const B& b, const std::vector<float>& in, int w, int h, int r) {
  device_array<float, B> z(b, in), scratch(b, in.size(), -1.f), out(b, in.size(), -1.f);
  close_depth(b, z.view(w, h), scratch.view(w, h), out.view(w, h), r);
  return out.host();
}

std::vector<std::pair<int, int>> block(int x0, int y0, int bw, int bh) {
  std::vector<std::pair<int, int>> v;
  for (int y = y0; y < y0 + bh; ++y)
    for (int x = x0; x < x0 + bw; ++x) v.push_back({x, y});
  return v;
}
}  // namespace

TEST_CASE_TEMPLATE("convert_depth: uint16 units times scale, out-of-range units become 0", B, EDGEPLANE_TEST_BACKENDS) {
  for (const B& b : variants<B>()) {
    CAPTURE(variant_name(b));
    // 4 x 2 input with a row pitch of 6 elements (the padding must never be read as pixels).
    const std::vector<std::uint16_t> raw = {0, 1000, 65535, 40, 7, 7,  //
                                            50, 500, 20000, 20001, 7, 7};
    device_array<std::uint16_t, B> in(b, raw);
    device_array<float, B> out(b, 8, -1.f);
    convert_depth(b, image_view<const std::uint16_t>{in.data(), 4, 2, 6}, 0.001f, 0.05f, 20.f, out.view(4, 2));
    const auto z = out.host();
    const std::vector<float> want = {0.f, 1.0f, 0.f, 0.f,  // 0 invalid, 65.535 m too far, 0.04 m too near
                                     0.05f, 0.5f, 20.f, 0.f};  // bounds inclusive; 20.001 m too far
    for (int i = 0; i < 8; ++i) {
      CAPTURE(i);
      CHECK(z[i] == doctest::Approx(want[i]).epsilon(1e-6));
    }
  }
}

TEST_CASE_TEMPLATE("convert_depth: float 0, NaN, infinities, negatives and too far become 0", B,
                   EDGEPLANE_TEST_BACKENDS) {
  for (const B& b : variants<B>()) {
    CAPTURE(variant_name(b));
    const std::vector<float> raw = {0.f, nan_f, inf_f, -inf_f, -1.f, 25.f, 0.01f, 2.5f};
    device_array<float, B> in(b, raw), out(b, raw.size(), -1.f);
    convert_depth(b, in.cview(4, 2), 1.f, 0.05f, 20.f, out.view(4, 2));
    const std::vector<float> want = {0, 0, 0, 0, 0, 0, 0, 2.5f};
    CHECK(out.host() == want);
  }
}

TEST_CASE_TEMPLATE("convert_depth: a non-positive or non-finite scale is an error", B, EDGEPLANE_TEST_BACKENDS) {
  const B b{};
  device_array<std::uint16_t, B> in(b, 4, 1000);
  device_array<float, B> out(b, 4, 0.f);
  CHECK_THROWS_AS(convert_depth(b, in.cview(2, 2), 0.f, 0.05f, 20.f, out.view(2, 2)), edgeplane::error);
  CHECK_THROWS_AS(convert_depth(b, in.cview(2, 2), nan_f, 0.05f, 20.f, out.view(2, 2)), edgeplane::error);
  CHECK_THROWS_AS(convert_depth(b, in.cview(2, 2), 0.001f, 0.05f, 20.f, out.view(1, 2)), edgeplane::error);
}

TEST_CASE_TEMPLATE("close_depth (r = 1) fills 1x1, 2x2 and 1xN holes, not 3x3 or 5x5 ones, never moves valid depth", B,
                   EDGEPLANE_TEST_BACKENDS) {
  const int w = 40, h = 30;
  const auto truth = plane_image(camera(w, h), w, h, normalized({0.2, -0.1, -1.0}), 2.0);
  struct hole_case {
    const char* name;
    std::vector<std::pair<int, int>> pixels;
    bool filled;
  };
  std::vector<std::pair<int, int>> line;
  for (int x = 10; x < 25; ++x) line.push_back({x, 15});  // a 1-pixel-wide crack, 15 pixels long
  const std::vector<hole_case> cases = {{"1x1", block(7, 9, 1, 1), true},
                                        {"2x2", block(20, 8, 2, 2), true},
                                        {"1x15 crack", line, true},
                                        {"3x3", block(5, 20, 3, 3), false},
                                        {"5x5", block(30, 20, 5, 5), false}};
  for (const B& b : variants<B>()) {
    CAPTURE(variant_name(b));
    for (const auto& c : cases) {
      CAPTURE(c.name);
      const auto in = plane_with_holes(w, h, c.pixels);
      const auto out = closed(b, in, w, h, 1);
      for (std::size_t i = 0; i < in.size(); ++i)
        if (in[i] > 0.f) REQUIRE(out[i] == in[i]);  // valid pixels are never changed, bit for bit
      for (auto [x, y] : c.pixels) {
        CAPTURE(x);
        CAPTURE(y);
        const float z = out[static_cast<std::size_t>(y) * w + x];
        if (c.filled) {  // a filled hole takes a depth of its 3x3 surroundings on the plane
          CHECK(z > 0.f);
          CHECK(std::abs(z - truth[static_cast<std::size_t>(y) * w + x]) < 0.01f);
        } else {
          CHECK(z == 0.f);
        }
      }
    }
  }
}

TEST_CASE_TEMPLATE("close_depth: a larger window fills a wider hole; r = 0 changes nothing; in place works", B,
                   EDGEPLANE_TEST_BACKENDS) {
  const int w = 40, h = 30;
  const B b{};
  const auto in = plane_with_holes(w, h, block(10, 10, 3, 3));
  const auto r2 = closed(b, in, w, h, 2);
  for (auto [x, y] : block(10, 10, 3, 3)) CHECK(r2[static_cast<std::size_t>(y) * w + x] > 0.f);
  CHECK(closed(b, in, w, h, 0) == in);
  // The doc says `depth` is filtered in place: passing it as the output must give the same result.
  device_array<float, B> z(b, in), scratch(b, in.size(), 0.f);
  close_depth(b, z.view(w, h), scratch.view(w, h), z.view(w, h), 2);
  CHECK(z.host() == r2);
}

TEST_CASE_TEMPLATE("downscale_depth: a block straddling a depth edge takes the near surface", B,
                   EDGEPLANE_TEST_BACKENDS) {
  // Five 2x2 blocks side by side, plus an odd last column and row that are dropped.
  const int w = 11, h = 3;
  std::vector<float> in(static_cast<std::size_t>(w) * h, 9.f);
  auto set_block = [&](int bx, float a, float c, float d, float e) {
    in[2 * bx] = a;
    in[2 * bx + 1] = c;
    in[w + 2 * bx] = d;
    in[w + 2 * bx + 1] = e;
  };
  set_block(0, 1.0f, 3.0f, 1.0f, 3.0f);    // depth edge: near surface 1.0 (the mean would be 2.0)
  set_block(1, 2.0f, 2.02f, 2.01f, 2.03f); // one surface: the mean of all four
  set_block(2, 0.f, 1.5f, 0.f, 0.f);       // one valid pixel
  set_block(3, 0.f, 0.f, 0.f, 0.f);        // nothing valid
  set_block(4, 4.0f, 1.0f, 1.01f, 0.f);    // edge and a hole: the mean of the near pair
  for (const B& b : variants<B>()) {
    CAPTURE(variant_name(b));
    device_array<float, B> zin(b, in), zout(b, 5, -1.f);
    downscale_depth(b, zin.cview(w, h), zout.view(5, 1));
    const auto z = zout.host();
    CHECK(z[0] == doctest::Approx(1.0f));
    CHECK(z[1] == doctest::Approx(2.015f));
    CHECK(z[2] == doctest::Approx(1.5f));
    CHECK(z[3] == 0.f);
    CHECK(z[4] == doctest::Approx(1.005f));
    CHECK_THROWS_AS(downscale_depth(b, zin.cview(w, h), zout.view(4, 1)), edgeplane::error);
  }
}

// Host backends downscale by rows, without branches; the per-pixel kernel is the reference.
TEST_CASE("downscale_depth: the host row kernel gives the per-pixel kernel's depths, bit for bit") {
  lcg_noise noise(21);
  for (const auto& size : {std::pair{37, 23}, std::pair{64, 40}, std::pair{3, 2}}) {
    const int w = size.first, h = size.second, pitch = w + 5;
    CAPTURE(w);
    std::vector<float> in(static_cast<std::size_t>(pitch) * h, 7.f);
    for (int by = 0; 2 * by < h; ++by)
      for (int bx = 0; 2 * bx < w; ++bx) {
        // per 2x2 block a base depth; the block's depths are the base, exactly the 2 % limit
        // base * 1.02f, just above it, 1-1.1 m at random (averaging several depths), invalid
        // ones (0, negative, NaN), a far surface or infinity
        const float base = 1.f + 0.0005f * static_cast<float>(noise.next_u32(200));
        const bool hole = noise.next_u32(8) == 0;  // a block without valid depth
        for (int j = 0; j < 4; ++j) {
          const int x = 2 * bx + j % 2, y = 2 * by + j / 2;
          if (x >= w || y >= h) continue;
          float z = 1.f + 0.0005f * static_cast<float>(noise.next_u32(200));
          switch (noise.next_u32(20)) {
            case 0: z = 0.f; break;
            case 1: z = std::numeric_limits<float>::quiet_NaN(); break;
            case 2: z = -1.f; break;
            case 3: z = 3.f; break;
            case 4: z = std::numeric_limits<float>::infinity(); break;
            case 5: case 6: case 7: z = base; break;
            case 8: case 9: case 10: z = base * 1.02f; break;
            case 11: z = std::nextafter(base * 1.02f, 2.f); break;
            default: break;
          }
          if (hole) z = j == 1 ? std::numeric_limits<float>::quiet_NaN() : 0.f;
          in[static_cast<std::size_t>(y) * pitch + x] = z;
        }
      }
    const image_view<const float> iv{in.data(), w, h, pitch};
    const int ow = w / 2, oh = h / 2;
    std::vector<float> rows(static_cast<std::size_t>(ow) * oh, -5.f), pixels(rows.size(), -6.f);
    downscale_depth(cpu{}, iv, make_view(rows.data(), ow, oh));
    for (int y = 0; y < oh; ++y)
      for (int x = 0; x < ow; ++x) detail::downscale_kernel{iv, make_view(pixels.data(), ow, oh)}(x, y);
    CHECK(std::memcmp(rows.data(), pixels.data(), rows.size() * sizeof(float)) == 0);
    int empty = 0, mixed = 0;
    for (const float z : pixels) {
      empty += z == 0.f;
      mixed += z > 1.f && z < 1.2f;
    }
    if (ow * oh > 100) {
      CHECK(empty > 0);  // blocks without a valid depth...
      CHECK(mixed > 0);  // ...and blocks averaged
    }
  }
}

TEST_CASE_TEMPLATE("smooth_depth: reduces noise on a plane and keeps a depth step sharp", B, EDGEPLANE_TEST_BACKENDS) {
  const int w = 48, h = 36, step_x = 24, r = 2;
  const float k = 2.5f, s0 = 0.0015f, s2 = 0.0015f;  // the default noise model: sigma(2 m) = 7.5 mm
  const auto cam = camera(w, h);
  const vec3 n = normalized({0.15, -0.1, -1.0});
  // Left: the plane at d = 2 m; right: the same plane 0.3 m farther (a step); 3 mm uniform noise.
  std::vector<float> truth(static_cast<std::size_t>(w) * h), noisy(truth.size());
  lcg_noise noise(7);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      truth[i] = plane_depth(cam, x, y, n, x < step_x ? 2.0 : 2.3);
      noisy[i] = truth[i] + noise(0.003f);
    }
  noisy[5 * w + 5] = 0.f;  // an invalid pixel stays invalid
  for (const B& b : variants<B>()) {
    CAPTURE(variant_name(b));
    device_array<float, B> zin(b, noisy), zout(b, noisy.size(), -1.f);
    smooth_depth(b, zin.cview(w, h), zout.view(w, h), r, k, s0, s2);
    const auto out = zout.host();
    CHECK(out[5 * w + 5] == 0.f);
    double var_in = 0, var_out = 0;
    int n_in = 0;
    for (int y = r; y < h - r; ++y)
      for (int x = r; x < w - r; ++x) {
        const std::size_t i = static_cast<std::size_t>(y) * w + x;
        if (noisy[i] == 0.f) continue;
        // Every output stays on its own side of the step (no depth between the two surfaces).
        CHECK(std::abs(out[i] - truth[i]) < 0.01f);
        if (std::abs(x - step_x) > r && std::abs(x - 5) + std::abs(y - 5) > 2 * r) {  // away from step/hole
          var_in += (noisy[i] - truth[i]) * (noisy[i] - truth[i]);
          var_out += (out[i] - truth[i]) * (out[i] - truth[i]);
          ++n_in;
        }
      }
    // 3 mm uniform noise: variance 3 mm^2; a 5x5 mean divides it by about 25.  Demand 8x.
    CHECK(n_in > 500);
    CHECK(var_out * 8 < var_in);
    // The step stays a step: the two columns beside it still differ by the full 0.3 m (minus noise).
    for (int y = 0; y < h; ++y)
      CHECK(out[static_cast<std::size_t>(y) * w + step_x] - out[static_cast<std::size_t>(y) * w + step_x - 1] > 0.28f);
  }
}

// The host backends smooth runs of 16 pixels at once (detail::smooth_kernel::lanes, through
// detail::window_runs, and border_lanes on a zero-padded copy where the windows leave the image);
// the device backend runs detail::smooth_kernel per pixel.  Both must give the same floats, bit for bit, at
// borders, around invalid pixels and for widths that are not multiples of 16.
TEST_CASE("smooth_depth: the 16-pixel row kernel equals the per-pixel kernel bit for bit") {
  lcg_noise noise(11);
  for (const int w : {1, 5, 16, 17, 40, 67})
    for (const int h : {1, 3, 9})
      for (const int r : {1, 2, 3, 8, 9}) {  // 8: the largest border tile; 9: border runs per pixel
        CAPTURE(w);
        CAPTURE(h);
        CAPTURE(r);
        std::vector<float> in(static_cast<std::size_t>(w) * h);
        for (std::size_t i = 0; i < in.size(); ++i) {
          const float u = noise(1.f);  // uniform in [-1, 1]
          in[i] = u > 0.8f ? 0.f : 1.5f + 0.002f * static_cast<float>(i % 7) + 0.01f * u;  // holes, steps, noise
        }
        std::vector<float> a(in.size(), -1.f), c(in.size(), -2.f);
        const detail::smooth_kernel px{make_view<const float>(in.data(), w, h), make_view(a.data(), w, h), r, 2.5f,
                                       0.0015f, 0.0015f};
        for (int y = 0; y < h; ++y)
          for (int x = 0; x < w; ++x) px(x, y);
        smooth_depth(cpu{}, make_view<const float>(in.data(), w, h), make_view(c.data(), w, h), r, 2.5f, 0.0015f,
                     0.0015f);
        int differ = 0;
        for (std::size_t i = 0; i < in.size(); ++i) differ += std::memcmp(&a[i], &c[i], sizeof(float)) != 0;
        CHECK(differ == 0);
      }
}

// The row kernel leaves out a tap's own z > 0 test in runs where every valid centre's tolerance
// is below its depth (|z - zc| <= tol then rejects z <= 0 by itself).  Here the tolerance
// k (s0 + s2 zc^2) is about 0.03 m and the depths lie between 0.005 and 0.06 m, so runs mix
// lanes whose tolerance is below their depth with lanes whose tolerance reaches past it (a
// zero, negative or -0 tap is within that tolerance and must still be skipped); every third row
// lies beyond it (runs that leave the test out).  The taps include negative depths, -0, NaN and
// infinities (an infinite centre's tolerance is NaN: no tap is taken, and both kernels give 0).
// Bit for bit as the per-pixel kernel.
TEST_CASE("smooth_depth: the row kernel equals the per-pixel kernel where tolerances reach past the depth") {
  lcg_noise noise(12);
  int wide_runs = 0, narrow_runs_with_odd_taps = 0;
  for (const int w : {16, 33, 67})
    for (const int r : {1, 2, 3}) {
      const int h = 11;
      CAPTURE(w);
      CAPTURE(r);
      std::vector<float> in(static_cast<std::size_t>(w) * h);
      for (std::size_t i = 0; i < in.size(); ++i) {
        const float u = noise(1.f);
        const int kind = static_cast<int>(i * 7919 % 23);
        in[i] = kind == 0   ? 0.f
                : kind == 1 ? -0.f
                : kind == 2 ? -0.01f
                : kind == 3 ? std::numeric_limits<float>::quiet_NaN()
                : kind == 4 ? std::numeric_limits<float>::infinity()
                : kind == 5 ? -std::numeric_limits<float>::infinity()
                : i / w % 3 == 0 ? 0.045f + 0.01f * u  // rows of depths beyond the tolerance
                            : 0.0325f + 0.0275f * u;  // 0.005 .. 0.06 m
      }
      const float k = 2.f, s0 = 0.015f, s2 = 0.f;  // tol = 0.03 m
      for (int y = 0; y < h; ++y)  // which runs take which path (so the test covers both)
        for (int x0 = 0; x0 + 16 <= w; x0 += 16) {
          bool wide = false, odd = false;
          for (int l = 0; l < 16; ++l) {
            const float z = in[static_cast<std::size_t>(y) * w + x0 + l];
            wide |= z > 0.f && !(k * (s0 + s2 * z * z) < z);
            odd |= !(z > 0.f);
          }
          wide_runs += wide;
          narrow_runs_with_odd_taps += !wide && odd;
        }
      std::vector<float> a(in.size(), -1.f), c(in.size(), -2.f);
      const detail::smooth_kernel px{make_view<const float>(in.data(), w, h), make_view(a.data(), w, h), r, k, s0, s2};
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) px(x, y);
      smooth_depth(cpu{}, make_view<const float>(in.data(), w, h), make_view(c.data(), w, h), r, k, s0, s2);
      int differ = 0;
      for (std::size_t i = 0; i < in.size(); ++i) differ += std::memcmp(&a[i], &c[i], sizeof(float)) != 0;
      CHECK(differ == 0);
    }
  CHECK(wide_runs > 10);
  CHECK(narrow_runs_with_odd_taps > 0);
}

TEST_CASE("close_depth: the host row kernels give the per-pixel kernels' depths, bit for bit, in place too") {
  // Random holes (single pixels, short runs, blocks, whole 32-pixel blocks and stretches longer
  // than a 256-pixel chunk, each row edge) over a noisy plane; widths around the 32-pixel block
  // and the chunk; radii 1 to 3; a separate output and in place.
  lcg_noise noise(21);
  int filled = 0, holes_left = 0;
  for (const int w : {5, 31, 33, 64, 257, 300, 611})
    for (const int r : {1, 2, 3}) {
      const int h = 23;
      CAPTURE(w);
      CAPTURE(r);
      std::vector<float> z(static_cast<std::size_t>(w) * h);
      for (std::size_t i = 0; i < z.size(); ++i) z[i] = 1.5f + 0.001f * static_cast<float>(i % 97) + noise(0.01f);
      for (int k = 0; k < w * h / 20; ++k) {  // holes of 1 to 40 pixels along a row, some two rows high
        const std::uint32_t at = noise.next_u32(static_cast<std::uint32_t>(z.size()));
        const int len = 1 + static_cast<int>(noise.next_u32(k % 5 == 0 ? 40u : 3u));
        for (int j = 0; j < len && at + j < z.size(); ++j) {
          z[at + j] = 0.f;
          if (k % 7 == 0 && at + j + w < z.size()) z[at + j + w] = 0.f;
        }
      }
      for (int x = 0; x < w && 7 * w < static_cast<int>(z.size()); ++x) z[static_cast<std::size_t>(6 * w + x)] = 0.f;  // a whole row
      const image_view<const float> in{z.data(), w, h, w};
      std::vector<float> dil(z.size(), -5.f), want(z.size(), -7.f);
      const cpu serial{cpu::mode::serial};
      detail::for_each_pixel(serial, w, h, detail::depth_dilate_kernel{in, make_view(dil.data(), w, h), r});
      detail::for_each_pixel(serial, w, h,
                             detail::depth_erode_kernel{in, make_view<const float>(dil.data(), w, h),
                                                        make_view(want.data(), w, h), r});
      std::vector<float> z1(z), scratch(z.size(), -3.f), out(z.size(), -9.f);
      close_depth(cpu{}, make_view(z1.data(), w, h), make_view(scratch.data(), w, h), make_view(out.data(), w, h), r);
      CHECK(scratch == dil);
      CHECK(out == want);
      CHECK(z1 == z);  // the input is left alone
      std::vector<float> z2(z);
      close_depth(cpu{}, make_view(z2.data(), w, h), make_view(scratch.data(), w, h), make_view(z2.data(), w, h), r);
      CHECK(z2 == want);
      for (std::size_t i = 0; i < z.size(); ++i) {
        filled += z[i] == 0.f && want[i] > 0.f;
        holes_left += z[i] == 0.f && want[i] == 0.f;
      }
    }
  CHECK(filled > 1000);     // holes the closing fills...
  CHECK(holes_left > 1000);  // ...and ones it leaves
}
