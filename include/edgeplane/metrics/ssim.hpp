// edgeplane: the SSIM of label images as the thesis used it (EVALUATION.md): both label images are
// rendered to 8 bits after the D2MC matching, then compared with Wang et al.'s reference SSIM
// (ssim.m, 2004/2011: automatic downsampling, 11x11 Gaussian window, 'valid' filtering).
// Host only, no I/O.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "edgeplane/error.hpp"
#include "edgeplane/image.hpp"
#include "edgeplane/metrics/d2mc.hpp"
#include "edgeplane/metrics/overlap_table.hpp"

namespace edgeplane::metrics {

/// Grey level of rank r >= 1 in the rendering: g(r) = 1 + (97 r mod 255), in [1, 255].
inline std::uint8_t ssim_grey_level(std::int64_t rank) { return static_cast<std::uint8_t>(1 + (97 * rank) % 255); }

/// Wang et al.'s automatic downsampling factor F = max(1, round(min(rows, cols) / 256)), rounding
/// halves up as MATLAB's round does (min = 384 gives 2).  Sizes in pixels.
inline int ssim_downsampling_factor(int width, int height) {
  const int m = std::min(width, height);
  return std::max(1, (m + 128) / 256);
}

/// Render both label images to 8 bits for the SSIM, writing into host images the caller owns (the
/// size of `pred`): label 0 -> 0; GT plane of rank r (1-based position in `t.gt_ids`, the GT ids
/// present on scored pixels, ascending) -> g(r); a segment matched by `matching` to GT rank r ->
/// g(r); unmatched segments (those of `t.segment_ids`, i.e. present on scored pixels), in ascending
/// id order j = 1, 2, ... -> g(G + j) with G the number of GT planes; unscored pixels -> 0 in both.
/// `t` and `matching` must come from the same three images.  Throws edgeplane::error on unusable
/// views, sizes that differ, or a matching that does not fit the table.
inline void render_labels_for_ssim(const overlap_table& t, const d2mc_result& matching,
                                   image_view<const std::uint16_t> pred, image_view<const std::uint16_t> gt,
                                   image_view<const std::uint8_t> scored, image_view<std::uint8_t> pred_out,
                                   image_view<std::uint8_t> gt_out) {
  using edgeplane::detail::check_same_size;
  using edgeplane::detail::check_view;
  check_view(pred, "pred");
  check_view(gt, "gt");
  check_view(scored, "scored");
  check_view(pred_out, "pred_out");
  check_view(gt_out, "gt_out");
  check_same_size(pred, gt, "pred", "gt");
  check_same_size(pred, scored, "pred", "scored");
  check_same_size(pred, pred_out, "pred", "pred_out");
  check_same_size(pred, gt_out, "pred", "gt_out");
  edgeplane::detail::require(matching.segment_to_gt.size() == t.segment_ids.size() + 1,
                             "render_labels_for_ssim: the matching does not belong to the overlap table");

  std::vector<std::uint8_t> gt_grey(65536, 0), pred_grey(65536, 0);
  const std::int64_t n_gt = t.gt_planes();
  for (std::int64_t k = 0; k < n_gt; ++k) gt_grey[t.gt_ids[static_cast<std::size_t>(k)]] = ssim_grey_level(k + 1);
  std::int64_t unmatched = 0;
  for (std::size_t k = 0; k < t.segment_ids.size(); ++k) {
    const int j = matching.segment_to_gt[k + 1];
    edgeplane::detail::require(j >= 0 && j <= n_gt, "render_labels_for_ssim: matched GT index out of range");
    pred_grey[t.segment_ids[k]] = j > 0 ? ssim_grey_level(j) : ssim_grey_level(n_gt + ++unmatched);
  }
  for (int y = 0; y < pred.height; ++y)
    for (int x = 0; x < pred.width; ++x) {
      const bool s = scored(x, y) != 0;
      pred_out(x, y) = s ? pred_grey[pred(x, y)] : 0;
      gt_out(x, y) = s ? gt_grey[gt(x, y)] : 0;
    }
}

namespace detail {
/// MATLAB's 'symmetric' padding: index -1 reads 0, index n reads n - 1.
inline int symmetric_index(int i, int n) {
  while (i < 0 || i >= n) i = i < 0 ? -i - 1 : 2 * n - i - 1;
  return i;
}

/// ssim.m's downsampling: imfilter(img, ones(F)/F^2, 'symmetric', 'same') then img(1:F:end, 1:F:end).
/// MATLAB anchors an even F x F kernel at floor((F + 1) / 2), so the box of output pixel (x, y)
/// spans x - (c - 1) .. x + F - c with c = floor((F + 1) / 2) (F = 2: x .. x + 1).
inline std::vector<double> ssim_downsample(image_view<const std::uint8_t> img, int f, int& out_w, int& out_h) {
  out_w = (img.width + f - 1) / f;
  out_h = (img.height + f - 1) / f;
  std::vector<double> out(static_cast<std::size_t>(out_w) * static_cast<std::size_t>(out_h));
  const int lo = -((f + 1) / 2 - 1), hi = f - (f + 1) / 2;
  const double area = static_cast<double>(f) * f;
  for (int oy = 0; oy < out_h; ++oy)
    for (int ox = 0; ox < out_w; ++ox) {
      double sum = 0;
      for (int dy = lo; dy <= hi; ++dy) {
        const int y = symmetric_index(oy * f + dy, img.height);
        for (int dx = lo; dx <= hi; ++dx) sum += img(symmetric_index(ox * f + dx, img.width), y);
      }
      out[static_cast<std::size_t>(oy) * static_cast<std::size_t>(out_w) + static_cast<std::size_t>(ox)] = sum / area;
    }
  return out;
}
}  // namespace detail

/// Wang et al.'s reference SSIM (ssim.m with its defaults) of two 8-bit host images of the same
/// size: downsampling by ssim_downsampling_factor(), an 11x11 Gaussian window with sigma 1.5
/// (normalized), 'valid' filtering (no border handling), K1 = 0.01, K2 = 0.03, L = 255, biased
/// (population) window variances, and the mean of the SSIM map.  Returns NaN when the downsampled
/// image is smaller than 11x11 (ssim.m gives no value there).  Throws edgeplane::error on unusable
/// views or sizes that differ.
inline double ssim(image_view<const std::uint8_t> a, image_view<const std::uint8_t> b) {
  edgeplane::detail::check_view(a, "a");
  edgeplane::detail::check_view(b, "b");
  edgeplane::detail::check_same_size(a, b, "a", "b");
  constexpr int win = 11, radius = 5;
  const int f = ssim_downsampling_factor(a.width, a.height);
  int w = 0, h = 0;
  const std::vector<double> x = detail::ssim_downsample(a, f, w, h);
  const std::vector<double> y = detail::ssim_downsample(b, f, w, h);
  if (w < win || h < win) return std::numeric_limits<double>::quiet_NaN();

  double g[win];  // fspecial('gaussian', 11, 1.5) is the outer product of this normalized 1-D kernel
  double g_sum = 0;
  for (int k = 0; k < win; ++k) {
    const double d = k - radius;
    g[k] = std::exp(-(d * d) / (2 * 1.5 * 1.5));
    g_sum += g[k];
  }
  for (double& gk : g) gk /= g_sum;

  // Horizontal pass ('valid' in x) of x, y, x^2, y^2, xy; then the vertical pass per output pixel.
  const int vw = w - 2 * radius, vh = h - 2 * radius;
  const std::size_t hsize = static_cast<std::size_t>(h) * static_cast<std::size_t>(vw);
  std::vector<double> hx(hsize), hy(hsize), hxx(hsize), hyy(hsize), hxy(hsize);
  for (int r = 0; r < h; ++r) {
    const std::size_t row = static_cast<std::size_t>(r) * static_cast<std::size_t>(w);
    for (int c = 0; c < vw; ++c) {
      double sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;
      for (int k = 0; k < win; ++k) {
        const double xv = x[row + static_cast<std::size_t>(c + k)], yv = y[row + static_cast<std::size_t>(c + k)];
        sx += g[k] * xv;
        sy += g[k] * yv;
        sxx += g[k] * (xv * xv);
        syy += g[k] * (yv * yv);
        sxy += g[k] * (xv * yv);
      }
      const std::size_t o = static_cast<std::size_t>(r) * static_cast<std::size_t>(vw) + static_cast<std::size_t>(c);
      hx[o] = sx;
      hy[o] = sy;
      hxx[o] = sxx;
      hyy[o] = syy;
      hxy[o] = sxy;
    }
  }
  const double c1 = (0.01 * 255) * (0.01 * 255), c2 = (0.03 * 255) * (0.03 * 255);
  double total = 0;
  for (int r = 0; r < vh; ++r)
    for (int c = 0; c < vw; ++c) {
      double mx = 0, my = 0, exx = 0, eyy = 0, exy = 0;
      for (int k = 0; k < win; ++k) {
        const std::size_t o =
            static_cast<std::size_t>(r + k) * static_cast<std::size_t>(vw) + static_cast<std::size_t>(c);
        mx += g[k] * hx[o];
        my += g[k] * hy[o];
        exx += g[k] * hxx[o];
        eyy += g[k] * hyy[o];
        exy += g[k] * hxy[o];
      }
      const double vx = exx - mx * mx, vy = eyy - my * my, cxy = exy - mx * my;
      total += ((2 * mx * my + c1) * (2 * cxy + c2)) / ((mx * mx + my * my + c1) * (vx + vy + c2));
    }
  return total / (static_cast<double>(vw) * static_cast<double>(vh));
}

/// The thesis SSIM of a predicted label image against a GT label image on scored pixels: the D2MC
/// matching, render_labels_for_ssim(), then ssim().  Host images of the same size; throws
/// edgeplane::error otherwise.  NaN when the (downsampled) image is smaller than 11x11.
inline double label_ssim(image_view<const std::uint16_t> pred, image_view<const std::uint16_t> gt,
                         image_view<const std::uint8_t> scored) {
  const overlap_table t = make_overlap_table(pred, gt, scored);
  const d2mc_result m = d2mc_matching(t);
  const std::size_t n = static_cast<std::size_t>(pred.width) * static_cast<std::size_t>(pred.height);
  std::vector<std::uint8_t> a(n), b(n);
  render_labels_for_ssim(t, m, pred, gt, scored, make_view(a.data(), pred.width, pred.height),
                         make_view(b.data(), pred.width, pred.height));
  return ssim(make_view(static_cast<const std::uint8_t*>(a.data()), pred.width, pred.height),
              make_view(static_cast<const std::uint8_t*>(b.data()), pred.width, pred.height));
}

}  // namespace edgeplane::metrics
