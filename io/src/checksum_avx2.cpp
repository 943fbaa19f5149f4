// XXH3-64 inlined into this file, which is built for AVX2 (io/CMakeLists.txt).
#define XXH_INLINE_ALL
#include <xxhash.h>

#include "checksum_paths.h"

namespace sluice::io::detail {

uint64_t xxh3_avx2(const void* data, size_t n) { return XXH3_64bits(data, n); }

}  // namespace sluice::io::detail
