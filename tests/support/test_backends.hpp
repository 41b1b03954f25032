// edgeplane tests: the list of backends every test is compiled for, a backend-memory array, and the
// few synthetic-scene helpers the unit tests share (pinhole camera, ray-cast planes, fixed noise).
//
// Every test is written once and instantiated per backend:
//   TEST_CASE_TEMPLATE("...", B, EDGEPLANE_TEST_BACKENDS) { for (const B& b : variants<B>()) ... }
// Besides the CPU backend they run on the device-path model (support/device_model.hpp: host memory,
// but every branch the CUDA backend takes).  A CUDA backend is added by appending it to
// EDGEPLANE_TEST_BACKENDS (in a .cu test TU) and giving it a variants<> specialisation; tests move
// data only through device_array, so they run unchanged on device memory.
#pragma once
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "edgeplane/backend/buffer.hpp"
#include "edgeplane/backend/cpu.hpp"
#include "edgeplane/camera.hpp"
#include "edgeplane/image.hpp"
#include "support/device_model.hpp"

// The CPU backend, and the device code paths run on the host (support/device_model.hpp).
#ifndef EDGEPLANE_TEST_BACKENDS
#define EDGEPLANE_TEST_BACKENDS edgeplane::cpu, edgeplane_test::device_model
#endif

TYPE_TO_STRING(edgeplane::cpu);
TYPE_TO_STRING(edgeplane_test::device_model);

namespace edgeplane_test {

/// The execution variants of a backend a test runs on (default: the default-constructed one).
template <class B>
std::vector<B> variants() {
  return {B{}};
}
/// The CPU backend runs both in parallel and serially (the serial run is the determinism reference).
template <>
inline std::vector<edgeplane::cpu> variants<edgeplane::cpu>() {
  return {edgeplane::cpu{edgeplane::cpu::mode::parallel}, edgeplane::cpu{edgeplane::cpu::mode::serial}};
}
inline std::string variant_name(const edgeplane::cpu& b) {
  return b.execution == edgeplane::cpu::mode::serial ? "cpu/serial" : "cpu/parallel";
}
/// The device-path model runs its work items concurrently, and serially in reverse index order.
template <>
inline std::vector<device_model> variants<device_model>() {
  return {device_model{device_model::order::parallel}, device_model{device_model::order::reversed}};
}
inline std::string variant_name(const device_model& b) {
  return b.run == device_model::order::reversed ? "device_model/reversed" : "device_model/parallel";
}

/// An array in the backend's memory, filled from and read back into host vectors.
template <class T, class B>
class device_array {
 public:
  device_array(const B& b, const std::vector<T>& host) : buf_(b) {
    buf_.resize(host.size());
    b.copy_from_host(buf_.data(), host.data(), host.size() * sizeof(T));
  }
  device_array(const B& b, std::size_t n, T fill) : device_array(b, std::vector<T>(n, fill)) {}
  T* data() const { return buf_.data(); }
  std::size_t size() const { return buf_.size(); }
  /// A dense w x h view (w * h must not exceed size()).
  edgeplane::image_view<T> view(int w, int h) const { return edgeplane::make_view(buf_.data(), w, h); }
  edgeplane::image_view<const T> cview(int w, int h) const { return view(w, h); }
  std::vector<T> host() const {
    std::vector<T> out(buf_.size());
    buf_.backend().synchronize();
    buf_.backend().copy_to_host(out.data(), buf_.data(), out.size() * sizeof(T));
    return out;
  }

 private:
  edgeplane::buffer<T, B> buf_;
};

// ---- synthetic scenes --------------------------------------------------------------------------

/// The test camera: fx = fy = 365 px (Kinect-v2-like), principal point at the image centre.
inline edgeplane::intrinsics camera(int w, int h, float f = 365.f) {
  return {f, f, 0.5f * static_cast<float>(w - 1), 0.5f * static_cast<float>(h - 1)};
}

struct vec3 {
  double x, y, z;
};
inline vec3 normalized(vec3 v) {
  const double n = std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
  return {v.x / n, v.y / n, v.z / n};
}

/// Depth (metres) at pixel (u, v) of the plane n . X + d = 0: z = -d / (n . ((u-cx)/fx, (v-cy)/fy, 1)),
/// or 0 when the ray misses the plane (parallel, or the plane is behind the camera).
inline float plane_depth(const edgeplane::intrinsics& k, int u, int v, vec3 n, double d) {
  const double rx = (u - k.cx) / k.fx, ry = (v - k.cy) / k.fy;
  const double den = n.x * rx + n.y * ry + n.z;
  if (den == 0.0) return 0.f;
  const double z = -d / den;
  return z > 0 ? static_cast<float>(z) : 0.f;
}

/// A w x h depth image of one plane.
inline std::vector<float> plane_image(const edgeplane::intrinsics& k, int w, int h, vec3 n, double d) {
  std::vector<float> z(static_cast<std::size_t>(w) * h);
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u) z[static_cast<std::size_t>(v) * w + u] = plane_depth(k, u, v, n, d);
  return z;
}

/// Deterministic uniform noise in [-a, a] (a 64-bit LCG: identical on every platform and run).
class lcg_noise {
 public:
  explicit lcg_noise(std::uint64_t seed) : s_(seed * 6364136223846793005ull + 1442695040888963407ull) {}
  double uniform01() {
    s_ = s_ * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<double>(s_ >> 11) * (1.0 / 9007199254740992.0);
  }
  float operator()(float a) { return static_cast<float>((2.0 * uniform01() - 1.0) * a); }
  std::uint32_t next_u32(std::uint32_t n) { return static_cast<std::uint32_t>(uniform01() * n); }

 private:
  std::uint64_t s_;
};

}  // namespace edgeplane_test
