// The device code paths (what edgeplane::cuda runs: a work item per pixel, per-element union-find
// and counting, uploads and downloads) run on the host through support/device_model.hpp, against
// the CPU backend: the same checks tests/cuda/test_cuda_backend.cu makes on a GPU
// (support/backend_equivalence.hpp), so that a machine without one still tests them.
#include <doctest/doctest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "edgeplane/edgeplane.hpp"
#include "support/backend_equivalence.hpp"
#include "support/device_model.hpp"
#include "support/scenes.hpp"

namespace ep = edgeplane;
using edgeplane_test::device_model;
namespace eq = edgeplane_test::equivalence;

namespace {
const device_model parallel{device_model::order::parallel};
const device_model reversed{device_model::order::reversed};
}  // namespace

TEST_CASE("device paths: random union-find pair lists give the CPU's parent array") {
  eq::check_union_find_matches_cpu(parallel);
  eq::check_union_find_matches_cpu(reversed);
}

TEST_CASE("device paths: filters, edges, segments, candidates and moments are identical to the CPU's") {
  SUBCASE("concurrent work items") { eq::check_kernels_match_cpu(parallel); }
  SUBCASE("work items in reverse order") { eq::check_kernels_match_cpu(reversed); }
}

TEST_CASE("device paths: the final-label kernels (sweeps, growth, closing) are identical to the CPU's") {
  SUBCASE("concurrent work items") { eq::check_label_kernels_match_cpu(parallel); }
  SUBCASE("work items in reverse order") { eq::check_label_kernels_match_cpu(reversed); }
}

TEST_CASE("device paths: the segmenter's labels and planes equal the CPU segmenter's") {
  SUBCASE("concurrent work items") { eq::check_segmenter_matches_cpu(parallel); }
  SUBCASE("work items in reverse order") { eq::check_segmenter_matches_cpu(reversed); }
}

TEST_CASE("device paths: float depth, pitched rows, half resolution, changing sizes, backend pointers") {
  eq::check_segmenter_inputs_match_cpu(parallel);
}

TEST_CASE("device paths: a pipeline of three lanes gives the CPU segmenter's results in order") {
  eq::check_pipeline_matches_cpu(std::vector<device_model>{parallel, reversed, parallel});
}

TEST_CASE("device paths: a frame costs one upload and one download; with backend pointers none") {
  const auto sc = eq::scenes()[0];
  const ep::test::rendered r = eq::frame(sc.s, sc.pose, 512, 424, 21);
  const auto mm = r.depth_mm();
  const std::int64_t n = static_cast<std::int64_t>(mm.size());
  const std::int64_t frame_bytes = n * static_cast<std::int64_t>(sizeof(std::uint16_t));
  // The smallest per-pixel array the segmenter holds is one byte a pixel: a transfer that large is
  // an image crossing; what else crosses are per-candidate numbers (moments, tables, flags).
  for (const std::string preset : {"thesis_full", "kinect2", "thesis_half"}) {
    CAPTURE(preset);
    edgeplane_test::transfer_log log;
    device_model b{device_model::order::parallel, &log};
    ep::segmenter<device_model> seg(ep::preset(preset), b);
    std::vector<std::uint16_t> labels(mm.size());
    ep::segmentation_result res;
    for (int frame = 0; frame < 2; ++frame) {  // the second frame reuses the scratch memory
      log.reset();
      seg.segment(ep::make_view(mm.data(), r.width, r.height), 0.001f, r.k,
                  ep::make_view(labels.data(), r.width, r.height), res);
      CHECK(log.largest_upload == frame_bytes);
      CHECK(log.largest_download == frame_bytes);
      // everything else is small: per-candidate numbers, not images
      const std::int64_t small_up = log.upload_bytes - frame_bytes, small_down = log.download_bytes - frame_bytes;
      CAPTURE(small_up);
      CAPTURE(small_down);
      CHECK(small_up < n / 8);
      CHECK(small_down < n / 8);
      CHECK(res.planes.size() >= 2);
    }
    // device pointers in and out: no image crosses
    ep::buffer<std::uint16_t, device_model> d_depth(b), d_labels(b);
    d_depth.resize(mm.size());
    d_labels.resize(mm.size());
    b.copy_from_host(d_depth.data(), mm.data(), static_cast<std::size_t>(frame_bytes));
    log.reset();
    seg.segment_on_backend(ep::make_view<const std::uint16_t>(d_depth.data(), r.width, r.height), 0.001f, r.k,
                           ep::make_view(d_labels.data(), r.width, r.height), res);
    CHECK(log.largest_upload < n / 8);
    CHECK(log.largest_download < n / 8);
    std::vector<std::uint16_t> back(mm.size());
    b.copy_to_host(back.data(), d_labels.data(), static_cast<std::size_t>(frame_bytes));
    CHECK(back == labels);
  }
}
