// Tests of include/edgeplane/segments/line_segments.hpp: the diagonal walk, run length, the line
// test with its splitting, and mask pixels ending runs.
#include <doctest/doctest.h>

#include <algorithm>
#include <cstdint>
#include <type_traits>
#include <utility>
#include <vector>

#include "edgeplane/segments/line_segments.hpp"
#include "support/scenes.hpp"
#include "support/test_backends.hpp"

using namespace edgeplane;
using namespace edgeplane_test;

namespace {

template <class D>
std::vector<std::pair<int, int>> diagonal_pixels(int w, int h, std::int64_t k) {
  int x = 0, y = 0;
  detail::diagonal_start<D>(w, h, k, x, y);
  std::vector<std::pair<int, int>> px;
  for (; x >= 0 && y >= 0 && x < w && y < h; x += D::dx, y += D::dy) px.push_back({x, y});
  return px;
}

template <class D, class B>
std::vector<std::uint8_t> extract(const B& b, const std::vector<float>& depth, const std::vector<std::uint8_t>& mask,
                                  int w, int h, const params& p) {
  device_array<float, B> z(b, depth);
  device_array<std::uint8_t, B> m(b, mask), cov(b, depth.size(), 0xEE);  // stale contents must be cleared
  extract_segments<D>(b, z.cview(w, h), m.cview(w, h), camera(w, h), p, cov.view(w, h));
  return cov.host();
}

std::size_t at(int w, int x, int y) { return static_cast<std::size_t>(y) * w + x; }

}  // namespace

TEST_CASE_TEMPLATE("diagonal_start: the diagonals cover every pixel exactly once", D, direction::left_diagonal,
                   direction::right_diagonal) {
  const std::pair<int, int> sizes[] = {{1, 1}, {1, 7}, {7, 1}, {5, 3}, {3, 5}, {8, 8}, {13, 4}};
  for (auto [w, h] : sizes) {
    CAPTURE(w);
    CAPTURE(h);
    REQUIRE(detail::diagonal_count(w, h) == w + h - 1);
    std::vector<int> seen(static_cast<std::size_t>(w) * h, 0);
    for (std::int64_t k = 0; k < detail::diagonal_count(w, h); ++k) {
      const auto px = diagonal_pixels<D>(w, h, k);
      REQUIRE(!px.empty());
      // The start is the diagonal's first pixel: stepping back leaves the image.
      const int bx = px[0].first - D::dx, by = px[0].second - D::dy;
      CHECK((bx < 0 || by < 0 || bx >= w || by >= h));
      for (auto [x, y] : px) ++seen[at(w, x, y)];
    }
    for (int c : seen) CHECK(c == 1);
  }
  CHECK(detail::diagonal_count(0, 5) == 0);
  CHECK(detail::diagonal_count(5, 0) == 0);
}

TEST_CASE_TEMPLATE("extract_segments: on a plane without edges, exactly the diagonals longer than t_length are kept", B,
                   EDGEPLANE_TEST_BACKENDS) {
  const int w = 40, h = 24;
  const auto depth = plane_image(camera(w, h), w, h, normalized({0.3, 0.2, -1.0}), 1.5);
  const std::vector<std::uint8_t> mask(depth.size(), 0);
  const params p = presets::thesis_full();  // t_length = 15
  for (const B& b : variants<B>()) {
    CAPTURE(variant_name(b));
    auto check_dir = [&](auto dir) {
      using D = decltype(dir);
      const auto cov = extract<D>(b, depth, mask, w, h, p);
      int kept = 0;
      for (std::int64_t k = 0; k < detail::diagonal_count(w, h); ++k) {
        const auto px = diagonal_pixels<D>(w, h, k);
        const std::uint8_t want = static_cast<int>(px.size()) > p.t_length ? 1 : 0;
        for (auto [x, y] : px) {
          CAPTURE(k);
          REQUIRE(cov[at(w, x, y)] == want);
          kept += want;
        }
      }
      CHECK(kept > w * h / 2);
    };
    check_dir(direction::left_diagonal{});
    check_dir(direction::right_diagonal{});
  }
}

TEST_CASE_TEMPLATE("extract_segments: a run of t_length pixels is dropped, one of t_length + 1 is kept", B,
                   EDGEPLANE_TEST_BACKENDS) {
  const int w = 48, h = 48;
  const auto depth = plane_image(camera(w, h), w, h, normalized({-0.2, 0.3, -1.0}), 2.0);
  params p = presets::thesis_full();
  for (int t_length : {15, 5}) {
    p.t_length = t_length;
    for (int len : {t_length, t_length + 1}) {
      CAPTURE(t_length);
      CAPTURE(len);
      std::vector<std::uint8_t> mask(depth.size(), 1);  // everything masked but one run on the main diagonal
      for (int i = 0; i < len; ++i) mask[at(w, 4 + i, 4 + i)] = 0;
      for (const B& b : variants<B>()) {
        const auto cov = extract<direction::left_diagonal>(b, depth, mask, w, h, p);
        int covered = 0;
        for (std::size_t i = 0; i < cov.size(); ++i) {
          REQUIRE(cov[i] <= 1);
          covered += cov[i];
          if (cov[i]) REQUIRE(mask[i] == 0);
        }
        CHECK(covered == (len > t_length ? len : 0));
      }
    }
  }
}

TEST_CASE_TEMPLATE("extract_segments: runs stop at mask pixels", B, EDGEPLANE_TEST_BACKENDS) {
  const int w = 40, h = 40;
  const auto depth = plane_image(camera(w, h), w, h, normalized({0.1, 0.1, -1.0}), 1.2);
  std::vector<std::uint8_t> mask(depth.size(), 0);
  mask[at(w, 10, 10)] = 1;            // main diagonal: runs 0..9 (10 px, dropped) and 11..39 (29, kept)
  mask[at(w, 30 - 20, 20)] = 1;       // anti-diagonal x + y = 30: splits it into 10 + 20 pixels
  const params p = presets::thesis_full();
  for (const B& b : variants<B>()) {
    CAPTURE(variant_name(b));
    const auto l = extract<direction::left_diagonal>(b, depth, mask, w, h, p);
    for (int i = 0; i < w; ++i) {
      CAPTURE(i);
      CHECK(l[at(w, i, i)] == (i > 10 ? 1 : 0));
    }
    const auto r = extract<direction::right_diagonal>(b, depth, mask, w, h, p);
    for (int y = 0; y <= 30; ++y) {  // pixels (30 - y, y): y = 0..19 (20 px, kept), 20 masked, 21..30 (10, dropped)
      CAPTURE(y);
      CHECK(r[at(w, 30 - y, y)] == (y < 20 ? 1 : 0));
    }
  }
}

TEST_CASE_TEMPLATE("extract_segments: a run across an unmarked crease fails the line test; splitting keeps its halves",
                   B, EDGEPLANE_TEST_BACKENDS) {
  // A V (valley, faces at +-45 degrees) along the main diagonal with its vertex at (20, 20); the
  // mask marks everything but that diagonal, and NOT the crease.
  const int w = 40, h = 40, c = 20;
  const auto k = camera(w, h);
  std::vector<float> depth(static_cast<std::size_t>(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      // The crease line is x + y = 2c; each face is a plane through it.
      const vec3 n = normalized(x + y < 2 * c ? vec3{1, 1, -1.4142} : vec3{-1, -1, -1.4142});
      const double rx = (c - k.cx) / k.fx, ry = (c - k.cy) / k.fy, zc = 1.0;
      const double d = -(n.x * rx * zc + n.y * ry * zc + n.z * zc);  // the plane passes through the vertex
      depth[at(w, x, y)] = plane_depth(k, x, y, n, d);
    }
  std::vector<std::uint8_t> mask(depth.size(), 1);
  for (int i = 0; i < w; ++i) mask[at(w, i, i)] = 0;
  for (const B& b : variants<B>()) {
    CAPTURE(variant_name(b));
    params p = presets::thesis_full();
    p.max_run_splits = 0;
    auto cov = extract<direction::left_diagonal>(b, depth, mask, w, h, p);
    int covered = 0;
    for (auto v : cov) covered += v;
    CHECK(covered == 0);
    for (int splits : {1, 4}) {
      CAPTURE(splits);
      p.max_run_splits = splits;
      cov = extract<direction::left_diagonal>(b, depth, mask, w, h, p);
      for (int i = 0; i < w; ++i) {
        CAPTURE(i);
        CHECK(cov[at(w, i, i)] == (i == c ? 0 : 1));  // both straight halves kept, only the vertex dropped
      }
    }
    // The same diagonal on a plane (no crease) is kept whole even without splitting.
    const auto flat = plane_image(k, w, h, normalized({0.3, 0.3, -1.0}), 1.0);
    p.max_run_splits = 0;
    cov = extract<direction::left_diagonal>(b, flat, mask, w, h, p);
    for (int i = 0; i < w; ++i) CHECK(cov[at(w, i, i)] == 1);
  }
}

TEST_CASE_TEMPLATE("extract_segments: a crease near one end leaves one half too short to keep", B,
                   EDGEPLANE_TEST_BACKENDS) {
  // Vertex at (10, 10): halves of 10 and 29 pixels; with t_length = 15 only the long one is kept.
  const int w = 40, h = 40, c = 10;
  const auto k = camera(w, h);
  std::vector<float> depth(static_cast<std::size_t>(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const vec3 n = normalized(x + y < 2 * c ? vec3{1, 1, -1.4142} : vec3{-1, -1, -1.4142});
      const double rx = (c - k.cx) / k.fx, ry = (c - k.cy) / k.fy;
      depth[at(w, x, y)] = plane_depth(k, x, y, n, -(n.x * rx + n.y * ry + n.z));
    }
  std::vector<std::uint8_t> mask(depth.size(), 1);
  for (int i = 0; i < w; ++i) mask[at(w, i, i)] = 0;
  params p = presets::thesis_full();
  const B b{};
  const auto cov = extract<direction::left_diagonal>(b, depth, mask, w, h, p);
  for (int i = 0; i < w; ++i) {
    CAPTURE(i);
    CHECK(cov[at(w, i, i)] == (i > c ? 1 : 0));
  }
}

TEST_CASE_TEMPLATE("line_test: the host lanes' search finds operator()'s worst point on runs of every length", D,
                   direction::left_diagonal, direction::right_diagonal) {
  // A tilted plane with depth noise of a few millimetres and sparse spikes, in a pitched view:
  // runs of every length from 1 to the diagonal's, starting anywhere, pass or fail the same way
  // and fail at the same point (the 16-lane blocks, the partial last block, each lane's first
  // worst point).
  const int w = 61, h = 57, pitch = 67;
  const auto k = camera(w, h);
  const auto flat = plane_image(k, w, h, normalized({0.2, -0.3, -1.0}), 1.7);
  std::vector<float> depth(static_cast<std::size_t>(pitch) * h, -1.f);
  edgeplane::test::noise_source rng{7};
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      float z = flat[at(w, x, y)] + static_cast<float>(0.003 * rng.gaussian());
      if (rng.uniform() < 0.01) z += 0.05f;
      depth[static_cast<std::size_t>(y) * pitch + x] = z;
    }
  const image_view<const float> view{depth.data(), w, h, pitch};
  const params p = presets::thesis_full();
  const detail::line_test test{p.t_line, p.noise_k, detail::make_noise(p.noise)};
  const auto proj = detail::make_projector(k);
  int failing = 0, passing = 0;
  for (int x0 = 0; x0 < w; x0 += 3)
    for (int y0 = 0; y0 < h; y0 += 4) {
      for (int len = 1; x0 + (len - 1) * D::dx >= 0 && x0 + (len - 1) * D::dx < w && y0 + len - 1 < h; ++len) {
        CAPTURE(x0);
        CAPTURE(y0);
        CAPTURE(len);
        const int want = test(view, proj, x0, y0, len, D{});
        REQUIRE(test.template worst_lanes<D>(view, proj, x0, y0, len) == want);
        (want < 0 ? passing : failing) += 1;
      }
    }
  CHECK(failing > 500);
  CHECK(passing > 1000);
}

TEST_CASE_TEMPLATE("line_test: of two points with the same largest excess, the first is the worst", D,
                   direction::left_diagonal, direction::right_diagonal) {
  // fx = fy = 1, the principal point on the diagonal and whole-number depths: every coordinate and
  // every product of the distance computation is a small integer, so two equal spikes (depth 4 ->
  // 68 on a plane at depth 4, the chord's line at depth 4) have exactly the same excess wherever
  // they lie. Pairs in the same lane of a 16-point block, in different lanes and in different
  // blocks all name the first spike; a larger second spike is named instead.
  const int n = 41;
  const intrinsics k{1.f, 1.f, 20.f, 20.f};
  const auto proj = detail::make_projector(k);
  const params p = presets::thesis_full();
  const detail::line_test test{p.t_line, 0.f, detail::make_noise(p.noise)};
  const int x0 = D::dx == 1 ? 0 : n - 1;
  std::vector<float> depth(static_cast<std::size_t>(n) * n);
  for (int i = 1; i < n - 1; ++i)
    for (int j = i + 1; j < n - 1; ++j)
      for (float second : {68.f, 69.f}) {
        CAPTURE(i);
        CAPTURE(j);
        CAPTURE(second);
        std::fill(depth.begin(), depth.end(), 4.f);
        depth[at(n, x0 + i * D::dx, i)] = 68.f;
        depth[at(n, x0 + j * D::dx, j)] = second;
        const image_view<const float> view{depth.data(), n, n, n};
        const int want = second == 68.f ? i : j;
        REQUIRE(test(view, proj, x0, 0, n, D{}) == want);
        REQUIRE(test.template worst_lanes<D>(view, proj, x0, 0, n) == want);
      }
}

TEST_CASE_TEMPLATE("extract_segments: the host's walk of diagonals in blocks keeps the runs one walk per diagonal keeps", D,
                   direction::left_diagonal, direction::right_diagonal) {
  // Noisy tilted planes with spikes (runs that pass, fail and split) under random masks whose
  // density changes across the image, with mask values other than 1 and zeros in the pitch padding
  // (a block that read past its row would join runs across it). The sizes take each block width
  // (4, 8 and 16 diagonals), blocks that lie partly or wholly outside the image, and the walk by
  // single diagonals of small images.
  const std::pair<int, int> sizes[] = {{1, 1},    {1, 40},    {40, 1},    {5, 3},     {3, 29},    {37, 29},
                                       {400, 30}, {200, 150}, {150, 200}, {300, 250}, {600, 500}};
  const std::uint8_t edge_values[] = {1, 2, 0x80, 0xff};
  edgeplane::test::noise_source rng{11};
  int kept_total = 0;
  for (auto [w, h] : sizes) {
    CAPTURE(w);
    CAPTURE(h);
    const int pitch = w + 5;
    const auto k = camera(w, h);
    const auto flat = plane_image(k, w, h, normalized({0.2, -0.3, -1.0}), 1.7);
    std::vector<float> depth(static_cast<std::size_t>(pitch) * h, 1.f);
    std::vector<std::uint8_t> mask(depth.size(), 0);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        float z = flat[at(w, x, y)] + static_cast<float>(0.003 * rng.gaussian());
        if (rng.uniform() < 0.01) z += 0.05f;
        const std::size_t i = static_cast<std::size_t>(y) * pitch + x;
        depth[i] = z;
        const double density = 0.01 + 0.2 * x / w + 0.1 * y / h;
        if (rng.uniform() < density) mask[i] = edge_values[rng.uniform() < 0.5 ? 0 : static_cast<int>(rng.uniform() * 4)];
      }
    const image_view<const float> zv{depth.data(), w, h, pitch};
    const image_view<const std::uint8_t> mv{mask.data(), w, h, pitch};
    const params p = presets::thesis_full();
    std::vector<std::uint8_t> want(depth.size(), 0), got(depth.size(), 0x5a);
    const detail::diagonal_runs_kernel<D, true> one{zv,
                                                    mv,
                                                    image_view<std::uint8_t>{want.data(), w, h, pitch},
                                                    detail::make_projector(k),
                                                    p.t_length,
                                                    p.max_run_splits,
                                                    detail::line_test{p.t_line, p.noise_k, detail::make_noise(p.noise)}};
    for (std::int64_t i = 0; i < detail::diagonal_count(w, h); ++i) one(i);
    extract_segments<D>(cpu{}, zv, mv, k, p, image_view<std::uint8_t>{got.data(), w, h, pitch});
    int kept = 0, differ = 0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const std::size_t i = static_cast<std::size_t>(y) * pitch + x;
        kept += want[i];
        differ += got[i] != want[i];
      }
    CHECK(differ == 0);
    kept_total += kept;
    // Each block width over 1, 2, 3 and 7 bands of rows (runs that cross a band's first row, start
    // on it, or end on it; bands of one row or none where the image is short), in reverse order
    // of the work items: the same covered pixels.
    const auto banded = [&](auto lanes, int bands) {
      constexpr int L = decltype(lanes)::value;
      std::vector<std::uint8_t> out(depth.size(), 0);
      const std::int64_t blocks = (detail::diagonal_count(w, h) + L - 1) / L;
      const detail::diagonal_block_runs_kernel<D, L> walk{
          {one.depth, one.mask, image_view<std::uint8_t>{out.data(), w, h, pitch}, one.proj, one.t_length, one.max_splits,
           one.test},
          blocks,
          bands};
      for (std::int64_t i = blocks * bands - 1; i >= 0; --i) walk(i);
      int wrong = 0;
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) wrong += out[static_cast<std::size_t>(y) * pitch + x] != want[static_cast<std::size_t>(y) * pitch + x];
      return wrong;
    };
    for (const int bands : {1, 2, 3, 7}) {
      CAPTURE(bands);
      CHECK(banded(std::integral_constant<int, 4>{}, bands) == 0);
      CHECK(banded(std::integral_constant<int, 8>{}, bands) == 0);
      CHECK(banded(std::integral_constant<int, 16>{}, bands) == 0);
    }
  }
  CHECK(kept_total > 20000);
}

TEST_CASE_TEMPLATE("extract_segments: a pitched covered view gets the dense view's pixels, its padding untouched", D,
                   direction::left_diagonal, direction::right_diagonal) {
  // A noisy tilted plane under a sparse mask (runs kept, dropped and split), written once into a
  // dense view and once into a view whose pitch exceeds its width.
  const int w = 90, h = 70, pitch = w + 13;
  const auto k = camera(w, h);
  const auto depth = plane_image(k, w, h, normalized({0.1, 0.25, -1.0}), 2.1);
  edgeplane::test::noise_source rng{3};
  std::vector<float> z(depth);
  std::vector<std::uint8_t> mask(depth.size(), 0);
  for (std::size_t i = 0; i < z.size(); ++i) {
    z[i] += static_cast<float>(0.002 * rng.gaussian());
    if (rng.uniform() < 0.02) mask[i] = 1;
  }
  const params p = presets::thesis_full();
  const image_view<const float> zv{z.data(), w, h, w};
  const image_view<const std::uint8_t> mv{mask.data(), w, h, w};
  std::vector<std::uint8_t> dense(z.size(), 0x5a), pitched(static_cast<std::size_t>(pitch) * h, 0x77);
  extract_segments<D>(cpu{}, zv, mv, k, p, image_view<std::uint8_t>{dense.data(), w, h, w});
  extract_segments<D>(cpu{}, zv, mv, k, p, image_view<std::uint8_t>{pitched.data(), w, h, pitch});
  int kept = 0, differ = 0, padding = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < pitch; ++x) {
      const std::uint8_t v = pitched[static_cast<std::size_t>(y) * pitch + x];
      if (x >= w) {
        padding += v != 0x77;
        continue;
      }
      kept += dense[at(w, x, y)];
      differ += v != dense[at(w, x, y)];
    }
  CHECK(differ == 0);
  CHECK(padding == 0);
  CHECK(kept > w * h / 3);
}
