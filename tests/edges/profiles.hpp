// edgeplane tests: depth images that vary along one direction only, ray-cast from 1-D profiles.
//
// For a direction D = (dx, dy), the profile coordinate of pixel (u, v) is s = u dx + v dy; with
// fx = fy its ray's lateral slope along D is rho(s) = ((u - cx) dx + (v - cy) dy) / (f |D|), which
// depends on s alone.  A surface extruded along the perpendicular of D is described in the
// (xi, z) plane (xi: lateral metres along D) as z = g(xi); the depth at s is the t solving
// t = g(t rho(s)).  So every image row (column, diagonal) across D sees the same 3-D profile.
#pragma once
#include <cmath>
#include <cstdint>
#include <vector>

#include "edgeplane/camera.hpp"
#include "support/test_backends.hpp"

namespace edgeplane_test {

struct profile {
  int w = 0, h = 0, dx = 0, dy = 0;
  edgeplane::intrinsics k{};
  std::vector<float> z;
  int s(int x, int y) const { return x * dx + y * dy; }
  double rho(int s_) const {
    const double sc = k.cx * dx + k.cy * dy;
    return (s_ - sc) / (k.fx * std::sqrt(double(dx * dx + dy * dy)));
  }
  float at(int x, int y) const { return z[static_cast<std::size_t>(y) * w + x]; }
  /// True when the n-th neighbours on both sides of (x, y) along D lie inside the image.
  bool full_arms(int x, int y, int n) const {
    auto in = [&](int u, int v) { return u >= 0 && v >= 0 && u < w && v < h; };
    return in(x + n * dx, y + n * dy) && in(x - n * dx, y - n * dy);
  }
};

/// The image size used for direction D: long along D, a few pixels across for the axes.
template <class D>
profile blank_profile() {
  profile p;
  p.dx = D::dx;
  p.dy = D::dy;
  if (D::dx != 0 && D::dy != 0) {
    p.w = p.h = 64;
  } else if (D::dx != 0) {
    p.w = 64;
    p.h = 5;
  } else {
    p.w = 5;
    p.h = 64;
  }
  p.k = camera(p.w, p.h);
  p.z.assign(static_cast<std::size_t>(p.w) * p.h, 0.f);
  return p;
}

/// Fills the profile image: depth(x, y) = f(s, rho(s)).
template <class D, class F>
profile make_profile(F f) {
  profile p = blank_profile<D>();
  for (int y = 0; y < p.h; ++y)
    for (int x = 0; x < p.w; ++x) {
      const int s = p.s(x, y);
      p.z[static_cast<std::size_t>(y) * p.w + x] = static_cast<float>(f(s, p.rho(s)));
    }
  return p;
}

/// The s-value at the middle of the image (the pixel at the image centre).
template <class D>
int mid_s() {
  const profile p = blank_profile<D>();
  return p.s(p.w / 2, p.h / 2);
}

/// Depth along ray slope rho of the line z = z0 + m (xi - xi0) through (xi0, z0).
inline double line_depth(double rho, double xi0, double z0, double m) { return (z0 - m * xi0) / (1.0 - m * rho); }

/// Two planes meeting at the pixel s0 at depth z0: slope m1 before (s < s0), m2 from s0 on.
struct crease {
  int s0;
  double z0, m1, m2;
  double rho0;
  double operator()(int s, double rho) const {
    const double xi0 = z0 * rho0;
    return line_depth(rho, xi0, z0, s < s0 ? m1 : m2);
  }
};

/// A flat (z = z0, fronto-parallel) region for s <= s0 joining, tangentially at s0, a circular
/// arc of radius R bending away from the camera (a cylinder with its axis across D).  Rays that
/// miss the near half of the circle get depth 0 (invalid).
struct flat_to_arc {
  int s0;
  double z0, R;
  double rho0;
  double operator()(int s, double rho) const {
    if (s <= s0) return z0;
    const double xc = z0 * rho0, zc = z0 + R;  // circle centre
    // (t rho - xc)^2 + (t - zc)^2 = R^2
    const double a = rho * rho + 1, bb = -2 * (rho * xc + zc), c = xc * xc + zc * zc - R * R;
    const double disc = bb * bb - 4 * a * c;
    if (disc < 0) return 0.0;
    const double t = (-bb - std::sqrt(disc)) / (2 * a);
    return t <= zc ? t : 0.0;  // near half only
  }
};

}  // namespace edgeplane_test
