// What the peer segmenters used by the comparisons share (pcl_peer.hpp, cape_peer.hpp): the plane
// each reports (in the camera frame, unit normal, d >= 0), and the parsing of the environment
// variable that overrides a peer's settings.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

namespace edgeplane_peer {

struct peer_plane {
  std::uint16_t id;  // its value in the label image
  double n[3];       // unit normal, n . X + d = 0 with d >= 0 (camera frame, metres)
  double d;
};

/// Appends plane `id` with the equation nx X + ny Y + nz Z + d = 0 (d in metres) scaled to a
/// unit normal with d >= 0; a zero (or NaN) normal is left out.
inline void push_plane(std::vector<peer_plane>& planes, std::uint16_t id, double nx, double ny, double nz,
                       double d) {
  const double len = std::sqrt(nx * nx + ny * ny + nz * nz);
  if (!(len > 0)) return;
  double s = 1.0 / len;
  if (d * s < 0) s = -s;
  planes.push_back({id, {nx * s, ny * s, nz * s}, d * s});
}

/// Calls set(key, value) for each "key=value" of the comma-separated list in environment variable
/// `name` (values read with atof; entries without '=' are ignored).
template <class Set>
void for_each_setting(const char* name, Set&& set) {
  const char* env = std::getenv(name);
  const std::string s = env ? env : "";
  std::size_t pos = 0;
  while (pos < s.size()) {
    const std::size_t end = std::min(s.find(',', pos), s.size()), eq = s.find('=', pos);
    if (eq < end) set(s.substr(pos, eq - pos), std::atof(s.substr(eq + 1, end - eq - 1).c_str()));
    pos = end + 1;
  }
}

}  // namespace edgeplane_peer
