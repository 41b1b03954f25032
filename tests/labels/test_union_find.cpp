// Tests of include/edgeplane/labels/union_find.hpp: the lock-free union-find against a serial
// reference, the grid adjacency, and determinism (every root is its component's smallest element).
#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <vector>

#include "edgeplane/labels/union_find.hpp"
#include "edgeplane/segmenter.hpp"
#include "support/test_backends.hpp"

using namespace edgeplane;
using namespace edgeplane_test;

namespace {

/// A serial reference union-find; component_min()[i] is the smallest element of i's component.
struct reference_uf {
  std::vector<int> parent;
  explicit reference_uf(int n) : parent(static_cast<std::size_t>(n)) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int x) {
    while (parent[x] != x) x = parent[x];
    return x;
  }
  void unite(int a, int b) {
    a = find(a);
    b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
  std::vector<std::int32_t> component_min() {
    std::vector<std::int32_t> out(parent.size());
    for (std::size_t i = 0; i < parent.size(); ++i) out[i] = find(static_cast<int>(i));
    return out;
  }
};

/// Active unless listed as inactive by a byte mask (host or backend memory alike).
struct mask_active {
  const std::uint8_t* on;
  bool operator()(std::int64_t i) const { return on[i] != 0; }
};

/// Each element's root, found by following the parents to their fixed point.  The union tests
/// compare these, so that they test the unions alone; whether flatten already stored every root
/// (the documented output) is the separate "after flatten" test below.
std::vector<std::int32_t> resolved(std::vector<std::int32_t> parent) {
  for (std::size_t i = 0; i < parent.size(); ++i) {
    std::int32_t r = parent[i];
    while (r >= 0 && parent[static_cast<std::size_t>(r)] != r) r = parent[static_cast<std::size_t>(r)];
    parent[i] = r;
  }
  return parent;
}

/// Runs connected_components over an explicit pair list; returns the parent array as written.
template <class B, class Active>
std::vector<std::int32_t> raw_components(const B& b, int n, Active active, const std::vector<std::int32_t>& first,
                                         const std::vector<std::int32_t>& second) {
  device_array<std::int32_t, B> f(b, first), s(b, second), parent(b, static_cast<std::size_t>(n), -7);
  connected_components(b, n, active, static_cast<std::int64_t>(first.size()),
                       detail::pair_list_adjacency{f.data(), s.data()}, parent.data());
  return parent.host();
}

/// As raw_components, with every element resolved to its root.
template <class B, class Active>
std::vector<std::int32_t> components(const B& b, int n, Active active, const std::vector<std::int32_t>& first,
                                     const std::vector<std::int32_t>& second) {
  return resolved(raw_components(b, n, active, first, second));
}

}  // namespace

TEST_CASE_TEMPLATE("union-find: chains in forward, reversed and interleaved order end rooted at 0", B,
                   EDGEPLANE_TEST_BACKENDS) {
  const int n = 5000;
  std::vector<std::int32_t> a, c;
  for (int i = 0; i + 1 < n; ++i) {
    a.push_back(i);
    c.push_back(i + 1);
  }
  for (const B& b : variants<B>()) {
    CAPTURE(variant_name(b));
    const std::vector<std::int32_t> zeros(n, 0);
    CHECK(components(b, n, detail::all_active{}, a, c) == zeros);
    const std::vector<std::int32_t> ra(a.rbegin(), a.rend()), rc(c.rbegin(), c.rend());
    CHECK(components(b, n, detail::all_active{}, rc, ra) == zeros);  // pairs reversed, (i+1, i)
    std::vector<std::int32_t> ia, ic;  // odd links first, then even ones
    for (int par = 1; par >= 0; --par)
      for (int i = par; i + 1 < n; i += 2) {
        ia.push_back(i + 1);
        ic.push_back(i);
      }
    CHECK(components(b, n, detail::all_active{}, ia, ic) == zeros);
  }
}

TEST_CASE_TEMPLATE("union-find: random pairs match a serial reference; roots are component minima", B,
                   EDGEPLANE_TEST_BACKENDS) {
  lcg_noise rng(11);
  for (int trial = 0; trial < 6; ++trial) {
    const int n = 500 + 700 * trial, m = trial % 2 ? n / 2 : n;  // sparse and dense unions
    std::vector<std::uint8_t> on(static_cast<std::size_t>(n));
    for (auto& v : on) v = rng.next_u32(10) != 0 ? 1 : 0;  // about 10 % inactive
    std::vector<std::int32_t> a, c;
    reference_uf ref(n);
    while (static_cast<int>(a.size()) < m) {
      const int x = static_cast<int>(rng.next_u32(n)), y = static_cast<int>(rng.next_u32(n));
      if (!on[x] || !on[y]) continue;  // pairs name active elements only
      a.push_back(x);
      c.push_back(y);
      ref.unite(x, y);
    }
    auto want = ref.component_min();
    for (int i = 0; i < n; ++i)
      if (!on[i]) want[i] = -1;
    for (const B& b : variants<B>()) {
      CAPTURE(variant_name(b));
      CAPTURE(trial);
      device_array<std::uint8_t, B> act(b, on);
      CHECK(components(b, n, mask_active{act.data()}, a, c) == want);
    }
  }
}

TEST_CASE_TEMPLATE("union-find: under contention (all pairs to one element) the result never varies", B,
                   EDGEPLANE_TEST_BACKENDS) {
  const int n = 1 << 15;
  std::vector<std::int32_t> a, c;
  for (int i = 0; i < n; ++i) {  // every element to the hub in the middle, then to the last element
    a.push_back(i);
    c.push_back(n / 2);
  }
  for (int i = 0; i < n; i += 3) {
    a.push_back(n - 1);
    c.push_back(i);
  }
  const std::vector<std::int32_t> zeros(n, 0);
  for (const B& b : variants<B>()) {
    CAPTURE(variant_name(b));
    for (int rep = 0; rep < 50; ++rep) {
      CAPTURE(rep);
      REQUIRE(components(b, n, detail::all_active{}, a, c) == zeros);
    }
  }
  // Every element to the last one, in descending order: both threads keep hooking the same current
  // root, so compare-and-swaps fail often and a lost retry would leave elements apart.
  for (int m : {1 << 12, 1 << 14}) {
    std::vector<std::int32_t> sa, sb;
    for (int i = m - 2; i >= 0; --i) {
      sa.push_back(m - 1);
      sb.push_back(i);
    }
    const std::vector<std::int32_t> mzeros(static_cast<std::size_t>(m), 0);
    for (const B& b : variants<B>())
      for (int rep = 0; rep < 50; ++rep) REQUIRE(components(b, m, detail::all_active{}, sa, sb) == mzeros);
  }
  // Two hubs that must stay apart: even elements to 0, odd elements to 1.
  std::vector<std::int32_t> e1, e2;
  for (int i = 2; i < n; ++i) {
    e1.push_back(i);
    e2.push_back(i % 2);
  }
  std::vector<std::int32_t> parity(n);
  for (int i = 0; i < n; ++i) parity[i] = i % 2;
  for (const B& b : variants<B>())
    for (int rep = 0; rep < 50; ++rep) REQUIRE(components(b, n, detail::all_active{}, e1, e2) == parity);
}

// Regression: flatten once called uf_find, whose path-halving stores could overwrite parent[x] with
// a non-root ancestor AFTER x's own flatten work item had stored its root.  Long chains (pairs
// (i, i+1) in descending order) showed it in about 40 % of parallel runs on a 2-core machine.
TEST_CASE_TEMPLATE("union-find: after flatten every element points at its root (long chains, 50 runs)", B,
                   EDGEPLANE_TEST_BACKENDS) {
  for (int n : {1 << 12, 1 << 13, 1 << 14}) {
    std::vector<std::int32_t> chain_a, chain_b, star_a, star_b;
    for (int i = n - 2; i >= 0; --i) {
      chain_a.push_back(i);  // descending links build parent chains n-1 -> n-2 -> ... before flatten
      chain_b.push_back(i + 1);
      star_a.push_back(n - 1);
      star_b.push_back(i);
    }
    const std::vector<std::int32_t> zeros(static_cast<std::size_t>(n), 0);
    for (const B& b : variants<B>()) {
      CAPTURE(variant_name(b));
      CAPTURE(n);
      int bad_chain = 0, bad_star = 0;
      for (int rep = 0; rep < 50; ++rep) {
        bad_chain += raw_components(b, n, detail::all_active{}, chain_a, chain_b) != zeros ? 1 : 0;
        bad_star += raw_components(b, n, detail::all_active{}, star_a, star_b) != zeros ? 1 : 0;
      }
      CHECK(bad_chain == 0);
      CHECK(bad_star == 0);
    }
  }
}

TEST_CASE_TEMPLATE("union-find: parallel and serial runs give identical parents", B, EDGEPLANE_TEST_BACKENDS) {
  lcg_noise rng(5);
  const int n = 20000;
  std::vector<std::int32_t> a, c;
  for (int i = 0; i < 3 * n / 4; ++i) {
    a.push_back(static_cast<std::int32_t>(rng.next_u32(n)));
    c.push_back(static_cast<std::int32_t>(rng.next_u32(n)));
  }
  const auto vs = variants<B>();
  const auto first = components(vs.front(), n, detail::all_active{}, a, c);
  for (const B& b : vs) {
    CAPTURE(variant_name(b));
    for (int rep = 0; rep < 5; ++rep) CHECK(components(b, n, detail::all_active{}, a, c) == first);
  }
}

TEST_CASE_TEMPLATE("grid4_adjacency: a wall of inactive pixels splits a grid in two", B, EDGEPLANE_TEST_BACKENDS) {
  const int w = 20, h = 10, wall = 7;
  std::vector<float> depth(static_cast<std::size_t>(w) * h, 1.5f);
  std::vector<std::uint8_t> cov(depth.size(), 1);
  for (int y = 0; y < h; ++y) cov[static_cast<std::size_t>(y) * w + wall] = 0;
  for (const B& b : variants<B>()) {
    CAPTURE(variant_name(b));
    device_array<float, B> z(b, depth);
    device_array<std::uint8_t, B> c(b, cov);
    device_array<std::int32_t, B> parent(b, depth.size(), -7);
    const detail::covered_active active{c.data(), nullptr};
    connected_components(b, w * h, active, w * h, detail::grid4_adjacency<detail::covered_active>{z.cview(w, h), active, 0.06f, 0.f, 0.f},
                         parent.data());
    const auto p = resolved(parent.host());
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        CAPTURE(x);
        CAPTURE(y);
        CHECK(p[static_cast<std::size_t>(y) * w + x] == (x < wall ? 0 : x == wall ? -1 : wall + 1));
      }
  }
}

TEST_CASE_TEMPLATE("grid4_adjacency: a depth step splits; a surface sloping within the slope term does not", B,
                   EDGEPLANE_TEST_BACKENDS) {
  const int w = 16, h = 12;
  // Left: 1.5 m; right: 1.8 m (a 30 cm step at x = 8).  Bottom rows: a ramp of 4 cm per pixel.
  std::vector<float> depth(static_cast<std::size_t>(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      depth[static_cast<std::size_t>(y) * w + x] = y < 6 ? (x < 8 ? 1.5f : 1.8f) : 3.0f + 0.04f * x;
  std::vector<std::uint8_t> cov_a(depth.size(), 1), cov_b(depth.size(), 0);
  for (int x = 0; x < w; ++x) cov_a[static_cast<std::size_t>(5) * w + x] = 0;  // rows 0-5 apart from 6-11
  for (int x = 0; x < w; ++x) {  // row 4 is active through the second mask only
    cov_a[static_cast<std::size_t>(4) * w + x] = 0;
    cov_b[static_cast<std::size_t>(4) * w + x] = 1;
  }
  for (const B& b : variants<B>()) {
    CAPTURE(variant_name(b));
    device_array<float, B> z(b, depth);
    device_array<std::uint8_t, B> ca(b, cov_a), cb(b, cov_b);
    const detail::covered_active active{ca.data(), cb.data()};
    for (float slope_inv_f : {0.f, 10.f / 365.f}) {
      CAPTURE(slope_inv_f);
      device_array<std::int32_t, B> parent(b, depth.size(), -7);
      connected_components(b, w * h, active, w * h,
                           detail::grid4_adjacency<detail::covered_active>{z.cview(w, h), active, 0.03f, 0.f, slope_inv_f}, parent.data());
      const auto p = resolved(parent.host());
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
          CAPTURE(x);
          CAPTURE(y);
          const std::int32_t got = p[static_cast<std::size_t>(y) * w + x];
          if (y == 5)
            CHECK(got == -1);
          else if (y < 5)
            CHECK(got == (x < 8 ? 0 : 8));  // the step is a boundary however the slope term is set
          else if (slope_inv_f > 0)
            CHECK(got == 6 * w);  // 4 cm steps at 3 m are within 3 cm + 10 footprints (8 cm)
          else
            CHECK(got == 6 * w + x);  // 4 cm > 3 cm: each ramp column apart (columns are level)
        }
    }
  }
}

TEST_CASE_TEMPLATE("eroded_failed_active: a narrow bridge between two parts of a failed candidate breaks", B,
                   EDGEPLANE_TEST_BACKENDS) {
  // Candidate 1 (failed): blocks x 1..10 and x 18..28 (y 1..10) joined by a 1-pixel bridge at y = 5.
  // Candidate 2 (not failed): a block at the bottom.  Eroded by r = 1, only the blocks' interiors stay.
  const int w = 30, h = 16;
  std::vector<std::int32_t> cand(static_cast<std::size_t>(w) * h, 0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const bool blocks = y >= 1 && y <= 10 && ((x >= 1 && x <= 10) || (x >= 18 && x <= 28));
      const bool bridge = y == 5 && x > 10 && x < 18;
      cand[static_cast<std::size_t>(y) * w + x] = blocks || bridge ? 1 : (y >= 12 ? 2 : 0);
    }
  const std::vector<std::uint8_t> failed = {0, 1, 0};
  const std::vector<float> depth(cand.size(), 2.f);
  for (const B& b : variants<B>()) {
    CAPTURE(variant_name(b));
    device_array<std::int32_t, B> c(b, cand), parent(b, cand.size(), -7);
    device_array<std::uint8_t, B> f(b, failed);
    device_array<float, B> z(b, depth);
    const detail::eroded_failed_active active{c.cview(w, h), f.data(), 1};
    connected_components(b, w * h, active, w * h,
                         detail::grid4_adjacency<detail::eroded_failed_active>{z.cview(w, h), active, 0.06f, 0.f, 0.f},
                         parent.data());
    const auto p = resolved(parent.host());
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        CAPTURE(x);
        CAPTURE(y);
        const bool in_y = y >= 2 && y <= 9;
        std::int32_t want = -1;
        if (in_y && x >= 2 && x <= 9) want = 2 * w + 2;     // left interior, rooted at (2, 2)
        if (in_y && x >= 19 && x <= 27) want = 2 * w + 19;  // right interior, rooted at (19, 2)
        CHECK(p[static_cast<std::size_t>(y) * w + x] == want);
      }
  }
}

TEST_CASE_TEMPLATE("erode_failed: the separable erosion marks exactly the pixels eroded_failed_active names", B,
                   EDGEPLANE_TEST_BACKENDS) {
  // Random rectangles of 6 candidate ids (ids 1, 3 and 5 failed) with sprinkled noise pixels, so
  // that windows are uniform, cut by other ids, and touch the border.  The widths take the host's
  // column blocks of 8 (157: a partial last block; 700), 16 (1100) and 64 (4200): the blocks
  // narrow until there are 64 of them.
  for (const int w : {157, 700, 1100, 4200}) {
    CAPTURE(w);
    const int h = 41;
    std::vector<std::int32_t> cand(static_cast<std::size_t>(w) * h, 0);
    std::uint64_t state = 12345;
    auto next = [&](int m) {
      state = state * 6364136223846793005ull + 1442695040888963407ull;
      return static_cast<int>((state >> 33) % static_cast<std::uint64_t>(m));
    };
    for (int k = 0; k < 70 * (w / 157 + 1); ++k) {
      const int x0 = next(w), y0 = next(h), x1 = std::min(w, x0 + 3 + next(25)), y1 = std::min(h, y0 + 3 + next(20));
      const int id = next(7);
      for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) cand[static_cast<std::size_t>(y) * w + x] = id;
    }
    // and one large failed block (runs of full windows far longer than the 8 bytes the host
    // finds their ends by), cut by the noise below
    for (int y = 4; y < h - 4; ++y)
      for (int x = 9; x < w - 9; ++x) cand[static_cast<std::size_t>(y) * w + x] = y < h / 2 ? 3 : 5;
    for (int k = 0; k < 110 * (w / 157 + 1); ++k) cand[static_cast<std::size_t>(next(h)) * w + next(w)] = next(7);
    const std::vector<std::uint8_t> failed = {0, 1, 0, 1, 0, 1, 0};
    for (const B& b : variants<B>()) {
      CAPTURE(variant_name(b));
      device_array<std::int32_t, B> c(b, cand);
      device_array<std::uint8_t, B> f(b, failed), mask(b, cand.size(), 0xAA);
      for (int r = 0; r <= 4; ++r) {
        CAPTURE(r);
        erode_failed(b, c.cview(w, h), f.data(), r, mask.view(w, h));
        const auto m = mask.host();
        const detail::eroded_failed_active reference{make_view(static_cast<const std::int32_t*>(cand.data()), w, h),
                                                     failed.data(), r};
        int differ = 0, active = 0;
        for (int i = 0; i < w * h; ++i) {
          const bool want = reference(i), got = (m[static_cast<std::size_t>(i)] & 2) != 0;
          differ += want != got ? 1 : 0;
          active += want ? 1 : 0;
        }
        CHECK(differ == 0);
        CHECK(active > 0);  // not vacuous
        // host backends' row spans: from each row's first failed pixel to its last, and from its
        // first marked pixel to its last (w, 0 where none); the marks the same
        std::vector<std::int32_t> fs(2 * static_cast<std::size_t>(h), -9), es(fs);
        if constexpr (B::host_accessible) {
          erode_failed(b, c.cview(w, h), f.data(), r, mask.view(w, h), fs.data(), es.data());
          CHECK(mask.host() == m);
          int wrong = 0, empty_eroded = 0;
          for (int y = 0; y < h; ++y) {
            int fa = w, fb = 0, ea = w, eb = 0;
            for (int x = 0; x < w; ++x) {
              const std::size_t i = static_cast<std::size_t>(y) * w + x;
              if (failed[static_cast<std::size_t>(cand[i])]) {
                fa = std::min(fa, x);
                fb = x + 1;
              }
              if (reference(static_cast<std::int64_t>(i))) {
                ea = std::min(ea, x);
                eb = x + 1;
              }
            }
            wrong += fs[2 * static_cast<std::size_t>(y)] != fa || fs[2 * static_cast<std::size_t>(y) + 1] != fb;
            wrong += es[2 * static_cast<std::size_t>(y)] != ea || es[2 * static_cast<std::size_t>(y) + 1] != eb;
            empty_eroded += eb == 0;
          }
          CHECK(wrong == 0);
          if (r > 0) CHECK(empty_eroded >= 2 * r);  // the rows whose windows leave the image
          // told where each row's failed pixels lie (exactly, or within wider columns), it looks
          // only there and marks the same
          std::vector<std::int32_t> wider(fs);
          for (int y = 0; y < h; ++y) {
            std::int32_t& a = wider[2 * static_cast<std::size_t>(y)];
            std::int32_t& e = wider[2 * static_cast<std::size_t>(y) + 1];
            if (a >= e) a = e = (y * 37) % (w + 1);  // empty, anywhere
            a = std::max(0, a - (y % 3) * 5);
            e = std::min(w, e + (y % 4) * 3);
          }
          for (const auto* scan : {&fs, &wider}) {
            std::vector<std::int32_t> fs2(fs.size(), -9), es2(fs.size(), -9);
            std::fill(mask.data(), mask.data() + mask.size(), std::uint8_t{0x3c});  // (host memory)
            erode_failed(b, c.cview(w, h), f.data(), r, mask.view(w, h), fs2.data(), es2.data(), scan->data());
            CHECK(mask.host() == m);
            CHECK(fs2 == fs);
            CHECK(es2 == es);
          }
        } else {
          CHECK_THROWS_AS(erode_failed(b, c.cview(w, h), f.data(), r, mask.view(w, h), fs.data(), es.data()),
                          edgeplane::error);
        }
      }
      CHECK_THROWS_AS(erode_failed(b, c.cview(w, h), f.data(), -1, mask.view(w, h)), edgeplane::error);
    }
  }
}

// The segmenter counts each component's elements; host backends count them by the row pass's runs
// (detail::uf_count_runs_kernel), one walk and at most one atomic add per run, and flatten only the
// runs' first elements.  Forests as the union-find leaves them, in rows of width w: each run of
// active elements points to its first element, which is a root or points to an earlier run's first
// element (a chain of any length); inactive runs between; some elements inside runs point to an
// ancestor of their run's first element instead (path halving's stores).  Runs of 1 to 300
// elements, rows of one element, rows without runs.
TEST_CASE("uf_count_runs_kernel counts the components by runs, lists each row's roots, and leaves parent[parent[i]] the root") {
  lcg_noise g(41);
  int checked_roots = 0;
  for (const auto& shape : {std::pair{1, 1}, std::pair{7, 3}, std::pair{64, 20}, std::pair{161, 70}, std::pair{400, 300}}) {
    const int w = shape.first, max_run = shape.second;  // (named copies: clang 14 does not capture structured bindings)
    CAPTURE(w);
    CAPTURE(max_run);
    const int h = 37;
    const std::size_t n = static_cast<std::size_t>(w) * h;
    std::vector<std::int32_t> parent(n, -1), len(n, 0x5a5a5a5a), heads(n, -7), nheads(static_cast<std::size_t>(h), 0);
    std::vector<std::int32_t> all_heads, run_of(n, -1);
    for (int y = 0; y < h; ++y) {
      const std::size_t o = static_cast<std::size_t>(y) * w;
      for (int x = 0; x < w;) {
        const int l = std::min(w - x, 1 + static_cast<int>(g.next_u32(static_cast<std::uint32_t>(max_run))));
        if (y % 11 == 5 || g.uniform01() < 0.25) {  // an inactive run (row 5 and 16, 27: all inactive)
          x += l;
          continue;
        }
        const auto head = static_cast<std::int32_t>(o + x);
        const std::int32_t up = !all_heads.empty() && g.uniform01() < 0.7
                                    ? all_heads[g.next_u32(static_cast<std::uint32_t>(all_heads.size()))]
                                    : head;
        parent[static_cast<std::size_t>(head)] = up;
        for (int j = 1; j < l; ++j) parent[o + x + j] = head;
        for (int j = 0; j < l; ++j) run_of[o + x + j] = head;
        len[static_cast<std::size_t>(head)] = l;
        heads[o + static_cast<std::size_t>(nheads[static_cast<std::size_t>(y)]++)] = head;
        all_heads.push_back(head);
        x += l;
      }
    }
    auto root_of = [&](std::int32_t r) {
      while (parent[static_cast<std::size_t>(r)] != r) r = parent[static_cast<std::size_t>(r)];
      return r;
    };
    std::vector<std::int32_t> flat(n, -1);
    for (std::size_t i = 0; i < n; ++i)
      if (parent[i] >= 0) flat[i] = root_of(parent[i]);
    // elements inside runs that point to an ancestor of their run's first element instead
    for (std::size_t i = 0; i < n; ++i)
      if (parent[i] >= 0 && parent[i] != static_cast<std::int32_t>(i) && run_of[i] != static_cast<std::int32_t>(i) && g.uniform01() < 0.3)
        parent[i] = parent[static_cast<std::size_t>(parent[i])];
    std::vector<std::int32_t> size(n, 0);
    for (std::size_t i = 0; i < n; ++i)
      if (flat[i] >= 0) ++size[static_cast<std::size_t>(flat[i])];
    for (const cpu::mode m : {cpu::mode::serial, cpu::mode::parallel}) {
      std::vector<std::int32_t> p = parent, c = len, hd = heads, nh = nheads;
      cpu{m}.for_each_index(h, detail::uf_count_runs_kernel{p.data(), detail::row_runs{c.data(), hd.data(), nh.data()}, w});
      int wrong_root = 0, wrong_size = 0, wrong_head = 0, roots = 0;
      for (std::size_t i = 0; i < n; ++i) {
        wrong_root += detail::uf_head_root(p.data(), static_cast<std::int64_t>(i)) != flat[i];
        const bool root = flat[i] == static_cast<std::int32_t>(i);
        roots += root;
        wrong_size += root && c[i] != size[i];
        wrong_head += run_of[i] == static_cast<std::int32_t>(i) && p[i] != flat[i];  // first elements flattened
      }
      CHECK(wrong_root == 0);
      CHECK(wrong_size == 0);
      CHECK(wrong_head == 0);
      // each row lists exactly its roots, in order
      for (int y = 0; y < h; ++y) {
        std::vector<std::int32_t> want;
        for (int x = 0; x < w; ++x)
          if (flat[static_cast<std::size_t>(y) * w + x] == static_cast<std::int32_t>(static_cast<std::size_t>(y) * w + x))
            want.push_back(static_cast<std::int32_t>(static_cast<std::size_t>(y) * w + x));
        REQUIRE(nh[static_cast<std::size_t>(y)] == static_cast<std::int32_t>(want.size()));
        CHECK(std::equal(want.begin(), want.end(), hd.begin() + static_cast<std::ptrdiff_t>(y) * w));
      }
      checked_roots += roots;
    }
    REQUIRE(parent != flat);  // chains and halving stores to walk
  }
  CHECK(checked_roots > 200);
}

TEST_CASE_TEMPLATE("grid4_adjacency: components equal a serial union-find on random images", B, EDGEPLANE_TEST_BACKENDS) {
  // Random depth in levels 4 cm apart (one step joins within the 6 cm bound, two do not, so
  // joining is not transitive), random holes, odd sizes, single rows and columns; the serial
  // reference unites every pair the adjacency names.  Widths of whole 16-pixel blocks and tails
  // (the host's lanes of joins), and sparse holes that leave long runs lying on runs (the host
  // skips the vertical pairs already joined through their left neighbours).  With `fresh` < 1 a
  // pixel mostly keeps its left neighbour's level: whole 16-pixel blocks then join into one run,
  // and runs cross blocks, which the host passes take in one step.
  lcg_noise rng(17);
  [[maybe_unused]] int all_roots = 0;  // (the host's counts by runs: not vacuous)
  for (const auto& [w, h] : {std::pair{1, 1}, std::pair{1, 9}, std::pair{13, 1}, std::pair{37, 23}, std::pair{64, 40},
                             std::pair{100, 30}, std::pair{161, 12}}) {
    for (const double holes : {0.0, 0.02, 0.2, 0.6})
    for (const double fresh : {1.0, 0.02}) {
      CAPTURE(w);
      CAPTURE(h);
      CAPTURE(holes);
      CAPTURE(fresh);
      const std::size_t n = static_cast<std::size_t>(w) * h;
      std::vector<float> depth(n);
      std::vector<std::uint8_t> cov(n);
      for (std::size_t i = 0; i < n; ++i) {
        const bool keep = i % static_cast<std::size_t>(w) != 0 && rng.uniform01() >= fresh;
        depth[i] = keep ? depth[i - 1] : 1.f + 0.04f * static_cast<float>(rng.next_u32(4));
        cov[i] = rng.uniform01() < holes ? 0 : 1;
      }
      const detail::covered_active host_active{cov.data(), nullptr};
      const detail::grid4_adjacency<detail::covered_active> host_adj{make_view<const float>(depth.data(), w, h),
                                                                     host_active, 0.06f, 0.f, 0.f};
      reference_uf ref(static_cast<int>(n));
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
          std::int32_t a[4], c[4];
          const int k = host_adj(x, y, a, c);
          for (int j = 0; j < k; ++j) ref.unite(a[j], c[j]);
        }
      std::vector<std::int32_t> want = ref.component_min();
      for (std::size_t i = 0; i < n; ++i)
        if (!cov[i]) want[i] = -1;
      for (const B& b : variants<B>()) {
        CAPTURE(variant_name(b));
        device_array<float, B> z(b, depth);
        device_array<std::uint8_t, B> c(b, cov);
        device_array<std::int32_t, B> parent(b, n, -7);
        const detail::covered_active active{c.data(), nullptr};
        connected_components(b, static_cast<std::int64_t>(n), active, static_cast<std::int64_t>(n),
                             detail::grid4_adjacency<detail::covered_active>{z.cview(w, h), active, 0.06f, 0.f, 0.f},
                             parent.data());
        CHECK(parent.host() == want);  // flattened: every element holds its root
        // The same depth as a rectangle of a larger image (pitch > width, other depths around it,
        // which would join or split differently if read): the same components.
        const int W = w + 7, H = h + 3, ox = 3, oy = 2;
        std::vector<float> big(static_cast<std::size_t>(W) * H);
        for (float& v : big) v = 1.f + 0.04f * static_cast<float>(rng.next_u32(4));
        for (int y = 0; y < h; ++y)
          for (int x = 0; x < w; ++x)
            big[static_cast<std::size_t>(y + oy) * W + x + ox] = depth[static_cast<std::size_t>(y) * w + x];
        device_array<float, B> zb(b, big);
        device_array<std::int32_t, B> parent_r(b, n, -7);
        const image_view<const float> rect{zb.data() + static_cast<std::ptrdiff_t>(oy) * W + ox, w, h, W};
        connected_components(b, static_cast<std::int64_t>(n), active, static_cast<std::int64_t>(n),
                             detail::grid4_adjacency<detail::covered_active>{rect, active, 0.06f, 0.f, 0.f},
                             parent_r.data());
        CHECK(parent_r.host() == want);
        if constexpr (B::host_accessible) {
          // The segmenter's form: the row pass keeps each block's right joins (scratch filled
          // with garbage first) and the vertical unions read them.  The same components, and the
          // kept joins are right_lanes'.
          const int blocks = detail::join_blocks(w);
          std::vector<std::uint16_t> right(static_cast<std::size_t>(blocks) * h, 0xa5a5);
          device_array<std::int32_t, B> parent_k(b, n, -7);
          const detail::grid4_adjacency<detail::covered_active> adj{z.cview(w, h), active, 0.06f, 0.f, 0.f};
          // ... and records its runs (detail::row_runs) in buffers full of garbage: each run's
          // length at its first element (other entries untouched) and each row's first elements in
          // order.  uf_count_runs_kernel then counts the components, and every element's root is
          // parent[parent[i]].
          std::vector<std::int32_t> len(n, 0x5a5a5a5a), heads(n, -7), nheads(static_cast<std::size_t>(h), -7);
          const detail::row_runs runs{len.data(), heads.data(), nheads.data()};
          detail::unite_components(b, static_cast<std::int64_t>(n), active, static_cast<std::int64_t>(n), adj,
                                   parent_k.data(), right.data(), runs);
          std::vector<std::int32_t> want_len(n, 0x5a5a5a5a), want_heads;
          std::vector<std::int32_t> want_nheads(static_cast<std::size_t>(h), 0);
          for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
              const std::size_t i = static_cast<std::size_t>(y) * w + x;
              // a run starts at an active element whose left neighbour does not join it
              if (!cov[i] || (x > 0 && cov[i - 1] && adj.joins_right(x - 1, y))) continue;
              int l = 1;
              while (x + l < w && adj.joins_right(x + l - 1, y)) ++l;
              want_len[i] = l;
              want_heads.push_back(static_cast<std::int32_t>(i));
              ++want_nheads[static_cast<std::size_t>(y)];
            }
          CHECK(len == want_len);
          CHECK(nheads == want_nheads);
          std::vector<std::int32_t> got_heads;
          for (int y = 0; y < h; ++y)
            for (int k = 0; k < nheads[static_cast<std::size_t>(y)]; ++k)
              got_heads.push_back(heads[static_cast<std::size_t>(y) * w + static_cast<std::size_t>(k)]);
          CHECK(got_heads == want_heads);
          b.for_each_index(h, detail::uf_count_runs_kernel{parent_k.data(), runs, w});
          std::vector<std::int32_t> size(n, 0);
          for (std::size_t i = 0; i < n; ++i)
            if (want[i] >= 0) ++size[static_cast<std::size_t>(want[i])];
          int roots = 0, wrong_root = 0, wrong_size = 0;
          for (std::size_t i = 0; i < n; ++i) {
            wrong_root += detail::uf_head_root(parent_k.data(), static_cast<std::int64_t>(i)) != want[i];
            const bool root = want[i] == static_cast<std::int32_t>(i);
            roots += root;
            wrong_size += root && len[i] != size[i];
          }
          all_roots += roots;
          CHECK(wrong_root == 0);
          CHECK(wrong_size == 0);
          int wrong = 0;
          for (int y = 0; y < h; ++y)
            for (int k = 0; k < blocks; ++k)
              wrong += right[static_cast<std::size_t>(y) * blocks + k] != adj.template right_lanes<16>(16 * k, y);
          CHECK(wrong == 0);
        }
      }
    }
  }
  if constexpr (B::host_accessible) CHECK(all_roots > 1000);
}

TEST_CASE_TEMPLATE("erode_failed: on the failed candidates' rectangle it marks what the whole image's erosion marks",
                   B, EDGEPLANE_TEST_BACKENDS) {
  // The segmenter's split rounds erode only the union of the failed candidates' bounding boxes.
  // Failed ids (1 and 3) lie in [x0, x1] x [y0, y1], some touching its sides and corners; the
  // other ids (2, 4, 5) lie anywhere, inside and outside it.
  const int w = 150, h = 50, x0 = 37, y0 = 9, x1 = 121, y1 = 40;
  lcg_noise rng(41);
  std::vector<std::int32_t> cand(static_cast<std::size_t>(w) * h, 0);
  auto paint = [&](int ax, int ay, int bx, int by, std::int32_t id) {
    for (int y = std::max(ay, 0); y <= std::min(by, h - 1); ++y)
      for (int x = std::max(ax, 0); x <= std::min(bx, w - 1); ++x) cand[static_cast<std::size_t>(y) * w + x] = id;
  };
  for (int k = 0; k < 60; ++k) {  // other ids anywhere
    const int ax = static_cast<int>(rng.next_u32(w)), ay = static_cast<int>(rng.next_u32(h));
    paint(ax, ay, ax + 2 + static_cast<int>(rng.next_u32(30)), ay + 2 + static_cast<int>(rng.next_u32(15)),
          static_cast<std::int32_t>(std::array<int, 3>{2, 4, 5}[rng.next_u32(3)]));
  }
  for (int k = 0; k < 40; ++k) {  // failed ids inside the rectangle, clipped to it
    const int ax = x0 + static_cast<int>(rng.next_u32(x1 - x0)), ay = y0 + static_cast<int>(rng.next_u32(y1 - y0));
    const int bx = std::min(x1, ax + 3 + static_cast<int>(rng.next_u32(25)));
    const int by = std::min(y1, ay + 3 + static_cast<int>(rng.next_u32(12)));
    paint(ax, ay, bx, by, rng.next_u32(2) ? 1 : 3);
  }
  paint(x0, y0, x0 + 12, y0 + 8, 1);  // corners of the rectangle
  paint(x1 - 12, y1 - 8, x1, y1, 3);
  const std::vector<std::uint8_t> failed = {0, 1, 0, 1, 0, 0};
  const int rw = x1 - x0 + 1, rh = y1 - y0 + 1;
  for (const B& b : variants<B>()) {
    CAPTURE(variant_name(b));
    device_array<std::int32_t, B> c(b, cand);
    device_array<std::uint8_t, B> f(b, failed), whole(b, cand.size(), 0xAA), part(b, static_cast<std::size_t>(rw) * rh, 0x55);
    for (int r = 1; r <= 4; ++r) {
      CAPTURE(r);
      erode_failed(b, c.cview(w, h), f.data(), r, whole.view(w, h));
      const image_view<const std::int32_t> rect{c.data() + static_cast<std::ptrdiff_t>(y0) * w + x0, rw, rh, w};
      erode_failed(b, rect, f.data(), r, part.view(rw, rh));
      const auto a = whole.host(), p = part.host();
      int differ = 0, marked = 0, outside = 0;
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
          const bool m = (a[static_cast<std::size_t>(y) * w + x] & 2) != 0;
          const bool in = x >= x0 && x <= x1 && y >= y0 && y <= y1;
          if (!in) {
            outside += m ? 1 : 0;
            continue;
          }
          const bool q = (p[static_cast<std::size_t>(y - y0) * rw + x - x0] & 2) != 0;
          differ += m != q ? 1 : 0;
          marked += m ? 1 : 0;
        }
      CHECK(outside == 0);  // the premise: failed pixels only inside
      CHECK(differ == 0);
      CHECK(marked > 100);  // not vacuous
    }
  }
}

TEST_CASE("unite_components: row runs asked of an adjacency without grid joins are refused") {
  // Only the host row pass records runs; an adjacency of explicit pairs has no rows, and the
  // buffers would be left as they were (the counts read from them garbage).
  const std::vector<std::int32_t> first{0, 1, 2}, second{1, 2, 3};
  std::vector<std::int32_t> parent(4, -7), len(4, -7), heads(4, -7), nheads(1, -7);
  const std::vector<std::uint8_t> on(4, 1);
  const detail::pair_list_adjacency adj{first.data(), second.data()};
  CHECK_THROWS_AS(detail::unite_components(cpu{}, 4, mask_active{on.data()}, 3, adj, parent.data(), nullptr,
                                           detail::row_runs{len.data(), heads.data(), nheads.data()}),
                  edgeplane::error);
  detail::unite_components(cpu{}, 4, mask_active{on.data()}, 3, adj, parent.data());  // without runs: fine
  CHECK(resolved(parent) == std::vector<std::int32_t>{0, 0, 0, 0});
}

TEST_CASE("unite_components: rows' column spans give the row passes' results without them") {
  // The segmenter's split rounds pass each row's span of eroded pixels: the row passes then read
  // only from the 16-pixel block of a span's first pixel to its end.  Active pixels lie only in
  // random spans (empty ones too, starting and ending anywhere in a block, at the row's ends);
  // given exactly or widened, the spans change nothing: the components, the right joins kept for
  // the vertical unions, and the runs recorded (lengths, each row's first elements).
  lcg_noise rng(77);
  for (const int w : {13, 16, 17, 37, 100, 161, 300}) {
    CAPTURE(w);
    const int h = 29;
    const std::size_t n = static_cast<std::size_t>(w) * h;
    std::vector<float> depth(n);
    std::vector<std::uint8_t> mask(n, 0);
    std::vector<std::int32_t> exact(2 * static_cast<std::size_t>(h)), wide(exact.size());
    for (int y = 0; y < h; ++y) {
      int a = static_cast<int>(rng.next_u32(static_cast<std::uint32_t>(w))), b = a + static_cast<int>(rng.next_u32(static_cast<std::uint32_t>(w - a + 1)));
      if (y % 7 == 3) b = a;  // no active pixel
      if (y % 5 == 1) a = 0, b = w;
      int fa = w, fb = 0;
      for (int x = 0; x < w; ++x) {
        const std::size_t i = static_cast<std::size_t>(y) * w + x;
        depth[i] = x > 0 && rng.uniform01() < 0.9 ? depth[i - 1] : 1.f + 0.04f * static_cast<float>(rng.next_u32(4));
        mask[i] = x >= a && x < b && rng.uniform01() < 0.9 ? 2 : 0;
        if (mask[i]) fa = std::min(fa, x), fb = x + 1;
      }
      exact[2 * static_cast<std::size_t>(y)] = fa;
      exact[2 * static_cast<std::size_t>(y) + 1] = fb;
      wide[2 * static_cast<std::size_t>(y)] = static_cast<std::int32_t>(rng.next_u32(static_cast<std::uint32_t>(std::min(fa, fb) + 1)));
      wide[2 * static_cast<std::size_t>(y) + 1] = fb + static_cast<std::int32_t>(rng.next_u32(static_cast<std::uint32_t>(w - fb + 1)));
    }
    const detail::mask_bit_active active{mask.data(), 2};
    const detail::grid4_adjacency<detail::mask_bit_active> adj{make_view<const float>(depth.data(), w, h), active, 0.06f,
                                                               0.f, 0.f};
    const int blocks = detail::join_blocks(w);
    // the flattened forest, the right joins, the run lengths and each row's listed first elements
    auto run = [&](const std::int32_t* spans, std::vector<std::int32_t>& parent, std::vector<std::uint16_t>& right,
                   std::vector<std::int32_t>& counts, std::vector<std::int32_t>& listed, cpu::mode m) {
      parent.assign(n, -7);
      right.assign(static_cast<std::size_t>(blocks) * h, 0xa5a5);
      counts.assign(n, 0x5a5a5a5a);
      std::vector<std::int32_t> heads(n, -7), nheads(static_cast<std::size_t>(h), -7);
      detail::unite_components(cpu{m}, static_cast<std::int64_t>(n), active, static_cast<std::int64_t>(n), adj,
                               parent.data(), right.data(), detail::row_runs{counts.data(), heads.data(), nheads.data()},
                               spans);
      cpu{m}.for_each_index(static_cast<std::int64_t>(n), detail::uf_flatten_kernel{parent.data()});
      listed.clear();
      for (int y = 0; y < h; ++y) {
        listed.push_back(nheads[static_cast<std::size_t>(y)]);
        for (int k = 0; k < nheads[static_cast<std::size_t>(y)]; ++k)
          listed.push_back(heads[static_cast<std::size_t>(y) * w + static_cast<std::size_t>(k)]);
      }
    };
    std::vector<std::int32_t> p0, c0, l0, p1, c1, l1;
    std::vector<std::uint16_t> r0, r1;
    run(nullptr, p0, r0, c0, l0, cpu::mode::serial);
    REQUIRE(std::count(p0.begin(), p0.end(), -1) > static_cast<std::ptrdiff_t>(n / 5));  // spans cut the rows
    REQUIRE(l0.size() > static_cast<std::size_t>(h) + 10);                                // runs listed
    for (const auto* spans : {&exact, &wide})
      for (const cpu::mode m : {cpu::mode::serial, cpu::mode::parallel}) {
        run(spans->data(), p1, r1, c1, l1, m);
        CHECK(p1 == p0);
        CHECK(r1 == r0);
        CHECK(c1 == c0);
        CHECK(l1 == l0);
      }
  }
}
