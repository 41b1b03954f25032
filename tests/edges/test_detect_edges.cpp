// Tests of include/edgeplane/edges/detect_edges.hpp: the fused detector against the per-(direction,
// type) kernels, the use_* switches, invalid pixels, and the closing of the edge map.
#include <doctest/doctest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "edgeplane/edges/detect_edges.hpp"
#include "support/test_backends.hpp"

using namespace edgeplane;
using namespace edgeplane_test;

namespace {

/// A 64 x 48 scene with every kind of structure: a slanted plane, a 30 cm step, a 90 degree roof,
/// a 5 cm spike, a small arc, a hole of invalid pixels, and 1 mm noise.
std::vector<float> mixed_scene(int w, int h, const intrinsics& k) {
  std::vector<float> z(static_cast<std::size_t>(w) * h);
  lcg_noise noise(3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      double v = plane_depth(k, x, y, normalized({0.1, -0.2, -1.0}), 1.8);
      if (x >= 40) v += 0.3;                                              // step
      if (y >= 30 && x < 40) v += 0.004 * std::abs(x + y - 50);           // roof-like crease along x + y = 50
      if (x == 20 && y == 12) v -= 0.05;                                  // spike
      if (y < 10 && x >= 10 && x < 30) v += 0.02 * std::sqrt(std::max(0, x - 10)); // bend
      z[static_cast<std::size_t>(y) * w + x] = static_cast<float>(v) + noise(0.001f);
    }
  for (int y = 20; y < 24; ++y)
    for (int x = 50; x < 55; ++x) z[static_cast<std::size_t>(y) * w + x] = 0.f;  // hole
  return z;
}

template <class D, class T, class B>
void or_kernel(const B& b, const device_array<float, B>& z, int w, int h, const intrinsics& k, const T& t,
               device_array<std::uint8_t, B>& e) {
  detect_edge<D>(b, z.cview(w, h), k, t, e.view(w, h));
}

template <class T, class B>
std::vector<std::uint8_t> all_directions(const B& b, const device_array<float, B>& z, int w, int h,
                                         const intrinsics& k, const T& t) {
  device_array<std::uint8_t, B> e(b, static_cast<std::size_t>(w) * h, 0);
  or_kernel<direction::horizontal>(b, z, w, h, k, t, e);
  or_kernel<direction::vertical>(b, z, w, h, k, t, e);
  or_kernel<direction::left_diagonal>(b, z, w, h, k, t, e);
  or_kernel<direction::right_diagonal>(b, z, w, h, k, t, e);
  return e.host();
}

}  // namespace

TEST_CASE_TEMPLATE("detect_edges equals the OR of the per-(direction, type) kernels, type by type", B,
                   EDGEPLANE_TEST_BACKENDS) {
  const int w = 64, h = 48;
  const auto k = camera(w, h);
  const auto scene = mixed_scene(w, h, k);
  for (params p : {presets::thesis_full(), presets::thesis_half(), presets::kinect360()}) {
    p.noise_k = 0.5f;  // small allowance: every type fires somewhere on this scene
    const auto set = detail::make_edge_set(p);
    for (const B& b : variants<B>()) {
      CAPTURE(variant_name(b));
      device_array<float, B> z(b, scene);
      device_array<std::uint8_t, B> fused(b, scene.size(), 0xA5);  // every pixel must be written
      detect_edges(b, z.cview(w, h), k, p, fused.view(w, h));
      const auto f = fused.host();
      const std::vector<std::uint8_t> per_type[4] = {
          all_directions(b, z, w, h, k, set.jump), all_directions(b, z, w, h, k, set.extrema),
          all_directions(b, z, w, h, k, set.corner), all_directions(b, z, w, h, k, set.curved)};
      const std::uint8_t bits[4] = {edge_jump, edge_extrema, edge_corner, edge_curved};
      for (int t = 0; t < 4; ++t) {
        CAPTURE(t);
        int fired = 0, mismatches = 0;
        for (std::size_t i = 0; i < f.size(); ++i) {
          if (scene[i] == 0.f) continue;
          const bool a = (f[i] & bits[t]) != 0, c = (per_type[t][i] & bits[t]) != 0;
          fired += a ? 1 : 0;
          mismatches += a != c ? 1 : 0;
        }
        CHECK(mismatches == 0);
        CHECK(fired > 0);  // the comparison is not vacuous
      }
      for (std::size_t i = 0; i < f.size(); ++i) {
        if (scene[i] == 0.f)
          REQUIRE(f[i] == edge_invalid);
        else
          REQUIRE((f[i] & ~(edge_jump | edge_extrema | edge_corner | edge_curved)) == 0);
      }
    }
  }
}

TEST_CASE_TEMPLATE("detect_edges: a disabled edge type never fires; detect_edge ORs into the map", B,
                   EDGEPLANE_TEST_BACKENDS) {
  const int w = 64, h = 48;
  const auto k = camera(w, h);
  const auto scene = mixed_scene(w, h, k);
  const B b{};
  device_array<float, B> z(b, scene);
  params p = presets::thesis_full();
  p.noise_k = 0.5f;
  p.use_jump = false;
  p.use_corner = false;
  device_array<std::uint8_t, B> e(b, scene.size(), 0);
  detect_edges(b, z.cview(w, h), k, p, e.view(w, h));
  int extrema = 0;
  for (auto v : e.host()) {
    CHECK((v & (edge_jump | edge_corner)) == 0);
    extrema += v & edge_extrema ? 1 : 0;
  }
  CHECK(extrema > 0);
  // detect_edge keeps the bits already in the map (the caller clears it).
  device_array<std::uint8_t, B> marked(b, scene.size(), 0x80);
  detect_edge<direction::horizontal>(b, z.cview(w, h), k, detail::make_edge_set(p).jump, marked.view(w, h));
  for (auto v : marked.host()) REQUIRE((v & 0x80) != 0);
}

TEST_CASE_TEMPLATE("detect_edges: a step seen by the fused detector marks exactly the two columns beside it", B,
                   EDGEPLANE_TEST_BACKENDS) {
  const int w = 40, h = 30, x0 = 20;
  const auto k = camera(w, h);
  std::vector<float> z(static_cast<std::size_t>(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) z[static_cast<std::size_t>(y) * w + x] = x < x0 ? 1.5f : 2.0f;
  for (const B& b : variants<B>()) {
    device_array<float, B> zd(b, z);
    device_array<std::uint8_t, B> e(b, z.size(), 0);
    detect_edges(b, zd.cview(w, h), k, presets::thesis_full(), e.view(w, h));
    const auto out = e.host();
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        CAPTURE(x);
        CAPTURE(y);
        CHECK(((out[static_cast<std::size_t>(y) * w + x] & edge_jump) != 0) == (x == x0 - 1 || x == x0));
      }
  }
}

TEST_CASE_TEMPLATE("close_edges: bridges a 1- and 2-pixel gap in an edge line, not a 3-pixel one, nor thickens it",
                   B, EDGEPLANE_TEST_BACKENDS) {
  const int w = 24, h = 30, lx = 12;
  // A vertical edge line at x = 12 with gaps at y = 5 (1 px), y = 12..13 (2 px), y = 20..22 (3 px).
  auto in_gap = [](int y) { return y == 5 || y == 12 || y == 13 || (y >= 20 && y <= 22); };
  std::vector<std::uint8_t> edges(static_cast<std::size_t>(w) * h, 0);
  for (int y = 0; y < h; ++y)
    if (!in_gap(y)) edges[static_cast<std::size_t>(y) * w + lx] = edge_corner;
  edges[3 * w + 3] = edge_invalid;  // an isolated invalid pixel stays in the mask
  for (const B& b : variants<B>()) {
    CAPTURE(variant_name(b));
    device_array<std::uint8_t, B> e(b, edges), scratch(b, edges.size(), 0), mask(b, edges.size(), 7);
    close_edges(b, e.cview(w, h), scratch.view(w, h), mask.view(w, h), 1);
    const auto m = mask.host();
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        CAPTURE(x);
        CAPTURE(y);
        const std::uint8_t v = m[static_cast<std::size_t>(y) * w + x];
        if (x == 3 && y == 3)
          CHECK(v == 1);
        else if (x != lx)
          CHECK(v == 0);  // the line is not thickened
        else
          CHECK(v == ((y >= 20 && y <= 22) ? 0 : 1));
      }
    // r = 0: the mask is "any bit set".
    close_edges(b, e.cview(w, h), scratch.view(w, h), mask.view(w, h), 0);
    const auto m0 = mask.host();
    for (std::size_t i = 0; i < m0.size(); ++i) REQUIRE(m0[i] == (edges[i] != 0 ? 1 : 0));
  }
}

TEST_CASE_TEMPLATE("close_edges: an edge line ending at the image border is kept to the border", B,
                   EDGEPLANE_TEST_BACKENDS) {
  const int w = 16, h = 10;
  std::vector<std::uint8_t> edges(static_cast<std::size_t>(w) * h, 0);
  for (int x = 0; x < w; ++x) edges[static_cast<std::size_t>(0) * w + x] = edge_jump;  // the top row
  for (int y = 0; y < h; ++y) edges[static_cast<std::size_t>(y) * w + 7] = edge_jump;  // a column to the bottom
  const B b{};
  device_array<std::uint8_t, B> e(b, edges), scratch(b, edges.size(), 0), mask(b, edges.size(), 0);
  close_edges(b, e.cview(w, h), scratch.view(w, h), mask.view(w, h), 1);
  const auto m = mask.host();
  for (std::size_t i = 0; i < m.size(); ++i) CHECK(m[i] == (edges[i] != 0 ? 1 : 0));
}

// On host backends detect_edges runs detail::all_edges_rows_kernel (cheap first conditions for 16
// pixels at once behind precomputed neighbour counts, the scalar kernel wherever one of them may
// fire); the device backend runs detail::all_edges_kernel per pixel after the interior pass.  The
// edge maps must be equal byte for byte, for every preset's thresholds, on a scene large enough
// that most runs take the 16-pixel path: with a hole, pepper noise and an invalid band (lanes whose
// lines end at invalid depth), and in a view whose pitch exceeds its width.
namespace {
std::vector<float> row_kernel_scene(int w, int h, const intrinsics& k, bool holes) {
  std::vector<float> z(static_cast<std::size_t>(w) * h);
  lcg_noise noise(5);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      double v = plane_depth(k, x, y, normalized({0.1, -0.2, -1.0}), 1.8);
      if (x >= 140) v += 0.3;                                                       // step
      if (y >= 90 && x < 140) v += 0.004 * std::abs(x + y - 150);                   // crease
      if (y < 40 && x >= 30 && x < 110) v += 0.05 * std::sqrt(std::max(0, x - 30) / 80.0);  // bend
      if ((x - 60) * (x - 60) + (y - 60) * (y - 60) < 200) v -= 0.02;               // a disc in front
      z[static_cast<std::size_t>(y) * w + x] = static_cast<float>(v) + noise(0.002f);
    }
  auto invalid = [&](int x, int y) {  // (the small images hold only part of the scene)
    if (x < w && y < h) z[static_cast<std::size_t>(y) * w + x] = 0.f;
  };
  for (int y = 100; y < 108; ++y)
    for (int x = 170; x < 180; ++x) invalid(x, y);  // hole
  if (holes) {
    for (int i = 0; i < w * h / 40; ++i) z[noise.next_u32(static_cast<std::uint32_t>(w * h))] = 0.f;  // pepper
    for (int y = 50; y < 53; ++y)
      for (int x = 0; x < 90; ++x) invalid(x, y);  // a band from the border
    // invalid columns two pixels either side of the step: jumps whose side holds one neighbour
    for (int y = 0; y < h; ++y) invalid(y < h / 2 ? 138 : 141, y);
  }
  return z;
}
}  // namespace

TEST_CASE("detect_edges: the 16-pixel row kernel gives the per-pixel kernel's edge map") {
  // 203 x 157: not a multiple of 16; 17 x 9 and 40 x 3: images narrower or lower than the reach,
  // whose runs read far into the point planes' padding rows
  const int sizes[3][2] = {{203, 157}, {17, 9}, {40, 3}};
  const intrinsics k{180.f, 180.f, 101.f, 78.f};
  for (const auto& size : sizes)
  for (const bool holes : {false, true})
    for (const int pitch : {size[0], size[0] + 21}) {
      const int w = size[0], h = size[1];
      const bool large = w > 100;
      CAPTURE(w);
      CAPTURE(holes);
      CAPTURE(pitch);
      const std::vector<float> dense = row_kernel_scene(w, h, k, holes);
      std::vector<float> z(static_cast<std::size_t>(pitch) * h, 7.f);  // padding: never read as depth
      for (int y = 0; y < h; ++y)
        std::copy_n(dense.begin() + static_cast<std::ptrdiff_t>(y) * w, w, z.begin() + static_cast<std::ptrdiff_t>(y) * pitch);
      const image_view<const float> zv{z.data(), w, h, pitch};
      // every preset, and two sets outside them: a straight-arm tolerance above the arc threshold
      // (an arc-like arm can then also count as straight, which the curved test must reject),
      // and short, loose arms (most pixels reach the finishing tests)
      std::vector<std::pair<std::string, params>> sets;
      for (const auto& name : presets::preset_names()) sets.emplace_back(name, preset(name));
      params crossed = presets::thesis_full();
      crossed.t_cue1 = 0.12f;
      crossed.t_cue2 = 0.02f;
      crossed.n_cue = 6;
      sets.emplace_back("t_cue1 > t_cue2", crossed);
      params loose = presets::kinect2();
      loose.t_coe = 0.01f;
      loose.t_coe_arm = 0.2f;
      loose.n_coe = 3;
      loose.n_ee = 3;
      loose.t_ee = 0.999f;
      sets.emplace_back("loose corners", loose);
      params longest = presets::thesis_full();  // the longest arms validate() allows: reach 32
      longest.n_coe = 32;
      longest.n_cue = 32;
      sets.emplace_back("reach 32", longest);
      for (const auto& set_of : sets) {  // (not a structured binding: clang 14 cannot capture one)
        const std::string& name = set_of.first;
        const params& p = set_of.second;
        CAPTURE(name);
        std::vector<std::uint8_t> rows(dense.size(), 0xee), pixels(dense.size(), 0xdd);
        detect_edges(cpu{}, zv, k, p, make_view(rows.data(), w, h));
        const detail::edge_set set = detail::make_edge_set(p);
        const int reach = set.reach();
        const auto ev = make_view(pixels.data(), w, h);
        const cpu serial{cpu::mode::serial};
        serial.for_each_index(h, detail::interior_rows_kernel{zv, ev, reach});
        serial.for_each_index(w, detail::interior_columns_kernel{ev, reach});
        for (int y = 0; y < h; ++y)  // the per-pixel kernel itself, pixel by pixel
          for (int x = 0; x < w; ++x) detail::all_edges_kernel{zv, ev, detail::make_projector(k), set, reach}(x, y);
        int differ = 0, edges = 0;
        for (std::size_t i = 0; i < dense.size(); ++i) {
          differ += rows[i] != pixels[i];
          edges += pixels[i] != 0 && pixels[i] != edge_invalid;
        }
        CHECK(differ == 0);
        if (large) {
          CHECK(edges > 100);                 // the scene has edges of several kinds...
          CHECK(edges < static_cast<int>(dense.size()) / 3);  // ...and mostly surface
        }
      }
    }
}

namespace {
/// Offsets in ulps around a flip found by bisection: every one within 40, then every 97th out to 3000.
std::vector<int> flip_offsets() {
  std::vector<int> d;
  for (int i = -40; i <= 40; ++i) d.push_back(i);
  for (int i = 41; i <= 3000; i += 97) {
    d.push_back(i);
    d.push_back(-i);
  }
  return d;
}
/// The 16-pixel row kernel's and the per-pixel kernel's edge maps of one dense image.
std::pair<std::vector<std::uint8_t>, std::vector<std::uint8_t>> both_maps(const std::vector<float>& z, int w, int h,
                                                                          const intrinsics& k, const params& p) {
  const image_view<const float> zv{z.data(), w, h, w};
  std::vector<std::uint8_t> rows(z.size(), 0xee), pixels(z.size(), 0xdd);
  detect_edges(cpu{}, zv, k, p, make_view(rows.data(), w, h));
  const detail::edge_set set = detail::make_edge_set(p);
  const auto ev = make_view(pixels.data(), w, h);
  const cpu serial{cpu::mode::serial};
  serial.for_each_index(h, detail::interior_rows_kernel{zv, ev, set.reach()});
  serial.for_each_index(w, detail::interior_columns_kernel{ev, set.reach()});
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) detail::all_edges_kernel{zv, ev, detail::make_projector(k), set, set.reach()}(x, y);
  return {rows, pixels};
}

/// The scalar test `type` along the row as a function of pixel i's depth: sets z[i] and returns
/// whether the test fires at pixel ic.
template <class Type>
auto row_test(std::vector<float>& z, int w, int h, const intrinsics& k, const Type& type, std::size_t i,
              std::size_t ic) {
  return [&z, w, h, k, type, i, ic](float depth) {
    z[i] = depth;
    std::vector<std::uint8_t> e(z.size(), 0);
    detect_edge<direction::horizontal>(cpu{cpu::mode::serial}, image_view<const float>{z.data(), w, h, w}, k, type,
                                       make_view(e.data(), w, h));
    return (e[ic] & Type::bit) != 0;
  };
}

/// Moves pixel i of z (w x h) between depths za and zb, at which the scalar test along the row
/// (scalar(depth): sets z[i], returns pixel ic's `bit`) decides differently, finds the flip by
/// bisection over the floats' bit patterns (ordered as the values for positive floats), then
/// requires at every flip_offsets() depth around it: the row kernel's map = the per-pixel
/// kernel's, and the map's bit at ic = the scalar test's (the other directions must not fire it).
template <class Scalar>
void check_flip(std::vector<float>& z, std::size_t i, float za, float zb, int w, int h, const intrinsics& k,
                const params& p, std::size_t ic, unsigned bit, Scalar scalar) {
  const bool at_a = scalar(za);
  REQUIRE(at_a != scalar(zb));
  std::uint32_t a = std::bit_cast<std::uint32_t>(za), b = std::bit_cast<std::uint32_t>(zb);
  while ((a > b ? a - b : b - a) > 1) {
    const std::uint32_t mid = std::min(a, b) + (a > b ? a - b : b - a) / 2;
    (scalar(std::bit_cast<float>(mid)) == at_a ? a : b) = mid;
  }
  int fired = 0, checked = 0;
  for (const int d : flip_offsets()) {
    const bool fires = scalar(std::bit_cast<float>(static_cast<std::uint32_t>(static_cast<std::int64_t>(b) + d)));
    const auto maps = both_maps(z, w, h, k, p);
    CAPTURE(d);
    CHECK(z[i] > 0.f);
    CHECK(maps.first == maps.second);
    CHECK(((maps.second[ic] & bit) != 0) == fires);
    fired += fires;
    ++checked;
  }
  CHECK(fired > 0);  // both decisions were seen
  CHECK(fired < checked);
}
}  // namespace

TEST_CASE("detect_edges: the row kernel's arm scans decide a point at the straightness bound as the scalar test does") {
  // A roof whose crease column C is a corner edge; one inner point P of C's left arm is moved
  // away from the arm's chord until the arm stops being straight.  The depth at which the scalar
  // test's decision flips is found by bisection over floats; depths within a few thousand ulps of
  // it put P's distance within the row kernel's 1e-4 band of doubt around the bound, where the
  // shortcut cannot decide and the exact expression must.  Every pixel must match at each depth.
  // 21 rows: the vertical and diagonal arms lack the 16 neighbours a corner test needs, so C's
  // corner bit in the map is the row's decision alone
  const int w = 64, h = 21, cx = 32, cy = 10, px = cx - 5;
  const intrinsics k{180.f, 180.f, 31.5f, 10.f};
  const params p = presets::thesis_full();
  std::vector<float> z(static_cast<std::size_t>(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) z[static_cast<std::size_t>(y) * w + x] = 2.0f - 0.01f * static_cast<float>(std::abs(x - cx));
  const std::size_t ip = static_cast<std::size_t>(cy) * w + px, ic = static_cast<std::size_t>(cy) * w + cx;
  const float z0 = z[ip];
  const detail::edge_set set = detail::make_edge_set(p);
  const auto corner_at_c = row_test(z, w, h, k, set.corner, ip, ic);  // the scalar test along the row
  REQUIRE(corner_at_c(z0));  // the crease is a corner, and no longer with P 5 cm off its arm:
  check_flip(z, ip, z0, z0 + 0.05f, w, h, k, p, ic, edge_type::corner::bit, corner_at_c);
}

TEST_CASE("detect_edges: the row kernel's corner bend decides a crease at its bound as the scalar test does") {
  // A shallow V (3 mm a column), too shallow for a corner at its crease C; C is moved deeper until
  // the bend (C's distance from the chord between C - 8 and C + 8) exceeds the test's bound, while
  // both arms stay well within their straightness bound.  The flip is found by bisection over
  // floats; within a few thousand ulps of it the row kernel's judgement of the bend is in doubt
  // and the exact expression must decide.  21 rows, as above.
  const int w = 64, h = 21, cx = 32, cy = 10;
  const intrinsics k{180.f, 180.f, 31.5f, 10.f};
  const params p = presets::thesis_full();
  const detail::edge_set set = detail::make_edge_set(p);
  std::vector<float> z(static_cast<std::size_t>(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) z[static_cast<std::size_t>(y) * w + x] = 2.0f - 0.003f * static_cast<float>(std::abs(x - cx));
  const std::size_t ic = static_cast<std::size_t>(cy) * w + cx;
  const auto corner_at_c = row_test(z, w, h, k, set.corner, ic, ic);  // the scalar test along the row
  const float z0 = z[ic];
  REQUIRE(!corner_at_c(z0));
  check_flip(z, ic, z0, z0 + 0.004f, w, h, k, p, ic, edge_type::corner::bit, corner_at_c);
}

TEST_CASE("detect_edges: the row kernel's arc test decides a point at its bound as the scalar test does") {
  // Flat up to column 24, a parabola bending toward the camera after it: column C = 22 is a curved
  // edge (its right arm the arc, its left arm straight).  One point P of the arc is moved until C
  // is no longer one, the flip found by bisection over floats: the quarter point (its distance
  // from the arc's chord falls below 0.6 of the midpoint's), the three-quarter point, and the
  // midpoint (whose distance the sagitta and both ratios use).  Within a few thousand ulps of a
  // flip the row kernel's judgement of that condition is in doubt and the exact expressions must
  // decide.  15 rows: the vertical and diagonal arms lack the 8 neighbours a curved test needs.
  // Mirrored too (the arc on C's left): the row kernel judges each arc's sagitta once for both of
  // its ends (arc_flat_rows_kernel), from differences taken about the midpoint, which neither
  // end's scalar test takes.
  const int w = 48, h = 15, cy = 7;
  const intrinsics k{180.f, 180.f, 23.5f, 7.f};  // the principal point mid-row: the mirror is exact
  const params p = presets::thesis_full();
  const detail::edge_set set = detail::make_edge_set(p);
  const struct {
    int px;
    float dz;  // a move of P that ends the curved edge at C
  } moves[] = {{2, -0.005f}, {6, -0.02f}, {4, 0.005f}};  // P's column: C's, this many columns into the arc
  for (const bool mirror : {false, true})
  for (const auto& mv : moves) {
    const auto col = [&](int x) { return mirror ? w - 1 - x : x; };
    const int cx = col(22), px = col(22 + mv.px);
    CAPTURE(mirror);
    CAPTURE(px);
    const std::size_t ic = static_cast<std::size_t>(cy) * w + cx;
    std::vector<float> z(static_cast<std::size_t>(w) * h);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const float u = static_cast<float>(std::max(0, col(x) - 24));
        z[static_cast<std::size_t>(y) * w + x] = 2.0f - 0.004f * u * u;
      }
    const std::size_t ip = static_cast<std::size_t>(cy) * w + px;
    const auto curved_at_c = row_test(z, w, h, k, set.curved, ip, ic);  // the scalar test along the row
    REQUIRE(curved_at_c(z[ip]));
    check_flip(z, ip, z[ip], z[ip] + mv.dz, w, h, k, p, ic, edge_type::curved::bit, curved_at_c);
  }
}

TEST_CASE("arc_flat_rows_kernel: a triple judged surely within is not an arc for the scalar test at either end") {
  // Random triples (a, q, b), q off the chord ab by a fraction of the curved test's bound
  // t |b - a| + noise: mostly near 1 (both sides of the bound), some far inside, and some with q
  // far out along the line (where the rounding of cross products about q, and about each end,
  // are far apart).  Wherever the shared judgement for an end is sure, farther_than there (the
  // scalar test's first condition, with that end's noise) must be false.
  edgeplane_test::lcg_noise rng(11);
  const detail::noise_sigma sigma{0.0015f, 0.0015f};
  int sure = 0, sure_near = 0, beyond = 0;
  for (int i = 0; i < 200000; ++i) {
    const float t = std::pow(10.f, -3.f + 2.5f * static_cast<float>(rng.uniform01())), noise_k = 2.f * static_cast<float>(rng.uniform01());
    const detail::point3 a{rng(3.f), rng(2.f), 0.3f + 8.f * static_cast<float>(rng.uniform01())};
    detail::point3 dir{rng(1.f), rng(1.f), rng(1.f)};
    dir = (1.f / detail::norm(dir)) * dir;
    const float chord = std::pow(10.f, -3.f + 3.3f * static_cast<float>(rng.uniform01()));
    const detail::point3 b = a + chord * dir;
    if (!(b.z > 0.f)) continue;
    const float na = noise_k * sigma(a.z), nb = noise_k * sigma(b.z);
    detail::point3 perp{rng(1.f), rng(1.f), rng(1.f)};
    perp = perp - detail::dot(perp, dir) * dir;
    if (detail::norm(perp) < 1e-3f) continue;
    perp = (1.f / detail::norm(perp)) * perp;
    const int kind = static_cast<int>(rng.next_u32(10));
    const float along = kind == 0 ? 1e4f * rng(1.f) : 0.5f + rng(0.3f);  // q's place along ab, in chords
    const float ratio = kind == 1 ? 0.5f * static_cast<float>(rng.uniform01()) : 1.f + rng(0.03f);
    const detail::point3 q = a + (along * chord) * dir + (ratio * (t * chord + (rng.uniform01() < 0.5 ? na : nb))) * perp;
    const unsigned in = detail::arc_flat_rows_kernel<16>::surely_within(a, q, b, t, na, nb);
    for (int end = 0; end < 2; ++end) {  // bit 0: judged for a (its noise), bit 1: for b
      if (!((in >> end) & 1u)) continue;
      ++sure;
      sure_near += kind > 1 && ratio > 0.98f;
      const bool fires = end == 0 ? detail::farther_than(q, a, b, t, na) : detail::farther_than(q, b, a, t, nb);
      beyond += fires;
      if (fires) {
        CAPTURE(i);
        CAPTURE(end);
        CAPTURE(ratio);
        CAPTURE(along);
        CHECK(!fires);
      }
    }
  }
  CHECK(beyond == 0);
  CHECK(sure > 20000);      // it does judge: points well inside...
  CHECK(sure_near > 1000);  // ...and near the bound
}

// The row kernel keeps a lane's extrema, corner and curved pre-tests open only where both of its
// neighbour counts reach the test's arm, comparing 8 count bytes at a time.
TEST_CASE("swar::bytes_at_least: bit i is byte i >= t, for every count, threshold and byte position") {
  lcg_noise noise(5);
  int wrong = 0, calls = 0;
  for (int t = -3; t <= 131; ++t)      // below 0 and above 127 included
    for (int v = 0; v < 128; ++v)      // counts are at most 127
      for (int pos = 0; pos < 8; ++pos) {
        std::uint8_t b[8];
        std::uint64_t x = 0;
        for (int i = 0; i < 8; ++i) {  // v at pos, random counts elsewhere
          b[i] = i == pos ? static_cast<std::uint8_t>(v) : static_cast<std::uint8_t>(noise.next_u32(128));
          x |= static_cast<std::uint64_t>(b[i]) << (8 * i);
        }
        unsigned want = 0;
        for (int i = 0; i < 8; ++i) want |= static_cast<unsigned>(b[i] >= t) << i;
        const unsigned got = detail::swar::bytes_at_least(x, t);
        wrong += got != want;
        ++calls;
        if (got != want && wrong <= 3) {
          CAPTURE(t);
          CAPTURE(x);
          CHECK(got == want);
        }
      }
  CHECK(calls == 135 * 128 * 8);
  CHECK(wrong == 0);
}

TEST_CASE("swar::nonzero_bytes: bit i is byte i != 0, for every byte value and position") {
  lcg_noise noise(9);
  int wrong = 0, calls = 0;
  for (int v = 0; v < 256; ++v)
    for (int pos = 0; pos < 8; ++pos)
      for (int rep = 0; rep < 16; ++rep) {
        std::uint64_t x = 0;
        unsigned want = 0;
        for (int i = 0; i < 8; ++i) {  // v at pos; elsewhere 0, 0x80 or any byte
          const unsigned pick = noise.next_u32(4);
          const unsigned b = i == pos ? static_cast<unsigned>(v) : pick == 0 ? 0u : pick == 1 ? 0x80u : noise.next_u32(256);
          x |= static_cast<std::uint64_t>(b) << (8 * i);
          want |= static_cast<unsigned>(b != 0) << i;
        }
        const unsigned got = detail::swar::nonzero_bytes(x);
        wrong += got != want;
        ++calls;
        if (got != want && wrong <= 3) {
          CAPTURE(x);
          CHECK(got == want);
        }
      }
  CHECK(calls == 256 * 8 * 16);
  CHECK(wrong == 0);
}

// The valid-neighbour counts the host edge pass reads: plane 2 d + s holds, for every pixel, how
// many consecutive valid pixels follow it on side s of direction d (at most r, stopping at the
// border), counted here one by one.
TEST_CASE("valid_runs kernels count each pixel's valid neighbours on all eight sides") {
  // bands of 8, 16 and 32 rows: band boundaries, and a short last band; 70 columns: every 64-pixel block of
  // the rows pass has its window cut by the row's ends; 230: blocks that read the row in place;
  // 207: at r = 16 the block at 128 ends its window one pixel past the row (so it must copy)
  for (const int w : {70, 207, 230}) {
  CAPTURE(w);
  const int h = 75;
  std::vector<float> z(static_cast<std::size_t>(w) * h, 1.5f);
  lcg_noise noise(11);
  for (int i = 0; i < w * h / 6; ++i) z[noise.next_u32(static_cast<std::uint32_t>(w * h))] = 0.f;
  for (int x = 10; x < 40; ++x) z[static_cast<std::size_t>(20) * w + x] = 0.f;  // a line, and one that ends at the border
  for (int y = 0; y < 30; ++y) z[static_cast<std::size_t>(y) * w + 50] = 0.f;
  const auto zv = make_view<const float>(z.data(), w, h);
  const int dxs[4] = {1, 0, 1, -1}, dys[4] = {0, 1, 1, 1};  // horizontal, vertical, left and right diagonal
  for (const int band : {8, 16, 32})
  for (const int r : {1, 5, 16, 32}) {
    CAPTURE(band);
    CAPTURE(r);
    std::vector<std::uint8_t> runs(static_cast<std::size_t>(8) * w * h, 0xab), valid(static_cast<std::size_t>(w) * h, 0xa5);  // garbage with bit 0 set: read as valid
    const cpu b{};
    b.for_each_index(h, detail::valid_runs_rows_kernel{zv, runs.data(), r, valid.data()});
    b.for_each_index(6 * ((h + band - 1) / band), detail::valid_runs_bands_kernel{zv, runs.data(), r, band, valid.data()});
    int wrong_valid = 0;
    for (int i = 0; i < w * h; ++i)
      wrong_valid += valid[static_cast<std::size_t>(i)] != (z[static_cast<std::size_t>(i)] > 0.f ? 0xff : 0);
    CHECK(wrong_valid == 0);
    int wrong = 0, full = 0;
    for (int d = 0; d < 4; ++d)
      for (int s = 0; s < 2; ++s)
        for (int y = 0; y < h; ++y)
          for (int x = 0; x < w; ++x) {
            const int sx = s == 0 ? -dxs[d] : dxs[d], sy = s == 0 ? -dys[d] : dys[d];
            int c = 0;
            while (c < r) {
              const int u = x + (c + 1) * sx, v = y + (c + 1) * sy;
              if (u < 0 || u >= w || v < 0 || v >= h || !(zv(u, v) > 0.f)) break;
              ++c;
            }
            wrong += runs[static_cast<std::size_t>(2 * d + s) * w * h + static_cast<std::size_t>(y) * w + x] != c;
            full += c == r;
          }
    CHECK(wrong == 0);
    CHECK(full > 0);  // not all counts cut short
  }
  }
}

TEST_CASE("valid_runs_band: bands of 32 rows, shorter where the six planes would make too few work items") {
  // The CPU backend runs fewer than host_parallel_items work items on one core.
  CHECK(detail::valid_runs_band(424) == 32);
  CHECK(detail::valid_runs_band(480) == 32);
  CHECK(detail::valid_runs_band(212) == 16);  // 42 work items of 32 rows
  CHECK(detail::valid_runs_band(1) == 8);
  for (int h = 1; h <= 1000; ++h) {
    const int band = detail::valid_runs_band(h);
    CAPTURE(h);
    REQUIRE((band == 8 || band == 16 || band == 32));
    const std::int64_t items = 6 * ((h + band - 1) / band);
    CHECK((items >= detail::host_parallel_items || band == 8));  // enough items, or the shortest band
    if (band < 32) CHECK(6 * ((h + 2 * band - 1) / (2 * band)) < detail::host_parallel_items);  // no longer band would do
  }
}

TEST_CASE("detect_edges: arms longer than 32 neighbours are refused with a clear error") {
  const int w = 40, h = 30;
  std::vector<float> z(static_cast<std::size_t>(w) * h, 1.5f);
  std::vector<std::uint8_t> e(z.size(), 0);
  params p = presets::thesis_full();
  p.n_coe = 33;
  CHECK_THROWS_AS(detect_edges(cpu{}, make_view<const float>(z.data(), w, h), camera(w, h), p, make_view(e.data(), w, h)),
                  edgeplane::error);
  p.n_coe = 32;  // the largest validate() allows still runs
  CHECK_NOTHROW(detect_edges(cpu{}, make_view<const float>(z.data(), w, h), camera(w, h), p, make_view(e.data(), w, h)));
}
