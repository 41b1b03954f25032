// edgeplane: the edge detector, written once over direction and edge-type policies.
#pragma once
#include <cstdint>

#include "edgeplane/camera.hpp"
#include "edgeplane/config.hpp"
#include "edgeplane/edges/directions.hpp"
#include "edgeplane/edges/edge_types.hpp"
#include "edgeplane/edges/neighbourhood.hpp"
#include "edgeplane/image.hpp"
#include "edgeplane/params.hpp"

namespace edgeplane {
namespace detail {

/// One edge type along one direction: ORs EdgeType::bit into the edge map where it fires.
/// (The per-kernel form, for tests and benchmarks; the segmenter runs the fused kernel below.)
template <class Direction, class EdgeType>
struct edge_kernel {
  image_view<const float> depth;
  image_view<std::uint8_t> edges;
  projector proj;
  EdgeType edge;
  EDGEPLANE_HD void operator()(std::int64_t i) const {
    const int x = static_cast<int>(i % depth.width), y = static_cast<int>(i / depth.width);
    if (!(depth(x, y) > 0.f)) return;
    neighbourhood nb;
    gather_along<Direction>(nb, depth, proj, x, y, edge.reach());
    if (edge(nb)) edges(x, y) = static_cast<std::uint8_t>(edges(x, y) | EdgeType::bit);
  }
};

/// The set of enabled edge types, built from params.
struct edge_set {
  bool use_jump, use_extrema, use_corner, use_curved;
  edge_type::jump jump;
  edge_type::extrema extrema;
  edge_type::corner corner;
  edge_type::curved curved;
  EDGEPLANE_HD int reach() const {
    int r = 1;
    if (use_extrema && extrema.reach() > r) r = extrema.reach();
    if (use_corner && corner.reach() > r) r = corner.reach();
    if (use_curved && curved.reach() > r) r = curved.reach();
    return r;
  }
};

inline edge_set make_edge_set(const params& p) {
  const noise_sigma s = make_noise(p.noise);
  edge_set e{};
  e.use_jump = p.use_jump;
  e.use_extrema = p.use_extrema;
  e.use_corner = p.use_corner;
  e.use_curved = p.use_curved;
  e.jump = {p.t_je, p.t_je_quad, p.t_je_ratio};
  e.extrema = {p.t_ee, p.n_ee};
  e.corner = {p.t_coe, p.t_coe_arm, p.noise_k, p.n_coe, s};
  e.curved = {p.t_cue1, p.t_cue2, p.noise_k, p.n_cue, s};
  return e;
}

template <class Direction>
EDGEPLANE_HD inline std::uint8_t edges_along(const edge_set& set, image_view<const float> depth, projector proj,
                                             int x, int y) {
  neighbourhood nb;
  gather_along<Direction>(nb, depth, proj, x, y, set.reach());
  std::uint8_t bits = 0;
  if (set.use_jump && set.jump(nb)) bits |= edge_type::jump::bit;
  if (set.use_extrema && set.extrema(nb)) bits |= edge_type::extrema::bit;
  if (set.use_corner && set.corner(nb)) bits |= edge_type::corner::bit;
  if (set.use_curved && set.curved(nb)) bits |= edge_type::curved::bit;
  return bits;
}

/// All enabled edge types along all four directions, one pass; invalid pixels get edge_invalid.
struct all_edges_kernel {
  image_view<const float> depth;
  image_view<std::uint8_t> edges;
  projector proj;
  edge_set set;
  EDGEPLANE_HD void operator()(std::int64_t i) const {
    const int x = static_cast<int>(i % depth.width), y = static_cast<int>(i / depth.width);
    if (!(depth(x, y) > 0.f)) {
      edges(x, y) = edge_invalid;
      return;
    }
    std::uint8_t b = edges_along<direction::horizontal>(set, depth, proj, x, y);
    b |= edges_along<direction::vertical>(set, depth, proj, x, y);
    b |= edges_along<direction::left_diagonal>(set, depth, proj, x, y);
    b |= edges_along<direction::right_diagonal>(set, depth, proj, x, y);
    edges(x, y) = b;
  }
};

/// Binary dilation of "any bit set" over a (2r+1)^2 window.
struct mask_dilate_kernel {
  image_view<const std::uint8_t> in;
  image_view<std::uint8_t> out;
  int r;
  EDGEPLANE_HD void operator()(std::int64_t i) const {
    const int x = static_cast<int>(i % in.width), y = static_cast<int>(i / in.width);
    std::uint8_t v = 0;
    for (int dy = -r; dy <= r && !v; ++dy)
      for (int dx = -r; dx <= r; ++dx)
        if (in.contains(x + dx, y + dy) && in(x + dx, y + dy)) {
          v = 1;
          break;
        }
    out(x, y) = v;
  }
};

/// Binary erosion: set only where the whole window is set (pixels outside the image count as set,
/// so the closing does not eat edges at the border).
struct mask_erode_kernel {
  image_view<const std::uint8_t> in;
  image_view<std::uint8_t> out;
  int r;
  EDGEPLANE_HD void operator()(std::int64_t i) const {
    const int x = static_cast<int>(i % in.width), y = static_cast<int>(i / in.width);
    std::uint8_t v = 1;
    for (int dy = -r; dy <= r && v; ++dy)
      for (int dx = -r; dx <= r; ++dx)
        if (in.contains(x + dx, y + dy) && !in(x + dx, y + dy)) {
          v = 0;
          break;
        }
    out(x, y) = v;
  }
};

}  // namespace detail

/// Runs one edge type along one direction, OR-ing its bit into `edges` (which the caller clears).
/// Depth: working depth in metres (0 = invalid), in the backend's memory.  Asynchronous on device
/// backends.
template <class Direction, class EdgeType, class Backend>
void detect_edge(const Backend& b, image_view<const float> depth, const intrinsics& k, const EdgeType& edge,
                 image_view<std::uint8_t> edges) {
  detail::check_intrinsics(k);
  detail::check_same_size(depth, edges, "depth", "edges");
  b.for_each_index(depth.pixels(),
                   detail::edge_kernel<Direction, EdgeType>{depth, edges, detail::make_projector(k), edge});
}

/// All enabled edge types over the four directions in one pass: writes every pixel of `edges`
/// (edge_bits; edge_invalid where depth is invalid).  Asynchronous on device backends.
template <class Backend>
void detect_edges(const Backend& b, image_view<const float> depth, const intrinsics& k, const params& p,
                  image_view<std::uint8_t> edges) {
  detail::check_intrinsics(k);
  detail::check_same_size(depth, edges, "depth", "edges");
  b.for_each_index(depth.pixels(),
                   detail::all_edges_kernel{depth, edges, detail::make_projector(k), detail::make_edge_set(p)});
}

/// Closing (dilate, then erode) of the edge map with a (2r+1)^2 window: `mask` becomes 1 on edge
/// and invalid pixels and on the gaps the closing bridges, 0 elsewhere.  r = 0 copies the map as a
/// mask.  `scratch` is the image's size.
template <class Backend>
void close_edges(const Backend& b, image_view<const std::uint8_t> edges, image_view<std::uint8_t> scratch,
                 image_view<std::uint8_t> mask, int r) {
  detail::check_same_size(edges, mask, "edges", "mask");
  detail::check_same_size(edges, scratch, "edges", "scratch");
  b.for_each_index(edges.pixels(), detail::mask_dilate_kernel{edges, scratch, r});
  b.for_each_index(edges.pixels(), detail::mask_erode_kernel{scratch, mask, r});
}

}  // namespace edgeplane
