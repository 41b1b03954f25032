// Segments a synthetic tilted floor and checks its plane: proves the package is usable as-is.
#include <edgeplane/edgeplane.hpp>

#include <cmath>
#include <cstdio>
#include <vector>

int main() {
  const int w = 128, h = 96;
  const edgeplane::intrinsics k{110.f, 110.f, 63.5f, 47.5f};
  // plane n . X + d = 0 with n = (0, -0.8, -0.6), d = 1.5: depth z = d / (0.8 y' + 0.6), y' = (v - cy)/fy
  std::vector<float> depth(w * h);
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u) depth[v * w + u] = 1.5f / (0.8f * (v - k.cy) / k.fy + 0.6f);
  std::vector<std::uint16_t> labels(w * h);
  edgeplane::params p = edgeplane::presets::thesis_half();
  p.downscale = false;
  edgeplane::segmenter<> seg(p);
  const auto r = seg.segment(edgeplane::make_view(static_cast<const float*>(depth.data()), w, h), k,
                             edgeplane::make_view(labels.data(), w, h));
  if (r.planes.size() != 1) {
    std::printf("expected 1 plane, got %zu\n", r.planes.size());
    return 1;
  }
  const auto& pl = r.planes[0];
  const double err = std::abs(pl.normal[1] + 0.8) + std::abs(pl.normal[2] + 0.6) + std::abs(pl.d - 1.5);
  std::printf("plane n=(%.4f %.4f %.4f) d=%.4f pixels=%lld\n", pl.normal[0], pl.normal[1], pl.normal[2], pl.d,
              static_cast<long long>(pl.pixels));
  return err < 0.01 ? 0 : 1;
}
