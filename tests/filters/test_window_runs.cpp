// The host row kernels of the closings (whole rows: the output row accumulates the window one
// shift at a time) must give exactly what the per-pixel kernels give, which the device backend
// runs.  Random images
// with many zeros (invalid depth, unlabelled pixels, empty mask), sizes that are not multiples of
// 16, and every radius the closings use.
#include <doctest/doctest.h>

#include <cstdint>
#include <cstring>
#include <vector>

#include "edgeplane/edges/detect_edges.hpp"
#include "edgeplane/filters/depth.hpp"
#include "edgeplane/labels/label_ops.hpp"
#include "support/test_backends.hpp"

using namespace edgeplane;
using namespace edgeplane_test;

namespace {

constexpr int w = 83, h = 41;

template <class T>
std::vector<T> random_image(lcg_noise& g, double zero_share, T lo, T hi) {
  std::vector<T> v(static_cast<std::size_t>(w) * h);
  for (T& e : v)
    e = g.uniform01() < zero_share ? T(0) : static_cast<T>(lo + (hi - lo) * g.uniform01());
  return v;
}

// Runs the per-pixel kernel per_pixel(out) pixel by pixel into an image of 7s and the host row
// kernel rows(out) (one work item per row) into `b`; whether the two outputs are equal byte for
// byte.
template <class T, class PerPixel, class Rows>
bool rows_match(int iw, int ih, std::vector<T> b, PerPixel per_pixel, Rows rows) {
  std::vector<T> a(b.size(), T(7));
  const auto k = per_pixel(make_view(a.data(), iw, ih));
  for (int y = 0; y < ih; ++y)
    for (int x = 0; x < iw; ++x) k(x, y);
  cpu{}.for_each_index(ih, rows(make_view(b.data(), iw, ih)));
  return std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

// Both halves of the depth closing, host rows against per-pixel kernels.
bool depth_rows_match(image_view<const float> zv, image_view<const float> dv, int r) {
  using F = image_view<float>;
  const std::vector<float> init(static_cast<std::size_t>(zv.width) * zv.height, 9.f);
  return rows_match<float>(zv.width, zv.height, init, [&](F o) { return detail::depth_dilate_kernel{zv, o, r}; },
                           [&](F o) { return detail::depth_rows_kernel<true>{zv, zv, o, r}; }) &&
         rows_match<float>(zv.width, zv.height, init, [&](F o) { return detail::depth_erode_kernel{zv, dv, o, r}; },
                           [&](F o) { return detail::depth_rows_kernel<false>{zv, dv, o, r}; });
}

}  // namespace

TEST_CASE("closings: the host row kernels equal the per-pixel kernels") {
  lcg_noise g(3);
  for (const double zeros : {0.05, 0.4, 0.9}) {
    CAPTURE(zeros);
    const auto depth = random_image<float>(g, zeros, 0.5f, 4.f);
    const auto dilated = random_image<float>(g, zeros / 3, 0.5f, 4.f);
    // labels and mask bytes over their whole range too: a high bit set must still count as nonzero
    const bool wide = zeros > 0.3;
    const auto labels = random_image<std::uint16_t>(g, zeros, 1, wide ? 65535 : 7);
    const auto ldil = random_image<std::uint16_t>(g, zeros / 3, 1, wide ? 65535 : 7);
    auto mask = random_image<std::uint8_t>(g, zeros, 1, wide ? 255 : 30);
    const auto zv = make_view<const float>(depth.data(), w, h), dv = make_view<const float>(dilated.data(), w, h);
    const auto lv = make_view<const std::uint16_t>(labels.data(), w, h);
    const auto ldv = make_view<const std::uint16_t>(ldil.data(), w, h);
    const auto mv = make_view<const std::uint8_t>(mask.data(), w, h);
    for (const int r : {0, 1, 2, 3, 8, 9}) {  // 8: the largest border tile; 9: border runs per pixel
      CAPTURE(r);
      // the depth closing: host rows (detail::depth_rows_kernel) against the per-pixel kernels,
      // bit for bit; the erosion also in place
      using F = image_view<float>;
      CHECK(depth_rows_match(zv, dv, r));
      CHECK(rows_match<float>(w, h, depth, [&](F o) { return detail::depth_erode_kernel{zv, dv, o, r}; },
                              [&](F o) { return detail::depth_rows_kernel<false>{image_view<const float>(o), dv, o, r}; }));
      // the label closing: host rows (detail::label_rows_kernel) against the per-pixel kernels
      using L = image_view<std::uint16_t>;
      CHECK(rows_match<std::uint16_t>(w, h, std::vector<std::uint16_t>(labels.size(), 9),
                                      [&](L o) { return detail::label_dilate_kernel{lv, o, r}; },
                                      [&](L o) { return detail::label_rows_kernel<true>{lv, lv, o, r}; }));
      CHECK(rows_match<std::uint16_t>(w, h, std::vector<std::uint16_t>(labels.size(), 9),
                                      [&](L o) { return detail::label_erode_kernel{lv, ldv, o, r}; },
                                      [&](L o) { return detail::label_rows_kernel<false>{lv, ldv, o, r}; }));
      // the edge map's closing: host rows (detail::mask_rows_kernel) against the per-pixel kernels
      using M = image_view<std::uint8_t>;
      CHECK(rows_match<std::uint8_t>(w, h, std::vector<std::uint8_t>(mask.size(), 9),
                                     [&](M o) { return detail::mask_dilate_kernel{mv, o, r}; },
                                     [&](M o) { return detail::mask_rows_kernel<true>{mv, o, r}; }));
      CHECK(rows_match<std::uint8_t>(w, h, std::vector<std::uint8_t>(mask.size(), 9),
                                     [&](M o) { return detail::mask_erode_kernel{mv, o, r}; },
                                     [&](M o) { return detail::mask_rows_kernel<false>{mv, o, r}; }));
    }
  }
}

TEST_CASE("label_rows_kernel: a single labelled pixel anywhere reaches the label closing's windows") {
  // Every shift of the window, at the image's edges too: a label missed by one would leave a gap
  // unfilled.
  constexpr int sw = 40, sh = 9;
  int wrong = 0;
  for (const int r : {1, 2, 3})
    for (int py = 0; py < sh; ++py)
      for (int px = 0; px < sw; ++px) {
        std::vector<std::uint16_t> in(static_cast<std::size_t>(sw) * sh, 0), a(in.size(), 1), b(in.size(), 2);
        in[static_cast<std::size_t>(py) * sw + px] = 5;
        const auto iv = make_view<const std::uint16_t>(in.data(), sw, sh);
        const detail::label_dilate_kernel pa{iv, make_view(a.data(), sw, sh), r};
        for (int y = 0; y < sh; ++y)
          for (int x = 0; x < sw; ++x) pa(x, y);
        cpu{}.for_each_index(sh, detail::label_rows_kernel<true>{iv, iv, make_view(b.data(), sw, sh), r});
        wrong += a != b;
      }
  CHECK(wrong == 0);
}

TEST_CASE("depth_rows_kernel: rows wider than its chunk of 256 pixels equal the per-pixel closing") {
  constexpr int ww = 600, hh = 7;
  lcg_noise g(17);
  std::vector<float> depth(static_cast<std::size_t>(ww) * hh), dilated(depth.size());
  for (float& z : depth) z = g.uniform01() < 0.3 ? 0.f : static_cast<float>(0.5 + 3.5 * g.uniform01());
  for (float& z : dilated) z = g.uniform01() < 0.1 ? 0.f : static_cast<float>(0.5 + 3.5 * g.uniform01());
  const auto zv = make_view<const float>(depth.data(), ww, hh), dv = make_view<const float>(dilated.data(), ww, hh);
  for (const int r : {1, 3}) {
    CAPTURE(r);
    CHECK(depth_rows_match(zv, dv, r));
  }
}
