// The host row kernels of the closings (detail::window_runs for the depth: 16 pixels of a row at
// once where their windows lie inside the image; whole rows for the edge map and the labels) must
// give exactly what the per-pixel kernels give, which the device backend runs.  Random images
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

// Runs the per-pixel kernel make(out) pixel by pixel and the row kernel through
// for_each_pixel_run (host: runs of 16); returns how many output elements differ byte for byte.
template <class T, class Make>
int differ(Make make) {
  std::vector<T> a(static_cast<std::size_t>(w) * h, T(7)), b(a.size(), T(9));
  const auto pa = make(make_view(a.data(), w, h));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) pa(x, y);
  const auto pb = make(make_view(b.data(), w, h));
  using K = decltype(pb);
  detail::for_each_pixel_run<detail::window_runs<K>::template kernel>(cpu{}, w, h, pb);
  std::vector<T> c(a.size(), T(5));  // and the form compiled once (plain_kernel)
  const auto pc = make(make_view(c.data(), w, h));
  detail::for_each_pixel_run<detail::window_runs<K>::template plain_kernel>(cpu{}, w, h, pc);
  int n = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    n += std::memcmp(&a[i], &b[i], sizeof(T)) != 0 || std::memcmp(&a[i], &c[i], sizeof(T)) != 0;
  return n;
}

template <class T>
std::vector<T> random_image(lcg_noise& g, double zero_share, T lo, T hi) {
  std::vector<T> v(static_cast<std::size_t>(w) * h);
  for (T& e : v)
    e = g.uniform01() < zero_share ? T(0) : static_cast<T>(lo + (hi - lo) * g.uniform01());
  return v;
}

}  // namespace

TEST_CASE("window_runs: the closings' row kernels equal their per-pixel kernels") {
  lcg_noise g(3);
  for (const double zeros : {0.05, 0.4, 0.9}) {
    CAPTURE(zeros);
    const auto depth = random_image<float>(g, zeros, 0.5f, 4.f);
    const auto dilated = random_image<float>(g, zeros / 3, 0.5f, 4.f);
    // labels and mask bytes over their whole range too: the host kernels test 8 bytes or 4 labels
    // of a word at once, where a high bit set must still count as nonzero
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
      CHECK(differ<float>([&](image_view<float> o) { return detail::depth_dilate_kernel{zv, o, r}; }) == 0);
      CHECK(differ<float>([&](image_view<float> o) { return detail::depth_erode_kernel{zv, dv, o, r}; }) == 0);
      // the label closing: host rows (detail::label_rows_kernel) against the per-pixel kernels
      for (const bool dilate : {true, false}) {
        CAPTURE(dilate);
        std::vector<std::uint16_t> a(labels.size(), 7), b(labels.size(), 9);
        const auto av = make_view(a.data(), w, h), bv = make_view(b.data(), w, h);
        for (int y = 0; y < h; ++y)
          for (int x = 0; x < w; ++x) {
            if (dilate)
              detail::label_dilate_kernel{lv, av, r}(x, y);
            else
              detail::label_erode_kernel{lv, ldv, av, r}(x, y);
          }
        if (dilate)
          cpu{}.for_each_index(h, detail::label_rows_kernel<true>{lv, lv, bv, r});
        else
          cpu{}.for_each_index(h, detail::label_rows_kernel<false>{lv, ldv, bv, r});
        CHECK(a == b);
      }
      // the edge map's closing: host rows (detail::mask_rows_kernel) against the per-pixel kernels
      for (const bool dilate : {true, false}) {
        CAPTURE(dilate);
        std::vector<std::uint8_t> a(mask.size(), 7), b(mask.size(), 9);
        for (int y = 0; y < h; ++y)
          for (int x = 0; x < w; ++x) {
            if (dilate)
              detail::mask_dilate_kernel{mv, make_view(a.data(), w, h), r}(x, y);
            else
              detail::mask_erode_kernel{mv, make_view(a.data(), w, h), r}(x, y);
          }
        if (dilate)
          cpu{}.for_each_index(h, detail::mask_rows_kernel<true>{mv, make_view(b.data(), w, h), r});
        else
          cpu{}.for_each_index(h, detail::mask_rows_kernel<false>{mv, make_view(b.data(), w, h), r});
        CHECK(a == b);
      }
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
