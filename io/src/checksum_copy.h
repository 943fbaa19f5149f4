// The body of copy_and_checksum() for one instruction set: included once by
// each checksum_*.cpp after <xxhash.h> (inlined there, built for that set).
#pragma once

#include <algorithm>

#include "sluice/io/reader.h"

namespace sluice::io::detail {

inline uint64_t copy_and_hash_blocks(std::byte* dst, const std::byte* src, size_t n, BlockCopy copy, void* context) {
  XXH3_state_t state;  // XXH3's own alignment; reset before use
  XXH3_64bits_reset(&state);
  for (size_t at = 0; at < n; at += kChecksumBlock) {
    const size_t length = std::min(kChecksumBlock, n - at);
    copy(dst + at, src + at, length, context);
    XXH3_64bits_update(&state, src + at, length);
  }
  return XXH3_64bits_digest(&state);
}

}  // namespace sluice::io::detail
