// Tests of include/edgeplane/metrics/*.hpp (EVALUATION.md): small label images whose figures are
// worked out by hand in the comments, plus reference scenes whose D2MC and SSIM come from an
// independent implementation (tests/metrics/ssim_reference.py: scipy + scikit-image).
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "edgeplane/error.hpp"
#include "edgeplane/image.hpp"
#include "edgeplane/metrics.hpp"

namespace {

namespace em = edgeplane::metrics;
using edgeplane::image_view;

/// Predicted labels, GT labels and the scored mask of one test image, owned here.
struct scene {
  int w = 0, h = 0;
  std::vector<std::uint16_t> pred, gt;
  std::vector<std::uint8_t> scored;

  scene() = default;
  scene(int width, int height)
      : w(width),
        h(height),
        pred(static_cast<std::size_t>(width) * static_cast<std::size_t>(height), 0),
        gt(pred.size(), 0),
        scored(pred.size(), 1) {}
  std::size_t at(int x, int y) const {
    return static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x);
  }
  image_view<const std::uint16_t> p() const { return edgeplane::make_view(pred.data(), w, h); }
  image_view<const std::uint16_t> g() const { return edgeplane::make_view(gt.data(), w, h); }
  image_view<const std::uint8_t> s() const { return edgeplane::make_view(scored.data(), w, h); }
  em::overlap_table table() const { return em::make_overlap_table(p(), g(), s()); }
};

/// Labels from text rows: '.' is 0, '1'..'9' are 1..9, 'a'.. are 10...
std::uint16_t label_of(char c) {
  if (c == '.') return 0;
  if (c >= '0' && c <= '9') return static_cast<std::uint16_t>(c - '0');
  return static_cast<std::uint16_t>(10 + (c - 'a'));
}
/// A scene from text rows of equal length; in `scored`, 'x' marks an unscored pixel.
scene from_text(const std::vector<std::string>& pred, const std::vector<std::string>& gt,
                const std::vector<std::string>& scored) {
  scene sc(static_cast<int>(pred[0].size()), static_cast<int>(pred.size()));
  for (int y = 0; y < sc.h; ++y)
    for (int x = 0; x < sc.w; ++x) {
      sc.pred[sc.at(x, y)] = label_of(pred[static_cast<std::size_t>(y)][static_cast<std::size_t>(x)]);
      sc.gt[sc.at(x, y)] = label_of(gt[static_cast<std::size_t>(y)][static_cast<std::size_t>(x)]);
      sc.scored[sc.at(x, y)] = scored[static_cast<std::size_t>(y)][static_cast<std::size_t>(x)] == 'x' ? 0 : 1;
    }
  return sc;
}

/// The reference scene of ssim_reference.py (make_reference_scene), formula for formula.
scene make_reference_scene(int W, int H) {
  scene sc(W, H);
  const std::int64_t w = W, h = H;
  for (std::int64_t y = 0; y < h; ++y)
    for (std::int64_t x = 0; x < w; ++x) {
      const auto sx = [&](std::int64_t v) { return v * w / 300; };
      const auto sy = [&](std::int64_t v) { return v * h / 260; };
      const auto box = [&](std::int64_t x0, std::int64_t x1, std::int64_t y0, std::int64_t y1) {
        return x >= sx(x0) && x < sx(x1) && y >= sy(y0) && y < sy(y1);
      };
      const bool diagonal = 5 * (x * h + y * w) < w * h;
      const bool hidden = box(200, 230, 130, 160);
      int g = 10;
      if (y >= sy(180)) g = 50;
      if (box(40, 140, 30, 120)) g = 20;
      if (box(160, 280, 20, 100)) g = 35;
      if (diagonal) g = 60;
      if (box(100, 130, 140, 170)) g = 0;
      if (hidden) g = 77;
      int p = 1;
      if (y >= sy(183)) p = 7;
      if (box(43, 143, 32, 122)) p = 3;
      if (box(158, 280, 22, 100)) p = x < sx(225) ? 4 : 9;
      if (diagonal) p = (x + y) % 3 == 0 ? 0 : 11;
      if (box(10, 30, 140, 160)) p = 12;
      if (hidden) p = 15;
      if ((x * x + 3 * y) % 53 == 0) p = 0;
      const std::size_t i = sc.at(static_cast<int>(x), static_cast<int>(y));
      sc.gt[i] = static_cast<std::uint16_t>(g);
      sc.pred[i] = static_cast<std::uint16_t>(p);
      sc.scored[i] = ((x * 7 + y * 13) % 97 == 0 || hidden) ? 0 : 1;
    }
  return sc;
}

/// A scene with three GT planes, a scored GT-0 patch and unscored pixels; pred == gt.
scene make_identical_scene() {
  scene sc(40, 30);
  for (int y = 0; y < sc.h; ++y)
    for (int x = 0; x < sc.w; ++x) {
      std::uint16_t g = 4;
      if (x < 15) g = 2;
      if (y >= 20) g = 9;
      if (x >= 30 && y < 5) g = 0;  // scored, no plane
      sc.gt[sc.at(x, y)] = g;
      sc.pred[sc.at(x, y)] = g;
      sc.scored[sc.at(x, y)] = (x + 2 * y) % 17 == 0 ? 0 : 1;  // scattered invalid depth
    }
  return sc;
}

em::plane_equation plane(std::uint16_t id, double nx, double ny, double nz, double d = -1.0) {
  return em::plane_equation{id, {nx, ny, nz}, d};
}
double deg(double a) { return a * std::numbers::pi / 180.0; }

/// Total weight of an assignment; also checks it is one-to-one and within range.
std::int64_t assignment_weight(const std::vector<std::int64_t>& w, int rows, int cols, const std::vector<int>& a) {
  REQUIRE(a.size() == static_cast<std::size_t>(rows));
  std::vector<int> used(static_cast<std::size_t>(cols), 0);
  std::int64_t total = 0;
  int assigned = 0;
  for (int i = 0; i < rows; ++i) {
    const int j = a[static_cast<std::size_t>(i)];
    if (j < 0) continue;
    REQUIRE(j < cols);
    REQUIRE(used[static_cast<std::size_t>(j)] == 0);
    used[static_cast<std::size_t>(j)] = 1;
    total += w[static_cast<std::size_t>(i * cols + j)];
    ++assigned;
  }
  CHECK(assigned == std::min(rows, cols));
  return total;
}
/// Brute force: the best total over all one-to-one partial assignments.
std::int64_t brute_force_best(const std::vector<std::int64_t>& w, int rows, int cols, int row,
                              std::vector<char>& used) {
  if (row == rows) return 0;
  std::int64_t best = brute_force_best(w, rows, cols, row + 1, used);  // row left unassigned
  for (int j = 0; j < cols; ++j) {
    if (used[static_cast<std::size_t>(j)]) continue;
    used[static_cast<std::size_t>(j)] = 1;
    const std::int64_t v = w[static_cast<std::size_t>(row * cols + j)] + brute_force_best(w, rows, cols, row + 1, used);
    used[static_cast<std::size_t>(j)] = 0;
    if (v > best) best = v;
  }
  return best;
}

}  // namespace

TEST_CASE("metrics: hungarian beats greedy on a small matrix") {
  // Greedy takes the 3 and is left with 0 (total 3); the optimum crosses over: 2 + 2 = 4.
  const std::vector<std::int64_t> w = {3, 2,  //
                                       2, 0};
  const std::vector<int> a = em::max_weight_assignment(w, 2, 2);
  CHECK(a == std::vector<int>{1, 0});
  CHECK(assignment_weight(w, 2, 2, a) == 4);

  // Rectangular, both orientations: 2 x 3 and its transpose.  Greedy (9 first) gives 9 + 1 = 10;
  // the optimum is 8 + 7 = 15.
  const std::vector<std::int64_t> r = {9, 8, 0,  //
                                       7, 1, 0};
  const std::vector<int> ar = em::max_weight_assignment(r, 2, 3);
  CHECK(ar == std::vector<int>{1, 0});
  const std::vector<std::int64_t> rt = {9, 7,  //
                                        8, 1,  //
                                        0, 0};
  const std::vector<int> art = em::max_weight_assignment(rt, 3, 2);
  CHECK(assignment_weight(rt, 3, 2, art) == 15);
  CHECK(art[0] == 1);
  CHECK(art[1] == 0);

  CHECK(em::max_weight_assignment(std::vector<std::int64_t>{}, 0, 4).empty());
  CHECK(em::max_weight_assignment(std::vector<std::int64_t>{}, 3, 0) == std::vector<int>{-1, -1, -1});
  CHECK_THROWS_AS(em::max_weight_assignment(w, 2, 3), edgeplane::error);
  CHECK_THROWS_AS(em::max_weight_assignment(std::vector<std::int64_t>{1, -1}, 1, 2), edgeplane::error);
}

TEST_CASE("metrics: hungarian equals brute force on random matrices") {
  std::mt19937 rng(12345);
  std::uniform_int_distribution<int> size(1, 6), value(0, 9);
  for (int trial = 0; trial < 300; ++trial) {
    const int rows = size(rng), cols = size(rng);
    std::vector<std::int64_t> w(static_cast<std::size_t>(rows * cols));
    for (std::int64_t& v : w) v = value(rng) < 3 ? 0 : value(rng);  // many zeros and ties
    std::vector<char> used(static_cast<std::size_t>(cols), 0);
    const std::int64_t best = brute_force_best(w, rows, cols, 0, used);
    CHECK(assignment_weight(w, rows, cols, em::max_weight_assignment(w, rows, cols)) == best);
  }
}

TEST_CASE("metrics: identical labels are perfect") {
  const scene sc = make_identical_scene();
  const std::vector<em::plane_equation> planes = {plane(2, 0, 0, 1), plane(4, 0, 1, 1), plane(9, 1, 0, 0)};
  const em::report r = em::evaluate(sc.p(), sc.g(), sc.s(), planes, planes);
  CHECK(r.d2mc == 1.0);
  CHECK(r.ssim == doctest::Approx(1.0).epsilon(1e-12));
  CHECK(r.segcomp.correct == 3);
  CHECK(r.segcomp.over == 0);
  CHECK(r.segcomp.under == 0);
  CHECK(r.segcomp.missed == 0);
  CHECK(r.segcomp.noise == 0);
  CHECK(r.segcomp.gt_planes == 3);
  CHECK(r.segcomp.segments == 3);
  CHECK(r.segcomp.angle_pairs == 3);
  CHECK(r.segcomp.mean_angle_deg == 0.0);
  CHECK(r.planes.matches == 3);
  CHECK(r.planes.precision == 1.0);
  CHECK(r.planes.recall == 1.0);
  CHECK(r.planes.mean_iou == 1.0);
  CHECK(r.planes.mean_angle_deg == 0.0);
  REQUIRE(r.d2mc_matches.size() == 3);
  CHECK(r.d2mc_matches[0].segment == 2);
  CHECK(r.d2mc_matches[0].gt == 2);
  // Every scored pixel: 1200 minus those with (x + 2y) % 17 == 0.
  int unscored = 0;
  for (int y = 0; y < sc.h; ++y)
    for (int x = 0; x < sc.w; ++x) unscored += (x + 2 * y) % 17 == 0 ? 1 : 0;
  CHECK(r.scored_pixels == 1200 - unscored);
}

TEST_CASE("metrics: over-segmentation of one GT plane (d2mc, segcomp, precision)") {
  // 20 x 10, all scored.  GT 1: columns 0-9, GT 2: columns 10-19.  Segment 5: columns 0-5,
  // segment 7: columns 6-9, segment 9: columns 10-19.
  scene sc(20, 10);
  for (int y = 0; y < sc.h; ++y)
    for (int x = 0; x < sc.w; ++x) {
      sc.gt[sc.at(x, y)] = x < 10 ? 1 : 2;
      sc.pred[sc.at(x, y)] = x < 6 ? 5 : (x < 10 ? 7 : 9);
    }
  // D2MC: Hungarian matches 5-1 (60) and 9-2 (100); 7 stays unmatched: 160 / 200.
  const em::d2mc_result d = em::d2mc_matching(sc.table());
  CHECK(d.d2mc == doctest::Approx(0.8).epsilon(1e-15));
  REQUIRE(d.matches.size() == 2);
  CHECK(d.matches[0].segment == 5);
  CHECK(d.matches[0].gt == 1);
  CHECK(d.matches[0].overlap == 60);
  CHECK(d.matches[1].segment == 9);
  CHECK(d.matches[1].overlap == 100);
  CHECK(em::d2mc(sc.p(), sc.g(), sc.s()) == doctest::Approx(0.8).epsilon(1e-15));
  // SegComp: (9, 2) correct; 5 and 7 each lie >= 80 % in GT 1 and cover 100 % of it: one over.
  const em::segcomp_counts c = em::segcomp(sc.p(), sc.g(), sc.s());
  CHECK(c.correct == 1);
  CHECK(c.over == 1);
  CHECK(c.under == 0);
  CHECK(c.missed == 0);
  CHECK(c.noise == 0);
  // Precision / recall: IoU(5,1) = 60/100, IoU(7,1) = 40/100, IoU(9,2) = 1.  Two matches.
  const em::plane_match_result pr = em::plane_precision_recall(sc.p(), sc.g(), sc.s());
  CHECK(pr.matches == 2);
  CHECK(pr.segments == 3);
  CHECK(pr.precision == doctest::Approx(2.0 / 3.0).epsilon(1e-15));
  CHECK(pr.recall == 1.0);
  CHECK(pr.mean_iou == doctest::Approx(0.8).epsilon(1e-15));
  // With tolerance 0.95 the 60 + 40 still cover all of GT 1, so it stays an over-segmentation.
  CHECK(em::segcomp(sc.p(), sc.g(), sc.s(), 0.95).over == 1);
  // Segment 7 half on GT 1 and half on GT 2 (rows 0-4 of columns 6-9 moved to GT 2): it no
  // longer lies >= 80 % in GT 1, so GT 1 is not over-segmented; 7 is noise and GT 1 missed
  // (segment 5 holds only 60 of its 80 pixels), while (9, 2) stays correct (100 >= 0.8 * 120).
  for (int y = 0; y < 5; ++y)
    for (int x = 6; x < 10; ++x) sc.gt[sc.at(x, y)] = 2;
  const em::segcomp_counts c2 = em::segcomp(sc.p(), sc.g(), sc.s());
  CHECK(c2.correct == 1);
  CHECK(c2.over == 0);
  CHECK(c2.missed == 1);
  CHECK(c2.noise == 2);
}

TEST_CASE("metrics: under-segmentation of two GT planes (d2mc, segcomp, precision)") {
  // 30 x 10, all scored.  GT 1, 2, 3: columns 0-9, 10-19, 20-29.  Segment 4: columns 0-19,
  // segment 6: columns 20-29.
  scene sc(30, 10);
  for (int y = 0; y < sc.h; ++y)
    for (int x = 0; x < sc.w; ++x) {
      sc.gt[sc.at(x, y)] = static_cast<std::uint16_t>(1 + x / 10);
      sc.pred[sc.at(x, y)] = x < 20 ? 4 : 6;
    }
  // D2MC: 4 matches one of GT 1 / GT 2 (100), 6 matches GT 3 (100): 200 / 300.
  CHECK(em::d2mc(sc.p(), sc.g(), sc.s()) == doctest::Approx(2.0 / 3.0).epsilon(1e-15));
  const em::segcomp_counts c = em::segcomp(sc.p(), sc.g(), sc.s());
  CHECK(c.correct == 1);
  CHECK(c.over == 0);
  CHECK(c.under == 1);
  CHECK(c.missed == 0);
  CHECK(c.noise == 0);
  // IoU(4,1) = IoU(4,2) = 100 / 200 = 0.5 exactly: >= 0.5 matches, one-to-one, the tie goes to
  // the lower GT id.  IoU(6,3) = 1.
  const em::plane_match_result pr = em::plane_precision_recall(sc.p(), sc.g(), sc.s());
  CHECK(pr.matches == 2);
  CHECK(pr.precision == 1.0);
  CHECK(pr.recall == doctest::Approx(2.0 / 3.0).epsilon(1e-15));
  CHECK(pr.mean_iou == doctest::Approx(0.75).epsilon(1e-15));
  REQUIRE(pr.matched.size() == 2);
  CHECK(pr.matched[0].segment == 6);  // best IoU first
  CHECK(pr.matched[1].segment == 4);
  CHECK(pr.matched[1].gt == 1);
  // One pixel of GT 2 more (row 0, column 20 becomes GT 2, still segment 6): IoU(4,2) = 100/201
  // drops below 0.5 and IoU(4,1) stays 0.5.
  sc.gt[sc.at(20, 0)] = 2;
  const em::plane_match_result pr2 = em::plane_precision_recall(sc.p(), sc.g(), sc.s());
  CHECK(pr2.matches == 2);
  CHECK(pr2.matched[1].gt == 1);
}

TEST_CASE("metrics: an empty prediction") {
  // 20 x 20: GT 1 left half and GT 2 right half of rows 0-14, rows 15-19 scored GT 0.
  scene sc(20, 20);
  for (int y = 0; y < sc.h; ++y)
    for (int x = 0; x < sc.w; ++x) sc.gt[sc.at(x, y)] = y >= 15 ? 0 : (x < 10 ? 1 : 2);
  const em::report r = em::evaluate(sc.p(), sc.g(), sc.s());
  CHECK(r.d2mc == doctest::Approx(100.0 / 400.0).epsilon(1e-15));  // only O(0,0) is covered
  CHECK(r.d2mc_matches.empty());
  CHECK(r.segcomp.correct == 0);
  CHECK(r.segcomp.missed == 2);
  CHECK(r.segcomp.noise == 0);
  CHECK(r.segcomp.segments == 0);
  CHECK(std::isnan(r.segcomp.mean_angle_deg));
  CHECK(r.planes.matches == 0);
  CHECK(std::isnan(r.planes.precision));  // 0 / 0
  CHECK(r.planes.recall == 0.0);
  CHECK(std::isnan(r.planes.mean_iou));
  CHECK(r.ssim < 0.9);
  CHECK(r.ssim > -1.0);
  CHECK(r.ssim == em::label_ssim(sc.p(), sc.g(), sc.s()));

  // Nothing scored at all: D2MC is undefined, no GT plane exists, nothing is missed.
  std::fill(sc.scored.begin(), sc.scored.end(), std::uint8_t{0});
  const em::report e = em::evaluate(sc.p(), sc.g(), sc.s());
  CHECK(std::isnan(e.d2mc));
  CHECK(e.segcomp.gt_planes == 0);
  CHECK(e.segcomp.missed == 0);
  CHECK(std::isnan(e.planes.recall));
}

TEST_CASE("metrics: don't-care pixels are never punished") {
  // The identical scene, then arbitrary labels on every unscored pixel: other segments, a segment
  // (42) that exists only there, and a GT plane (99) that exists only there.  GT stays non-zero on
  // those pixels (invalid depth, not GT 0), so no segment falls under the fragment rule.
  const scene clean = make_identical_scene();
  scene sc = clean;
  int k = 0;
  for (std::size_t i = 0; i < sc.pred.size(); ++i) {
    if (sc.scored[i] != 0) continue;
    static const std::uint16_t pred_ids[] = {2, 4, 9, 42, 0};
    static const std::uint16_t gt_ids[] = {99, 4, 2, 9};
    sc.pred[i] = pred_ids[k % 5];
    sc.gt[i] = gt_ids[k % 4];
    ++k;
  }
  REQUIRE(k > 10);
  const em::report r = em::evaluate(sc.p(), sc.g(), sc.s());
  CHECK(r.d2mc == 1.0);
  CHECK(r.ssim == doctest::Approx(1.0).epsilon(1e-12));
  CHECK(r.segcomp.correct == 3);
  CHECK(r.segcomp.gt_planes == 3);  // 99 has no scored pixel: it does not exist
  CHECK(r.segcomp.missed == 0);
  CHECK(r.segcomp.segments == 3);  // 42 has no scored pixel: not noise
  CHECK(r.segcomp.noise == 0);
  CHECK(r.segcomp.excluded == 0);
  CHECK(r.planes.precision == 1.0);
  CHECK(r.planes.recall == 1.0);

  // A segment reaching over unscored GT-0 pixels (fewer than its scored ones) is not excluded
  // and loses nothing: segment 2 takes 5 unscored GT-0 pixels.
  scene sc2 = clean;
  int taken = 0;
  for (int y = 0; y < sc2.h && taken < 5; ++y)
    for (int x = 0; x < 15 && taken < 5; ++x)
      if (sc2.scored[sc2.at(x, y)] == 0) {
        sc2.gt[sc2.at(x, y)] = 0;
        ++taken;
      }
  REQUIRE(taken == 5);
  const em::report r2 = em::evaluate(sc2.p(), sc2.g(), sc2.s());
  CHECK(r2.segcomp.correct == 3);
  CHECK(r2.segcomp.excluded == 0);
  CHECK(r2.d2mc == 1.0);
}

TEST_CASE("metrics: tiny fragments on don't-care GT-0 pixels are left out of region metrics") {
  // Rows 0-5: GT 1 / segment 3.  Rows 6-11, columns 0-9: GT 2 / segment 4, except the pixels
  // marked 8 (3 of them, scored, on GT 2).  Rows 6-11, columns 10-19: unscored.  Fragment 8 has 3
  // scored pixels and `n_dont_care` pixels on the unscored block.
  const auto build = [](int n_dont_care, std::uint16_t dont_care_gt) {
    scene sc(20, 12);
    int placed = 0;
    for (int y = 0; y < sc.h; ++y)
      for (int x = 0; x < sc.w; ++x) {
        const std::size_t i = sc.at(x, y);
        if (y < 6) {
          sc.gt[i] = 1;
          sc.pred[i] = 3;
        } else if (x < 10) {
          sc.gt[i] = 2;
          sc.pred[i] = (x == 9 && y < 9) ? 8 : 4;
        } else {
          sc.scored[i] = 0;
          sc.gt[i] = dont_care_gt;
          sc.pred[i] = placed++ < n_dont_care ? 8 : 0;
        }
      }
    return sc;
  };
  // 60 don't-care GT-0 pixels > 3 scored: left out.  Not noise, not a segment for precision.
  {
    const scene sc = build(60, 0);
    const em::overlap_table t = sc.table();
    REQUIRE(t.segments() == 3);
    CHECK(t.segment_ids[2] == 8);
    CHECK(t.segment_size[3] == 3);
    CHECK(t.segment_dont_care_gt0[3] == 60);
    CHECK(t.excluded_from_region_metrics(3));
    const em::report r = em::evaluate(sc.p(), sc.g(), sc.s());
    CHECK(r.segcomp.correct == 2);  // (3, 1) and (4, 2): 57 >= 0.8 * 60
    CHECK(r.segcomp.noise == 0);
    CHECK(r.segcomp.segments == 2);
    CHECK(r.segcomp.excluded == 1);
    CHECK(r.planes.segments == 2);
    CHECK(r.planes.precision == 1.0);
    CHECK(r.planes.recall == 1.0);
    // D2MC still sees the fragment: its 3 pixels on GT 2 are not covered: (120 + 57) / 180.
    CHECK(r.d2mc == doctest::Approx(177.0 / 180.0).epsilon(1e-15));
  }
  // 3 don't-care pixels = 3 scored: not fewer, so the fragment counts, as noise.
  {
    const scene sc = build(3, 0);
    const em::report r = em::evaluate(sc.p(), sc.g(), sc.s());
    CHECK(r.segcomp.excluded == 0);
    CHECK(r.segcomp.noise == 1);
    CHECK(r.planes.segments == 3);
    CHECK(r.planes.precision == doctest::Approx(2.0 / 3.0).epsilon(1e-15));
  }
  // 4 don't-care pixels > 3 scored: left out again.
  CHECK(em::segcomp(build(4, 0).table()).noise == 0);
  // 60 unscored pixels whose GT is a plane (invalid depth, not GT 0) do not count: noise.
  {
    const scene sc = build(60, 2);
    const em::overlap_table t = sc.table();
    CHECK(t.segment_dont_care_gt0[3] == 0);
    CHECK(em::segcomp(t).noise == 1);
  }
}

TEST_CASE("metrics: segcomp thresholds are inclusive, also where T * P rounds up") {
  // One row: segment 3 has `o` pixels on GT 1 and `p - o` on scored GT 0; GT 1 has `p - o` more
  // pixels predicted 0.  So P_3 = P_1 = p and O(3,1) = o.
  const auto row = [](int o, int p) {
    scene sc(2 * p - o, 1);
    for (int x = 0; x < sc.w; ++x) {
      sc.pred[sc.at(x, 0)] = (x < o || x >= p) ? 3 : 0;
      sc.gt[sc.at(x, 0)] = x < p ? 1 : 0;
    }
    return sc;
  };
  const scene a = row(8, 10);  // O = 0.8 P exactly
  CHECK(em::segcomp(a.table(), 0.8).correct == 1);
  CHECK(em::segcomp(a.table(), 0.81).correct == 0);
  const scene b = row(55, 100);  // 0.55 * 100 is 55.00000000000001 in doubles
  CHECK(em::segcomp(b.table(), 0.55).correct == 1);
  const em::segcomp_counts c = em::segcomp(b.table(), 0.56);
  CHECK(c.correct == 0);
  CHECK(c.missed == 1);
  CHECK(c.noise == 1);
}

TEST_CASE("metrics: d2mc uses the optimal assignment, not the greedy one") {
  // One row of 75 pixels.  Segment 1 (a): 30 pixels on GT 1 then 25 on GT 2; segment 2 (b): 20 on
  // GT 1.  Greedy takes a-1 (30) and leaves b with nothing: 30 / 75 = 0.4.  Hungarian: a-2 (25) +
  // b-1 (20) = 45 / 75 = 0.6.
  scene sc(75, 1);
  for (int x = 0; x < 75; ++x) {
    sc.pred[sc.at(x, 0)] = x < 55 ? 1 : 2;
    sc.gt[sc.at(x, 0)] = (x < 30 || x >= 55) ? 1 : 2;
  }
  const em::d2mc_result d = em::d2mc_matching(sc.table());
  CHECK(d.d2mc == doctest::Approx(0.6).epsilon(1e-15));
  REQUIRE(d.matches.size() == 2);
  CHECK(d.matches[0].segment == 1);
  CHECK(d.matches[0].gt == 2);
  CHECK(d.matches[0].overlap == 25);
  CHECK(d.matches[1].segment == 2);
  CHECK(d.matches[1].gt == 1);
  CHECK(d.matches[1].overlap == 20);
  // Zero-overlap pairs are dropped: a third segment touching only GT 0 stays unmatched although
  // a GT plane is free.
  scene sc3(3, 1);
  sc3.pred = {1, 2, 3};
  sc3.gt = {1, 0, 2};
  sc3.pred[2] = 0;  // GT 2 predicted 0
  const em::d2mc_result d3 = em::d2mc_matching(sc3.table());
  REQUIRE(d3.matches.size() == 1);
  CHECK(d3.matches[0].segment == 1);
  CHECK(d3.d2mc == doctest::Approx(1.0 / 3.0).epsilon(1e-15));
}

TEST_CASE("metrics: ssim rendering of label images") {
  // GT ids on scored pixels: 3 (rank 1 -> 98) and 8 (rank 2 -> 195).  Segment 5 matches GT 8,
  // segment 2 matches GT 3 (one pixel); segments 1 and 9 are unmatched: ranks G + 1 = 3 -> 37 and
  // G + 2 = 4 -> 134 in ascending id order.  Segment 7 lies only on unscored pixels: no rank.
  //            index:  0 1 2 3 4 5 6 7 8 9 10 11
  const scene sc = from_text({"..55529772.1"}, {"33888..883.."}, {".......xx..."});
  const em::overlap_table t = sc.table();
  CHECK(t.segment_ids == std::vector<std::uint16_t>{1, 2, 5, 9});
  CHECK(t.gt_ids == std::vector<std::uint16_t>{3, 8});
  const em::d2mc_result m = em::d2mc_matching(t);
  std::vector<std::uint8_t> a(12), b(12);
  em::render_labels_for_ssim(t, m, sc.p(), sc.g(), sc.s(), edgeplane::make_view(a.data(), 12, 1),
                             edgeplane::make_view(b.data(), 12, 1));
  CHECK(a == std::vector<std::uint8_t>{0, 0, 195, 195, 195, 98, 134, 0, 0, 98, 0, 37});
  CHECK(b == std::vector<std::uint8_t>{98, 98, 195, 195, 195, 0, 0, 0, 0, 98, 0, 0});
  CHECK(em::ssim_grey_level(1) == 98);
  CHECK(em::ssim_grey_level(3) == 37);
  CHECK(em::ssim_grey_level(255) == 1);
  CHECK(em::ssim_grey_level(256) == 98);
}

TEST_CASE("metrics: ssim of simple images and the downsampling factor") {
  CHECK(em::ssim_downsampling_factor(640, 480) == 2);   // 1.875
  CHECK(em::ssim_downsampling_factor(383, 1000) == 1);  // 1.496
  CHECK(em::ssim_downsampling_factor(1000, 384) == 2);  // 1.5 rounds up, as MATLAB's round
  CHECK(em::ssim_downsampling_factor(640, 640) == 3);   // 2.5
  CHECK(em::ssim_downsampling_factor(100, 50) == 1);
  // Two constant images: no variance, SSIM = (2ab + C1) / (a^2 + b^2 + C1), C1 = (0.01 * 255)^2.
  std::vector<std::uint8_t> a(30 * 20, 100), b(30 * 20, 50);
  const double c1 = 2.55 * 2.55;
  CHECK(em::ssim(edgeplane::make_view(static_cast<const std::uint8_t*>(a.data()), 30, 20),
                 edgeplane::make_view(static_cast<const std::uint8_t*>(b.data()), 30, 20)) ==
        doctest::Approx((2 * 100.0 * 50.0 + c1) / (100.0 * 100.0 + 50.0 * 50.0 + c1)).epsilon(1e-12));
  // Below 11 x 11 (after downsampling) there is no SSIM.
  CHECK(std::isnan(em::ssim(edgeplane::make_view(static_cast<const std::uint8_t*>(a.data()), 60, 10),
                            edgeplane::make_view(static_cast<const std::uint8_t*>(b.data()), 60, 10))));
  CHECK_THROWS_AS(em::ssim(edgeplane::make_view(static_cast<const std::uint8_t*>(a.data()), 30, 20),
                           edgeplane::make_view(static_cast<const std::uint8_t*>(b.data()), 20, 30)),
                  edgeplane::error);
}

TEST_CASE("metrics: ssim and d2mc match the independent reference (F = 1, 2, 3)") {
  // Values printed by tests/metrics/ssim_reference.py (scipy linear_sum_assignment, numpy
  // downsampling as ssim.m, skimage.metrics.structural_similarity); see that script.  The SSIM is
  // checked to 1e-6 relative (the two implementations agree to about 1e-14).
  struct reference {
    int w, h, f;
    double d2mc, ssim, mean_iou;
  };
  const reference refs[] = {
      {300, 260, 1, 0.87542427300247683, 0.56949588774043347, 0.7757668247224633},
      {701, 541, 2, 0.87591567440531692, 0.63809789534628558, 0.7764175659341056},
      {820, 700, 3, 0.87492276380057299, 0.69586570556996119, 0.7750558401381612},
  };
  for (const reference& ref : refs) {
    CAPTURE(ref.w);
    const scene sc = make_reference_scene(ref.w, ref.h);
    CHECK(em::ssim_downsampling_factor(ref.w, ref.h) == ref.f);
    const em::report r = em::evaluate(sc.p(), sc.g(), sc.s());
    CHECK(r.d2mc == doctest::Approx(ref.d2mc).epsilon(1e-12));
    CHECK(r.ssim == doctest::Approx(ref.ssim).epsilon(1e-6));
    CHECK(std::abs(r.ssim - ref.ssim) <= 1e-6 * ref.ssim);
    // The matching the script found: 1-10, 3-20, 4-35, 7-50, 11-60; 9, 12 unmatched; 15 and GT 77
    // have no scored pixel.
    REQUIRE(r.d2mc_matches.size() == 5);
    const std::uint16_t seg[] = {1, 3, 4, 7, 11}, gt[] = {10, 20, 35, 50, 60};
    for (std::size_t k = 0; k < 5; ++k) {
      CHECK(r.d2mc_matches[k].segment == seg[k]);
      CHECK(r.d2mc_matches[k].gt == gt[k]);
    }
    CHECK(r.segcomp.gt_planes == 5);
    // The script's plain re-reading of the region rules: (1,10), (3,20), (7,50) correct; 35 split
    // by 4 and 9; 60 missed (11 covers too little of it); 11 and 12 noise.  IoU >= 0.5 for all
    // five matched pairs above.
    CHECK(r.segcomp.correct == 3);
    CHECK(r.segcomp.over == 1);
    CHECK(r.segcomp.under == 0);
    CHECK(r.segcomp.missed == 1);
    CHECK(r.segcomp.noise == 2);
    CHECK(r.segcomp.segments == 7);
    CHECK(r.planes.matches == 5);
    CHECK(r.planes.precision == doctest::Approx(5.0 / 7.0).epsilon(1e-15));
    CHECK(r.planes.recall == 1.0);
    CHECK(r.planes.mean_iou == doctest::Approx(ref.mean_iou).epsilon(1e-12));
  }
  // The 300 x 260 overlaps, as the script printed them.
  const em::d2mc_result d = em::d2mc_matching(make_reference_scene(300, 260).table());
  const std::int64_t overlaps[] = {30081, 8299, 4919, 22440, 1046};
  for (std::size_t k = 0; k < 5; ++k) CHECK(d.matches[k].overlap == overlaps[k]);
}

TEST_CASE("metrics: segcomp and precision report the angle between plane normals") {
  // GT 1 and 2 found exactly by segments 5 and 6; GT 3 by segment 7 without a plane equation.
  scene sc(30, 10);
  for (int y = 0; y < sc.h; ++y)
    for (int x = 0; x < sc.w; ++x) {
      sc.gt[sc.at(x, y)] = static_cast<std::uint16_t>(1 + x / 10);
      sc.pred[sc.at(x, y)] = static_cast<std::uint16_t>(5 + x / 10);
    }
  const std::vector<em::plane_equation> gt = {plane(1, 0, 0, 1), plane(2, 1, 0, 0, 2.0), plane(3, 0, 1, 0)};
  // 10 degrees off (normal scaled by 2), and 20 degrees off with the opposite sign convention.
  const std::vector<em::plane_equation> pred = {plane(5, 0, 2 * std::sin(deg(10)), 2 * std::cos(deg(10))),
                                                plane(6, -std::cos(deg(20)), 0, -std::sin(deg(20)), -2.0)};
  const em::segcomp_counts c = em::segcomp(sc.p(), sc.g(), sc.s(), 0.8, pred, gt);
  CHECK(c.correct == 3);
  CHECK(c.angle_pairs == 2);
  CHECK(c.mean_angle_deg == doctest::Approx(15.0).epsilon(1e-12));
  const em::plane_match_result pr = em::plane_precision_recall(sc.p(), sc.g(), sc.s(), pred, gt);
  CHECK(pr.angle_pairs == 2);
  CHECK(pr.mean_angle_deg == doctest::Approx(15.0).epsilon(1e-12));
  CHECK(em::normal_angle_deg(plane(1, 0, 0, 1), plane(2, 0, 0, -3)) == 0.0);
  CHECK(em::normal_angle_deg(plane(1, 0, 0, 1), plane(2, 0, 1, 0)) == doctest::Approx(90.0));
}

TEST_CASE("metrics: bad arguments throw edgeplane::error") {
  const scene sc = make_identical_scene();
  const scene other(10, 10);
  CHECK_THROWS_AS(em::evaluate(sc.p(), other.g(), sc.s()), edgeplane::error);
  CHECK_THROWS_AS(em::make_overlap_table(sc.p(), sc.g(), other.s()), edgeplane::error);
  CHECK_THROWS_AS(em::segcomp(sc.p(), sc.g(), sc.s(), 0.5), edgeplane::error);
  CHECK_THROWS_AS(em::segcomp(sc.p(), sc.g(), sc.s(), 1.01), edgeplane::error);
  const std::vector<em::plane_equation> twice = {plane(2, 0, 0, 1), plane(2, 0, 1, 0)};
  CHECK_THROWS_AS(em::plane_precision_recall(sc.p(), sc.g(), sc.s(), twice), edgeplane::error);
  const std::vector<em::plane_equation> zero = {plane(2, 0, 0, 0)};
  CHECK_THROWS_AS(em::segcomp(sc.p(), sc.g(), sc.s(), 0.8, {}, zero), edgeplane::error);
  const std::vector<em::plane_equation> id0 = {plane(0, 0, 0, 1)};
  CHECK_THROWS_AS(em::evaluate(sc.p(), sc.g(), sc.s(), id0), edgeplane::error);
  const image_view<const std::uint16_t> null_view{nullptr, 4, 4, 4};
  CHECK_THROWS_AS(em::d2mc(null_view, null_view, edgeplane::make_view(sc.scored.data(), 4, 4)), edgeplane::error);
}

TEST_CASE("metrics: scored masks from an ignore image and from ABW GT") {
  const std::vector<std::uint8_t> ignore = {0, 255, 0, 1};
  std::vector<std::uint8_t> out(4, 7);
  em::scored_mask_from_ignore(edgeplane::make_view(ignore.data(), 2, 2), edgeplane::make_view(out.data(), 2, 2));
  CHECK(out == std::vector<std::uint8_t>{1, 0, 1, 0});
  const std::vector<std::uint16_t> ignore16 = {0, 0, 3, 0};
  em::scored_mask_from_ignore(edgeplane::make_view(ignore16.data(), 2, 2), edgeplane::make_view(out.data(), 2, 2));
  CHECK(out == std::vector<std::uint8_t>{1, 1, 0, 1});
  const std::vector<std::uint16_t> abw = {0, 9, 10, 255};
  em::scored_mask_from_abw_gt(edgeplane::make_view(abw.data(), 2, 2), edgeplane::make_view(out.data(), 2, 2));
  CHECK(out == std::vector<std::uint8_t>{0, 0, 1, 1});
  CHECK_THROWS_AS(
      em::scored_mask_from_abw_gt(edgeplane::make_view(abw.data(), 2, 2), edgeplane::make_view(out.data(), 1, 2)),
      edgeplane::error);
}
