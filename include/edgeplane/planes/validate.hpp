// edgeplane: candidate validation and merging (the few small per-plane decisions; host code).
#pragma once
#include <cmath>
#include <cstdint>
#include <numeric>
#include <vector>

#include "edgeplane/detail/geometry.hpp"
#include "edgeplane/params.hpp"
#include "edgeplane/planes/plane_stats.hpp"

namespace edgeplane {

/// A candidate is a plane when it has at least t_size points, PCA eigenvalues l1 >= l2 > l3 (the
/// thesis writes l1 > l2 > l3; a square patch seen head-on has l1 == l2 and is still a plane) with
/// l3/l1 < t_cu and l3/l2 < t_cu, and (when t_residual > 0) a residual
/// sqrt(l3) below t_residual times the sensor noise at its mean depth.
inline bool is_plane(const plane_fit& f, const params& p) {
  if (f.points < p.t_size) return false;
  const double l1 = f.eigenvalues(0), l2 = f.eigenvalues(1), l3 = f.eigenvalues(2);
  if (!(l1 >= l2 && l2 > l3) || !(l2 > 0)) return false;
  if (!(l3 / l1 < p.t_cu && l3 / l2 < p.t_cu)) return false;
  if (p.t_residual > 0) {
    const double z = std::abs(f.centroid.z());
    const double sigma = p.noise.sigma0 + p.noise.sigma2 * z * z;
    if (!(std::sqrt(l3) < p.t_residual * sigma)) return false;
  }
  return true;
}

/// Two planes are merged when parallel (|n1 x n2| < t_par) and coplanar: both normals are
/// perpendicular to the line joining the centroids (|n . u| < t_ps with u that line's direction).
inline bool should_merge(const plane_fit& a, const plane_fit& b, const params& p) {
  if (a.normal.cross(b.normal).norm() >= p.t_par) return false;
  const Eigen::Vector3d u = b.centroid - a.centroid;
  const double len = u.norm();
  if (len <= 0) return true;
  return std::abs(a.normal.dot(u)) / len < p.t_ps && std::abs(b.normal.dot(u)) / len < p.t_ps;
}

/// Merges plane fits: writes, for each input fit, the index of its group into `group` (0-based,
/// numbered in order of their first member; -1 for fits not marked `keep`).  Host union-find over
/// the few candidates; `parent` is scratch.  The vectors keep their capacity across calls.
inline void merge_groups(const std::vector<plane_fit>& fits, const std::vector<char>& keep, const params& p,
                         std::vector<int>& group, std::vector<int>& parent) {
  const int n = static_cast<int>(fits.size());
  parent.resize(static_cast<std::size_t>(n));
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (int i = 0; i < n; ++i) {
    if (!keep[i]) continue;
    for (int j = i + 1; j < n; ++j) {
      if (!keep[j]) continue;
      if (should_merge(fits[i], fits[j], p)) {
        const int a = find(i), b = find(j);
        if (a != b) parent[std::max(a, b)] = std::min(a, b);
      }
    }
  }
  // roots are the smallest member, so numbering roots in index order numbers groups by first member
  group.assign(static_cast<std::size_t>(n), -1);
  int next = 0;
  for (int i = 0; i < n; ++i)
    if (keep[i] && find(i) == i) group[i] = next++;
  for (int i = 0; i < n; ++i)
    if (keep[i]) group[i] = group[find(i)];
}

/// As above, returning the groups.
inline std::vector<int> merge_groups(const std::vector<plane_fit>& fits, const std::vector<char>& keep,
                                     const params& p) {
  std::vector<int> group, parent;
  merge_groups(fits, keep, p, group, parent);
  return group;
}

/// Sums two moment blocks (host).
inline void add_moments(std::uint64_t* into, const std::uint64_t* m) {
  for (int k = 0; k < moment_slots; ++k) into[k] += m[k];
}

}  // namespace edgeplane
