// edgeplane: small 3-D geometry used inside kernels (host and device).
#pragma once
#include <bit>
#include <cmath>
#include <cstdint>

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

/// c ? a : b without a branch (by bits), so that a loop whose values are computed either way (a
/// division that may be by zero in the lanes it does not select) vectorizes on every target.
EDGEPLANE_HD EDGEPLANE_INLINE float select_f(bool c, float a, float b) {
  const std::uint32_t m = 0u - static_cast<std::uint32_t>(c);
  return std::bit_cast<float>((std::bit_cast<std::uint32_t>(a) & m) | (std::bit_cast<std::uint32_t>(b) & ~m));
}

/// Squared distance of p from the line through a and b (a != b); |p - a|^2 when a == b.  Without
/// a branch (the host's 16-pixel edge tests call it lane by lane).
EDGEPLANE_HD EDGEPLANE_INLINE float dist2_to_line(point3 p, point3 a, point3 b) {
  const point3 ab = b - a, ap = p - a;
  const float l2 = dot(ab, ab);
  const point3 c = cross(ap, ab);
  return select_f(l2 <= 0.f, dot(ap, ap), dot(c, c) / l2);
}

/// sqrtf(dist2_to_line(p, a, b)) > t * norm(b - a) + noise, evaluated with exactly the float
/// operations of that expression whenever the answer is in doubt, but answering "no" without a
/// square root or a division when it is clearly no: with l2 = |b - a|^2 and num = |(p - a) x (b - a)|^2
/// (the shared values), num < l2 (t^2 l2 + noise^2) (1 - 1e-4) implies the distance is below
/// t |b - a| + noise by a relative margin of 5e-5, far beyond the few float roundings of either side,
/// so the exact expression is false too.  The guards keep every quantity of the shortcut in the
/// normal float range (t, noise >= 0; l2 >= 1e-12 m^2; t^2 l2 + noise^2 >= 1e-20 m^2; num < 1e30):
/// outside them the exact expression decides.  Most pixels lie on surfaces and stop here.
EDGEPLANE_HD EDGEPLANE_INLINE bool farther_than(point3 p, point3 a, point3 b, float t, float noise) {
  const point3 ab = b - a, ap = p - a;
  const float l2 = dot(ab, ab);
  const point3 c = cross(ap, ab);
  const float num = dot(c, c);
  const float floor2 = t * t * l2 + noise * noise;
  if (t >= 0.f && noise >= 0.f && l2 >= 1e-12f && floor2 >= 1e-20f && num < 1e30f && num < l2 * floor2 * 0.9999f)
    return false;
  const float d2 = l2 <= 0.f ? dot(ap, ap) : num / l2;  // = dist2_to_line(p, a, b), the same operations
  return sqrtf(d2) > t * sqrtf(l2) + noise;            // sqrtf(l2) = norm(b - a), the same operations
}

EDGEPLANE_HD EDGEPLANE_INLINE bool valid_depth(float z) { return z > 0.f; }

/// |n . p + d| for plane l of a table holding nx, ny, nz, d per plane (metres).
EDGEPLANE_HD EDGEPLANE_INLINE float plane_distance(const float* planes, int l, point3 p) {
  const float* q = planes + 4 * l;
  return fabsf(q[0] * p.x + q[1] * p.y + q[2] * p.z + q[3]);
}

}  // namespace edgeplane::detail
