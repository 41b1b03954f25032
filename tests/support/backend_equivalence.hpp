// edgeplane tests: one backend against the CPU backend on the same input, written once and
// compiled by g++ (tests/pipeline/test_device_path.cpp, on the device-path model of
// support/device_model.hpp) and by nvcc (tests/cuda/test_cuda_backend.cu, on edgeplane::cuda).
//
//   check_union_find_matches_cpu(b)    random pair lists: the CPU's parent array exactly
//   check_kernels_match_cpu(b)         every kernel stage on three scenes x two presets: identical
//   check_label_kernels_match_cpu(b)   the final-label kernels (sweep and one-pixel growth, label
//                                      closing), launch by launch: identical
//   check_segmenter_matches_cpu(b)     the segmenter: labels equal up to renumbering, planes within
//                                      float tolerance, twice through one segmenter
//   check_segmenter_inputs_match_cpu(b) float depth, pitched rows, half resolution at odd sizes,
//                                      changing sizes, backend pointers in and out, all-invalid
//   check_pipeline_matches_cpu(lanes)  frames in flight on a pipeline of these lanes (for CUDA: one
//                                      stream each) give the CPU segmenter's results, in order
//
// Bit-identical kernels are demanded because every float operation of the kernels is an IEEE
// + - * / or sqrtf (the CUDA build compiles with --fmad=false), and moments are integer sums.
#pragma once
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "edgeplane/edgeplane.hpp"
#include "support/labels_equal.hpp"
#include "support/scenes.hpp"
#include "support/test_backends.hpp"

namespace edgeplane_test::equivalence {

namespace ep = edgeplane;

/// The scene frame of the tests: Kinect-v2-like intrinsics, noise sigma(z) = 1.5 mm + 0.5 mm z^2
/// and 2 % pepper holes.
inline ep::test::rendered frame(const ep::test::scene& s, const ep::test::camera_pose& pose, int w, int h,
                                std::uint64_t seed) {
  return ep::test::render(s, pose, w, h, ep::test::kinect2_intrinsics(w, h), {0.0015, 0.0005, 0.02, seed});
}

struct named_scene {
  const char* name;
  ep::test::scene s;
  ep::test::camera_pose pose;
};
inline std::vector<named_scene> scenes() {
  return {{"room_with_box", ep::test::room_with_box(), ep::test::room_camera()},
          {"stairs_scene", ep::test::stairs_scene(), ep::test::stairs_camera()},
          {"cylinder_scene", ep::test::cylinder_scene(), ep::test::cylinder_camera()}};
}

/// Number of positions where two equally long arrays differ (-1 when the lengths differ).
template <class T>
long long differing(const std::vector<T>& a, const std::vector<T>& b) {
  if (a.size() != b.size()) return -1;
  long long n = 0;
  for (std::size_t i = 0; i < a.size(); ++i) n += !(a[i] == b[i]);
  return n;
}

/// Active where a byte mask (backend memory) is non-zero.
struct mask_active {
  const std::uint8_t* on;
  EDGEPLANE_HD bool operator()(std::int64_t i) const { return on[i] != 0; }
};

// ---- union-find --------------------------------------------------------------------------------

/// Random pair lists (up to 450 000 elements, sparse and dense unions, long local chains and far
/// pairs, about 10 % inactive elements) give exactly the serial CPU's parent array, three times over.
template <class B>
void check_union_find_matches_cpu(const B& g) {
  edgeplane_test::lcg_noise rng(17);
  const ep::cpu c{ep::cpu::mode::serial};
  for (int trial = 0; trial < 4; ++trial) {
    CAPTURE(trial);
    const int n = 1000 + 150000 * trial, m = trial % 2 ? n / 2 : 2 * n;
    std::vector<std::uint8_t> on(static_cast<std::size_t>(n));
    for (auto& v : on) v = rng.next_u32(10) != 0 ? 1 : 0;
    std::vector<std::int32_t> a, b;
    while (static_cast<int>(a.size()) < m) {
      const auto x = static_cast<std::int32_t>(rng.next_u32(static_cast<std::uint32_t>(n)));
      const auto y = rng.next_u32(4) != 0
                         ? std::min<std::int32_t>(n - 1, x + static_cast<std::int32_t>(rng.next_u32(8)))
                         : static_cast<std::int32_t>(rng.next_u32(static_cast<std::uint32_t>(n)));
      if (!on[x] || !on[y]) continue;
      a.push_back(x);
      b.push_back(y);
    }
    auto run = [&](const auto& be) {
      using BE = std::decay_t<decltype(be)>;
      device_array<std::uint8_t, BE> act(be, on);
      device_array<std::int32_t, BE> fa(be, a), fb(be, b), parent(be, static_cast<std::size_t>(n), -7);
      ep::connected_components(be, n, mask_active{act.data()}, static_cast<std::int64_t>(a.size()),
                               ep::detail::pair_list_adjacency{fa.data(), fb.data()}, parent.data());
      return parent.host();
    };
    const auto want = run(c);
    for (int rep = 0; rep < 3; ++rep) CHECK(differing(run(g), want) == 0);
  }
}

// ---- every kernel stage on one backend -----------------------------------------------------------

struct kernel_outputs {
  std::vector<float> converted, closed, smoothed;
  std::vector<std::uint8_t> edges, typed_edges, mask, cov_l, cov_r;
  std::vector<std::int32_t> parent;
  std::vector<std::uint64_t> moments;
  std::vector<std::int32_t> bbox;
};

/// Runs the pipeline's kernels one after the other on backend b (millimetre depth in, the frame's
/// ground-truth ids as the label image of the moments) and downloads every intermediate image.
template <class B>
kernel_outputs run_kernels(const B& b, const ep::test::rendered& r, const std::vector<std::uint16_t>& mm,
                           const std::vector<std::uint16_t>& gt, std::int32_t num_gt, const ep::params& p) {
  const int w = r.width, h = r.height;
  const std::size_t n = mm.size();
  device_array<std::uint16_t, B> raw(b, mm), labels(b, gt);
  device_array<float, B> za(b, n, -1.f), zb(b, n, -1.f), zc(b, n, -1.f), zs(b, n, -1.f);
  ep::convert_depth(b, raw.cview(w, h), 0.001f, p.min_depth, p.max_depth, za.view(w, h));
  ep::close_depth(b, za.view(w, h), zb.view(w, h), zc.view(w, h), p.depth_closing_radius);
  ep::smooth_depth(b, zc.cview(w, h), zs.view(w, h), p.smooth_radius, p.smooth_k, p.noise.sigma0, p.noise.sigma2);

  device_array<std::uint8_t, B> edges(b, n, 0xee), typed(b, n, 0), scratch(b, n, 0xee), mask(b, n, 0xee),
      cov_l(b, n, 0xee), cov_r(b, n, 0xee);
  ep::detect_edges(b, zs.cview(w, h), r.k, p, edges.view(w, h));
  // the per-(direction, type) kernels: each type along one diagonal
  const ep::detail::edge_set set = ep::detail::make_edge_set(p);
  ep::detect_edge<ep::direction::left_diagonal>(b, zs.cview(w, h), r.k, set.jump, typed.view(w, h));
  ep::detect_edge<ep::direction::left_diagonal>(b, zs.cview(w, h), r.k, set.extrema, typed.view(w, h));
  ep::detect_edge<ep::direction::left_diagonal>(b, zs.cview(w, h), r.k, set.corner, typed.view(w, h));
  ep::detect_edge<ep::direction::left_diagonal>(b, zs.cview(w, h), r.k, set.curved, typed.view(w, h));
  ep::close_edges(b, edges.cview(w, h), scratch.view(w, h), mask.view(w, h), p.edge_closing_radius);

  ep::extract_segments<ep::direction::left_diagonal>(b, zs.cview(w, h), mask.cview(w, h), r.k, p, cov_l.view(w, h));
  ep::extract_segments<ep::direction::right_diagonal>(b, zs.cview(w, h), mask.cview(w, h), r.k, p,
                                                      cov_r.view(w, h));

  device_array<std::int32_t, B> parent(b, n, -7);
  const ep::detail::covered_active covered{cov_l.data(), cov_r.data()};
  const float slope_inv_f = p.adjacency_slope / std::min(std::abs(r.k.fx), std::abs(r.k.fy));
  ep::connected_components(
      b, static_cast<std::int64_t>(n), covered, static_cast<std::int64_t>(n),
      ep::detail::grid4_adjacency<ep::detail::covered_active>{zs.cview(w, h), covered, p.t_je, p.t_je_quad, slope_inv_f},
      parent.data());

  device_array<std::uint64_t, B> moments(b, static_cast<std::size_t>(num_gt + 1) * ep::moment_slots, 0xabcdef);
  device_array<std::int32_t, B> bbox(b, static_cast<std::size_t>(num_gt + 1) * 4, 12345);
  ep::accumulate_moments(b, zs.cview(w, h), r.k, ep::detail::image_labels{labels.cview(w, h)}, num_gt,
                         moments.data(), bbox.data());

  return {za.host(),    zc.host(),    zs.host(),     edges.host(),   typed.host(), mask.host(),
          cov_l.host(), cov_r.host(), parent.host(), moments.host(), bbox.host()};
}

/// Every kernel stage on b against the CPU backend, on three scenes under thesis_full and kinect2:
/// filters, edges (fused and per type), edge closing, both diagonal segment passes, the candidate
/// union-find and the moments and boxes must be identical.
template <class B>
void check_kernels_match_cpu(const B& b) {
  for (const auto& sc : scenes())
    for (const std::string preset : {"thesis_full", "kinect2"}) {
      const std::string scene = sc.name;
      CAPTURE(scene);
      CAPTURE(preset);
      const ep::params p = ep::preset(preset);
      const ep::test::rendered r = frame(sc.s, sc.pose, 512, 424, 42);
      const auto mm = r.depth_mm();
      // the ground-truth ids (planes and the cylinder's side), renumbered 1..num_gt, as the label
      // image of the moments
      std::vector<std::uint16_t> gt(r.gt.size());
      std::vector<int> ids;
      for (const int id : r.gt)
        if (id != 0 && std::find(ids.begin(), ids.end(), id) == ids.end()) ids.push_back(id);
      for (std::size_t i = 0; i < gt.size(); ++i)
        gt[i] = r.gt[i] != 0 ? static_cast<std::uint16_t>(std::find(ids.begin(), ids.end(), r.gt[i]) - ids.begin() + 1)
                             : 0;
      const auto num_gt = static_cast<std::int32_t>(ids.size());

      const kernel_outputs c = run_kernels(ep::cpu{}, r, mm, gt, num_gt, p);
      const kernel_outputs g = run_kernels(b, r, mm, gt, num_gt, p);
      // stage by stage: the first CHECK that fails names the kernel that differs
      CHECK(differing(g.converted, c.converted) == 0);
      CHECK(differing(g.closed, c.closed) == 0);
      CHECK(differing(g.smoothed, c.smoothed) == 0);
      CHECK(differing(g.edges, c.edges) == 0);
      CHECK(differing(g.typed_edges, c.typed_edges) == 0);
      CHECK(differing(g.mask, c.mask) == 0);
      CHECK(differing(g.cov_l, c.cov_l) == 0);
      CHECK(differing(g.cov_r, c.cov_r) == 0);
      CHECK(differing(g.parent, c.parent) == 0);
      CHECK(differing(g.moments, c.moments) == 0);
      CHECK(differing(g.bbox, c.bbox) == 0);
      // the scene exercised every stage
      CHECK(std::count_if(c.edges.begin(), c.edges.end(),
                          [](std::uint8_t e) { return e != 0 && e != ep::edge_invalid; }) > 1000);
      CHECK(std::count(c.cov_l.begin(), c.cov_l.end(), std::uint8_t(1)) > 10000);
      CHECK(num_gt >= 3);
    }
}

/// The final-label kernels on b against the CPU backend, launch by launch, on a 512x424 frame of
/// three planes (noise, 2 % holes) with sparse seeds: rounds of row and column sweeps with their
/// line flags (labels, flags and `changed` after every launch), rounds of one-pixel growth, and
/// the label closing.  Seeds lie anywhere on their rows, so labels travel both ways along a line.
template <class B>
void check_label_kernels_match_cpu(const B& b) {
  const int w = 512, h = 424;
  const ep::intrinsics k{365.5f, 365.5f, 254.9f, 205.4f};
  const auto proj = ep::detail::make_projector(k);
  const auto sigma = ep::detail::make_noise(ep::presets::kinect2().noise);
  // planes n . X + d = 0: a floor (rows below 250), a wall and a slanted face
  const std::vector<float> planes = {0, 0, 0, 0, 0, -0.8f, -0.6f, 1.5f, 0, 0, -1, 2.5f, 0.6f, 0, -0.8f, 1.8f};
  const std::vector<float> caps = {0.f, 0.02f, 0.02f, 0.02f};
  std::vector<float> z(static_cast<std::size_t>(w) * h);
  std::vector<std::uint16_t> seeds(z.size(), 0);
  lcg_noise rng(77);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const int l = y > 250 ? 1 : (x < 300 ? 2 : 3);
      const float* q = &planes[4 * static_cast<std::size_t>(l)];
      const float den = q[0] * (x - k.cx) / k.fx + q[1] * (y - k.cy) / k.fy + q[2];
      float d = den != 0.f ? -q[3] / den : 0.f;
      if (!(d > 0.3f && d < 8.f)) d = 0.f;
      d += static_cast<float>(rng.uniform01() - 0.5) * 0.02f;
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      z[i] = rng.uniform01() < 0.02 ? 0.f : d;
      if (rng.uniform01() < 0.01) seeds[i] = static_cast<std::uint16_t>(l);
    }
  const ep::cpu c{};
  device_array<float, ep::cpu> cz(c, z), cpl(c, planes), ccap(c, caps);
  device_array<float, B> gz(b, z), gpl(b, planes), gcap(b, caps);
  SUBCASE("sweeps with line flags") {
    device_array<std::uint16_t, ep::cpu> cl(c, seeds);
    device_array<std::uint16_t, B> gl(b, seeds);
    device_array<std::int32_t, ep::cpu> cdirty(c, static_cast<std::size_t>(w + h), -1), cflag(c, 1, 0);
    device_array<std::int32_t, B> gdirty(b, static_cast<std::size_t>(w + h), -1), gflag(b, 1, 0);
    int rounds = 0;
    for (bool more = true; more && rounds < 64; ++rounds) {
      for (int axis = 0; axis < 2; ++axis) {
        CAPTURE(rounds);
        CAPTURE(axis);
        const auto before = cl.host();
        if (axis == 0) {
          c.for_each_index(h, ep::detail::grow_sweep_kernel<0>{cz.cview(w, h), cl.view(w, h), proj, sigma, 3.f,
                                                               cpl.data(), ccap.data(), cflag.data(), cdirty.data()});
          b.for_each_index(h, ep::detail::grow_sweep_kernel<0>{gz.cview(w, h), gl.view(w, h), proj, sigma, 3.f,
                                                               gpl.data(), gcap.data(), gflag.data(), gdirty.data()});
        } else {
          c.for_each_index(w, ep::detail::grow_sweep_kernel<1>{cz.cview(w, h), cl.view(w, h), proj, sigma, 3.f,
                                                               cpl.data(), ccap.data(), cflag.data(), cdirty.data()});
          b.for_each_index(w, ep::detail::grow_sweep_kernel<1>{gz.cview(w, h), gl.view(w, h), proj, sigma, 3.f,
                                                               gpl.data(), gcap.data(), gflag.data(), gdirty.data()});
        }
        const auto after = cl.host();
        if (rounds == 0) CHECK(differing(after, before) > 10000);  // the first sweeps label a lot
        REQUIRE(differing(gl.host(), after) == 0);
        REQUIRE(differing(gdirty.host(), cdirty.host()) == 0);
      }
      REQUIRE(gflag.host() == cflag.host());
      more = cflag.host()[0] != 0;
      cflag = device_array<std::int32_t, ep::cpu>(c, 1, 0);
      gflag = device_array<std::int32_t, B>(b, 1, 0);
    }
    CHECK(rounds >= 2);
    CHECK(rounds < 64);
  }
  SUBCASE("one-pixel growth rounds and the label closing") {
    device_array<std::uint16_t, ep::cpu> ca(c, seeds), cb(c, seeds.size(), 0), cc(c, seeds.size(), 0);
    device_array<std::uint16_t, B> ga(b, seeds), gb(b, seeds.size(), 0), gc(b, seeds.size(), 0);
    device_array<std::int32_t, ep::cpu> cflag(c, 1, 0);
    device_array<std::int32_t, B> gflag(b, 1, 0);
    for (int round = 0; round < 6; ++round) {
      CAPTURE(round);
      const bool even = round % 2 == 0;
      ep::detail::for_each_pixel(c, w, h,
                                 ep::detail::grow_kernel{cz.cview(w, h), (even ? ca : cb).cview(w, h),
                                                         (even ? cb : ca).view(w, h), proj, sigma, 3.f, cpl.data(),
                                                         ccap.data(), cflag.data()});
      ep::detail::for_each_pixel(b, w, h,
                                 ep::detail::grow_kernel{gz.cview(w, h), (even ? ga : gb).cview(w, h),
                                                         (even ? gb : ga).view(w, h), proj, sigma, 3.f, gpl.data(),
                                                         gcap.data(), gflag.data()});
      REQUIRE(differing(gb.host(), cb.host()) == 0);
      REQUIRE(differing(ga.host(), ca.host()) == 0);
    }
    CHECK(gflag.host() == cflag.host());
    CHECK(differing(ca.host(), seeds) > 10000);
    for (const int r : {1, 2}) {
      CAPTURE(r);
      ep::close_labels(c, ca.cview(w, h), cb.view(w, h), cc.view(w, h), r);
      ep::close_labels(b, ga.cview(w, h), gb.view(w, h), gc.view(w, h), r);
      CHECK(differing(gc.host(), cc.host()) == 0);
      CHECK(differing(cc.host(), ca.host()) > 0);  // the closing filled something
    }
  }
}

// ---- the segmenter on one backend ----------------------------------------------------------------

struct segmenter_output {
  std::vector<std::uint16_t> labels;  // dense w x h
  ep::segmentation_result result;
  std::vector<std::uint8_t> edge_map, edge_mask;
};

/// Downloads the segmenter's edge map and mask of its last frame into o.
template <class B>
void download_edges(const ep::segmenter<B>& seg, segmenter_output& o) {
  const auto em = seg.edge_map(), mk = seg.edge_mask();
  o.edge_map.resize(static_cast<std::size_t>(em.pixels()));
  o.edge_mask.resize(static_cast<std::size_t>(mk.pixels()));
  seg.backend().copy_to_host(o.edge_map.data(), em.data, o.edge_map.size());
  seg.backend().copy_to_host(o.edge_mask.data(), mk.data, o.edge_mask.size());
}

/// Segments `depth` (w x h, stored with row pitch `pitch` elements; labels get the same pitch) and
/// downloads the labels and the segmenter's edge map and mask.  The label rows' padding must be
/// left untouched.
template <class B, class In>
segmenter_output segment(ep::segmenter<B>& seg, const std::vector<In>& depth, float scale, const ep::intrinsics& k,
                         int w, int h, int pitch) {
  std::vector<std::uint16_t> padded(static_cast<std::size_t>(pitch) * h, 0xbeef);
  segmenter_output o;
  seg.segment(ep::make_view(depth.data(), w, h, pitch), scale, k, ep::make_view(padded.data(), w, h, pitch), o.result);
  o.labels.resize(static_cast<std::size_t>(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      o.labels[static_cast<std::size_t>(y) * w + x] = padded[static_cast<std::size_t>(y) * pitch + x];
      if (x == w - 1 && pitch > w) REQUIRE(padded[static_cast<std::size_t>(y) * pitch + w] == 0xbeef);
    }
  download_edges(seg, o);
  return o;
}

/// Depth of a rendered frame in millimetres, stored with row pitch `pitch` (padding 0xffff).
inline std::vector<std::uint16_t> pitched_mm(const ep::test::rendered& r, int pitch) {
  const auto mm = r.depth_mm();
  std::vector<std::uint16_t> out(static_cast<std::size_t>(pitch) * r.height, 0xffff);
  for (int y = 0; y < r.height; ++y)
    std::copy_n(mm.begin() + static_cast<std::ptrdiff_t>(y) * r.width, r.width,
                out.begin() + static_cast<std::ptrdiff_t>(y) * pitch);
  return out;
}

inline bool close_to(float a, float b, float tol) { return std::abs(a - b) <= tol; }

/// g must be c: same candidate counts, same edge map and mask, labels equal up to renumbering, and
/// each plane (matched through the labels) with the same counts and box and its equation,
/// centroid and eigenvalues within float tolerance.
inline void check_same_segmentation(const segmenter_output& c, const segmenter_output& g) {
  CHECK(g.result.candidates == c.result.candidates);
  CHECK(g.result.valid_candidates == c.result.valid_candidates);
  CHECK(differing(g.edge_map, c.edge_map) == 0);
  CHECK(differing(g.edge_mask, c.edge_mask) == 0);
  const auto corr = edgeplane_test::correspond(g.labels, c.labels);  // g id -> c id
  CAPTURE(corr.conflicts);
  CHECK(corr.equal);
  REQUIRE(g.result.planes.size() == c.result.planes.size());
  for (const ep::plane& gp : g.result.planes) {
    CAPTURE(gp.id);
    const auto it = corr.a_to_b.find(gp.id);
    const std::int64_t cpu_id = it != corr.a_to_b.end() ? it->second : gp.id;  // planes left without pixels keep ids
    const auto cp = std::find_if(c.result.planes.begin(), c.result.planes.end(),
                                 [&](const ep::plane& q) { return q.id == cpu_id; });
    REQUIRE(cp != c.result.planes.end());
    CHECK(gp.pixels == cp->pixels);
    CHECK(gp.points == cp->points);
    CHECK(gp.bbox == cp->bbox);
    CHECK(close_to(gp.d, cp->d, 1e-5f));
    for (int j = 0; j < 3; ++j) {
      CHECK(close_to(gp.normal[j], cp->normal[j], 1e-5f));
      CHECK(close_to(gp.centroid[j], cp->centroid[j], 1e-5f));
      CHECK(close_to(gp.eigenvalues[j], cp->eigenvalues[j], 1e-7f + 1e-4f * std::abs(cp->eigenvalues[j])));
    }
  }
}

/// The segmenter on b against the CPU segmenter on three scenes under thesis_full and kinect2, and
/// a second frame through the same segmenter (scratch memory reused).
template <class B>
void check_segmenter_matches_cpu(const B& b) {
  for (const auto& sc : scenes())
    for (const std::string preset : {"thesis_full", "kinect2"}) {
      const std::string scene = sc.name;
      CAPTURE(scene);
      CAPTURE(preset);
      const ep::test::rendered r = frame(sc.s, sc.pose, 512, 424, 7);
      const auto mm = r.depth_mm();
      ep::segmenter<ep::cpu> cs(ep::preset(preset));
      ep::segmenter<B> gs(ep::preset(preset), b);
      const auto c = segment(cs, mm, 0.001f, r.k, r.width, r.height, r.width);
      const auto g = segment(gs, mm, 0.001f, r.k, r.width, r.height, r.width);
      CHECK(c.result.planes.size() >= 2);  // the scenes have planes to find
      check_same_segmentation(c, g);
      const auto g2 = segment(gs, mm, 0.001f, r.k, r.width, r.height, r.width);
      check_same_segmentation(c, g2);
    }
}

/// The segmenter on b against the CPU's for the other ways a frame comes in.
template <class B>
void check_segmenter_inputs_match_cpu(const B& b) {
  const auto sc = scenes()[0];
  SUBCASE("float metres, thesis_full") {
    const ep::test::rendered r = frame(sc.s, sc.pose, 512, 424, 3);
    ep::segmenter<ep::cpu> cs;
    ep::segmenter<B> gs(ep::presets::thesis_full(), b);
    check_same_segmentation(segment(cs, r.depth, 1.f, r.k, r.width, r.height, r.width),
                            segment(gs, r.depth, 1.f, r.k, r.width, r.height, r.width));
  }
  SUBCASE("pitched millimetres, kinect2") {
    const ep::test::rendered r = frame(sc.s, sc.pose, 640, 480, 5);
    const int pitch = 640 + 13;
    const auto mm = pitched_mm(r, pitch);
    ep::segmenter<ep::cpu> cs(ep::presets::kinect2());
    ep::segmenter<B> gs(ep::presets::kinect2(), b);
    check_same_segmentation(segment(cs, mm, 0.001f, r.k, r.width, r.height, pitch),
                            segment(gs, mm, 0.001f, r.k, r.width, r.height, pitch));
  }
  SUBCASE("thesis_half (2x downscale and upsampling) at 511 x 423") {
    const ep::test::rendered r = frame(sc.s, sc.pose, 511, 423, 9);
    const auto mm = r.depth_mm();
    ep::segmenter<ep::cpu> cs(ep::presets::thesis_half());
    ep::segmenter<B> gs(ep::presets::thesis_half(), b);
    check_same_segmentation(segment(cs, mm, 0.001f, r.k, r.width, r.height, r.width),
                            segment(gs, mm, 0.001f, r.k, r.width, r.height, r.width));
  }
  SUBCASE("one segmenter over frames of changing size") {
    ep::segmenter<B> gs(ep::presets::kinect2(), b);
    for (const auto& size : {std::pair{256, 212}, std::pair{640, 480}, std::pair{320, 240}, std::pair{640, 480}}) {
      const int w = size.first, h = size.second;  // (not a structured binding: clang 14 cannot capture one)
      CAPTURE(w);
      CAPTURE(h);
      const ep::test::rendered r = frame(sc.s, sc.pose, w, h, 11);
      const auto mm = r.depth_mm();
      ep::segmenter<ep::cpu> cs(ep::presets::kinect2());
      check_same_segmentation(segment(cs, mm, 0.001f, r.k, w, h, w), segment(gs, mm, 0.001f, r.k, w, h, w));
    }
  }
  SUBCASE("backend pointers in and out (segment_on_backend): no upload or download, the same result") {
    const ep::test::rendered r = frame(sc.s, sc.pose, 512, 424, 13);
    const int pitch = 512 + 7;
    const auto mm = pitched_mm(r, pitch);
    ep::segmenter<ep::cpu> cs(ep::presets::kinect2());
    const auto c = segment(cs, mm, 0.001f, r.k, r.width, r.height, pitch);
    ep::buffer<std::uint16_t, B> d_depth(b), d_labels(b);
    d_depth.resize(mm.size());
    d_labels.resize(mm.size());
    b.copy_from_host(d_depth.data(), mm.data(), mm.size() * sizeof(std::uint16_t));
    b.memset(d_labels.data(), 0xff, mm.size() * sizeof(std::uint16_t));
    ep::segmenter<B> gs(ep::presets::kinect2(), b);
    segmenter_output g;
    gs.segment_on_backend(ep::make_view<const std::uint16_t>(d_depth.data(), r.width, r.height, pitch), 0.001f, r.k,
                          ep::make_view(d_labels.data(), r.width, r.height, pitch), g.result);
    std::vector<std::uint16_t> padded(mm.size());
    b.copy_to_host(padded.data(), d_labels.data(), padded.size() * sizeof(std::uint16_t));
    g.labels.resize(static_cast<std::size_t>(r.width) * r.height);
    for (int y = 0; y < r.height; ++y)
      for (int x = 0; x < r.width; ++x)
        g.labels[static_cast<std::size_t>(y) * r.width + x] = padded[static_cast<std::size_t>(y) * pitch + x];
    CHECK(padded[static_cast<std::size_t>(pitch) - 1] == 0xffff);  // the row padding is untouched
    download_edges(gs, g);
    check_same_segmentation(c, g);
  }
  SUBCASE("an all-invalid frame gives no planes and all-zero labels") {
    const std::vector<std::uint16_t> zeros(64 * 48, 0);
    ep::segmenter<B> gs(ep::presets::thesis_full(), b);
    const auto g = segment(gs, zeros, 0.001f, ep::test::kinect2_intrinsics(64, 48), 64, 48, 64);
    CHECK(g.result.planes.empty());
    CHECK(std::all_of(g.labels.begin(), g.labels.end(), [](std::uint16_t l) { return l == 0; }));
  }
}

/// Nine frames (three scenes, three seeds, kinect2) streamed through a pipeline with the given
/// lanes, retrieving the oldest whenever it is full: each equals the CPU segmenter's result.
template <class B>
void check_pipeline_matches_cpu(const std::vector<B>& lanes) {
  std::vector<ep::test::rendered> frames;
  std::vector<std::vector<std::uint16_t>> mm;
  for (std::uint64_t seed = 31; seed < 34; ++seed)
    for (const auto& sc : scenes()) {
      frames.push_back(frame(sc.s, sc.pose, 512, 424, seed));
      mm.push_back(frames.back().depth_mm());
    }
  ep::segmenter<ep::cpu> cs(ep::presets::kinect2());
  ep::pipeline<B> pl(ep::presets::kinect2(), lanes);
  std::size_t next_out = 0;
  auto retrieve_one = [&] {
    CAPTURE(next_out);
    const ep::test::rendered& r = frames[next_out];
    const segmenter_output c = segment(cs, mm[next_out], 0.001f, r.k, r.width, r.height, r.width);
    segmenter_output g;
    g.labels.resize(mm[next_out].size());
    CHECK(pl.retrieve(ep::make_view(g.labels.data(), r.width, r.height), g.result) == next_out);
    // the pipeline does not expose its lanes' edge maps: compare the CPU's with itself
    g.edge_map = c.edge_map;
    g.edge_mask = c.edge_mask;
    check_same_segmentation(c, g);
    ++next_out;
  };
  for (std::size_t i = 0; i < frames.size(); ++i) {
    if (pl.full()) retrieve_one();
    pl.submit(ep::make_view<const std::uint16_t>(mm[i].data(), frames[i].width, frames[i].height), 0.001f, frames[i].k);
  }
  while (next_out < frames.size()) retrieve_one();
}

}  // namespace edgeplane_test::equivalence
