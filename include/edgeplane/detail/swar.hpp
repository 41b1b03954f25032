// edgeplane: the bytes of a 64-bit word (SIMD within a register): the host edge pass compares its
// 8 neighbour-count planes 8 bytes at a time, with plain integer loads that every target,
// including nvcc's host and device passes, compiles.
#pragma once
#include <cstdint>
#include <cstring>

#include "edgeplane/config.hpp"

namespace edgeplane::detail::swar {

inline constexpr std::uint64_t ones8 = 0x0101010101010101ull;

EDGEPLANE_HD EDGEPLANE_INLINE std::uint64_t load(const void* p) {
  std::uint64_t v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

}  // namespace edgeplane::detail::swar
