// The fuzz_chunk input: 4 bytes that set up the chunk, then its payload.
//   byte 0: attribute count (mod 3);
//   byte 1: codec (mod 3, of bits 0-1); bits 2-3: the fine part's codec
//           (mod 3); bit 6: the fine part left out (coarse); bit 7: positions
//           split (format 3.0): 2 more setup bytes follow, and the
//           payload's tail is the record's fine part;
//   bytes 2-3: particle count - 1 (little-endian, mod 4096);
//   split only, bytes 4-5: the fine part's size (little-endian, at most
//           the payload's).
// The chunk's checksum is computed from the payload, so the fuzzer reaches
// the plane parsers (zstd, packed, stored) rather than the checksum test.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>

namespace sluice::fuzz {

struct ChunkSetup {
  size_t attributes = 0;
  uint8_t codec = 0;
  uint32_t particles = 1;
  bool split = false, coarse = false;
  uint8_t fine_codec = 0;
  uint32_t fine_bytes = 0;
  size_t bytes = 4;  // setup bytes before the payload
};

inline constexpr size_t kChunkSetupBytes = 4;

inline constexpr uint8_t kSplitSetup = 0x80, kCoarseSetup = 0x40;

// `size` >= kChunkSetupBytes.
inline ChunkSetup chunk_setup(const uint8_t* data, size_t size) {
  ChunkSetup s{size_t(data[0] % 3), uint8_t((data[1] & 3) % 3), 1 + uint32_t((data[2] | data[3] << 8) % 4096)};
  if ((data[1] & kSplitSetup) != 0 && size >= kChunkSetupBytes + 2) {
    s.split = true;
    s.coarse = (data[1] & kCoarseSetup) != 0;
    s.fine_codec = uint8_t(((data[1] >> 2) & 3) % 3);
    s.bytes = kChunkSetupBytes + 2;
    s.fine_bytes = std::min<uint32_t>(uint32_t(data[4] | data[5] << 8), uint32_t(size - s.bytes));
  }
  return s;
}

}  // namespace sluice::fuzz
