// XXH3-64 of a chunk's bytes, with the widest vectors the CPU has. Debian's
// libxxhash is built for baseline x86-64 (SSE2): 12.2 GB/s on one core of
// the development machine against 22.4 for the same hash with AVX2 (64 MiB,
// /tmp probe, 2026-12-03). Checking chunks is most of what the decode
// workers do for frames the GPU decodes, so the hash picks its code path at
// run time. Every path gives the same value (XXH3 is defined on bytes).
#define XXH_STATIC_LINKING_ONLY  // XXH3_state_t's definition, for the streaming state on the stack
#include <xxhash.h>

#include "bytes.h"
#include "checksum_copy.h"
#include "checksum_paths.h"

namespace sluice::io {
namespace {

struct Paths {
  uint64_t (*hash)(const void*, size_t);
  uint64_t (*copy)(std::byte*, const std::byte*, size_t, BlockCopy, void*);
};

Paths widest() {
#if defined(__x86_64__) && defined(__GNUC__)
  __builtin_cpu_init();
  if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw")) {
    return {detail::xxh3_avx512, detail::xxh3_copy_avx512};
  }
  if (__builtin_cpu_supports("avx2")) return {detail::xxh3_avx2, detail::xxh3_copy_avx2};
#endif
  return {detail::xxh3_baseline, detail::xxh3_copy_baseline};
}

const Paths& paths() {
  static const Paths chosen = widest();
  return chosen;
}

}  // namespace

uint64_t checksum(std::span<const std::byte> data) { return paths().hash(data.data(), data.size()); }

uint64_t chunk_checksum(std::span<const std::byte> payload) { return checksum(payload); }

uint64_t copy_and_checksum(std::byte* dst, const std::byte* src, size_t n, BlockCopy copy, void* context) {
  return paths().copy(dst, src, n, copy, context);
}

namespace detail {
uint64_t xxh3_baseline(const void* data, size_t n) { return XXH3_64bits(data, n); }
uint64_t xxh3_copy_baseline(std::byte* dst, const std::byte* src, size_t n, BlockCopy copy, void* context) {
  return copy_and_hash_blocks(dst, src, n, copy, context);
}
}  // namespace detail

}  // namespace sluice::io
