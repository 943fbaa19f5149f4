// Morton (Z-order) codes: interleave the bits of three coordinates.
#pragma once

#include <cstdint>

namespace sluice::io {

// Spreads the low 21 bits of v so that bit i lands on bit 3i.
constexpr uint64_t spread_bits_by_3(uint64_t v) {
  v &= 0x1fffff;
  v = (v | v << 32) & 0x1f00000000ffffull;
  v = (v | v << 16) & 0x1f0000ff0000ffull;
  v = (v | v << 8) & 0x100f00f00f00f00full;
  v = (v | v << 4) & 0x10c30c30c30c30c3ull;
  v = (v | v << 2) & 0x1249249249249249ull;
  return v;
}

// Inverse of spread_bits_by_3: gathers bits 0, 3, 6, ... into the low bits.
constexpr uint64_t compact_bits_by_3(uint64_t v) {
  v &= 0x1249249249249249ull;
  v = (v ^ (v >> 2)) & 0x10c30c30c30c30c3ull;
  v = (v ^ (v >> 4)) & 0x100f00f00f00f00full;
  v = (v ^ (v >> 8)) & 0x1f0000ff0000ffull;
  v = (v ^ (v >> 16)) & 0x1f00000000ffffull;
  v = (v ^ (v >> 32)) & 0x1fffffull;
  return v;
}

// x in bits 0,3,..; y in 1,4,..; z in 2,5,.. (up to 21 bits per axis).
constexpr uint64_t morton_encode(uint32_t x, uint32_t y, uint32_t z) {
  return spread_bits_by_3(x) | spread_bits_by_3(y) << 1 | spread_bits_by_3(z) << 2;
}

inline void morton_decode(uint64_t code, uint32_t& x, uint32_t& y, uint32_t& z) {
  x = static_cast<uint32_t>(compact_bits_by_3(code));
  y = static_cast<uint32_t>(compact_bits_by_3(code >> 1));
  z = static_cast<uint32_t>(compact_bits_by_3(code >> 2));
}

}  // namespace sluice::io

static_assert(sluice::io::morton_encode(1, 0, 0) == 1);
static_assert(sluice::io::morton_encode(0, 1, 0) == 2);
static_assert(sluice::io::morton_encode(0, 0, 1) == 4);
static_assert(sluice::io::morton_encode(0x1fffff, 0x1fffff, 0x1fffff) == 0x7fffffffffffffffull);
