// What the peer segmenters used by the comparisons share (pcl_peer.hpp, cape_peer.hpp): the plane
// each reports, and the parsing of the environment variable that overrides a peer's settings.
#pragma once
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

namespace edgeplane_peer {

struct peer_plane {
  std::uint16_t id;  // its value in the label image
  double n[3];       // unit normal, n . X + d = 0 with d >= 0 (camera frame, metres)
  double d;
};

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
