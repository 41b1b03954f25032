// edgeplane: plane equations given to the angle metrics, and the angle between two planes'
// normals.  Host only, no I/O.
#pragma once
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <numbers>
#include <span>
#include <string>
#include <vector>

#include "edgeplane/error.hpp"

namespace edgeplane::metrics {

/// The plane of one label: n . X + d = 0 with X in the camera frame, in metres.  The normal need
/// not be unit length, and its sign is free: (n, d) and (-n, -d) are the same plane.
struct plane_equation {
  std::uint16_t id = 0;            ///< the label (segment id or GT id) this plane belongs to, non-zero
  std::array<double, 3> normal{};  ///< n, finite and non-zero
  double d = 0;                    ///< offset, metres
};

/// Angle between the normals of two planes, in degrees in [0, 90]: the sign of a normal does not
/// matter.  Computed as atan2(|n1 x n2|, |n1 . n2|), which stays accurate for small angles (acos
/// of a cosine near 1 does not).
inline double normal_angle_deg(const plane_equation& a, const plane_equation& b) {
  const std::array<double, 3>& p = a.normal;
  const std::array<double, 3>& q = b.normal;
  const double dot = p[0] * q[0] + p[1] * q[1] + p[2] * q[2];
  const double cx = p[1] * q[2] - p[2] * q[1], cy = p[2] * q[0] - p[0] * q[2], cz = p[0] * q[1] - p[1] * q[0];
  return std::atan2(std::sqrt(cx * cx + cy * cy + cz * cz), std::fabs(dot)) * (180.0 / std::numbers::pi);
}

namespace detail {
/// Plane equations by label id.  Throws edgeplane::error on id 0, a repeated id, or a normal that
/// is zero or not finite.
class plane_lookup {
 public:
  plane_lookup(std::span<const plane_equation> planes, const char* name) : planes_(planes) {
    if (planes.empty()) return;
    index_.assign(65536, -1);
    for (std::size_t k = 0; k < planes.size(); ++k) {
      const plane_equation& p = planes[k];
      const std::string what = std::string(name) + ": plane equation of id " + std::to_string(p.id);
      edgeplane::detail::require(p.id != 0, std::string(name) + ": plane equation with id 0 (0 is 'no plane')");
      edgeplane::detail::require(index_[p.id] < 0, what + " given twice");
      const double n2 = p.normal[0] * p.normal[0] + p.normal[1] * p.normal[1] + p.normal[2] * p.normal[2];
      edgeplane::detail::require(std::isfinite(n2) && n2 > 0 && std::isfinite(p.d),
                                 what + " has a zero or non-finite normal or offset");
      index_[p.id] = static_cast<int>(k);
    }
  }
  /// The plane of `id`, or nullptr when none was given.
  const plane_equation* find(std::uint16_t id) const {
    if (index_.empty() || index_[id] < 0) return nullptr;
    return &planes_[static_cast<std::size_t>(index_[id])];
  }

 private:
  std::span<const plane_equation> planes_;
  std::vector<int> index_;
};

/// Running mean of angles between matched pairs whose two plane equations are both known.
struct angle_mean {
  double sum_deg = 0;
  int pairs = 0;
  void add(const plane_lookup& pred, std::uint16_t segment, const plane_lookup& gt, std::uint16_t gt_id) {
    const plane_equation* a = pred.find(segment);
    const plane_equation* b = gt.find(gt_id);
    if (a == nullptr || b == nullptr) return;
    sum_deg += normal_angle_deg(*a, *b);
    ++pairs;
  }
  double mean() const { return pairs > 0 ? sum_deg / pairs : std::numeric_limits<double>::quiet_NaN(); }
};
}  // namespace detail

}  // namespace edgeplane::metrics
