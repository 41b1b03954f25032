// edgeplane: non-owning 2-D image views.  Memory is owned by the caller.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <type_traits>

#include "edgeplane/config.hpp"
#include "edgeplane/error.hpp"

namespace edgeplane {

/// A view of a row-major 2-D image.  `pitch` is the distance between rows in ELEMENTS (not bytes).
/// The memory space (host or device) is whatever the call taking the view documents.
template <class T>
struct image_view {
  T* data = nullptr;
  int width = 0;
  int height = 0;
  std::ptrdiff_t pitch = 0;

  EDGEPLANE_HD T& operator()(int x, int y) const { return data[static_cast<std::ptrdiff_t>(y) * pitch + x]; }
  EDGEPLANE_HD bool contains(int x, int y) const { return x >= 0 && y >= 0 && x < width && y < height; }
  EDGEPLANE_HD std::int64_t pixels() const { return static_cast<std::int64_t>(width) * height; }
  EDGEPLANE_HD bool empty() const { return width <= 0 || height <= 0; }
  /// Implicit conversion to a view of const elements (a template, so that it does not exist, and
  /// nvcc does not warn about it, for views that are already const).
  template <class U = T>
    requires(std::is_same_v<U, T> && !std::is_const_v<U>)
  EDGEPLANE_HD operator image_view<const U>() const {
    return {data, width, height, pitch};
  }
};

/// Make a view; pitch defaults to the width (a dense image).
template <class T>
image_view<T> make_view(T* data, int width, int height, std::ptrdiff_t pitch = -1) {
  return image_view<T>{data, width, height, pitch < 0 ? static_cast<std::ptrdiff_t>(width) : pitch};
}

namespace detail {
/// Throws edgeplane::error when a view cannot describe an image: null data with pixels, negative
/// sizes, or a pitch smaller than the width.
template <class T>
void check_view(const image_view<T>& v, const char* name) {
  require(v.width >= 0 && v.height >= 0,
          std::string(name) + ": negative size " + std::to_string(v.width) + "x" + std::to_string(v.height));
  require(v.pitch >= v.width, std::string(name) + ": pitch " + std::to_string(v.pitch) + " is smaller than width " +
                                  std::to_string(v.width));
  require(v.data != nullptr || v.pixels() == 0, std::string(name) + ": null data for a " + std::to_string(v.width) +
                                                    "x" + std::to_string(v.height) + " image");
}
template <class A, class B>
void check_same_size(const image_view<A>& a, const image_view<B>& b, const char* an, const char* bn) {
  require(a.width == b.width && a.height == b.height,
          std::string(an) + " is " + std::to_string(a.width) + "x" + std::to_string(a.height) + " but " + bn + " is " +
              std::to_string(b.width) + "x" + std::to_string(b.height));
}
/// The shifts of a (2r+1)^2 window at row y of an image (host row kernels of the closings): calls
/// f(row, dx, x0, x1) for every dy whose row y + dy lies inside the image (row: its first
/// element) and every dx, with [x0, x1) the x for which x + dx lies inside the row.  Taps outside
/// the image are skipped, as the per-pixel closings skip them.
template <class T, class F>
inline void for_each_window_shift(const image_view<T>& img, int y, int r, F&& f) {
  for (int dy = -r; dy <= r; ++dy) {
    const int v = y + dy;
    if (v < 0 || v >= img.height) continue;
    for (int dx = -r; dx <= r; ++dx) f(&img(0, v), dx, dx < 0 ? -dx : 0, dx > 0 ? img.width - dx : img.width);
  }
}
}  // namespace detail
}  // namespace edgeplane
