// A split round's pieces on host backends: where a failed candidate's largest piece outweighs the
// pixels of it that no piece took, that piece's sums are derived (the candidate's less the rest's
// and its other pieces') instead of summed (segmenter::split_refit).  This executable defines
// EDGEPLANE_VERIFY_SPLIT_SUMS (tests/CMakeLists.txt), under which the segmenter also sums every
// such piece directly and throws unless the blocks are identical and the box it keeps contains the
// piece's own; so every test that segments a frame checks it.  Here: frames that do derive pieces
// (the benchmark's frame, in which the room's floor fails and loses only its rim to the erosion),
// and the device path (which sums the pieces directly) giving the same segmentation.
#include <doctest/doctest.h>

#include <utility>

#include "edgeplane/edgeplane.hpp"
#include "support/backend_equivalence.hpp"
#include "support/device_model.hpp"
#include "support/scenes.hpp"

#if !defined(EDGEPLANE_VERIFY_SPLIT_SUMS)
#error "tests/CMakeLists.txt defines EDGEPLANE_VERIFY_SPLIT_SUMS for the test executable"
#endif

namespace ep = edgeplane;
namespace eq = edgeplane_test::equivalence;

TEST_CASE("split rounds: derived piece sums are the direct sums; labels and planes equal the device path's") {
  for (const auto& [w, h] : {std::pair{512, 424}, std::pair{640, 480}}) {
    CAPTURE(w);
    const auto sc = eq::scenes()[0];  // room_with_box, rendered as the benchmarks render it
    const ep::test::rendered r = eq::frame(sc.s, sc.pose, w, h, 42);
    const auto mm = r.depth_mm();
    ep::segmenter<ep::cpu> cs(ep::presets::thesis_full());
    const auto c = eq::segment(cs, mm, 0.001f, r.k, r.width, r.height, r.width);
    CHECK(cs.verified_derived_pieces > 0);  // a piece was derived (and matched its direct sums)
    CHECK(c.result.planes.size() >= 2);
    // without split rounds fewer candidates: the rounds did split
    ep::params no_split = ep::presets::thesis_full();
    no_split.split_rounds = 0;
    ep::segmenter<ep::cpu> ns(no_split);
    CHECK(eq::segment(ns, mm, 0.001f, r.k, r.width, r.height, r.width).result.candidates < c.result.candidates);
    const edgeplane_test::device_model dev{edgeplane_test::device_model::order::parallel};
    ep::segmenter<edgeplane_test::device_model> ds(ep::presets::thesis_full(), dev);
    eq::check_same_segmentation(c, eq::segment(ds, mm, 0.001f, r.k, r.width, r.height, r.width));
    // serial CPU runs too (the same blocks whatever the threads)
    ep::segmenter<ep::cpu> ss(ep::presets::thesis_full(), ep::cpu{ep::cpu::mode::serial});
    eq::check_same_segmentation(c, eq::segment(ss, mm, 0.001f, r.k, r.width, r.height, r.width));
    CHECK(ss.verified_derived_pieces == cs.verified_derived_pieces);
  }
}
