// Chunk checksums: every code path (baseline, AVX2, AVX-512) gives the same
// XXH3-64 as the others and as checksum(), on lengths around each of XXH3's
// internal boundaries (16, 128, 240 bytes, stripes, blocks of 1 KiB) and on
// large, unaligned spans.
#include <gtest/gtest.h>

#include <cstddef>
#include <random>
#include <vector>

#include "bytes.h"
#include "checksum_paths.h"

namespace sluice {
namespace {

TEST(Checksum, EveryCodePathGivesTheSameHash) {
  std::mt19937_64 rng(7);
  std::vector<std::byte> data((1 << 20) + 64);
  for (auto& b : data) b = std::byte(rng());
  const bool avx2 = __builtin_cpu_supports("avx2");
  const bool avx512 = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw");
  if (!avx2) std::printf("this CPU has no AVX2: that path is not checked\n");
  if (!avx512) std::printf("this CPU has no AVX-512: that path is not checked\n");
  for (size_t n : {0, 1, 3, 4, 8, 9, 16, 17, 128, 129, 240, 241, 1023, 1024, 1025, 4096, 65537, 1 << 20}) {
    for (size_t offset : {0, 1, 13}) {
      const std::byte* p = data.data() + offset;
      const uint64_t expected = io::detail::xxh3_baseline(p, n);
      EXPECT_EQ(io::checksum({p, n}), expected) << n << " bytes at offset " << offset;
      if (avx2) EXPECT_EQ(io::detail::xxh3_avx2(p, n), expected) << n << " bytes at offset " << offset;
      if (avx512) EXPECT_EQ(io::detail::xxh3_avx512(p, n), expected) << n << " bytes at offset " << offset;
    }
  }
  EXPECT_EQ(io::detail::xxh3_baseline(nullptr, 0), 0x2d06800538d394c2u) << "XXH3-64 of nothing, as the spec gives it";
}

}  // namespace
}  // namespace sluice
