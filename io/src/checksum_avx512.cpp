// XXH3-64 inlined into this file, which is built for AVX512 (io/CMakeLists.txt).
#define XXH_INLINE_ALL
#include <xxhash.h>

#include "checksum_copy.h"
#include "checksum_paths.h"

namespace sluice::io::detail {

uint64_t xxh3_avx512(const void* data, size_t n) { return XXH3_64bits(data, n); }

uint64_t xxh3_copy_avx512(std::byte* dst, const std::byte* src, size_t n, BlockCopy copy, void* context) {
  return copy_and_hash_blocks(dst, src, n, copy, context);
}

}  // namespace sluice::io::detail
