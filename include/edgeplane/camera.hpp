// edgeplane: pinhole camera intrinsics and depth conversion.
#pragma once
#include <cmath>
#include <string>

#include "edgeplane/config.hpp"
#include "edgeplane/error.hpp"

namespace edgeplane {

/// Pinhole intrinsics in pixels.  A pixel (u, v) with depth z (metres, along the optical axis)
/// back-projects to X = ((u - cx) z / fx, (v - cy) z / fy, z) in the camera frame
/// (x right, y down, z forward).  fy may be negative (ICL-NUIM convention); fx and fy must be
/// finite and non-zero, cx and cy finite.
struct intrinsics {
  float fx = 0.f;
  float fy = 0.f;
  float cx = 0.f;
  float cy = 0.f;
};

namespace detail {
inline void check_intrinsics(const intrinsics& k) {
  auto bad = [](float f) { return !std::isfinite(f) || f == 0.f; };
  require(!bad(k.fx) && !bad(k.fy) && std::isfinite(k.cx) && std::isfinite(k.cy),
          "intrinsics must be finite with non-zero focal lengths (fx=" + std::to_string(k.fx) +
              ", fy=" + std::to_string(k.fy) + ", cx=" + std::to_string(k.cx) + ", cy=" + std::to_string(k.cy) + ")");
}
}  // namespace detail

/// Intrinsics of an image downscaled by an integer factor (pixel centres kept consistent).
inline intrinsics scaled(const intrinsics& k, int factor) {
  const float s = 1.f / static_cast<float>(factor);
  return {k.fx * s, k.fy * s, (k.cx + 0.5f) * s - 0.5f, (k.cy + 0.5f) * s - 0.5f};
}

}  // namespace edgeplane
