// edgeplane::pipeline: frames in flight on several lanes give, frame by frame and in submission
// order, exactly what one segmenter's segment() gives; errors surface at the right frame; the
// lanes' threads and host memory are released.
#include <doctest/doctest.h>

#include <atomic>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "edgeplane/edgeplane.hpp"
#include "support/device_model.hpp"
#include "support/scenes.hpp"

namespace ep = edgeplane;
using edgeplane_test::device_model;

namespace {

/// A frame of the test sequence: depth as uint16 millimetres or float metres, stored with a pitch.
struct test_frame {
  int w = 0, h = 0, pitch = 0;
  bool is_float = false;
  ep::intrinsics k{};
  std::vector<std::uint16_t> mm;
  std::vector<float> metres;
};

/// Twelve frames: three scenes, four sizes (the size changes from frame to frame), uint16 and
/// float, dense and pitched rows, noise and pepper holes.
std::vector<test_frame> sequence() {
  const ep::test::scene scenes[] = {ep::test::room_with_box(), ep::test::stairs_scene(), ep::test::table_scene()};
  const ep::test::camera_pose poses[] = {ep::test::room_camera(), ep::test::stairs_camera(), ep::test::table_camera()};
  const int sizes[][2] = {{320, 240}, {256, 212}, {160, 120}, {321, 239}};
  std::vector<test_frame> out;
  for (int i = 0; i < 12; ++i) {
    test_frame f;
    f.w = sizes[i % 4][0];
    f.h = sizes[i % 4][1];
    f.pitch = f.w + (i % 3 == 2 ? 5 : 0);
    f.is_float = i % 2 == 1;
    f.k = ep::test::kinect2_intrinsics(f.w, f.h);
    const auto r = ep::test::render(scenes[i % 3], poses[i % 3], f.w, f.h, f.k,
                                    {0.0015, 0.0005, 0.02, static_cast<std::uint64_t>(100 + i)});
    const auto mm = r.depth_mm();
    f.mm.assign(static_cast<std::size_t>(f.pitch) * f.h, 0xffff);
    f.metres.assign(static_cast<std::size_t>(f.pitch) * f.h, -1.f);
    for (int y = 0; y < f.h; ++y)
      for (int x = 0; x < f.w; ++x) {
        f.mm[static_cast<std::size_t>(y) * f.pitch + x] = mm[static_cast<std::size_t>(y) * f.w + x];
        f.metres[static_cast<std::size_t>(y) * f.pitch + x] = r.depth[static_cast<std::size_t>(y) * f.w + x];
      }
    out.push_back(std::move(f));
  }
  return out;
}

struct frame_result {
  std::vector<std::uint16_t> labels;
  ep::segmentation_result result;
};

template <class B>
frame_result reference(ep::segmenter<B>& seg, const test_frame& f) {
  frame_result o;
  o.labels.assign(static_cast<std::size_t>(f.w) * f.h, 0xbeef);
  const auto lv = ep::make_view(o.labels.data(), f.w, f.h);
  if (f.is_float)
    seg.segment(ep::make_view(f.metres.data(), f.w, f.h, f.pitch), 1.f, f.k, lv, o.result);
  else
    seg.segment(ep::make_view(f.mm.data(), f.w, f.h, f.pitch), 0.001f, f.k, lv, o.result);
  return o;
}

template <class B>
std::uint64_t submit(ep::pipeline<B>& pl, const test_frame& f) {
  if (f.is_float) return pl.submit(ep::make_view(f.metres.data(), f.w, f.h, f.pitch), 1.f, f.k);
  return pl.submit(ep::make_view(f.mm.data(), f.w, f.h, f.pitch), 0.001f, f.k);
}

template <class B>
frame_result retrieve(ep::pipeline<B>& pl, const test_frame& f, std::uint64_t want_seq) {
  frame_result o;
  o.labels.assign(static_cast<std::size_t>(f.w) * f.h, 0xbeef);
  const std::uint64_t seq = pl.retrieve(ep::make_view(o.labels.data(), f.w, f.h), o.result);
  CHECK(seq == want_seq);
  return o;
}

/// Identical labels (not only up to renumbering: the same backend numbers planes the same way)
/// and planes.
void check_same(const frame_result& got, const frame_result& want) {
  CHECK(got.labels == want.labels);
  CHECK(got.result.candidates == want.result.candidates);
  CHECK(got.result.valid_candidates == want.result.valid_candidates);
  REQUIRE(got.result.planes.size() == want.result.planes.size());
  for (std::size_t i = 0; i < want.result.planes.size(); ++i) {
    const ep::plane &a = got.result.planes[i], &b = want.result.planes[i];
    CHECK(a.id == b.id);
    CHECK(a.normal == b.normal);
    CHECK(a.d == b.d);
    CHECK(a.centroid == b.centroid);
    CHECK(a.pixels == b.pixels);
    CHECK(a.points == b.points);
    CHECK(a.eigenvalues == b.eigenvalues);
    CHECK(a.bbox == b.bbox);
  }
}

/// Streams the sequence through the pipeline (submitting while there is room, retrieving the
/// oldest when full) and compares every frame with one segmenter's result.
template <class B>
void check_stream(ep::pipeline<B>& pl, const ep::params& p, const B& ref_backend) {
  const auto frames = sequence();
  ep::segmenter<B> ref(p, ref_backend);
  std::vector<frame_result> want;
  int planes = 0;
  for (const auto& f : frames) {
    want.push_back(reference(ref, f));
    planes += static_cast<int>(want.back().result.planes.size());
  }
  CHECK(planes >= 12);  // the frames have planes to find
  for (int pass = 0; pass < 2; ++pass) {  // twice: the lanes' scratch and the slots are reused
    std::size_t next_out = 0;
    for (std::size_t i = 0; i < frames.size(); ++i) {
      if (pl.full()) {
        CAPTURE(next_out);
        check_same(retrieve(pl, frames[next_out], next_out + pass * frames.size()), want[next_out]);
        ++next_out;
      }
      CHECK(submit(pl, frames[i]) == i + pass * frames.size());
    }
    CHECK(pl.in_flight() == frames.size() - next_out);
    for (; next_out < frames.size(); ++next_out) {
      CAPTURE(next_out);
      check_same(retrieve(pl, frames[next_out], next_out + pass * frames.size()), want[next_out]);
    }
    CHECK(pl.in_flight() == 0);
  }
}

/// The CPU backend, whose kernel launches fail (backend_error) once a shared countdown runs out.
struct failing_cpu : ep::cpu {
  std::atomic<long>* countdown = nullptr;
  template <class F>
  void for_each_index(std::int64_t n, F f) const {
    if (countdown && countdown->fetch_sub(1) == 0) throw ep::backend_error("edgeplane test: injected launch failure");
    ep::cpu::for_each_index(n, f);
  }
};

}  // namespace

TEST_CASE("pipeline: every frame gives what segment() gives, in submission order") {
  SUBCASE("two serial CPU lanes") {
    const ep::cpu serial{ep::cpu::mode::serial};
    ep::pipeline<ep::cpu> pl(ep::presets::kinect2(), 2, serial);
    CHECK(pl.lanes() == 2);
    CHECK(pl.capacity() == 4);
    check_stream(pl, ep::presets::kinect2(), serial);
  }
  SUBCASE("three parallel CPU lanes, capacity 3, thesis_full") {
    ep::pipeline<ep::cpu> pl(ep::presets::thesis_full(), 3, ep::cpu{}, 3);
    check_stream(pl, ep::presets::thesis_full(), ep::cpu{});
  }
  SUBCASE("one lane, capacity 1, thesis_half") {
    ep::pipeline<ep::cpu> pl(ep::presets::thesis_half(), 1, ep::cpu{}, 1);
    check_stream(pl, ep::presets::thesis_half(), ep::cpu{});
  }
  SUBCASE("device code paths on two lanes: page-locked slots, threads bound to the device") {
    edgeplane_test::transfer_log log;
    {
      const device_model b{device_model::order::parallel, &log};
      ep::pipeline<device_model> pl(ep::presets::kinect2(), {b, b});
      check_stream(pl, ep::presets::kinect2(), b);
      CHECK(log.host_blocks > 0);  // the frames in flight are in the backend's host memory
    }
    CHECK(log.host_blocks == 0);   // and it was all given back
    CHECK(log.bound_threads == 2);  // each lane's thread was bound to the device (threads joined)
  }
}

TEST_CASE("pipeline: segment_batch gives what segment() gives for each frame") {
  const auto frames = sequence();
  std::vector<ep::image_view<const std::uint16_t>> in;
  std::vector<std::vector<std::uint16_t>> labels;
  std::vector<ep::image_view<std::uint16_t>> out;
  // one camera: the 320x240 frames
  for (const auto& f : frames)
    if (f.w == 320) {
      in.push_back(ep::make_view(f.mm.data(), f.w, f.h, f.pitch));
      labels.emplace_back(static_cast<std::size_t>(f.w) * f.h, 0xbeef);
      out.push_back(ep::make_view(labels.back().data(), f.w, f.h));
    }
  // reference: one segmenter, one frame at a time
  ep::segmenter<ep::cpu> ref(ep::presets::kinect2());
  const ep::intrinsics k = ep::test::kinect2_intrinsics(320, 240);
  for (const int lanes : {1, 2, 3}) {
    CAPTURE(lanes);
    ep::pipeline<ep::cpu> pl(ep::presets::kinect2(), lanes, ep::cpu{ep::cpu::mode::serial}, lanes);
    // more frames than the capacity: the batch retrieves while it submits
    std::vector<ep::image_view<const std::uint16_t>> many;
    std::vector<std::vector<std::uint16_t>> many_labels;
    std::vector<ep::image_view<std::uint16_t>> many_out;
    for (int rep = 0; rep < 3; ++rep)
      for (std::size_t i = 0; i < in.size(); ++i) {
        many.push_back(in[i]);
        many_labels.emplace_back(labels[i].size(), 0xbeef);
      }
    for (auto& l : many_labels) many_out.push_back(ep::make_view(l.data(), 320, 240));
    std::vector<ep::segmentation_result> results;
    pl.segment_batch(many, 0.001f, k, many_out, results);
    REQUIRE(results.size() == many.size());
    for (std::size_t i = 0; i < many.size(); ++i) {
      CAPTURE(i);
      frame_result want;
      want.labels.assign(labels[0].size(), 0);
      want.result = ref.segment(many[i], 0.001f, k, ep::make_view(want.labels.data(), 320, 240));
      check_same({many_labels[i], results[i]}, want);
    }
    CHECK(pl.in_flight() == 0);
  }
}

TEST_CASE("pipeline: a frame that fails rethrows at its retrieve; the frames after it are right") {
  const auto frames = sequence();
  // the kernel launches of frame 2
  std::atomic<long> launches{1L << 40};
  {
    ep::segmenter<failing_cpu> probe(ep::presets::kinect2(), failing_cpu{{}, &launches});
    reference(probe, frames[2]);
  }
  const long per_frame = (1L << 40) - launches.load();
  REQUIRE(per_frame > 10);
  ep::segmenter<ep::cpu> ref(ep::presets::kinect2());
  // One lane, so frames run in order; the countdown is armed once frames 0 and 1 are done, and
  // runs out half-way through frame 2.
  std::atomic<long> countdown{-1};
  ep::pipeline<failing_cpu> pl(ep::presets::kinect2(), 1, failing_cpu{{}, &countdown}, 6);
  CHECK(submit(pl, frames[0]) == 0);
  CHECK(submit(pl, frames[1]) == 1);
  check_same(retrieve(pl, frames[0], 0), reference(ref, frames[0]));
  check_same(retrieve(pl, frames[1], 1), reference(ref, frames[1]));
  countdown = per_frame / 2;
  for (std::uint64_t i = 2; i < 6; ++i) CHECK(submit(pl, frames[i]) == i);
  frame_result bad;
  bad.labels.resize(static_cast<std::size_t>(frames[2].w) * frames[2].h);
  CHECK_THROWS_AS(pl.retrieve(ep::make_view(bad.labels.data(), frames[2].w, frames[2].h), bad.result),
                  ep::backend_error);
  CHECK(pl.in_flight() == 3);  // the failed frame was retrieved
  for (std::uint64_t i = 3; i < 6; ++i) {
    CAPTURE(i);
    check_same(retrieve(pl, frames[i], i), reference(ref, frames[i]));
  }
}

TEST_CASE("pipeline: unusable arguments throw edgeplane::error and change nothing") {
  const auto frames = sequence();
  const test_frame& f = frames[0];
  CHECK_THROWS_AS(ep::pipeline<ep::cpu>(ep::presets::kinect2(), 0), ep::error);
  CHECK_THROWS_AS(ep::pipeline<ep::cpu>(ep::presets::kinect2(), 3, ep::cpu{}, 2), ep::error);
  CHECK_THROWS_AS(ep::pipeline<ep::cpu>(ep::presets::kinect2(), -4), ep::error);
  CHECK_THROWS_AS(ep::pipeline<ep::cpu>(ep::presets::kinect2(), 100000), ep::error);
  CHECK_THROWS_AS(ep::pipeline<ep::cpu>(ep::presets::kinect2(), 1, ep::cpu{}, std::size_t(1) << 62), ep::error);
  ep::params bad_p = ep::presets::kinect2();
  bad_p.t_size = 0;
  CHECK_THROWS_AS(ep::pipeline<ep::cpu>(bad_p, 1), ep::error);

  ep::pipeline<ep::cpu> pl(ep::presets::kinect2(), 1, ep::cpu{}, 2);
  std::vector<std::uint16_t> labels(static_cast<std::size_t>(f.w) * f.h);
  ep::segmentation_result res;
  CHECK_THROWS_AS(pl.retrieve(ep::make_view(labels.data(), f.w, f.h), res), ep::error);  // nothing in flight
  ep::intrinsics bad_k = f.k;
  bad_k.fx = 0.f;
  CHECK_THROWS_AS(pl.submit(ep::make_view(f.mm.data(), f.w, f.h, f.pitch), 0.001f, bad_k), ep::error);
  CHECK_THROWS_AS(pl.submit(ep::make_view(f.mm.data(), f.w, f.h, f.pitch), -1.f, f.k), ep::error);
  CHECK_THROWS_AS(pl.submit(ep::make_view(f.mm.data(), f.w, f.h, f.w - 1), 0.001f, f.k), ep::error);
  CHECK_THROWS_AS(pl.submit(ep::make_view<const std::uint16_t>(nullptr, f.w, f.h), 0.001f, f.k), ep::error);
  CHECK(pl.in_flight() == 0);
  CHECK(submit(pl, f) == 0);
  CHECK(submit(pl, f) == 1);
  CHECK(pl.full());
  CHECK_THROWS_AS(submit(pl, f), ep::error);  // full
  // labels of the wrong size: the frame stays in flight, and a right-sized retrieve then gets it
  std::vector<std::uint16_t> small(100);
  CHECK_THROWS_AS(pl.retrieve(ep::make_view(small.data(), 10, 10), res), ep::error);
  CHECK(pl.in_flight() == 2);
  ep::segmenter<ep::cpu> ref(ep::presets::kinect2());
  const frame_result want = reference(ref, f);
  check_same(retrieve(pl, f, 0), want);
  check_same(retrieve(pl, f, 1), want);
  // batch: counts that differ, a frame that is unusable: nothing runs
  std::vector<ep::segmentation_result> results;
  const auto in = ep::make_view<const std::uint16_t>(f.mm.data(), f.w, f.h, f.pitch);
  const auto out = ep::make_view(labels.data(), f.w, f.h);
  CHECK_THROWS_AS(pl.segment_batch<std::uint16_t>({in, in}, 0.001f, f.k, {out}, results), ep::error);
  CHECK_THROWS_AS(pl.segment_batch<std::uint16_t>({in}, 0.001f, f.k, {ep::make_view(small.data(), 10, 10)}, results),
                  ep::error);
  CHECK(pl.in_flight() == 0);
}

TEST_CASE("pipeline: a producer thread submits while a consumer thread retrieves") {
  const auto frames = sequence();
  ep::segmenter<ep::cpu> ref(ep::presets::kinect2());
  std::vector<frame_result> want;
  for (const auto& f : frames) want.push_back(reference(ref, f));
  ep::pipeline<ep::cpu> pl(ep::presets::kinect2(), 2, ep::cpu{ep::cpu::mode::serial}, 3);
  const int total = 3 * static_cast<int>(frames.size());
  std::atomic<int> submitted{0};
  std::thread producer([&] {
    for (int i = 0; i < total; ++i) {
      while (pl.full()) std::this_thread::yield();
      submit(pl, frames[static_cast<std::size_t>(i) % frames.size()]);
      ++submitted;
    }
  });
  for (int i = 0; i < total; ++i) {
    while (submitted.load() <= i) std::this_thread::yield();
    CAPTURE(i);
    const std::size_t j = static_cast<std::size_t>(i) % frames.size();
    check_same(retrieve(pl, frames[j], static_cast<std::uint64_t>(i)), want[j]);
  }
  producer.join();
  CHECK(pl.in_flight() == 0);
}

TEST_CASE("pipeline: destroyed with frames in flight, it stops without waiting for them all") {
  const auto frames = sequence();
  edgeplane_test::transfer_log log;
  {
    const device_model b{device_model::order::parallel, &log};
    ep::pipeline<device_model> pl(ep::presets::thesis_full(), {b, b}, 6);
    for (int i = 0; i < 6; ++i) submit(pl, frames[static_cast<std::size_t>(i)]);
    CHECK(pl.full());
  }  // the lanes finish the frames they run; the rest are dropped; threads joined, memory freed
  CHECK(log.host_blocks == 0);
  CHECK(log.bound_threads == 2);
}

TEST_CASE("pipeline: empty, 1x1 and one-row frames give what segment() gives") {
  ep::segmenter<ep::cpu> ref(ep::presets::thesis_full());
  ep::pipeline<ep::cpu> pl(ep::presets::thesis_full(), 2);
  const ep::intrinsics k{365.f, 365.f, 0.f, 0.f};
  const std::vector<std::pair<int, int>> sizes = {{0, 5}, {5, 0}, {0, 0}, {1, 1}, {300, 1}, {1, 200}};
  std::vector<std::vector<std::uint16_t>> depth;
  for (const auto& size : sizes)
    depth.emplace_back(static_cast<std::size_t>(size.first) * size.second, std::uint16_t(1500));
  for (std::size_t i = 0; i < sizes.size(); ++i) {
    const int w = sizes[i].first, h = sizes[i].second;
    CHECK(pl.submit(ep::make_view<const std::uint16_t>(depth[i].empty() ? nullptr : depth[i].data(), w, h), 0.001f, k) == i);
    std::vector<std::uint16_t> got(depth[i].size(), 0xbeef), want(depth[i].size(), 0xbeef);
    ep::segmentation_result r;
    CHECK(pl.retrieve(ep::make_view(got.empty() ? nullptr : got.data(), w, h), r) == i);
    const auto wr = ref.segment(ep::make_view<const std::uint16_t>(depth[i].empty() ? nullptr : depth[i].data(), w, h),
                                0.001f, k, ep::make_view(want.empty() ? nullptr : want.data(), w, h));
    CHECK(got == want);
    CHECK(r.planes.size() == wr.planes.size());
  }
}
