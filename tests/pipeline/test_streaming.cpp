// Streaming and determinism tests of edgeplane::segmenter (include/edgeplane/segmenter.hpp):
//  - a soak test: thousands of frames of changing content and size through one segmenter, whose
//    labels must match a fresh segmenter's on every frame while its memory stays flat;
//  - determinism for any number of threads: the same frame under TBB arenas of 1, 2, 3 and 8
//    threads (the last oversubscribes this 2-core machine, so the union-find's hooks contend)
//    gives bit-identical labels and planes.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#if defined(__GLIBC__)
#include <malloc.h>
#endif
#if EDGEPLANE_HAVE_TBB
#include <oneapi/tbb/task_arena.h>
#endif

#include "edgeplane/edgeplane.hpp"
#include "support/scenes.hpp"

using namespace edgeplane;

namespace {

#if defined(__SANITIZE_ADDRESS__)
constexpr bool heap_counters_meaningful = false;  // ASan's allocator does not feed mallinfo2
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
constexpr bool heap_counters_meaningful = false;
#else
constexpr bool heap_counters_meaningful = true;
#endif
#else
constexpr bool heap_counters_meaningful = true;
#endif

/// Bytes of heap in use by this process (glibc); 0 where unknown.
std::size_t heap_in_use() {
#if defined(__GLIBC__) && (__GLIBC__ > 2 || (__GLIBC__ == 2 && __GLIBC_MINOR__ >= 33))
  return mallinfo2().uordblks;
#else
  return 0;
#endif
}

struct frame {
  int w = 0, h = 0;
  intrinsics k;
  std::vector<float> depth;
};

/// The stream's frames: the room-with-box scene from several camera positions at four sizes, with
/// noise and holes, and degenerate frames (all invalid, NaN and infinities) in between.
std::vector<frame> stream_frames() {
  const auto s = test::room_with_box();
  const std::pair<int, int> sizes[] = {{128, 106}, {96, 80}, {192, 160}, {80, 66}};
  std::vector<frame> out;
  for (int i = 0; i < 8; ++i) {
    const auto [w, h] = sizes[i % 4];
    const double a = 0.15 * i;
    const auto pose = test::look_at({0.3 * std::sin(a), -1.2 + 0.1 * i, 1.3 + 0.05 * (i % 3)}, {2.6, 0.9, 0.4});
    const auto r = test::render(s, pose, w, h, test::kinect2_intrinsics(w, h),
                                {0.001, 0.0005, 0.01, static_cast<std::uint64_t>(100 + i)});
    out.push_back({w, h, r.k, r.depth});
    if (i % 3 == 2) {  // a degenerate frame of the same size
      frame bad{w, h, r.k, std::vector<float>(r.depth.size(), 0.f)};
      if (i % 2)
        for (std::size_t j = 0; j < bad.depth.size(); ++j)
          bad.depth[j] = j % 2 ? std::numeric_limits<float>::quiet_NaN() : std::numeric_limits<float>::infinity();
      out.push_back(std::move(bad));
    }
  }
  return out;
}

std::vector<std::uint16_t> segment_once(segmenter<cpu>& seg, const frame& f, segmentation_result* res = nullptr) {
  std::vector<std::uint16_t> labels(f.depth.size(), 0xffff);
  segmentation_result r;
  seg.segment(make_view(f.depth.data(), f.w, f.h), 1.f, f.k, make_view(labels.data(), f.w, f.h), r);
  if (res) *res = r;
  return labels;
}

bool same_planes(const segmentation_result& a, const segmentation_result& b) {
  if (a.planes.size() != b.planes.size()) return false;
  for (std::size_t i = 0; i < a.planes.size(); ++i) {
    const plane &p = a.planes[i], &q = b.planes[i];
    if (p.id != q.id || p.pixels != q.pixels || p.points != q.points || p.bbox != q.bbox ||
        std::memcmp(&p.normal, &q.normal, sizeof p.normal) != 0 || std::memcmp(&p.d, &q.d, sizeof p.d) != 0 ||
        std::memcmp(&p.centroid, &q.centroid, sizeof p.centroid) != 0)
      return false;
  }
  return true;
}

}  // namespace

TEST_CASE("segmenter: a soak of 2400 frames of changing content and size stays right with flat memory") {
  const params p = presets::thesis_half();
  const std::vector<frame> frames = stream_frames();
  // reference labels and plane counts from a fresh segmenter per frame
  std::vector<std::vector<std::uint16_t>> ref;
  std::vector<std::size_t> ref_planes;
  for (const frame& f : frames) {
    segmenter<cpu> fresh(p);
    segmentation_result r;
    ref.push_back(segment_once(fresh, f, &r));
    ref_planes.push_back(r.planes.size());
  }
  // the scene frames do find planes (so matching the reference means something); degenerate ones none
  std::size_t scene_frames = 0, scene_planes = 0;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    CAPTURE(i);
    const bool degenerate = std::none_of(frames[i].depth.begin(), frames[i].depth.end(),
                                         [](float z) { return std::isfinite(z) && z > 0.f; });
    if (degenerate) {
      CHECK(ref_planes[i] == 0);
    } else {
      CHECK(ref_planes[i] >= 1);
      ++scene_frames;
      scene_planes += ref_planes[i];
    }
  }
  CHECK(scene_frames == 8);
  CHECK(scene_planes >= 2 * scene_frames);

  segmenter<cpu> seg(p);
  segmentation_result r;  // reused: its plane vector keeps its capacity
  std::vector<std::uint16_t> labels(192 * 160);
  const int total = 2400;
  std::size_t scratch_after_first_pass = 0, heap_warm = 0;
  int mismatches = 0;
  for (int i = 0; i < total; ++i) {
    const std::size_t j = static_cast<std::size_t>(i) % frames.size();
    const frame& f = frames[j];
    seg.segment(make_view(f.depth.data(), f.w, f.h), 1.f, f.k, make_view(labels.data(), f.w, f.h), r);
    if (!std::equal(ref[j].begin(), ref[j].end(), labels.begin()) || r.planes.size() != ref_planes[j]) ++mismatches;
    if (i + 1 == static_cast<int>(frames.size())) scratch_after_first_pass = seg.scratch_bytes();
    if (i == 200) heap_warm = heap_in_use();
  }
  CHECK(mismatches == 0);
  // every size has been seen in the first pass: the buffers grew then and never again
  CHECK(seg.scratch_bytes() == scratch_after_first_pass);
  if (heap_counters_meaningful && heap_warm > 0) {
    const std::size_t heap_end = heap_in_use();
    CAPTURE(heap_warm);
    CAPTURE(heap_end);
    CHECK(heap_end <= heap_warm + 64 * 1024);  // nothing accumulates per frame
  }
}

TEST_CASE("segmenter: a larger frame reallocates once, smaller frames after it reuse the buffers") {
  const std::vector<frame> frames = stream_frames();
  segmenter<cpu> seg(presets::thesis_half());
  const frame* small = nullptr;
  const frame* large = nullptr;
  for (const frame& f : frames) {
    if (f.w == 80 && !small) small = &f;
    if (f.w == 192 && !large) large = &f;
  }
  REQUIRE(small);
  REQUIRE(large);
  const auto a = segment_once(seg, *small);
  const std::size_t after_small = seg.scratch_bytes();
  segment_once(seg, *large);
  const std::size_t after_large = seg.scratch_bytes();
  CHECK(after_large > after_small);
  CHECK(segment_once(seg, *small) == a);
  segment_once(seg, *large);
  CHECK(seg.scratch_bytes() == after_large);
}

#if EDGEPLANE_HAVE_TBB
TEST_CASE("segmenter: labels and planes are identical for 1, 2, 3 and 8 threads") {
  const auto s = test::room_with_box();
  const auto r = test::render(s, test::room_camera(), 256, 212, test::kinect2_intrinsics(256, 212),
                              {0.001, 0.0005, 0.02, 21});
  for (const std::string name : {"thesis_full", "kinect2", "kinect1"}) {
    CAPTURE(name);
    const params p = preset(name);
    frame f{r.width, r.height, r.k, r.depth};
    segmenter<cpu> serial(p, cpu{cpu::mode::serial});
    segmentation_result ref;
    const auto ref_labels = segment_once(serial, f, &ref);
    CHECK(ref.planes.size() >= 2);
    for (int threads : {1, 2, 3, 8}) {
      CAPTURE(threads);
      oneapi::tbb::task_arena arena(threads);
      for (int rep = 0; rep < 3; ++rep) {
        segmentation_result got;
        std::vector<std::uint16_t> labels;
        arena.execute([&] {
          segmenter<cpu> seg(p);
          labels = segment_once(seg, f, &got);
        });
        CHECK(labels == ref_labels);
        CHECK(same_planes(got, ref));
      }
    }
  }
}
#endif
