// Codec-level checks: Morton codes, chunk planning, quantization bounds.
#include <gtest/gtest.h>

#include <random>

#include "chunking.h"
#include "morton.h"
#include "sluice/io/codec.h"
#include "sluice/io/lod.h"

using namespace sluice::io;

TEST(Morton, RoundTripsRandomTriples) {
  std::mt19937 rng(7);
  for (int i = 0; i < 100000; ++i) {
    const uint32_t x = rng() & 0x1fffff, y = rng() & 0x1fffff, z = rng() & 0x1fffff;
    uint32_t a, b, c;
    morton_decode(morton_encode(x, y, z), a, b, c);
    ASSERT_EQ(std::tie(a, b, c), std::tie(x, y, z));
  }
}

TEST(Morton, OrdersByOctreeCell) {
  // Every point of the lower octant (all coordinates < 2^15) precedes every
  // point with x >= 2^15, whatever y and z.
  EXPECT_LT(morton_encode(0x7fff, 0x7fff, 0x7fff), morton_encode(0x8000, 0, 0));
}

TEST(ChunkPlan, CoversEveryParticleOnceWithinTheLimit) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  std::vector<float> xyz(3 * 50000);
  for (float& v : xyz) v = u(rng);
  Aabb bounds;
  for (size_t i = 0; i < xyz.size(); i += 3) bounds.extend(xyz[i], xyz[i + 1], xyz[i + 2]);
  const ChunkPlan plan = plan_chunks(xyz, bounds, 1000);
  std::vector<int> seen(50000, 0);
  uint32_t expected_begin = 0;
  for (const auto& r : plan.chunks) {
    EXPECT_EQ(r.begin, expected_begin);
    EXPECT_GT(r.end, r.begin);
    EXPECT_LE(r.end - r.begin, 1000u);
    expected_begin = r.end;
  }
  EXPECT_EQ(expected_begin, 50000u);
  for (uint32_t i : plan.order) ++seen[i];
  for (int s : seen) ASSERT_EQ(s, 1);
  // Octree-aligned chunks stay compact: uniform points in a 2-unit cube with
  // <=1000 per chunk need boxes far smaller than the cube.
  double mean_volume = 0;
  for (const auto& r : plan.chunks) {
    Aabb b;
    for (uint32_t k = r.begin; k < r.end; ++k) {
      const uint32_t p = plan.order[k];
      b.extend(xyz[3 * p], xyz[3 * p + 1], xyz[3 * p + 2]);
    }
    mean_volume += double(b.max[0] - b.min[0]) * (b.max[1] - b.min[1]) * (b.max[2] - b.min[2]);
  }
  mean_volume /= double(plan.chunks.size());
  EXPECT_LT(mean_volume, 8.0 * 2000 / 50000);  // at most twice the volume 1000 points occupy
}

TEST(ChunkPlan, IdenticalPointsAreSplitEvenly) {
  std::vector<float> xyz(3 * 2500, 0.5f);
  Aabb bounds;
  bounds.extend(0.5f, 0.5f, 0.5f);
  const ChunkPlan plan = plan_chunks(xyz, bounds, 1000);
  ASSERT_EQ(plan.chunks.size(), 3u);
  EXPECT_EQ(plan.chunks[2].end - plan.chunks[2].begin, 500u);
}

TEST(Lod, ValuesAreStableAndUniform) {
  EXPECT_EQ(lod_value_from_id(42), lod_value_from_id(42));
  // Chi-square over 16 bins of 160k consecutive ids (as solvers number them).
  std::array<double, 16> bins{};
  const int n = 160000;
  for (int i = 0; i < n; ++i) bins[lod_value_from_id(uint64_t(i)) >> 12] += 1;
  double chi2 = 0;
  for (double b : bins) chi2 += (b - n / 16.0) * (b - n / 16.0) / (n / 16.0);
  EXPECT_LT(chi2, 37.7);  // p = 0.001 for 15 degrees of freedom
}

TEST(Dequantize, EndpointsAreExact) {
  EXPECT_EQ(dequantize(0, -2.5f, 7.f), -2.5f);
  EXPECT_NEAR(dequantize(65535, -2.5f, 7.f), 7.f, 1e-6f);
}

#include "sluice/io/point_set.h"

TEST(Spacing, LatticeSpacingIsFound) {
  std::vector<float> xyz;
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 20; ++j)
      for (int k = 0; k < 20; ++k) xyz.insert(xyz.end(), {i * 0.04f, j * 0.04f + 1.f, k * 0.04f});
  EXPECT_NEAR(estimate_spacing(xyz), 0.04f, 1e-5f);
  EXPECT_EQ(estimate_spacing(std::vector<float>{1, 2, 3}), 0.f);
}

// A few particles flung far away (spray, or a byte changed in a damaged
// file) do not size the grid: the lattice's spacing is still found. Before,
// one particle at 1e30 put every particle into one cell (0.5 s for 56k
// particles, quadratic in the frame size).
TEST(Spacing, FarOutliersDoNotChangeIt) {
  std::vector<float> xyz;
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 20; ++j)
      for (int k = 0; k < 20; ++k) xyz.insert(xyz.end(), {i * 0.04f, j * 0.04f + 1.f, k * 0.04f});
  xyz.insert(xyz.end(), {1e30f, 0.f, 0.f, -3e38f, 5.f, 1e20f});
  EXPECT_NEAR(estimate_spacing(xyz), 0.04f, 1e-5f);
}

TEST(Morton, TableDecodeMatchesBitDecode) {
  std::mt19937_64 rng(5);
  for (int i = 0; i < 100000; ++i) {
    const uint64_t code = rng();
    uint32_t x, y, z;
    morton_decode(code & ((uint64_t{1} << 48) - 1), x, y, z);
    ASSERT_EQ(morton_to_packed16(code), uint64_t(x) | uint64_t(y) << 16 | uint64_t(z) << 32);
  }
}
