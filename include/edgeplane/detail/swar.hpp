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

inline constexpr std::uint64_t high8 = 0x8080808080808080ull;  // the top bit of every byte

/// Bit i set where the top bit of byte i of f is (the other bits of f are ignored): three folds
/// (shifts and ors, no multiply) gather the 8 flags into the low byte.
EDGEPLANE_HD EDGEPLANE_INLINE unsigned gather_high_bits(std::uint64_t f) {
  f = (f & high8) >> 7;  // flag i at bit 8 i
  f |= f >> 7;           // flags 2j, 2j + 1 at bits 16 j, 16 j + 1
  f |= f >> 14;          // flags 4j .. 4j + 3 at bits 32 j .. 32 j + 3
  f |= f >> 28;          // all 8 at bits 0 .. 7
  return static_cast<unsigned>(f & 0xffu);
}

/// The comparison of 8 bytes with a threshold t, made once: at_least(t)(x) has the top bit of
/// byte i set where byte i of x (every byte at most 127) is at least t, the other bits 0.  Bytes
/// or-ed with 0x80 less t (clamped to 0..128) cannot borrow from their neighbours, and keep their
/// top bit exactly where they were >= t.  t <= 0: every byte; t > 127: none.
struct at_least {
  std::uint64_t t8;  // t, clamped, in every byte
  EDGEPLANE_HD explicit at_least(int t) : t8(ones8 * static_cast<std::uint64_t>(t < 0 ? 0 : t > 128 ? 128 : t)) {}
  EDGEPLANE_HD EDGEPLANE_INLINE std::uint64_t operator()(std::uint64_t x) const { return ((x | high8) - t8) & high8; }
};

/// Bit i set where byte i of x (every byte at most 127) is at least t (at_least, gathered).
/// t <= 0: every bit; t > 127: none.
EDGEPLANE_HD EDGEPLANE_INLINE unsigned bytes_at_least(std::uint64_t x, int t) {
  return gather_high_bits(at_least(t)(x));
}

/// Bit i set where byte i of x is not 0 (any value): the low 7 bits plus 0x7f carry into the top
/// bit exactly when one of them is set, without reaching the next byte; gathered as above.
EDGEPLANE_HD EDGEPLANE_INLINE unsigned nonzero_bytes(std::uint64_t x) {
  constexpr std::uint64_t low7 = 0x7f7f7f7f7f7f7f7full;
  return gather_high_bits(((x & low7) + low7) | x);
}

}  // namespace edgeplane::detail::swar
