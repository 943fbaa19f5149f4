// Chunk checksums: every code path (baseline, AVX2, AVX-512) gives the same
// XXH3-64 as the others and as checksum(), on lengths around each of XXH3's
// internal boundaries (16, 128, 240 bytes, stripes, blocks of 1 KiB) and on
// large, unaligned spans; and hashing while copying gives that hash and
// the bytes, whatever the blocks.
#include <gtest/gtest.h>

#include <cstddef>
#include <cstring>
#include <random>
#include <vector>

#include "sluice/io/reader.h"

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

// The blocks a copy was asked for: each at most kChecksumBlock, in order,
// covering the span once.
struct CopyLog {
  const std::byte* src = nullptr;
  size_t next = 0;
  bool in_order = true;
};

void logged_copy(std::byte* dst, const std::byte* src, size_t n, void* context) {
  auto& log = *static_cast<CopyLog*>(context);
  log.in_order = log.in_order && src == log.src + log.next && n > 0 && n <= io::kChecksumBlock;
  log.next += n;
  std::memcpy(dst, src, n);
}

TEST(Checksum, HashingWhileCopyingGivesTheHashAndTheBytes) {
  std::mt19937_64 rng(11);
  std::vector<std::byte> data((1 << 20) + 64);
  for (auto& b : data) b = std::byte(rng());
  using CopyPath = uint64_t (*)(std::byte*, const std::byte*, size_t, io::BlockCopy, void*);
  std::vector<std::pair<const char*, CopyPath>> paths = {{"baseline", io::detail::xxh3_copy_baseline}};
  if (__builtin_cpu_supports("avx2")) paths.emplace_back("avx2", io::detail::xxh3_copy_avx2);
  if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw")) paths.emplace_back("avx512", io::detail::xxh3_copy_avx512);
  const size_t block = io::kChecksumBlock;
  for (size_t n : {size_t(0), size_t(1), size_t(240), size_t(241), block - 1, block, block + 1, 3 * block + 7, size_t(1) << 20}) {
    for (size_t offset : {0, 5}) {
      const std::byte* src = data.data() + offset;
      const uint64_t expected = io::chunk_checksum({src, n});
      for (const auto& [name, path] : paths) {
        std::vector<std::byte> dst(n + 1, std::byte{0x5a});
        CopyLog log{src};
        EXPECT_EQ(path(dst.data(), src, n, logged_copy, &log), expected) << name << ", " << n << " bytes at offset " << offset;
        EXPECT_TRUE(log.in_order && log.next == n) << name << ", " << n << " bytes";
        EXPECT_TRUE(std::equal(src, src + n, dst.begin())) << name << ", " << n << " bytes";
        EXPECT_EQ(dst[n], std::byte{0x5a}) << name << ": wrote past the end";
      }
      CopyLog log{src};
      std::vector<std::byte> dst(n);
      EXPECT_EQ(io::copy_and_checksum(dst.data(), src, n, logged_copy, &log), expected);
    }
  }
}

}  // namespace
}  // namespace sluice
