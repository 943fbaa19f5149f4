// Internal: a chunk payload's plane table (codecs Zstd and Packed; Stored
// chunks have none), read once for the CPU decoder (codec.cpp) and the GPU
// decoder's plans (gpu_decode_plan.cpp).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "sluice/error.h"
#include "sluice/io/format.h"

namespace sluice::io {

// One plane of a chunk's payload, in file order: where its bytes start (as
// a position in whatever `payload_at` counts from), how many, and how they
// are coded.
struct PlaneSource {
  uint64_t at = 0;
  uint32_t size = 0;
  enum Kind : uint8_t { Stored, Packed, Zstd } kind = Stored;
};

// Reads a chunk's plane table (codecs Zstd and Packed) or lays out its
// concatenated planes (Stored) into `out` (`planes` planes of `n` values),
// checking every size against the payload. Throws io::Error at `where`.
void read_plane_table(std::span<const std::byte> payload, uint64_t payload_at, ChunkCodec codec, uint64_t n,
                      size_t planes, std::vector<PlaneSource>& out, const ErrorLocation& where);

}  // namespace sluice::io
