// The benchmark frame shared by the CPU and CUDA benchmarks: the room corner with a box of
// tests/support/scenes.hpp (Kinect-v2-like noise, 2 % pepper holes), rendered once per size.
#pragma once
#include <cstdint>
#include <utility>
#include <vector>

#include "support/scenes.hpp"

namespace edgeplane::bench {

struct frame {
  test::rendered r;
  std::vector<std::uint16_t> mm;
};

inline const frame& scene_at(int w, int h) {
  static std::vector<std::pair<int, frame>> cache;
  for (auto& [key, f] : cache)
    if (key == w * 100000 + h) return f;
  frame f;
  f.r = test::render(test::room_with_box(), test::room_camera(), w, h, test::kinect2_intrinsics(w, h),
                     {0.0015, 0.0005, 0.02, 42});
  f.mm = f.r.depth_mm();
  cache.emplace_back(w * 100000 + h, std::move(f));
  return cache.back().second;
}

}  // namespace edgeplane::bench
