// Bit-packed byte planes with escapes (chunk codec 2, docs/format.md): a
// plane of small values (the high bytes of Morton deltas) stored at `width`
// bits per value, values too large for the width escaped to a byte list.
// Unpacking runs at memory speed (PDEP on x86), several times faster than
// zstd's entropy decoder on the same plane, at some cost in size.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "sluice/error.h"

namespace sluice::io {

inline constexpr int kMaxPackedWidth = 7;

// A chunk's plane table entry with this bit set is a packed plane of the
// remaining size (codec Packed; codec.cpp has the table's layout).
inline constexpr uint32_t kPackedPlaneFlag = 0x80000000u;

// The width (1..7) that packs `plane` smallest, and that size in bytes.
struct PackedPlan {
  int width = 0;
  size_t bytes = 0;
};
PackedPlan plan_packed_plane(std::span<const uint8_t> plane);

// Appends the packed form of `plane` at `width` bits (plan.bytes bytes).
void pack_plane(std::span<const uint8_t> plane, int width, std::vector<std::byte>& out);

// Unpacks one packed plane of n values into dst[0..n). Checks the width, the
// size and the escape count against `payload`; throws io::Error at `where`
// (prefixed with `what`) if they disagree. Never reads outside `payload` or
// writes outside dst[0..n).
void unpack_plane(std::span<const std::byte> payload, size_t n, uint8_t* dst, const ErrorLocation& where,
                  const std::string& what);

// unpack_plane without the x86 kernels, for tests that compare kernels.
void unpack_plane_portable(std::span<const std::byte> payload, size_t n, uint8_t* dst, const ErrorLocation& where,
                           const std::string& what);

}  // namespace sluice::io
