// The fuzz_chunk input: 4 bytes that set up the chunk, then its payload.
//   byte 0: attribute count (mod 3); byte 1: codec (mod 3);
//   bytes 2-3: particle count - 1 (little-endian, mod 4096).
// The chunk's checksum is computed from the payload, so the fuzzer reaches
// the plane parsers (zstd, packed, stored) rather than the checksum test.
#pragma once

#include <cstddef>
#include <cstdint>

namespace sluice::fuzz {

struct ChunkSetup {
  size_t attributes = 0;
  uint8_t codec = 0;
  uint32_t particles = 1;
};

inline constexpr size_t kChunkSetupBytes = 4;

inline ChunkSetup chunk_setup(const uint8_t* data) {
  return {size_t(data[0] % 3), uint8_t(data[1] % 3), 1 + uint32_t((data[2] | data[3] << 8) % 4096)};
}

}  // namespace sluice::fuzz
