// edgeplane tests: comparing two labelings up to renumbering.  Which root wins a union, or which
// candidate is numbered first, must never decide a test: two labelings are equal when one becomes
// the other by a one-to-one renaming of its non-zero labels (0, "no label", maps to 0 only).
#pragma once
#include <cstddef>
#include <cstdint>
#include <map>
#include <vector>

namespace edgeplane_test {

/// The canonical form of a labeling: 0 stays 0; the other labels become 1, 2, ... in raster order
/// of their first pixel.  Two labelings are equal up to renumbering iff their canonical forms are.
template <class T>
std::vector<std::int64_t> canonical_labels(const std::vector<T>& labels) {
  std::map<std::int64_t, std::int64_t> id;
  std::vector<std::int64_t> out(labels.size());
  for (std::size_t i = 0; i < labels.size(); ++i) {
    const auto l = static_cast<std::int64_t>(labels[i]);
    if (l == 0) {
      out[i] = 0;
      continue;
    }
    auto it = id.find(l);
    if (it == id.end()) it = id.emplace(l, static_cast<std::int64_t>(id.size()) + 1).first;
    out[i] = it->second;
  }
  return out;
}

/// How two labelings of the same image correspond.
struct label_correspondence {
  bool equal = false;                         ///< same size and equal up to renumbering
  std::size_t conflicts = 0;                  ///< pixels that break a one-to-one renaming (0 when equal)
  std::map<std::int64_t, std::int64_t> a_to_b;  ///< each label of a -> the label of b it first met
};

/// Matches the labels of `a` with those of `b` (pixel by pixel, first meeting wins) and counts
/// the pixels that contradict a one-to-one renaming with 0 -> 0.
template <class A, class B>
label_correspondence correspond(const std::vector<A>& a, const std::vector<B>& b) {
  label_correspondence r;
  if (a.size() != b.size()) {
    r.conflicts = a.size() > b.size() ? a.size() : b.size();
    return r;
  }
  std::map<std::int64_t, std::int64_t> b_to_a;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const auto la = static_cast<std::int64_t>(a[i]), lb = static_cast<std::int64_t>(b[i]);
    if ((la == 0) != (lb == 0)) {
      ++r.conflicts;
      continue;
    }
    if (la == 0) continue;
    const auto fa = r.a_to_b.emplace(la, lb).first;
    const auto fb = b_to_a.emplace(lb, la).first;
    if (fa->second != lb || fb->second != la) ++r.conflicts;
  }
  r.equal = r.conflicts == 0;
  return r;
}

/// True when `a` and `b` are the same labeling up to renumbering.
template <class A, class B>
bool labels_equal(const std::vector<A>& a, const std::vector<B>& b) {
  return correspond(a, b).equal;
}

}  // namespace edgeplane_test
