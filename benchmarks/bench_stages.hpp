// The inputs of every pipeline stage for one benchmark frame, computed once with the library's own
// stage functions on the CPU backend (the same chain segmenter runs), so that each kernel can be
// timed alone on realistic data: the depth after conversion, closing and smoothing, the edge map,
// its closing, the diagonal runs, the union-find parents, the candidate image, their moments and
// fits, and the validation flags.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "bench_frames.hpp"
#include "edgeplane/edgeplane.hpp"

namespace edgeplane::bench {

struct stage_data {
  int w = 0, h = 0;
  intrinsics k;
  params p;
  std::vector<float> z_raw, z_closed, z_smooth, zscratch;
  std::vector<std::uint8_t> edges, mask, scratch8, cov_l, cov_r;
  std::vector<std::int32_t> parent, cand;
  std::int32_t num_cand = 0;
  std::vector<std::uint64_t> moments;
  std::vector<std::int32_t> bbox;
  std::vector<plane_fit> fits;
  std::vector<char> keep;

  image_view<const float> depth() const { return make_view(z_smooth.data(), w, h); }
  detail::grid4_adjacency<detail::covered_active> adjacency() const {
    const detail::covered_active covered{cov_l.data(), cov_r.data()};
    const float slope_inv_f = p.adjacency_slope / std::min(std::abs(k.fx), std::abs(k.fy));
    return {depth(), covered, p.t_je, p.t_je_quad, slope_inv_f};
  }
};

/// Runs the stages on the room frame at w x h with preset `name` (no downscale: every stage at
/// the frame's own resolution).
inline stage_data make_stage_data(int w, int h, const char* name) {
  const frame& f = scene_at(w, h);
  const cpu b{};
  stage_data s;
  s.w = w;
  s.h = h;
  s.k = f.r.k;
  s.p = preset(name);
  s.p.downscale = false;
  const std::size_t n = static_cast<std::size_t>(w) * h;
  s.z_raw.resize(n);
  s.z_closed.resize(n);
  s.z_smooth.resize(n);
  s.zscratch.resize(n);
  s.edges.resize(n);
  s.mask.resize(n);
  s.scratch8.resize(n);
  s.cov_l.resize(n);
  s.cov_r.resize(n);
  s.parent.resize(n);
  s.cand.assign(n, 0);
  auto v = [&](auto& vec) { return make_view(vec.data(), w, h); };
  convert_depth(b, make_view(f.mm.data(), w, h), 0.001f, s.p.min_depth, s.p.max_depth, v(s.z_raw));
  close_depth(b, v(s.z_raw), v(s.zscratch), v(s.z_closed), std::max(1, s.p.depth_closing_radius));
  smooth_depth(b, make_view<const float>(s.z_closed.data(), w, h), v(s.z_smooth), std::max(1, s.p.smooth_radius),
               s.p.smooth_k, s.p.noise.sigma0, s.p.noise.sigma2);
  detect_edges(b, s.depth(), s.k, s.p, v(s.edges));
  close_edges(b, make_view<const std::uint8_t>(s.edges.data(), w, h), v(s.scratch8), v(s.mask),
              s.p.edge_closing_radius);
  extract_segments<direction::left_diagonal>(b, s.depth(), make_view<const std::uint8_t>(s.mask.data(), w, h), s.k,
                                             s.p, v(s.cov_l));
  extract_segments<direction::right_diagonal>(b, s.depth(), make_view<const std::uint8_t>(s.mask.data(), w, h), s.k,
                                              s.p, v(s.cov_r));
  const auto adj = s.adjacency();
  connected_components(b, static_cast<std::int64_t>(n), adj.active, static_cast<std::int64_t>(n), adj, s.parent.data());
  // candidates: components of at least t_size pixels, numbered in raster order of their roots
  std::vector<std::int32_t> count(n, 0), id(n, 0);
  for (std::size_t i = 0; i < n; ++i)
    if (s.parent[i] >= 0) ++count[static_cast<std::size_t>(s.parent[i])];
  for (std::size_t i = 0; i < n; ++i)
    if (s.parent[i] == static_cast<std::int32_t>(i) && count[i] >= s.p.t_size) id[i] = ++s.num_cand;
  for (std::size_t i = 0; i < n; ++i)
    if (s.parent[i] >= 0) s.cand[i] = id[static_cast<std::size_t>(s.parent[i])];
  s.moments.resize(static_cast<std::size_t>(s.num_cand + 1) * moment_slots);
  s.bbox.resize(static_cast<std::size_t>(s.num_cand + 1) * 4);
  accumulate_moments(b, s.depth(), s.k, detail::candidate_image_labels{make_view<const std::int32_t>(s.cand.data(), w, h)},
                     s.num_cand, s.moments.data(), s.bbox.data());
  for (std::int32_t c = 1; c <= s.num_cand; ++c) {
    s.fits.push_back(fit_plane(s.moments.data() + static_cast<std::size_t>(c) * moment_slots,
                               s.bbox.data() + static_cast<std::size_t>(c) * 4));
    s.keep.push_back(is_plane(s.fits.back(), s.p) ? 1 : 0);
  }
  return s;
}

}  // namespace edgeplane::bench
