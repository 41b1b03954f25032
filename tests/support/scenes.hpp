// Synthetic depth scenes built in code, with their ground truth known by construction: a pinhole
// camera ray-casts planes, boxes and vertical cylinders.  Used by the tests and the benchmarks
// (never by the library).  World frame: z up, floor at z = 0; camera frame: x right, y down,
// z forward; depth is z in the camera frame (metres).
#pragma once
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include <Eigen/Dense>

#include "edgeplane/camera.hpp"

namespace edgeplane::test {

struct world_plane {  // n . X + d = 0 (world), rendered where the ray meets it first
  Eigen::Vector3d n;
  double d;
  int id;
};
struct world_box {  // axis-aligned box; its faces get ids first_id .. first_id + 5 (-x,+x,-y,+y,-z,+z)
  Eigen::Vector3d lo, hi;
  int first_id;
};
struct world_cylinder {  // vertical cylinder; side gets id 0 (not a plane), top cap cap_id
  double cx, cy, r, z0, z1;
  int cap_id;
};

struct camera_pose {
  Eigen::Matrix3d R;  // world from camera
  Eigen::Vector3d t;  // camera centre in the world
};

/// Camera at `eye` looking at `target` with world z up (no roll).
inline camera_pose look_at(Eigen::Vector3d eye, Eigen::Vector3d target) {
  const Eigen::Vector3d f = (target - eye).normalized();
  const Eigen::Vector3d x = f.cross(Eigen::Vector3d(0, 0, 1)).normalized();
  const Eigen::Vector3d y = f.cross(x);
  camera_pose p;
  p.R.col(0) = x;
  p.R.col(1) = y;
  p.R.col(2) = f;
  p.t = eye;
  return p;
}

struct scene {
  std::vector<world_plane> planes;
  std::vector<world_box> boxes;
  std::vector<world_cylinder> cylinders;
};

struct rendered {
  int width = 0, height = 0;
  intrinsics k;
  std::vector<float> depth;       // metres, 0 = no hit
  std::vector<std::int32_t> gt;   // plane id, 0 = not a plane / no hit, -1 = cylinder side
  std::vector<std::uint16_t> depth_mm() const {
    std::vector<std::uint16_t> o(depth.size());
    for (std::size_t i = 0; i < depth.size(); ++i) o[i] = static_cast<std::uint16_t>(std::lround(depth[i] * 1000.0));
    return o;
  }
};

/// Plane of id `id` in the camera frame: n . X + d = 0 with d >= 0.
inline std::array<double, 4> plane_in_camera(const scene& s, const camera_pose& pose, int id) {
  auto conv = [&](Eigen::Vector3d nw, double dw) {
    Eigen::Vector3d nc = pose.R.transpose() * nw;
    double dc = nw.dot(pose.t) + dw;
    if (dc < 0) {
      nc = -nc;
      dc = -dc;
    }
    return std::array<double, 4>{nc.x(), nc.y(), nc.z(), dc};
  };
  for (const auto& p : s.planes)
    if (p.id == id) return conv(p.n, p.d);
  for (const auto& b : s.boxes)
    for (int f = 0; f < 6; ++f)
      if (b.first_id + f == id) {
        Eigen::Vector3d n = Eigen::Vector3d::Zero();
        n(f / 2) = 1;
        const double c = (f % 2 == 0) ? b.lo(f / 2) : b.hi(f / 2);
        return conv(n, -c);
      }
  for (const auto& c : s.cylinders)
    if (c.cap_id == id) return conv(Eigen::Vector3d(0, 0, 1), -c.z1);
  return {0, 0, 0, 0};
}

/// Deterministic Gaussian noise (portable: own generator, Box-Muller).
struct noise_source {
  std::uint64_t state;
  double uniform() {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return (static_cast<double>(state >> 11) + 0.5) / 9007199254740992.0;
  }
  double gaussian() {
    const double u = uniform(), v = uniform();
    return std::sqrt(-2.0 * std::log(u)) * std::cos(6.283185307179586 * v);
  }
};

struct render_options {
  double sigma0 = 0.0, sigma2 = 0.0;  // depth noise sigma(z) = sigma0 + sigma2 z^2
  double hole_fraction = 0.0;         // pepper holes (depth 0)
  std::uint64_t seed = 1;
};

inline rendered render(const scene& s, const camera_pose& pose, int w, int h, intrinsics k,
                       render_options opt = {}) {
  rendered r;
  r.width = w;
  r.height = h;
  r.k = k;
  r.depth.assign(static_cast<std::size_t>(w) * h, 0.f);
  r.gt.assign(static_cast<std::size_t>(w) * h, 0);
  noise_source rng{opt.seed * 0x9E3779B97F4A7C15ull + 12345};
  const double inf = std::numeric_limits<double>::infinity();
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u) {
      const Eigen::Vector3d dc((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0);
      const Eigen::Vector3d dir = pose.R * dc, o = pose.t;
      double best = inf;
      int id = 0;
      for (const auto& p : s.planes) {
        const double den = p.n.dot(dir);
        if (std::abs(den) < 1e-12) continue;
        const double t = -(p.n.dot(o) + p.d) / den;
        if (t > 1e-6 && t < best) {
          best = t;
          id = p.id;
        }
      }
      for (const auto& b : s.boxes) {
        double t0 = -inf, t1 = inf;
        int face = -1;
        bool miss = false;
        for (int a = 0; a < 3 && !miss; ++a) {
          if (std::abs(dir(a)) < 1e-12) {
            if (o(a) < b.lo(a) || o(a) > b.hi(a)) miss = true;
            continue;
          }
          double ta = (b.lo(a) - o(a)) / dir(a), tb = (b.hi(a) - o(a)) / dir(a);
          int fa = 2 * a, fb = 2 * a + 1;
          if (ta > tb) {
            std::swap(ta, tb);
            std::swap(fa, fb);
          }
          if (ta > t0) {
            t0 = ta;
            face = fa;
          }
          t1 = std::min(t1, tb);
        }
        if (!miss && t0 <= t1 && t0 > 1e-6 && t0 < best) {
          best = t0;
          id = b.first_id + face;
        }
      }
      for (const auto& c : s.cylinders) {
        const double ox = o.x() - c.cx, oy = o.y() - c.cy;
        const double A = dir.x() * dir.x() + dir.y() * dir.y(), B = 2 * (ox * dir.x() + oy * dir.y()),
                     C = ox * ox + oy * oy - c.r * c.r;
        const double disc = B * B - 4 * A * C;
        if (A > 1e-12 && disc >= 0) {
          const double t = (-B - std::sqrt(disc)) / (2 * A);
          const double zz = o.z() + t * dir.z();
          if (t > 1e-6 && t < best && zz >= c.z0 && zz <= c.z1) {
            best = t;
            id = -1;
          }
        }
        if (std::abs(dir.z()) > 1e-12) {  // top cap
          const double t = (c.z1 - o.z()) / dir.z();
          const Eigen::Vector3d p = o + t * dir;
          if (t > 1e-6 && t < best && (p.x() - c.cx) * (p.x() - c.cx) + (p.y() - c.cy) * (p.y() - c.cy) <= c.r * c.r) {
            best = t;
            id = c.cap_id;
          }
        }
      }
      if (best == inf) continue;
      double z = best;  // dc.z == 1, so the ray parameter is the camera-frame depth
      if (opt.sigma0 > 0 || opt.sigma2 > 0) z += (opt.sigma0 + opt.sigma2 * z * z) * rng.gaussian();
      if (opt.hole_fraction > 0 && rng.uniform() < opt.hole_fraction) z = 0;
      const std::size_t i = static_cast<std::size_t>(v) * w + u;
      r.depth[i] = static_cast<float>(z);
      r.gt[i] = id;
    }
  return r;
}

// ---- the scenes of the tests and benchmarks ------------------------------------------------------

inline intrinsics kinect2_intrinsics(int w = 512, int h = 424) {
  const float f = 365.5f * static_cast<float>(w) / 512.f;
  return {f, f, (static_cast<float>(w) - 1.f) / 2.f, (static_cast<float>(h) - 1.f) / 2.f};
}

/// A room corner (floor, two walls) with a box on the floor.  Ids: floor 1, walls 2 and 3, box
/// faces 10..15.
inline scene room_with_box() {
  scene s;
  s.planes.push_back({Eigen::Vector3d(0, 0, 1), 0.0, 1});
  s.planes.push_back({Eigen::Vector3d(1, 0, 0), -3.5, 2});
  s.planes.push_back({Eigen::Vector3d(0, 1, 0), -2.0, 3});
  s.boxes.push_back({Eigen::Vector3d(1.8, -0.2, 0.0), Eigen::Vector3d(2.4, 0.5, 0.5), 10});
  return s;
}
inline camera_pose room_camera() { return look_at({0.0, -1.2, 1.3}, {2.6, 0.9, 0.4}); }

/// A table (top 1.0 x 0.7 m at 0.75 m on four 5 cm legs) in front of a wall.  Ids: floor 1, wall 2,
/// table top slab 20..25, legs 30.., 40.., 50.., 60...
inline scene table_scene() {
  scene s;
  s.planes.push_back({Eigen::Vector3d(0, 0, 1), 0.0, 1});
  s.planes.push_back({Eigen::Vector3d(1, 0, 0), -3.8, 2});
  s.boxes.push_back({Eigen::Vector3d(1.8, -0.5, 0.72), Eigen::Vector3d(2.5, 0.5, 0.75), 20});
  const double lx[2] = {1.85, 2.4}, ly[2] = {-0.45, 0.4};
  int id = 30;
  for (double x : lx)
    for (double y : ly) {
      s.boxes.push_back({Eigen::Vector3d(x, y, 0), Eigen::Vector3d(x + 0.05, y + 0.05, 0.72), id});
      id += 10;
    }
  return s;
}
inline camera_pose table_camera() { return look_at({0.0, -0.3, 1.6}, {2.2, 0.0, 0.5}); }

/// Three stairs (treads 0.3 m deep, risers 0.18 m high) rising away from the camera, a wall
/// behind.  Ids: floor 1, wall 2, steps 10.., 20.., 30...
inline scene stairs_scene() {
  scene s;
  s.planes.push_back({Eigen::Vector3d(0, 0, 1), 0.0, 1});
  s.planes.push_back({Eigen::Vector3d(1, 0, 0), -3.6, 2});
  for (int k = 0; k < 3; ++k)
    s.boxes.push_back({Eigen::Vector3d(1.6 + 0.3 * k, -0.8, 0.0), Eigen::Vector3d(3.6, 0.8, 0.18 * (k + 1)),
                       10 * (k + 1)});
  return s;
}
inline camera_pose stairs_camera() { return look_at({0.0, 0.0, 1.5}, {2.3, 0.0, 0.3}); }

/// A vertical cylinder (r = 0.3 m) standing on the floor in front of a wall.  Ids: floor 1,
/// wall 2, cap 9 (side -1).
inline scene cylinder_scene() {
  scene s;
  s.planes.push_back({Eigen::Vector3d(0, 0, 1), 0.0, 1});
  s.planes.push_back({Eigen::Vector3d(1, 0, 0), -3.5, 2});
  s.cylinders.push_back({2.2, 0.0, 0.3, 0.0, 2.5, 9});
  return s;
}
inline camera_pose cylinder_camera() { return look_at({0.0, 0.0, 1.2}, {2.2, 0.0, 0.8}); }

}  // namespace edgeplane::test
