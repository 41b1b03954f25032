// edgeplane: bytes and 16-bit lanes of a 64-bit word (SIMD within a register), for the host row
// kernels of the closings.  Compilers leave byte-array loops of a window scalar (a load and an OR
// per byte); these do 8 bytes or 4 labels per operation, with plain integer arithmetic that every
// target, including nvcc's host and device passes, compiles.  No operation carries from one lane
// into the next, so the results do not depend on the byte order.
#pragma once
#include <cstdint>
#include <cstring>

#include "edgeplane/config.hpp"

namespace edgeplane::detail::swar {

inline constexpr std::uint64_t low7 = 0x7f7f7f7f7f7f7f7full, ones8 = 0x0101010101010101ull;
inline constexpr std::uint64_t low15 = 0x7fff7fff7fff7fffull, high16 = 0x8000800080008000ull;

EDGEPLANE_HD EDGEPLANE_INLINE std::uint64_t load(const void* p) {
  std::uint64_t v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
EDGEPLANE_HD EDGEPLANE_INLINE void store(void* p, std::uint64_t v) { std::memcpy(p, &v, sizeof v); }

/// 1 in each byte of v that is nonzero, 0 in the others.  (b & 0x7f) + 0x7f sets bit 7 when the
/// low seven bits are not all zero, and stays below 0x100, so it never carries out of its byte.
EDGEPLANE_HD EDGEPLANE_INLINE std::uint64_t nonzero_bytes(std::uint64_t v) {
  return ((((v & low7) + low7) | v) >> 7) & ones8;
}
/// 0xffff in each 16-bit lane of v that is nonzero, 0 in the others (the same trick per lane).
EDGEPLANE_HD EDGEPLANE_INLINE std::uint64_t nonzero_lanes16(std::uint64_t v) {
  const std::uint64_t bit = ((((v & low15) + low15) | v) & high16) >> 15;  // 1 per nonzero lane
  return bit * 0xffffull;  // each 1 becomes 0xffff within its lane: the lanes' products do not overlap
}

}  // namespace edgeplane::detail::swar
