// The decode kernels: the x86 ones against the portable ones on the same
// bytes, bit-packed planes against their input, and bad packed planes.
#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <vector>

#include "dequantize.h"
#include "packed_plane.h"
#include "quantized_unpack.h"
#include "sluice/io/codec.h"
#include "sluice/error.h"

using namespace sluice::io;

namespace {

// n values with a geometric-like distribution (Morton delta high bytes):
// mostly small, a long tail up to 255.
std::vector<uint8_t> skewed_plane(size_t n, double p_zero, uint32_t seed) {
  std::mt19937 rng(seed);
  std::geometric_distribution<int> g(p_zero);
  std::vector<uint8_t> v(n);
  for (auto& x : v) x = uint8_t(std::min(255, g(rng)));
  return v;
}

std::vector<uint8_t> unpack(const std::vector<std::byte>& packed, size_t n, bool portable) {
  std::vector<uint8_t> out(n, 0xAA);
  if (portable) unpack_plane_portable(packed, n, out.data(), {}, "plane");
  else unpack_plane(packed, n, out.data(), {}, "plane");
  return out;
}

}  // namespace

TEST(QuantizedUnpack, EveryKernelMatchesPortableAtEveryLengthAndAlignment) {
  const UnpackKernel kernels[] = {UnpackKernel::Avx2Table, UnpackKernel::Avx2Pext};
  if (!unpack_kernel_runs_here(UnpackKernel::Avx2Pext)) GTEST_SKIP() << "this CPU has no AVX2 + BMI2";
  std::mt19937 rng(7);
  for (size_t n : {size_t(1), size_t(7), size_t(31), size_t(32), size_t(33), size_t(100), size_t(16383),
                   size_t(16384), size_t(20001)}) {
    std::vector<std::vector<uint8_t>> planes(8, std::vector<uint8_t>(n));
    for (int k = 0; k < 8; ++k) {
      // Small deltas in the high bytes (as in real files), noise in the rest.
      for (auto& b : planes[size_t(k)]) b = uint8_t(k == 4 || k == 5 ? rng() % 3 : rng());
    }
    const uint8_t* ptrs[8];
    for (int k = 0; k < 8; ++k) ptrs[k] = planes[size_t(k)].data();
    for (size_t offset : {0, 8, 16, 24, 3}) {  // 3: no 32-byte boundary on an 8-byte grid
      std::vector<std::byte> expected(8 * n + 32);
      unpack_quantized16_with(UnpackKernel::Portable, ptrs, n, expected.data() + offset);
      for (UnpackKernel kernel : kernels) {
        std::vector<std::byte> got(8 * n + 32);
        unpack_quantized16_with(kernel, ptrs, n, got.data() + offset);
        ASSERT_EQ(0, std::memcmp(got.data() + offset, expected.data() + offset, 8 * n))
            << "kernel " << int(kernel) << " n=" << n << " offset=" << offset;
      }
      std::vector<std::byte> chosen(8 * n + 32);
      unpack_quantized16(ptrs, n, chosen.data() + offset);
      ASSERT_EQ(0, std::memcmp(chosen.data() + offset, expected.data() + offset, 8 * n));
    }
  }
}

TEST(QuantizedUnpack, DecodesKnownCodes) {
  // Two particles: code 0b111 (x=y=z=1), then code 0b111 + 0b1000 (x=3... ) via deltas.
  const uint8_t d0[2] = {0x07, 0x08}, zero[2] = {0, 0}, lod_lo[2] = {0x34, 0x78}, lod_hi[2] = {0x12, 0x56};
  const uint8_t* planes[8] = {d0, zero, zero, zero, zero, zero, lod_lo, lod_hi};
  uint64_t out[2];
  unpack_quantized16(planes, 2, reinterpret_cast<std::byte*>(out));
  // code 7: x=1,y=1,z=1. code 15: x bit1 = code bit 3 -> x=3, y=1, z=1.
  EXPECT_EQ(out[0], 1ull | 1ull << 16 | 1ull << 32 | 0x1234ull << 48);
  EXPECT_EQ(out[1], 3ull | 1ull << 16 | 1ull << 32 | 0x5678ull << 48);
}

TEST(PackedPlane, RoundTripsEveryWidthAndLength) {
  for (size_t n : {size_t(1), size_t(2), size_t(7), size_t(8), size_t(9), size_t(63), size_t(64), size_t(65),
                   size_t(1000), size_t(65536)}) {
    for (double p : {0.99, 0.6, 0.3, 0.05}) {
      const auto plane = skewed_plane(n, p, uint32_t(n));
      for (int width = 1; width <= kMaxPackedWidth; ++width) {
        std::vector<std::byte> packed;
        pack_plane(plane, width, packed);
        ASSERT_EQ(unpack(packed, n, false), plane) << "n=" << n << " width=" << width;
        ASSERT_EQ(unpack(packed, n, true), plane) << "n=" << n << " width=" << width;
      }
    }
  }
}

TEST(PackedPlane, PlanPicksTheSmallestWidthAndStatesItsSize) {
  const auto plane = skewed_plane(65536, 0.57, 3);
  const PackedPlan plan = plan_packed_plane(plane);
  for (int width = 1; width <= kMaxPackedWidth; ++width) {
    std::vector<std::byte> packed;
    pack_plane(plane, width, packed);
    if (width == plan.width) EXPECT_EQ(packed.size(), plan.bytes);
    EXPECT_GE(packed.size(), plan.bytes) << "width " << width << " is smaller than the plan's";
  }
  EXPECT_LT(plan.bytes, plane.size() / 2);  // such a plane packs to under half
}

TEST(PackedPlane, BadPlanesAreErrorsNotCrashes) {
  const auto plane = skewed_plane(1000, 0.5, 9);
  std::vector<std::byte> good;
  pack_plane(plane, 2, good);
  std::vector<uint8_t> out(1000);
  auto fails = [&](std::vector<std::byte> bytes, const char* expected) {
    for (bool portable : {false, true}) {
      try {
        if (portable) unpack_plane_portable(bytes, 1000, out.data(), {"f.sluice", 3, 7}, "plane 4");
        else unpack_plane(bytes, 1000, out.data(), {"f.sluice", 3, 7}, "plane 4");
        ADD_FAILURE() << "accepted a bad plane (" << expected << ")";
      } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("chunk 7"), std::string::npos) << e.what();
      }
    }
  };
  fails({}, "empty");
  auto bad_width = good;
  bad_width[0] = std::byte(0);
  fails(bad_width, "width 0");
  bad_width[0] = std::byte(8);
  fails(bad_width, "width 8");
  fails(std::vector<std::byte>(good.begin(), good.begin() + 100), "shorter than its values");
  fails(std::vector<std::byte>(good.begin(), good.end() - 1), "escape");  // one escape byte missing
  auto extra = good;
  extra.push_back(std::byte(9));
  fails(extra, "escape");  // one escape byte too many
}

TEST(PackedPlane, FramesDecodeTheSameWithAndWithoutPacking) {
  // Uniform random particles: Morton deltas of ~2^32, whose byte 4 is small
  // (packed) and bytes 0-3 noise (stored).
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  const size_t n = 100000;
  std::vector<float> positions(3 * n);
  for (auto& p : positions) p = u(rng);
  std::vector<uint16_t> lod(n);
  for (auto& l : lod) l = uint16_t(rng());
  FileHeader header;
  header.position_coding = PositionCoding::Quantized16;
  FrameInput in;
  in.positions = positions;
  in.lod = lod;
  EncodeOptions packed_options, zstd_options;
  zstd_options.planes = PlaneCoding::Zstd;
  const EncodedFrame packed = encode_frame(in, header, packed_options);
  const EncodedFrame zstd = encode_frame(in, header, zstd_options);
  size_t packed_chunks = 0;
  for (const ChunkDesc& c : packed.header.chunks) packed_chunks += c.codec == ChunkCodec::Packed;
  EXPECT_GT(packed_chunks, 0u);
  for (const ChunkDesc& c : zstd.header.chunks) EXPECT_NE(c.codec, ChunkCodec::Packed);
  ASSERT_EQ(packed.header.chunks.size(), zstd.header.chunks.size());
  DecodeScratch scratch;
  for (size_t c = 0; c < packed.header.chunks.size(); ++c) {
    const size_t count = packed.header.chunks[c].particle_count;
    std::vector<std::byte> a(8 * count), b(8 * count);
    decode_chunk(packed.record, packed.header.chunks[c], header, {a, {}}, scratch, {});
    decode_chunk(zstd.record, zstd.header.chunks[c], header, {b, {}}, scratch, {});
    ASSERT_EQ(a, b) << "chunk " << c;
  }
}

namespace {

// 16-byte aligned float and uint16 arrays, filled with a marker.
struct Destination {
  std::vector<float> xyz_store;
  std::vector<uint16_t> lod_store;
  float* xyz;
  uint16_t* lod;
  explicit Destination(size_t n) : xyz_store(3 * n + 8, -7.0f), lod_store(n + 8, 0xBEEF) {
    xyz = xyz_store.data() + (16 - reinterpret_cast<uintptr_t>(xyz_store.data()) % 16) % 16 / sizeof(float);
    lod = lod_store.data() + (16 - reinterpret_cast<uintptr_t>(lod_store.data()) % 16) % 16 / sizeof(uint16_t);
  }
};

}  // namespace

// The streaming kernels write what the plain loop writes, bit for bit, from
// every start a caller may give (a multiple of four) and at every length.
TEST(Dequantize, EveryStreamingKernelMatchesThePlainLoop) {
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> word(0, 65535);
  const ChunkScale scale{{-1.5f, 0.25f, 3.0f}, {1.0f / 65535, 2.5f / 65535, 0.01f / 65535}};
  size_t kernels = 0;
  for (const StreamingKernel kernel : {StreamingKernel::Sse2, StreamingKernel::Avx2}) {
    if (!streaming_kernel_runs_here(kernel)) continue;
    ++kernels;
    for (size_t n = 0; n < 70; ++n) {
      for (size_t start = 0; start <= 8 && start <= n; start += 4) {
        std::vector<uint16_t> q(4 * n);
        for (auto& v : q) v = uint16_t(word(rng));
        Destination want(n), got(n);
        dequantize_plain(q.data(), 0, n, scale, want.xyz, want.lod);
        dequantize_plain(q.data(), 0, start, scale, got.xyz, got.lod);
        const size_t done = dequantize_streaming(kernel, q.data(), start, n, scale, got.xyz, got.lod);
        ASSERT_LE(done, n);
        EXPECT_LT(n - done, 4u) << "whole groups left undone";
        dequantize_plain(q.data(), done, n, scale, got.xyz, got.lod);
        ASSERT_EQ(0, std::memcmp(got.xyz, want.xyz, 3 * n * sizeof(float))) << "n " << n << " start " << start;
        ASSERT_EQ(0, std::memcmp(got.lod, want.lod, n * sizeof(uint16_t))) << "n " << n << " start " << start;
        EXPECT_EQ(got.xyz[3 * n], -7.0f) << "wrote past the end";
        EXPECT_EQ(got.lod[n], 0xBEEF) << "wrote past the end";
      }
    }
  }
#if defined(__x86_64__)
  EXPECT_GE(kernels, 1u) << "SSE2 runs on every x86-64";
#endif
}
