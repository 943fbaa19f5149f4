// XXH3-64 of a chunk's bytes, with the widest vectors the CPU has. Debian's
// libxxhash is built for baseline x86-64 (SSE2): 12.2 GB/s on one core of
// the development machine against 22.4 for the same hash with AVX2 (64 MiB,
// /tmp probe, 2026-12-03). Checking chunks is most of what the decode
// workers do for frames the GPU decodes, so the hash picks its code path at
// run time. Every path gives the same value (XXH3 is defined on bytes).
#include <xxhash.h>

#include "bytes.h"
#include "checksum_paths.h"

namespace sluice::io {
namespace {

using Hash = uint64_t (*)(const void*, size_t);

Hash widest() {
#if defined(__x86_64__) && defined(__GNUC__)
  __builtin_cpu_init();
  if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw")) return detail::xxh3_avx512;
  if (__builtin_cpu_supports("avx2")) return detail::xxh3_avx2;
#endif
  return detail::xxh3_baseline;
}

}  // namespace

uint64_t checksum(std::span<const std::byte> data) {
  static const Hash hash = widest();
  return hash(data.data(), data.size());
}

namespace detail {
uint64_t xxh3_baseline(const void* data, size_t n) { return XXH3_64bits(data, n); }
}  // namespace detail

}  // namespace sluice::io
