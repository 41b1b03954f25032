// edgeplane: small 3-D geometry used inside kernels (host and device).
#pragma once
#include <cmath>

#include "edgeplane/camera.hpp"
#include "edgeplane/config.hpp"
#include "edgeplane/params.hpp"

namespace edgeplane::detail {

struct point3 {
  float x, y, z;
};
EDGEPLANE_HD EDGEPLANE_INLINE point3 operator-(point3 a, point3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
EDGEPLANE_HD EDGEPLANE_INLINE point3 operator+(point3 a, point3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
EDGEPLANE_HD EDGEPLANE_INLINE point3 operator*(float s, point3 a) { return {s * a.x, s * a.y, s * a.z}; }
EDGEPLANE_HD EDGEPLANE_INLINE float dot(point3 a, point3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
EDGEPLANE_HD EDGEPLANE_INLINE point3 cross(point3 a, point3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
EDGEPLANE_HD EDGEPLANE_INLINE float norm(point3 a) { return sqrtf(dot(a, a)); }

/// Back-projection of pixel (u, v) at depth z (metres) into the camera frame.
struct projector {
  float inv_fx, inv_fy, cx, cy;
  EDGEPLANE_HD EDGEPLANE_INLINE point3 operator()(int u, int v, float z) const {
    return {(static_cast<float>(u) - cx) * z * inv_fx, (static_cast<float>(v) - cy) * z * inv_fy, z};
  }
};
inline projector make_projector(const intrinsics& k) { return {1.f / k.fx, 1.f / k.fy, k.cx, k.cy}; }

/// Depth noise standard deviation at range z (metres).
struct noise_sigma {
  float s0, s2;
  EDGEPLANE_HD EDGEPLANE_INLINE float operator()(float z) const { return s0 + s2 * z * z; }
};
inline noise_sigma make_noise(const noise_model& m) { return {m.sigma0, m.sigma2}; }

/// Squared distance of p from the line through a and b (a != b); |p - a|^2 when a == b.
EDGEPLANE_HD EDGEPLANE_INLINE float dist2_to_line(point3 p, point3 a, point3 b) {
  const point3 ab = b - a, ap = p - a;
  const float l2 = dot(ab, ab);
  if (l2 <= 0.f) return dot(ap, ap);
  const point3 c = cross(ap, ab);
  return dot(c, c) / l2;
}

EDGEPLANE_HD EDGEPLANE_INLINE bool valid_depth(float z) { return z > 0.f; }

/// |n . p + d| for plane l of a table holding nx, ny, nz, d per plane (metres).
EDGEPLANE_HD EDGEPLANE_INLINE float plane_distance(const float* planes, int l, point3 p) {
  const float* q = planes + 4 * l;
  return fabsf(q[0] * p.x + q[1] * p.y + q[2] * p.z + q[3]);
}

}  // namespace edgeplane::detail
