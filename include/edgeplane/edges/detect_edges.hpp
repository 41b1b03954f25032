// edgeplane: the edge detector, written once over direction and edge-type policies.
#pragma once
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "edgeplane/backend/buffer.hpp"
#include "edgeplane/camera.hpp"
#include "edgeplane/config.hpp"
#include "edgeplane/detail/swar.hpp"
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
  EDGEPLANE_HD void operator()(int x, int y) const {
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

/// The enabled tests of one direction whose bits `tests` holds (bit 0 jump, 1 extrema, 2 corner,
/// 3 curved) on neighbourhood nb; a test left out must be one that cannot fire there.
EDGEPLANE_HD EDGEPLANE_INLINE std::uint8_t edges_of(const edge_set& set, const neighbourhood& nb, unsigned tests) {
  std::uint8_t bits = 0;
  if ((tests & 1u) && set.use_jump && set.jump(nb)) bits |= edge_type::jump::bit;
  if ((tests & 2u) && set.use_extrema && set.extrema(nb)) bits |= edge_type::extrema::bit;
  if ((tests & 4u) && set.use_corner && set.corner(nb)) bits |= edge_type::corner::bit;
  if ((tests & 8u) && set.use_curved && set.curved(nb)) bits |= edge_type::curved::bit;
  return bits;
}

template <class Direction>
EDGEPLANE_HD EDGEPLANE_INLINE std::uint8_t edges_along(const edge_set& set, image_view<const float> depth, projector proj,
                                             int x, int y, int reach, bool interior) {
  neighbourhood nb;
  gather_along<Direction>(nb, depth, proj, x, y, reach, interior);
  return edges_of(set, nb, 15u);
}

/// Flags of the interior pass, kept in the edge map's two spare bits until the edge pass
/// overwrites each pixel: the row's (2r+1) window is valid and inside / the square one is.
inline constexpr std::uint8_t interior_row_flag = 0x40, interior_flag = 0x80;

/// Interior pass, rows (one work item per row): marks interior_row_flag on pixels whose
/// horizontal window [x - r, x + r] lies inside the image and holds only valid depth.  Writes
/// every pixel of the row (the flag or 0).
struct interior_rows_kernel {
  image_view<const float> depth;
  image_view<std::uint8_t> flags;
  int r;
  EDGEPLANE_HD void operator()(std::int64_t row) const {
    const int y = static_cast<int>(row);
    int run = 0;  // valid pixels ending at x
    for (int x = 0; x < depth.width; ++x) {
      run = depth(x, y) > 0.f ? run + 1 : 0;
      flags(x, y) = 0;
      if (run >= 2 * r + 1) flags(x - r, y) = interior_row_flag;
    }
  }
};
/// Interior pass, columns (one work item per column): adds interior_flag where the vertical
/// window of row flags [y - r, y + r] is complete, i.e. the whole (2r+1)^2 square is valid.
struct interior_columns_kernel {
  image_view<std::uint8_t> flags;
  int r;
  EDGEPLANE_HD void operator()(std::int64_t col) const {
    const int x = static_cast<int>(col);
    int run = 0;
    for (int y = 0; y < flags.height; ++y) {
      run = (flags(x, y) & interior_row_flag) ? run + 1 : 0;
      if (run >= 2 * r + 1) flags(x, y - r) = static_cast<std::uint8_t>(flags(x, y - r) | interior_flag);
    }
  }
};

/// Interior pass on device backends, one work item per pixel: interior_flag where the (2r+1)^2
/// window lies inside the image and holds only valid depth, else 0 (the row and column passes'
/// interior_flag, without their row flags, which nothing reads).  Reads depth only, so the work
/// items are independent; the window is read row by row and stops at the first invalid pixel.
/// (The row and column passes walk a whole line per work item: a GPU ran them on a few hundred
/// threads, 0.9 ms at 512x424 on an H200.)
struct interior_pixel_kernel {
  image_view<const float> depth;
  image_view<std::uint8_t> flags;
  int r;
  EDGEPLANE_HD void operator()(int x, int y) const {
    bool inside = x >= r && y >= r && x + r < depth.width && y + r < depth.height;
    for (int dy = -r; dy <= r && inside; ++dy)
      for (int dx = -r; dx <= r; ++dx)
        if (!(depth(x + dx, y + dy) > 0.f)) {
          inside = false;
          break;
        }
    flags(x, y) = inside ? interior_flag : std::uint8_t(0);
  }
};

/// The edge pass's point planes on host backends: depth, X and Y of every pixel (floats, in that
/// order), each a dense w-wide image with pad_rows rows of zeros above and below, as many as a
/// run's neighbours r steps of up to w + 1 elements away can reach: r + ceil(r / w).
struct edge_points_layout {
  int w = 0, pad_rows = 0;
  std::int64_t plane = 0, z = 0, x = 0, y = 0;  // elements per plane; each plane's first element
  edge_points_layout() = default;
  EDGEPLANE_HD edge_points_layout(int width, int height, int r)
      : w(width), pad_rows(r + (r + width - 1) / width), plane(static_cast<std::int64_t>(height + 2 * pad_rows) * width),
        z(0), x(plane), y(2 * plane) {}
  /// the element of pixel (u, v) within a plane
  EDGEPLANE_HD std::int64_t offset(int u, int v) const { return static_cast<std::int64_t>(v + pad_rows) * w + u; }
  EDGEPLANE_HD std::int64_t elements() const { return 3 * plane; }
};

/// Valid-neighbour counts, the neighbourhood's nl and nr for every pixel and direction at once:
/// plane 2 d + s of `runs` (8 dense w x h byte planes, d in the order horizontal, vertical, left
/// diagonal, right diagonal; s = 0 the left side (-dx, -dy), 1 the right side) holds how many
/// consecutive valid pixels follow the pixel on that side, at most r (0..r, r <= 255), stopping
/// at the image border.  The horizontal planes: one work item per row, a running count.
/// It also writes the validity plane the bands read (0xff valid, 0 invalid) and, with `points`
/// given, the depth and the X and Y of every pixel's back-projected point (the projector's
/// operations, so the same floats) into the three planes of edge_points_layout, which pad the
/// image with rows of zeros (invalid) so that the edge pass's row runs can read every neighbour
/// they may look at without a bounds check.  Item 0 also zeroes the padding rows above the image,
/// item h - 1 those below.
struct valid_runs_rows_kernel {
  static constexpr bool even_work = true;  // see detail::even_work_v
  image_view<const float> depth;
  std::uint8_t* runs;
  int r;
  std::uint8_t* valid;  // dense w x h: 0xff where depth is valid, 0 elsewhere (for the bands)
  projector proj{};
  float* points = nullptr;  // the point planes, laid out as `at` says, or null
  edge_points_layout at{};
  EDGEPLANE_HOST_CLONES EDGEPLANE_HD void operator()(std::int64_t row) const {
    const int y = static_cast<int>(row), w = depth.width;
    std::uint8_t* vr = valid + static_cast<std::int64_t>(y) * w;
    // From a local row pointer: through depth(x, y), every byte store may alias the view's own
    // data pointer and pitch, so g++ reloaded them per pixel and kept the loop scalar (one byte
    // store per pixel, which the block loads below then waited on).
    const float* drow = &depth(0, y);
    for (int x = 0; x < w; ++x) vr[x] = static_cast<std::uint8_t>(0u - static_cast<unsigned>(drow[x] > 0.f));
    if (points != nullptr) {
      float* zs = points + at.z + at.offset(0, y);
      float* xs = points + at.x + at.offset(0, y);
      float* ys = points + at.y + at.offset(0, y);
      const float* d = &depth(0, y);
      for (int x = 0; x < w; ++x) {
        const point3 p = proj(x, y, d[x]);
        zs[x] = d[x];
        xs[x] = p.x;
        ys[x] = p.y;
      }
      const std::int64_t pad = static_cast<std::int64_t>(at.pad_rows) * w;
      if (y == 0)
        for (const std::int64_t plane : {at.z, at.x, at.y})
          for (std::int64_t i = 0; i < pad; ++i) points[plane + i] = 0.f;
      if (y == depth.height - 1)
        for (const std::int64_t plane : {at.z, at.x, at.y})
          for (std::int64_t i = 0; i < pad; ++i) points[plane + at.offset(0, y + 1) + i] = 0.f;
    }
    const std::int64_t n = static_cast<std::int64_t>(w) * depth.height, o = static_cast<std::int64_t>(y) * w;
    std::uint8_t* left = runs + o;
    std::uint8_t* right = runs + n + o;
    // Blocks of 64 pixels walk their neighbours together, byte lanes (vectorizable), instead of
    // a running count whose every step waits for the one before: a copy of the block's window of
    // validity bytes, 0 outside the row, then per step k the lanes still on valid pixels count.
    // A block whose window lies inside the row reads the validity row in place; only the blocks
    // at the row's ends copy theirs, padded with zeros.  (A copy made just before its reads cost a
    // fifth of this kernel: each unaligned 64-byte read of it spans two of the copy's pending
    // stores, and such a load waits until they have retired.)
    constexpr int block = 64;
    std::uint8_t win[block + 2 * 255];
    for (int x0 = 0; x0 < w; x0 += block) {
      const std::uint8_t* wv = win;  // wv[j]: the validity of pixel x0 - r + j
      if (x0 - r >= 0 && x0 + block + r <= w) {
        wv = vr + (x0 - r);
      } else {
        for (int j = 0; j < block + 2 * r; ++j) {
          const int u = x0 - r + j;
          win[j] = u >= 0 && u < w ? vr[u] : 0;
        }
      }
      std::uint8_t okl[block], cl[block], okr[block], cr[block];
      for (int l = 0; l < block; ++l) okl[l] = okr[l] = 1, cl[l] = cr[l] = 0;
      for (int k = 1; k <= r; ++k)
        for (int l = 0; l < block; ++l) {
          okl[l] = static_cast<std::uint8_t>(okl[l] & wv[r + l - k]);
          cl[l] = static_cast<std::uint8_t>(cl[l] + okl[l]);
          okr[l] = static_cast<std::uint8_t>(okr[l] & wv[r + l + k]);
          cr[l] = static_cast<std::uint8_t>(cr[l] + okr[l]);
        }
      const int m = w - x0 < block ? w - x0 : block;
      for (int l = 0; l < m; ++l) {
        left[x0 + l] = cl[l];
        right[x0 + l] = cr[l];
      }
    }
  }
};
/// Rows per work item of valid_runs_bands_kernel for an image h rows high: 32, halved (to 8 at
/// least) until the six planes' bands make host_parallel_items work items, since the CPU backend
/// runs fewer serially (a 256x212 frame made 42 of 32 rows).  Each band counts its first row's
/// neighbours one step at a time, so shorter bands cost more in all, but on every core.
inline int valid_runs_band(int h) {
  int band = 32;
  while (band > 8 && 6 * ((static_cast<std::int64_t>(h) + band - 1) / band) < host_parallel_items) band /= 2;
  return band;
}

/// The vertical and diagonal planes: one work item per band of `band` rows.  A row's count is the
/// previous row's count at (x - dx) plus one where that pixel is valid (the next row's for the
/// right side), so only each band's first row (last, for the right side) counts its neighbours
/// one by one.  Validity comes from the byte plane valid_runs_rows_kernel writes (byte
/// operations only: 64 pixels per AVX-512 instruction).  1 <= r <= 127.
struct valid_runs_bands_kernel {
  static constexpr bool even_work = true;  // see detail::even_work_v
  image_view<const float> depth;
  std::uint8_t* runs;
  int r, band;
  const std::uint8_t* valid;  // dense w x h: 0xff where depth is valid, 0 elsewhere
  template <int Dx>
  EDGEPLANE_HD EDGEPLANE_INLINE void plane(std::uint8_t* out, int y0, int y1, int sy) const {
    // sy = -1: the left side (rows above, x - Dx); +1: the right side (rows below, x + Dx)
    const int w = depth.width, h = depth.height, sx = sy * Dx;
    const int first = sy < 0 ? y0 : y1 - 1, last = sy < 0 ? y1 : y0 - 1;
    // The first row counts its neighbours one step at a time for all x together: bit 7 of its
    // bytes marks the pixels whose walk has met invalid depth or the border.
    std::uint8_t* o = out + static_cast<std::int64_t>(first) * w;
    for (int x = 0; x < w; ++x) o[x] = 0;
    for (int k = 1; k <= r; ++k) {
      const int v = first + k * sy, s = k * sx;
      if (v < 0 || v >= h) break;  // every walk has ended
      const std::uint8_t* vr = valid + static_cast<std::int64_t>(v) * w;
      const int xa = s < 0 ? (-s < w ? -s : w) : 0, xb = s > 0 ? (w - s > 0 ? w - s : 0) : w;  // x + s inside
      for (int x = 0; x < xa; ++x) o[x] = static_cast<std::uint8_t>(o[x] | 0x80);
      for (int x = xb; x < w; ++x) o[x] = static_cast<std::uint8_t>(o[x] | 0x80);
      for (int x = xa; x < xb; ++x) {
        const std::uint8_t dead = static_cast<std::uint8_t>((o[x] | static_cast<std::uint8_t>(~vr[x + s])) & 0x80);
        o[x] = static_cast<std::uint8_t>(dead | ((o[x] & 0x7f) + ((dead >> 7) ^ 1)));
      }
    }
    for (int x = 0; x < w; ++x) o[x] = static_cast<std::uint8_t>(o[x] & 0x7f);
    for (int y = first - sy; y != last; y -= sy) {  // then each row from its predecessor on that side
      const int v = y + sy;
      const std::uint8_t* prev = out + static_cast<std::int64_t>(v) * w;
      std::uint8_t* cur = out + static_cast<std::int64_t>(y) * w;
      const std::uint8_t* vp = valid + static_cast<std::int64_t>(v) * w;
      const int xa = sx < 0 ? 1 : 0, xb = sx > 0 ? w - 1 : w;  // x + sx inside the image
      const std::uint8_t below_r = static_cast<std::uint8_t>(r - 1);
      if (sx < 0) cur[0] = 0;
      if (sx > 0) cur[w - 1] = 0;
      for (int x = xa; x < xb; ++x) {  // min(prev + 1, r), 0 where the neighbour is invalid
        const std::uint8_t p = prev[x + sx];
        cur[x] = static_cast<std::uint8_t>(((p < below_r ? p : below_r) + 1) & vp[x + sx]);
      }
    }
  }
  /// Work item 6 b + q: plane q of the six (vertical left, right, left diagonal left, right,
  /// right diagonal left, right) over band b, so that even a short image has enough items for
  /// both cores (the CPU backend runs fewer than 64 items serially).
  EDGEPLANE_HOST_CLONES EDGEPLANE_HD void operator()(std::int64_t item) const {
    const int y0 = static_cast<int>(item / 6) * band, q = static_cast<int>(item % 6);
    const int y1 = y0 + band < depth.height ? y0 + band : depth.height;
    const std::int64_t n = static_cast<std::int64_t>(depth.width) * depth.height;
    std::uint8_t* out = runs + (2 + q) * n;
    const int side = q % 2 == 0 ? -1 : +1;
    if (q < 2)
      plane<0>(out, y0, y1, side);
    else if (q < 4)
      plane<1>(out, y0, y1, side);
    else
      plane<-1>(out, y0, y1, side);
  }
};

/// The curved test's arc pre-test, shared between neighbours (host backends, an even arm of n =
/// 2 m neighbours).  The scalar test's first condition on side s at pixel c is that the arm's
/// midpoint c + s m lies farther than t_bend * chord + noise(z_c) from the chord between c and the
/// arm's end c + s n.  That is one triple of points, (q - m, q, q + m) with q = c + s m: the right
/// side's at c and the left side's at c + n.  So each triple's geometry is computed once, here,
/// per pixel q and direction d, and judged for each end with that end's noise: bit d of flat[q]
/// says its middle point surely lies within the bound of the end q - m (so the right side of
/// q - m cannot be an arc), bit 4 + d the same for the end q + m (its left side).  The edge pass
/// keeps a curved test open where either of its two sides' bits is clear.  This halves the
/// pre-test's cross products (8 to 4 a pixel).
///
/// A judgement must imply the scalar expression's "no" at its end, which computes from other
/// operands (c's own differences).  Here: u = a - q, v = b - q (a = q - m, b = q + m), num =
/// |u x v|^2, l2 = |b - a|^2 (the very bits each end's l2 has: b - a is the scalar test's e - c
/// at a and exactly its negation at b), S = |u|^2 + |v|^2, T = l2 (t^2 l2 + noise^2) with the
/// end's noise.  Sure: num < 0.99 T, and S^2 1e-6 <= T, and the guards of farther_than's shortcut
/// (t, noise >= 0, l2 >= 1e-12, t^2 l2 + noise^2 >= 1e-20; T at most 1e29, so num < 1e29).  Why
/// that suffices: each cross product of rounded differences differs from the exact one of the
/// points by at most 4.01 eps (|x_j y_k| + |x_k y_j|) a component (eps = 2^-24: the differences,
/// the products, the subtraction), at most 5.7 eps |x| |y| in all; |u| |v| <= S / 2 here, and at an
/// end (ap = -u or -v, ab = +-(b - a)) |ap| |ab| <= |u| (|u| + |v|) <= 1.21 S, so the two computed
/// crosses differ by at most 9.8 eps S, which the second condition keeps below 1.2e-3 sqrt(T);
/// with num < 0.99 T the end's num is then below 0.9917 T (1 + 3 eps) < 0.9999 l2 floor2 of its
/// own farther_than shortcut, which is sure that the scalar expression is false.  On surfaces S
/// is about l2 / 2, and the second condition holds for any t above 4e-4.  (One judgement with the
/// smaller of the two ends' noise, a bit per direction, left 7 % more curved tests open on a TUM
/// frame, whose finishing cost more than the pass saved.)
template <int Lanes>
struct arc_flat_rows_kernel {
  static constexpr bool even_work = true;  // see detail::even_work_v
  const float* points;                     // the point planes, laid out as `at` says
  edge_points_layout at;
  int w, m;  // the image's width; the half arm (n / 2)
  float t, noise_k;
  noise_sigma sigma;
  std::uint8_t* flat;  // dense w x h bytes

  // The triple's judgements for its two ends, noise na at a and nb at b: bit 0 for a, bit 1 for b
  // (t >= 0 and the noises >= 0 are the caller's: detect_edges runs this kernel only then).
  EDGEPLANE_HD EDGEPLANE_INLINE static unsigned surely_within(point3 a, point3 q, point3 b, float t, float na,
                                                             float nb) {
    const point3 u = a - q, v = b - q, ab = b - a;
    const float l2 = dot(ab, ab);
    const point3 cr = cross(u, v);
    const float num = dot(cr, cr), s = dot(u, u) + dot(v, v);
    const float tl = t * t * l2, fa = tl + na * na, fb = tl + nb * nb, ta = l2 * fa, tb = l2 * fb;
    const float s2 = s * s * 1e-6f;
    const bool ok = l2 >= 1e-12f;
    const bool in_a = ok & (fa >= 1e-20f) & (ta <= 1e29f) & (num < ta * 0.99f) & (s2 <= ta);
    const bool in_b = ok & (fb >= 1e-20f) & (tb <= 1e29f) & (num < tb * 0.99f) & (s2 <= tb);
    return static_cast<unsigned>(in_a) | static_cast<unsigned>(in_b) << 1;
  }
  // (32-bit flags, as the edge pass's: byte lanes would set the vector width to 16 floats' quarter)
  template <class Direction, int D, int N>
  EDGEPLANE_HD EDGEPLANE_INLINE static void along(const float* z, const float* xs, const float* ys, std::ptrdiff_t pitch,
                                                  int m, float t, float noise_k, noise_sigma sigma, unsigned* f) {
    const std::ptrdiff_t o = m * (static_cast<std::ptrdiff_t>(Direction::dy) * pitch + Direction::dx);
    for (int l = 0; l < N; ++l) {
      const float za = z[l - o], zb = z[l + o];
      // the curved test's noise at each end (its own expression there)
      const unsigned in = surely_within(point3{xs[l - o], ys[l - o], za}, point3{xs[l], ys[l], z[l]},
                                        point3{xs[l + o], ys[l + o], zb}, t, noise_k * sigma(za), noise_k * sigma(zb));
      f[l] |= (in & 1u) << D | (in >> 1) << (4 + D);
    }
  }
  // the N pixels from element i of the planes (inside a row); from locals, not members: the byte
  // stores could alias them
  template <int N>
  EDGEPLANE_HD EDGEPLANE_INLINE static void run(const float* z, const float* xs, const float* ys, std::ptrdiff_t pitch,
                                                int m, float t, float noise_k, noise_sigma sigma, std::uint8_t* out) {
    unsigned f[N] = {};
    along<direction::horizontal, 0, N>(z, xs, ys, pitch, m, t, noise_k, sigma, f);
    along<direction::vertical, 1, N>(z, xs, ys, pitch, m, t, noise_k, sigma, f);
    along<direction::left_diagonal, 2, N>(z, xs, ys, pitch, m, t, noise_k, sigma, f);
    along<direction::right_diagonal, 3, N>(z, xs, ys, pitch, m, t, noise_k, sigma, f);
    for (int l = 0; l < N; ++l) out[l] = static_cast<std::uint8_t>(f[l]);
  }
  EDGEPLANE_HOST_CLONES EDGEPLANE_HD void operator()(std::int64_t row) const {
    const int y = static_cast<int>(row);
    // Runs of Lanes pixels; the last one, where the row is not a multiple, overlaps the one before
    // (the same bits again).  A pixel's points reach at most the padding rows (m <= the reach).
    const std::int64_t i = at.offset(0, y);
    const float* z = points + at.z + i;
    const float* xs = points + at.x + i;
    const float* ys = points + at.y + i;
    std::uint8_t* out = flat + static_cast<std::int64_t>(y) * w;
    const int wd = w, half = m;
    const float tb = t, nk = noise_k;
    const noise_sigma sg = sigma;
    int x0 = 0;
    for (; x0 + Lanes <= wd; x0 += Lanes) run<Lanes>(z + x0, xs + x0, ys + x0, wd, half, tb, nk, sg, out + x0);
    if (x0 < wd) {
      if (wd >= Lanes)
        run<Lanes>(z + (wd - Lanes), xs + (wd - Lanes), ys + (wd - Lanes), wd, half, tb, nk, sg, out + (wd - Lanes));
      else
        for (; x0 < wd; ++x0) run<1>(z + x0, xs + x0, ys + x0, wd, half, tb, nk, sg, out + x0);
    }
  }
};

/// All enabled edge types along all four directions, one pass; invalid pixels get edge_invalid.
/// A pixel's neighbour counts come from `runs` (valid_runs_*_kernel) when it is given; otherwise
/// from the interior flag the interior pass left in `edges` (a pixel whose whole window of
/// `reach` is valid needs no counting) or by reading the neighbours.  Overwrites the pixel with
/// its edge bits.
struct all_edges_kernel {
  image_view<const float> depth;
  image_view<std::uint8_t> edges;
  projector proj;
  edge_set set;
  int reach;
  const std::uint8_t* runs = nullptr;  // 8 dense planes of valid-neighbour counts, or null
  // the point planes (the host's row runs need them, with runs), laid out as points_at says
  const float* points = nullptr;
  edge_points_layout points_at{};
  // the curved pre-test's shared judgements (arc_flat_rows_kernel; dense w x h, readable m rows and
  // a run beyond either end), or null: the row runs judge each side in place
  const std::uint8_t* arc_flat = nullptr;

  template <class Direction, int D>
  EDGEPLANE_HD EDGEPLANE_INLINE std::uint8_t along(int x, int y, bool interior, unsigned tests) const {
    const unsigned t = (tests >> (4 * D)) & 15u;
    if (!t) return 0;
    neighbourhood nb;
    if (runs != nullptr) {
      gather_along<Direction>(nb, depth, proj, x, y, reach, true);
      const std::int64_t n = static_cast<std::int64_t>(depth.width) * depth.height;
      const std::int64_t i = static_cast<std::int64_t>(y) * depth.width + x;
      nb.nl = runs[2 * D * n + i];
      nb.nr = runs[(2 * D + 1) * n + i];
    } else {
      gather_along<Direction>(nb, depth, proj, x, y, reach, interior);
    }
    return edges_of(set, nb, t);
  }
  /// The tests of `tests` (bit 4 d + j: test j along direction d, in the order of `along`); the
  /// others must be tests that cannot fire at this pixel.
  EDGEPLANE_HD EDGEPLANE_INLINE void run(int x, int y, unsigned tests) const {
    if (!(depth(x, y) > 0.f)) {
      edges(x, y) = edge_invalid;
      return;
    }
    const bool interior = runs == nullptr && (edges(x, y) & interior_flag) != 0;
    std::uint8_t b = along<direction::horizontal, 0>(x, y, interior, tests);
    b |= along<direction::vertical, 1>(x, y, interior, tests);
    b |= along<direction::left_diagonal, 2>(x, y, interior, tests);
    b |= along<direction::right_diagonal, 3>(x, y, interior, tests);
    edges(x, y) = b;
  }
  EDGEPLANE_HD void operator()(int x, int y) const { run(x, y, 0xffffu); }
};

/// all_edges_kernel over runs of Lanes pixels of one row (work item = row * chunks + chunk), for
/// host backends, with the neighbour counts (px.runs) given.  Most pixels lie on surfaces, where
/// every test stops at its first, cheap condition.  Those first conditions are evaluated here for
/// all lanes at once, with exactly the float operations of the scalar tests (so g++ can vectorize
/// them and the decisions are the same): the jump test, the nearest-neighbour extrema condition,
/// the corner's bend pre-test at c and the curved arc pre-test of both sides
/// (detail::farther_than's sure rejection), in all four directions, each behind the neighbour
/// counts its scalar test requires.  A test that its counts or its first condition reject cannot
/// fire.  The tests they leave open (near creases and steps) are then finished for all lanes at
/// once too (finish_along: the arm scans, the arc shape, the extrema's farther neighbours), again
/// with the scalar tests' operations, the lanes in step and a lane's neighbours contiguous with
/// the next lane's.  So the edge map is identical bit for bit.
template <int Lanes>
struct all_edges_rows_kernel {
  all_edges_kernel px;
  int chunks;  // runs per row: ceil(width / Lanes)

  // farther_than(p, a, b, t, noise) is surely false (its shortcut), for lane-wise points.
  EDGEPLANE_HD EDGEPLANE_INLINE static bool surely_not_farther(point3 p, point3 a, point3 b, float t, float noise) {
    const point3 ab = b - a, ap = p - a;
    const float l2 = dot(ab, ab);
    const point3 c = cross(ap, ab);
    const float num = dot(c, c);
    const float floor2 = t * t * l2 + noise * noise;
    return (t >= 0.f) & (noise >= 0.f) & (l2 >= 1e-12f) & (floor2 >= 1e-20f) & (num < 1e30f) &
           (num < l2 * floor2 * 0.9999f);
  }

  // The lanes' pixels: depth, and the X and Y of their back-projected points (valid_runs_rows_kernel),
  // at the same offsets in the padded point planes.  c[i] is the depth i elements from lane 0's pixel.
  struct lane_points {
    const float* z;
    const float* x;
    const float* y;
    EDGEPLANE_HD EDGEPLANE_INLINE float operator[](std::ptrdiff_t i) const { return z[i]; }
  };
  // neighbour k (signed: k < 0 on the left side, `step` elements apart) of lane l's pixel,
  // back-projected as neighbourhood does (the planes hold the projector's results)
  EDGEPLANE_HD EDGEPLANE_INLINE static point3 at(const lane_points& c, std::ptrdiff_t step, int l, int k) {
    const std::ptrdiff_t i = l + k * step;
    return {c.x[i], c.y[i], c.z[i]};
  }

  // ORs into maybe[l] the bit 4 D + j of every test j along Direction whose first condition does
  // not reject lane l (x0: lane 0's column).  The jump test takes its sides' presence (nl, nr >= 1)
  // into account (Checked = false: every count is at reach, so no masks are needed); the extrema, corner and
  // curved bits are the caller's to clear where the counts reject the test (the scalar test's
  // first check).  A lane reads neighbours beyond its counts (invalid depth, or pixels of other
  // rows past the border: garbage, whose bits are cleared).
  template <class Direction, int D, bool Checked>
  EDGEPLANE_HD EDGEPLANE_INLINE void maybe_along(const lane_points& c, std::ptrdiff_t pitch, int x0,
                                                 const float* zc, const float* noise_co, const float* noise_cu,
                                                 unsigned* maybe) const {
    constexpr int dx = Direction::dx, dy = Direction::dy;
    const std::ptrdiff_t step = static_cast<std::ptrdiff_t>(dy) * pitch + dx;
    const edge_set& s = px.set;
    if (s.use_jump) {
      // The whole jump test, as edge_type::jump computes it, without a select on floats (which
      // g++ does not vectorize): a missing side's step is -1 there, so it never jumps, and the
      // other side's bound is t + t_ratio * 0 = t; a present side's step is >= 0, so
      // (d > 0 ? d : 0) is d.
      // A side has its nearest neighbour (nl >= 1) where that pixel is inside the image and
      // valid: the padded planes hold 0 above and below the image, so only a column past the
      // first or last needs its own check.  (From the depths, not the count bytes: g++ widens
      // bytes to the lanes' 32 bits in 16-byte pieces, which the next full-width read of `maybe`
      // then waits for.)
      const edge_type::jump& j = s.jump;
      const int w = px.depth.width;
      for (int l = 0; l < Lanes; ++l) {
        const float z = zc[l];
        const float t = j.t_abs + j.t_quad * z * z;
        const float zl = c[l - step], zr = c[l + step];
        const float dl = fabsf(zl - z), dr = fabsf(zr - z);
        const int u = x0 + l;
        const bool hl = !Checked || ((zl > 0.f) & (u - dx >= 0) & (u - dx < w)),
                   hr = !Checked || ((zr > 0.f) & (u + dx >= 0) & (u + dx < w));
        const bool jl = hl & ((hr & (dl > t + j.t_ratio * dr)) | (!hr & (dl > t)));
        const bool jr = hr & ((hl & (dr > t + j.t_ratio * dl)) | (!hl & (dr > t)));
        maybe[l] |= static_cast<unsigned>(jl | jr) << (4 * D);
      }
    }
    if (s.use_extrema) {
      const float t = s.extrema.t;
      for (int l = 0; l < Lanes; ++l) {
        const float z = zc[l], a = c[l - step], b = c[l + step];
        const bool nearer = (z < t * a) & (z < t * b), farther = (z * t > a) & (z * t > b);
        maybe[l] |= static_cast<unsigned>(nearer | farther) << (4 * D + 1);
      }
    }
    if (s.use_corner) {
      const int n = s.corner.n, h = n / 2 > 0 ? n / 2 : 1;
      const float t = s.corner.t_bend;
      for (int l = 0; l < Lanes; ++l) {
        const bool bend = !surely_not_farther(at(c, step, l, 0),
                                              at(c, step, l, -h),
                                              at(c, step, l, h), t, noise_co[l]);
        maybe[l] |= static_cast<unsigned>(bend) << (4 * D + 2);
      }
    }
    if (s.use_curved && px.arc_flat == nullptr) {  // (else from the shared judgements: maybe_all)
      const int n = s.curved.n, mid = n / 2 > 0 ? n / 2 : 1;
      const float t = s.curved.t_bend;
      for (int l = 0; l < Lanes; ++l) {
        const point3 p = at(c, step, l, 0);
        const point3 ml = at(c, step, l, -mid), el = at(c, step, l, -n);
        const point3 mr = at(c, step, l, mid), er = at(c, step, l, n);
        const bool no_l = surely_not_farther(ml, p, el, t, noise_cu[l]);
        const bool no_r = surely_not_farther(mr, p, er, t, noise_cu[l]);
        maybe[l] |= static_cast<unsigned>(!(no_l & no_r)) << (4 * D + 3);
      }
    }
  }

  // ---- the open tests, finished for all lanes at once ------------------------------------------
  // Where the pre-tests leave a test open, it is finished here lane by lane with exactly the float
  // operations of edge_type's scalar test (the same points, the same expressions; a branch of the
  // scalar code becomes a select between values computed the same way), so each lane's decision
  // is the scalar test's.  Lanes whose bit is not open compute garbage from readable memory and
  // are masked.  ok[l] is 0 or 1.

  // arm_within for every lane with ok[l] set: clears ok[l] where an inner point of the arm of m
  // neighbours on side s lies beyond t * chord + noise[l] of the chord from c to the arm's end,
  // with the scalar test's expression, sqrtf(dist2_to_line(p, c, e)) > bound, at every point.
  // (Out of line: arms_within runs it rarely; inlined four times, it slowed the edge pass by 3 %.)
  EDGEPLANE_NOINLINE EDGEPLANE_HD void arms_within_exact(const lane_points& c, std::ptrdiff_t step, int s, int m,
                                                       float t, const float* noise, unsigned* ok) const {
    float cx[Lanes], cy[Lanes], cz[Lanes], ex[Lanes], ey[Lanes], ez[Lanes], bound[Lanes];
    for (int l = 0; l < Lanes; ++l) {
      const point3 p0 = at(c, step, l, 0), e = at(c, step, l, s * m);
      cx[l] = p0.x;
      cy[l] = p0.y;
      cz[l] = p0.z;
      ex[l] = e.x;
      ey[l] = e.y;
      ez[l] = e.z;
      bound[l] = t * norm(e - p0) + noise[l];
    }
    for (int k = 1; k < m; ++k) {
      unsigned alive = 0;
      for (int l = 0; l < Lanes; ++l) {
        const float d2 = dist2_to_line(at(c, step, l, s * k), point3{cx[l], cy[l], cz[l]},
                                       point3{ex[l], ey[l], ez[l]});
        ok[l] = ok[l] & static_cast<unsigned>(!(sqrtf(d2) > bound[l]));
        alive |= ok[l];
      }
      if (!alive) return;
    }
  }

  // One inner point (neighbour q) of arms_within's arms: the largest num so far, and ok cleared
  // where the point lies surely beyond.  (A member with the arrays as arguments: as a lambda in
  // arms_within, g++ 12 made the edge pass's x86-64-v4 kernel a quarter more instructions, and
  // with the arrays in a struct it kept that struct on the stack, a larger frame.)
  EDGEPLANE_HD EDGEPLANE_INLINE static void arm_point(const lane_points& c, std::ptrdiff_t step, int q, const float* cx,
                                                      const float* cy, const float* cz, const float* ax,
                                                      const float* ay, const float* az, const float* hi, float* top,
                                                      unsigned* ok) {
    for (int l = 0; l < Lanes; ++l) {
      const point3 ap = at(c, step, l, q) - point3{cx[l], cy[l], cz[l]};
      const point3 cr = cross(ap, point3{ax[l], ay[l], az[l]});
      const float num = dot(cr, cr);
      top[l] = num > top[l] ? num : top[l];
      ok[l] = ok[l] & static_cast<unsigned>(!(num > hi[l]));
    }
  }

  // arms_within_exact's decisions without its division and square root at every point: the
  // scalar test compares sqrtf(num / l2) with the bound B (num = |(p - c) x (e - c)|^2, l2 =
  // |e - c|^2, the same floats here).  num < B^2 l2 (1 - 1e-4) means within and num > B^2 l2
  // (1 + 1e-4) beyond, as the scalar expression decides too: its division and square root round
  // by half an ulp each and the two limits by a few, far inside the 1e-4 margin, for lanes whose
  // l2 >= 1e-12, B >= 1e-15 and B^2 l2 within [1e-30, 1e30] (normal floats, the quotient near B^2
  // too; other lanes are always in doubt).  A lane still within at the arm's end (no point surely
  // beyond) whose largest num is not surely within (some point was in doubt) is decided again by
  // arms_within_exact, which then runs for the initial lanes (rare: 16 doubtful points in 300 000
  // on a TUM frame).  (The division and square root at every point
  // cost a tenth of the edge pass on frames with many open corner tests on an Intel Xeon, whose
  // 16-lane divider is slow.)
  EDGEPLANE_HD EDGEPLANE_INLINE void arms_within(const lane_points& c, std::ptrdiff_t step, int s, int m,
                                                 float t, const float* noise, unsigned* ok) const {
    float cx[Lanes], cy[Lanes], cz[Lanes], ax[Lanes], ay[Lanes], az[Lanes], lo[Lanes], hi[Lanes];
    float top[Lanes];  // the largest num so far
    unsigned ok0[Lanes];
    for (int l = 0; l < Lanes; ++l) {
      const point3 p0 = at(c, step, l, 0), e = at(c, step, l, s * m);
      const point3 ab = e - p0;  // dist2_to_line's b - a, once per arm
      cx[l] = p0.x;
      cy[l] = p0.y;
      cz[l] = p0.z;
      ax[l] = ab.x;
      ay[l] = ab.y;
      az[l] = ab.z;
      const float l2 = dot(ab, ab), bound = t * norm(e - p0) + noise[l];
      const float b2l2 = bound * bound * l2;
      const bool sure = (l2 >= 1e-12f) & (bound >= 1e-15f) & (bound < 1e30f) & (b2l2 >= 1e-30f) & (b2l2 <= 1e30f);
      lo[l] = select_f(sure, b2l2 * 0.9999f, -1.f);     // num >= 0: never below -1
      hi[l] = select_f(sure, b2l2 * 1.0001f, 3.4e38f);  // nor above the largest float
      ok0[l] = ok[l];
      top[l] = 0.f;
    }
    // Two points between the tests for a lane still within: the test, a reduction across the
    // lanes, took 10 of the 37 instructions of a point's iteration (g++ 12, x86-64-v4).  An odd
    // number of inner points leaves one for after the loop.
    int k = 1;
    for (; k + 1 < m; k += 2) {
      arm_point(c, step, s * k, cx, cy, cz, ax, ay, az, hi, top, ok);
      arm_point(c, step, s * (k + 1), cx, cy, cz, ax, ay, az, hi, top, ok);
      unsigned alive = 0;
      for (int l = 0; l < Lanes; ++l) alive |= ok[l];
      if (!alive) return;  // every lane surely beyond at some point
    }
    if (k < m) arm_point(c, step, s * k, cx, cy, cz, ax, ay, az, hi, top, ok);
    unsigned redo = 0;
    for (int l = 0; l < Lanes; ++l) redo |= ok[l] & static_cast<unsigned>(!(top[l] < lo[l]));
    if (redo) {
      for (int l = 0; l < Lanes; ++l) ok[l] = ok0[l];
      arms_within_exact(c, step, s, m, t, noise, ok);
    }
  }

  // farther_than(p, a, b, t, noise) for one lane, without branches: false where its shortcut says
  // so (the exact expression is then false too), the exact expression elsewhere.
  EDGEPLANE_HD EDGEPLANE_INLINE static bool farther_lane(point3 p, point3 a, point3 b, float t, float noise) {
    const point3 ab = b - a, ap = p - a;
    const float l2 = dot(ab, ab);
    const point3 cr = cross(ap, ab);
    const float num = dot(cr, cr), self = dot(ap, ap);
    const float floor2 = t * t * l2 + noise * noise;
    const bool sure_no = (t >= 0.f) & (noise >= 0.f) & (l2 >= 1e-12f) & (floor2 >= 1e-20f) & (num < 1e30f) &
                         (num < l2 * floor2 * 0.9999f);
    const float d2 = select_f(l2 <= 0.f, self, num / l2);  // dist2_to_line's operations
    return !sure_no & (sqrtf(d2) > t * sqrtf(l2) + noise);
  }

  // A lane's condition where judged without division or square root: yes (1) or no (1) where it
  // is sure, neither where in doubt.
  struct lane_judgement {
    unsigned yes, no;
  };
  // farther_lane(p, a, b, t, noise), which is sqrtf(num / l2) > t * sqrtf(l2) + noise = R (its
  // shortcut's "no" is that expression's answer too), judged from num against R^2 l2 (1 -/+ 1e-4):
  // the division, the square root of the quotient and R^2 l2 round by a few ulps, far inside the
  // margin.  Sure only where l2 >= 1e-12, R >= 1e-15 and R^2 l2 lies in [1e-30, 1e30] (so the
  // quotient near R^2 is a normal float).
  EDGEPLANE_HD EDGEPLANE_INLINE static lane_judgement farther_judged(float num, float l2, float t, float noise) {
    const float r = t * sqrtf(l2) + noise;
    const float r2l2 = r * r * l2;
    const bool sure = (l2 >= 1e-12f) & (r >= 1e-15f) & (r < 1e30f) & (r2l2 >= 1e-30f) & (r2l2 <= 1e30f);
    return {static_cast<unsigned>(sure & (num > r2l2 * 1.0001f)), static_cast<unsigned>(sure & (num < r2l2 * 0.9999f))};
  }
  // sqrtf(n / l2) >= 0.6f * sqrtf(nm / l2) (two distances to one line, as the arc test compares
  // them), judged from n against 0.36 nm (1 -/+ 1e-4), sure where l2 lies in [1e-12, 1e10] and nm in
  // [1e-25, 1e26], so that both quotients are normal floats (or n / l2 is far below the bound).
  EDGEPLANE_HD EDGEPLANE_INLINE static lane_judgement not_nearer_judged(float n, float nm, float l2) {
    const float lim = nm * (0.6f * 0.6f);
    const bool sure = (l2 >= 1e-12f) & (l2 <= 1e10f) & (nm >= 1e-25f) & (nm <= 1e26f);
    return {static_cast<unsigned>(sure & (n > lim * 1.0001f)), static_cast<unsigned>(sure & (n < lim * 0.9999f))};
  }
  // The arc test of one side (sg) for every lane with bit `bit` of maybe[l], with the scalar
  // test's expressions (the rare lanes the judgements leave in doubt).
  EDGEPLANE_NOINLINE EDGEPLANE_HD void arcs_exact(const lane_points& c, std::ptrdiff_t step, int sg, int n, int q1,
                                                  int mid, int q3, float t, const float* noise, const unsigned* maybe,
                                                  int bit, unsigned* arc) const {
    for (int l = 0; l < Lanes; ++l) {  // arc_like(nb, sg, noise)
      const point3 p0 = at(c, step, l, 0), e = at(c, step, l, sg * n);
      const point3 pm = at(c, step, l, sg * mid);
      const bool far = farther_lane(pm, p0, e, t, noise[l]);
      const float dm = sqrtf(dist2_to_line(pm, p0, e));
      const float d1 = sqrtf(dist2_to_line(at(c, step, l, sg * q1), p0, e));
      const float d3 = sqrtf(dist2_to_line(at(c, step, l, sg * q3), p0, e));
      arc[l] = ((maybe[l] >> bit) & 1u) & static_cast<unsigned>(far & (d1 >= 0.6f * dm) & (d3 >= 0.6f * dm));
    }
  }

  // Finishes the open tests along Direction (bits 4 D + j of maybe[l]) and ORs the edge bits into
  // bits[l].  The jump pre-test is the whole jump test.
  template <class Direction, int D>
  EDGEPLANE_HD EDGEPLANE_INLINE void finish_along(const lane_points& c, std::ptrdiff_t pitch, const float* zc,
                                                  const float* noise_co, const float* noise_cu, const unsigned* maybe,
                                                  unsigned any, unsigned* bits) const {
    const std::ptrdiff_t step = static_cast<std::ptrdiff_t>(Direction::dy) * pitch + Direction::dx;
    const edge_set& s = px.set;
    if (any & (1u << (4 * D)))
      for (int l = 0; l < Lanes; ++l)
        bits[l] |= ((maybe[l] >> (4 * D)) & 1u) * edge_type::jump::bit;
    if (any & (2u << (4 * D))) {
      const float t = s.extrema.t;
      const int n = s.extrema.n;
      unsigned nearer[Lanes], farther[Lanes];
      for (int l = 0; l < Lanes; ++l) nearer[l] = farther[l] = (maybe[l] >> (4 * D + 1)) & 1u;
      for (int k = 1; k <= n; ++k)
        for (int l = 0; l < Lanes; ++l) {
          const float z = zc[l], a = c[l - k * step], b = c[l + k * step];
          nearer[l] &= static_cast<unsigned>((z < t * a) & (z < t * b));
          farther[l] &= static_cast<unsigned>((z * t > a) & (z * t > b));
        }
      for (int l = 0; l < Lanes; ++l) bits[l] |= (nearer[l] | farther[l]) * edge_type::extrema::bit;
    }
    if (any & (4u << (4 * D))) {
      const int n = s.corner.n, h = n / 2 > 0 ? n / 2 : 1;
      unsigned ok[Lanes], ok_r[Lanes];
      unsigned open = 0;
      for (int l = 0; l < Lanes; ++l) {
        const bool bend = farther_lane(at(c, step, l, 0),
                                       at(c, step, l, -h),
                                       at(c, step, l, h), s.corner.t_bend, noise_co[l]);
        ok[l] = ((maybe[l] >> (4 * D + 2)) & 1u) & static_cast<unsigned>(bend);
        open |= ok[l];
      }
      if (open) {
        arms_within(c, step, -1, n, s.corner.t_arm, noise_co, ok);
        for (int l = 0; l < Lanes; ++l) ok_r[l] = ok[l];
        arms_within(c, step, +1, n, s.corner.t_arm, noise_co, ok_r);
        for (int l = 0; l < Lanes; ++l) bits[l] |= ok_r[l] * edge_type::corner::bit;
      }
    }
    if (any & (8u << (4 * D))) {
      const edge_type::curved& cu = s.curved;
      const int n = cu.n, q1 = n / 4 > 0 ? n / 4 : 1, mid = n / 2 > 0 ? n / 2 : 1, q3 = (3 * n) / 4;
      unsigned arc[2][Lanes], straight[2][Lanes];
      unsigned open = 0;
      for (int side = 0; side < 2; ++side) {
        const int sg = side == 0 ? -1 : 1;
        unsigned doubt = 0;
        for (int l = 0; l < Lanes; ++l) {  // arc_like(nb, sg, noise), without division or square root where sure
          const point3 p0 = at(c, step, l, 0), ab = at(c, step, l, sg * n) - p0;
          const float l2 = dot(ab, ab);
          const point3 cm = cross(at(c, step, l, sg * mid) - p0, ab), c1 = cross(at(c, step, l, sg * q1) - p0, ab),
                       c3 = cross(at(c, step, l, sg * q3) - p0, ab);
          const lane_judgement far = farther_judged(dot(cm, cm), l2, cu.t_bend, noise_cu[l]);
          const lane_judgement r1 = not_nearer_judged(dot(c1, c1), dot(cm, cm), l2);
          const lane_judgement r3 = not_nearer_judged(dot(c3, c3), dot(cm, cm), l2);
          const unsigned bit = (maybe[l] >> (4 * D + 3)) & 1u;
          arc[side][l] = bit & far.yes & r1.yes & r3.yes;
          // in doubt: no condition surely false, and one not surely decided
          doubt |= bit & ((far.no | r1.no | r3.no) ^ 1u) & ((far.yes & r1.yes & r3.yes) ^ 1u);
        }
        if (doubt)  // rare: the scalar expressions for the whole side
          arcs_exact(c, step, sg, n, q1, mid, q3, cu.t_bend, noise_cu, maybe, 4 * D + 3, arc[side]);
        for (int l = 0; l < Lanes; ++l) open |= arc[side][l];
      }
      if (open) {  // straight(nb, side) where the other side is arc-like (and this side, unless
                   // an arc-like side is surely not straight: curved::arc_excludes_straight)
        const bool excl = cu.arc_excludes_straight();
        for (int side = 0; side < 2; ++side) {
          unsigned scan = 0;
          for (int l = 0; l < Lanes; ++l) {
            straight[side][l] = excl ? arc[1 - side][l] & (arc[side][l] ^ 1u) : arc[0][l] | arc[1][l];
            scan |= straight[side][l];
          }
          if (scan) arms_within(c, step, side == 0 ? -1 : 1, n, cu.t_straight, noise_cu, straight[side]);
        }
        for (int l = 0; l < Lanes; ++l) {
          const unsigned fire = (arc[0][l] & straight[1][l] & (straight[0][l] ^ 1u)) |
                                (arc[1][l] & straight[0][l] & (straight[1][l] ^ 1u));
          bits[l] |= fire * edge_type::curved::bit;
        }
      }
    }
  }

  template <bool Checked>
  EDGEPLANE_HD EDGEPLANE_INLINE void maybe_all(const lane_points& c, std::ptrdiff_t pitch, int x0, const float* zc,
                                               const float* noise_co, const float* noise_cu, unsigned* maybe) const {
    maybe_along<direction::horizontal, 0, Checked>(c, pitch, x0, zc, noise_co, noise_cu, maybe);
    maybe_along<direction::vertical, 1, Checked>(c, pitch, x0, zc, noise_co, noise_cu, maybe);
    maybe_along<direction::left_diagonal, 2, Checked>(c, pitch, x0, zc, noise_co, noise_cu, maybe);
    maybe_along<direction::right_diagonal, 3, Checked>(c, pitch, x0, zc, noise_co, noise_cu, maybe);
    if (px.set.use_curved && px.arc_flat != nullptr) {
      // The curved test stays open along d unless both of its triples, centred m = n / 2 steps
      // either side, were judged surely within for this end (arc_flat_rows_kernel: bit d of the
      // byte m steps right, bit 4 + d of the byte m steps left): the two bytes of 8 lanes at a
      // time, bit d of each byte moved to its top and gathered to one bit per lane.
      const std::uint8_t* f = px.arc_flat + (c.z - (px.points + px.points_at.offset(0, 0)));  // lane 0's byte
      const int m = px.set.curved.n / 2;
      const std::ptrdiff_t steps[4] = {direction::horizontal::dy * pitch + direction::horizontal::dx,
                                       direction::vertical::dy * pitch + direction::vertical::dx,
                                       direction::left_diagonal::dy * pitch + direction::left_diagonal::dx,
                                       direction::right_diagonal::dy * pitch + direction::right_diagonal::dx};
      unsigned open[4];
      for (int d = 0; d < 4; ++d) {
        const std::ptrdiff_t o = m * steps[d];
        open[d] = 0;
        for (int l = 0; l < Lanes; l += 8)
          open[d] |= swar::gather_high_bits(~((swar::load(f + l - o) >> 4) & swar::load(f + l + o)) >> d << 7) << l;
      }
      for (int l = 0; l < Lanes; ++l)
        maybe[l] |= ((open[0] >> l) & 1u) << 3 | ((open[1] >> l) & 1u) << 7 | ((open[2] >> l) & 1u) << 11 |
                    ((open[3] >> l) & 1u) << 15;
    }
  }

  EDGEPLANE_PAGE_ALIGNED EDGEPLANE_HOST_CLONES EDGEPLANE_HD void operator()(std::int64_t item) const {
    const int y = static_cast<int>(item / chunks), x0 = static_cast<int>(item % chunks) * Lanes;
    const int w = px.depth.width, h = px.depth.height, r = px.reach;
    // A run must not pass the row's end.  Every lane reads up to r steps of up to w + 1 elements
    // either way, in the padded point planes (zeros, invalid, beyond the top and bottom rows; a
    // step past the first or last column lands in the row before or after): garbage that the
    // counts mask.
    if (x0 + Lanes > w) {
      for (int x = x0; x < w; ++x) px(x, y);
      return;
    }
    const std::ptrdiff_t pitch = w;
    const edge_points_layout& at = px.points_at;
    const std::int64_t first = at.offset(x0, y);
    const lane_points c{px.points + at.z + first, px.points + at.x + first, px.points + at.y + first};
    const std::int64_t n = static_cast<std::int64_t>(w) * h, i0 = static_cast<std::int64_t>(y) * w + x0;
    float zc[Lanes], noise_co[Lanes], noise_cu[Lanes];
    unsigned maybe[Lanes];
    for (int l = 0; l < Lanes; ++l) {
      zc[l] = c[l];
      noise_co[l] = px.set.corner.noise_k * px.set.corner.sigma(zc[l]);
      noise_cu[l] = px.set.curved.noise_k * px.set.curved.sigma(zc[l]);
      maybe[l] = 0;
    }
    const std::uint8_t* cnt = px.runs + i0;  // plane q of the counts at cnt + q * n
    int full = 1;  // every lane valid, with all its counts at reach (most runs: surface)
    for (int l = 0; l < Lanes; ++l) full &= zc[l] > 0.f;
    if (full) {  // the counts compared 8 bytes at a time: every byte of each word equals r
      const std::uint64_t rr = swar::ones8 * static_cast<std::uint64_t>(r);
      static_assert(Lanes % 8 == 0, "runs of whole 8-byte words");
      std::uint64_t diff = 0;
      for (int q = 0; q < 8; ++q)
        for (int l = 0; l < Lanes; l += 8) diff |= swar::load(cnt + q * n + l) ^ rr;
      full = diff == 0;
    }
    if (full) {
      maybe_all<false>(c, pitch, x0, zc, noise_co, noise_cu, maybe);
    } else {
      maybe_all<true>(c, pitch, x0, zc, noise_co, noise_cu, maybe);
      // The extrema, corner and curved pre-tests ran on every lane; each stays open only where
      // both of its counts reach its neighbours (the scalar test's first check).  The counts
      // (<= 32) are compared 8 bytes at a time (swar::at_least, both sides, each test's
      // threshold, made once).  The three tests' flags of direction d become bits 1..3 of each lane's byte,
      // shifted by 4 for the odd directions, so that two bytes per lane hold its four directions'
      // bits in maybe's order (bit 4 d + j).
      static_assert(Lanes % 8 == 0, "whole 8-byte words of counts");
      const swar::at_least need[3] = {swar::at_least(px.set.extrema.n), swar::at_least(px.set.corner.n),
                                      swar::at_least(px.set.curved.n)};
      std::uint8_t keep[2][Lanes];  // directions 0 and 1 / 2 and 3 of lane l
      for (int l = 0; l < Lanes; l += 8) {
        std::uint64_t k[2] = {0, 0};
        for (int d = 0; d < 4; ++d) {
          const std::uint64_t a = swar::load(cnt + 2 * d * n + l), b = swar::load(cnt + (2 * d + 1) * n + l);
          std::uint64_t f = 0;
          for (int j = 0; j < 3; ++j) f |= (need[j](a) & need[j](b)) >> (6 - j);
          k[d / 2] |= f << (4 * (d % 2));
        }
        std::memcpy(&keep[0][l], &k[0], 8);
        std::memcpy(&keep[1][l], &k[1], 8);
      }
      for (int l = 0; l < Lanes; ++l)
        maybe[l] &= 0x1111u | static_cast<unsigned>(keep[0][l]) | static_cast<unsigned>(keep[1][l]) << 8;
    }
    std::uint8_t* e = &px.edges(x0, y);
    unsigned any = 0;
    for (int l = 0; l < Lanes; ++l) any |= maybe[l];
    unsigned bits[Lanes] = {};
    if (any) {
      finish_along<direction::horizontal, 0>(c, pitch, zc, noise_co, noise_cu, maybe, any, bits);
      finish_along<direction::vertical, 1>(c, pitch, zc, noise_co, noise_cu, maybe, any, bits);
      finish_along<direction::left_diagonal, 2>(c, pitch, zc, noise_co, noise_cu, maybe, any, bits);
      finish_along<direction::right_diagonal, 3>(c, pitch, zc, noise_co, noise_cu, maybe, any, bits);
    }
    for (int l = 0; l < Lanes; ++l) e[l] = static_cast<std::uint8_t>(zc[l] > 0.f ? bits[l] : static_cast<unsigned>(edge_invalid));
  }
};

/// Binary dilation of "any bit set" over a (2r+1)^2 window.
struct mask_dilate_kernel {
  image_view<const std::uint8_t> in;
  image_view<std::uint8_t> out;
  int r;
  EDGEPLANE_HD void operator()(int x, int y) const {
    std::uint8_t v = 0;
    if (x >= r && y >= r && x < in.width - r && y < in.height - r) {  // the window is inside: no checks
      for (int dy = -r; dy <= r; ++dy) {
        const std::uint8_t* row = &in(x - r, y + dy);
        for (int j = 0; j <= 2 * r; ++j) v = static_cast<std::uint8_t>(v | row[j]);
      }
      out(x, y) = v ? 1 : 0;
      return;
    }
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
  EDGEPLANE_HD void operator()(int x, int y) const {
    std::uint8_t v = 1;
    if (!in(x, y)) {  // the centre is in its own window
      out(x, y) = 0;
      return;
    }
    for (int dy = -r; dy <= r && v; ++dy)
      for (int dx = -r; dx <= r; ++dx)
        if (in.contains(x + dx, y + dy) && !in(x + dx, y + dy)) {
          v = 0;
          break;
        }
    out(x, y) = v;
  }
};

/// Host form of the edge map's closing, one work item per row: the output row accumulates the
/// window one shift at a time, each a pass over the row (64 bytes per AVX-512 instruction).
/// Rows and columns outside the image are skipped, as the per-pixel kernels skip them: the
/// dilation ORs in the taps (then 1 where any is set), the erosion ANDs them with the centre.
template <bool Dilate>
struct mask_rows_kernel {
  static constexpr bool even_work = true;  // see detail::even_work_v
  image_view<const std::uint8_t> in;
  image_view<std::uint8_t> out;
  int r;
  EDGEPLANE_HOST_CLONES void operator()(std::int64_t row) const {
    const int y = static_cast<int>(row), w = in.width;
    std::uint8_t* o = &out(0, y);
    const std::uint8_t* c = &in(0, y);
    if constexpr (Dilate)
      for (int x = 0; x < w; ++x) o[x] = 0;
    else
      for (int x = 0; x < w; ++x) o[x] = c[x] != 0;
    for_each_window_shift(in, y, r, [&](const std::uint8_t* t, int dx, int x0, int x1) {
      if constexpr (Dilate)
        for (int x = x0; x < x1; ++x) o[x] = static_cast<std::uint8_t>(o[x] | t[x + dx]);
      else
        for (int x = x0; x < x1; ++x) o[x] = static_cast<std::uint8_t>(o[x] & (t[x + dx] != 0));
    });
    if constexpr (Dilate)
      for (int x = 0; x < w; ++x) o[x] = o[x] != 0;
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
  detail::for_each_pixel(b, depth.width, depth.height,
                         detail::edge_kernel<Direction, EdgeType>{depth, edges, detail::make_projector(k), edge});
}

namespace detail {
/// The layout of detect_edges' host scratch for a w x h image (w, h > 0) and the edge tests'
/// reach r, as byte offsets: the valid-neighbour counts (8 w x h bytes), the validity plane (w x h
/// bytes; once the counts are made, the curved pre-test's judgements, arc_flat_rows_kernel), then,
/// 64-byte aligned, the point planes (edge_points_layout).
struct edge_scratch_layout {
  std::size_t valid, points, bytes;
  edge_scratch_layout(int w, int h, int r) {
    const std::size_t n = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
    valid = 8 * n;
    points = (9 * n + 63) / 64 * 64;
    bytes = points + static_cast<std::size_t>(edge_points_layout(w, h, r).elements()) * sizeof(float);
  }
};
}  // namespace detail

/// Bytes of detect_edges' host scratch for a w x h image under params p (see
/// detail::edge_scratch_layout).
inline std::size_t edge_scratch_bytes(int w, int h, const params& p) {
  return w > 0 && h > 0 ? detail::edge_scratch_layout(w, h, detail::make_edge_set(p).reach()).bytes : 0;
}

/// All enabled edge types over the four directions in one pass: writes every pixel of `edges`
/// (edge_bits; edge_invalid where depth is invalid).  `scratch`: edge_scratch_bytes(w, h, p)
/// bytes of the backend's memory, 64-byte aligned, used by host backends (null:
/// allocated per call) for the valid-neighbour counts and the back-projected points.  Device
/// backends mark, in `edges` itself, the pixels whose whole neighbourhood is valid, and count
/// the neighbours of the others in the edge pass.  Asynchronous on device backends.
template <class Backend>
void detect_edges(const Backend& b, image_view<const float> depth, const intrinsics& k, const params& p,
                  image_view<std::uint8_t> edges, std::uint8_t* scratch = nullptr) {
  detail::check_intrinsics(k);
  detail::check_same_size(depth, edges, "depth", "edges");
  const detail::edge_set set = detail::make_edge_set(p);
  const int reach = set.reach();
  detail::require(reach >= 1 && reach <= 32,
                  "detect_edges: the edge tests' arms (n_ee, n_coe, n_cue) must reach 1 to 32 neighbours, got " +
                      std::to_string(reach));
  const int w = depth.width, h = depth.height;
  if (w <= 0 || h <= 0) return;
  detail::all_edges_kernel px{depth, edges, detail::make_projector(k), set, reach};
  buffer<std::uint8_t, Backend> own;  // lives until the edge pass is done
  if constexpr (detail::row_lanes<Backend> > 1) {
    if (scratch == nullptr) {
      own = buffer<std::uint8_t, Backend>(b);
      own.resize(edge_scratch_bytes(w, h, p));
      scratch = own.data();
    }
    const detail::edge_scratch_layout at(w, h, reach);
    std::uint8_t* runs = scratch;
    std::uint8_t* valid = scratch + at.valid;
    float* points = reinterpret_cast<float*>(scratch + at.points);
    const int band = detail::valid_runs_band(h);
    const detail::edge_points_layout points_at(w, h, reach);
    b.for_each_index(h, detail::valid_runs_rows_kernel{depth, runs, reach, valid, px.proj, points, points_at});
    b.for_each_index(6 * ((h + band - 1) / band), detail::valid_runs_bands_kernel{depth, runs, reach, band, valid});
    px.runs = runs;
    px.points = points;
    px.points_at = points_at;
    // The curved pre-test's shared triples, where the arm's midpoint halves it, into the validity
    // plane (read by the counts only).  The edge pass reads the judgements of every lane m steps
    // either way, past the plane's ends for lanes its counts then reject: in the count planes
    // before it and the point planes after it, so the counts must span m rows and a run.
    const edge_type::curved& cu = set.curved;
    const int m = cu.n / 2;
    if (set.use_curved && cu.n % 2 == 0 && cu.t_bend >= 0.f && cu.noise_k >= 0.f && cu.sigma.s0 >= 0.f &&
        cu.sigma.s2 >= 0.f &&
        8 * static_cast<std::int64_t>(w) * h >= static_cast<std::int64_t>(m) * (w + 1) + 2 * detail::row_lanes<Backend>) {
      b.for_each_index(h, detail::arc_flat_rows_kernel<detail::row_lanes<Backend>>{
                              points, points_at, w, m, cu.t_bend, cu.noise_k, cu.sigma, valid});
      px.arc_flat = valid;
    }
  } else {
    detail::for_each_pixel(b, w, h, detail::interior_pixel_kernel{depth, edges, reach});
  }
  detail::for_each_pixel_run<detail::all_edges_rows_kernel>(b, w, h, px);
}

/// Closing (dilate, then erode) of the edge map with a (2r+1)^2 window: `mask` becomes 1 on edge
/// and invalid pixels and on the gaps the closing bridges, 0 elsewhere.  r = 0 copies the map as a
/// mask.  `scratch` is the image's size.
template <class Backend>
void close_edges(const Backend& b, image_view<const std::uint8_t> edges, image_view<std::uint8_t> scratch,
                 image_view<std::uint8_t> mask, int r) {
  detail::check_same_size(edges, mask, "edges", "mask");
  detail::check_same_size(edges, scratch, "edges", "scratch");
  if constexpr (Backend::host_accessible) {  // host: by rows
    b.for_each_index(edges.height, detail::mask_rows_kernel<true>{edges, scratch, r});
    b.for_each_index(edges.height, detail::mask_rows_kernel<false>{scratch, mask, r});
  } else {
    detail::for_each_pixel(b, edges.width, edges.height, detail::mask_dilate_kernel{edges, scratch, r});
    detail::for_each_pixel(b, edges.width, edges.height, detail::mask_erode_kernel{scratch, mask, r});
  }
}

}  // namespace edgeplane
