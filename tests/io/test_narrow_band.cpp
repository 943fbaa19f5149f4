// The narrow band (io/narrow_band.h) on shapes whose surface is known: a box
// and a ball of particles on a lattice of spacing h. The exact reference
// finds exactly the outer shell; the LNM classifier marks every particle of
// it as surface, and leaves the deep inside interior.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "sluice/error.h"
#include "sluice/io/narrow_band.h"

namespace {

using sluice::io::BandLayer;
using sluice::io::NarrowBandOptions;

constexpr float kH = 0.1f;

struct Lattice {
  std::vector<float> xyz;
  std::vector<std::array<int, 3>> cell;  // lattice coordinates
  std::vector<bool> shell;               // a lattice neighbour along an axis is missing
};

// Lattice points (spacing kH) for which `inside` holds.
template <class F>
Lattice lattice(int extent, F inside) {
  Lattice l;
  const auto present = [&](int x, int y, int z) { return inside(x, y, z); };
  for (int x = -extent; x <= extent; ++x)
    for (int y = -extent; y <= extent; ++y)
      for (int z = -extent; z <= extent; ++z) {
        if (!present(x, y, z)) continue;
        l.xyz.insert(l.xyz.end(), {x * kH, y * kH + 3.f, z * kH - 1.f});
        l.cell.push_back({x, y, z});
        const bool all = present(x + 1, y, z) && present(x - 1, y, z) && present(x, y + 1, z) &&
                         present(x, y - 1, z) && present(x, y, z + 1) && present(x, y, z - 1);
        l.shell.push_back(!all);
      }
  return l;
}

Lattice box() {
  return lattice(9, [](int x, int y, int z) { return std::abs(x) <= 8 && std::abs(y) <= 8 && std::abs(z) <= 8; });
}

Lattice ball(int radius = 10) {
  return lattice(radius + 1, [radius](int x, int y, int z) { return x * x + y * y + z * z <= radius * radius; });
}

TEST(NarrowBand, ExactReferenceIsTheOuterShellOfABoxAndABall) {
  for (const Lattice& l : {box(), ball()}) {
    const std::vector<bool> exact = sluice::io::exact_narrow_band(l.xyz, kH, 96);
    ASSERT_EQ(exact.size(), l.shell.size());
    size_t shell = 0;
    for (size_t i = 0; i < exact.size(); ++i) {
      EXPECT_EQ(exact[i], l.shell[i]) << "particle " << l.cell[i][0] << "," << l.cell[i][1] << "," << l.cell[i][2];
      shell += l.shell[i];
    }
    EXPECT_GT(shell, 0u);
    EXPECT_LT(shell, exact.size());
  }
}

// Deeper than an L1 voxel and a selected L2 voxel can reach: a box's faces
// are flat (two voxels, four spacings); on a ball's curve voxels meet the
// outside at their corners, so three voxel diagonals (3 x 2h x sqrt 3 =
// 10.4 spacings) from the surface of a ball of radius 16.
bool deep_in_box(const std::array<int, 3>& c) { return std::max({std::abs(c[0]), std::abs(c[1]), std::abs(c[2])}) <= 4; }
bool deep_in_ball(const std::array<int, 3>& c) { return c[0] * c[0] + c[1] * c[1] + c[2] * c[2] <= 25; }

void expect_shell_covered_and_deep_interior(const Lattice& l, bool (*deep)(const std::array<int, 3>&)) {
  const auto band = sluice::io::classify_narrow_band(l.xyz, NarrowBandOptions{.diameter = kH});
  ASSERT_EQ(band.layer.size(), l.shell.size());
  EXPECT_EQ(band.counts[0] + band.surface(), l.shell.size());
  size_t inner = 0, inner_interior = 0;
  for (size_t i = 0; i < l.shell.size(); ++i) {
    if (l.shell[i]) EXPECT_TRUE(is_surface(band.layer[i])) << "shell particle " << i << " missed";
    if (deep(l.cell[i])) {
      ++inner;
      inner_interior += band.layer[i] == BandLayer::Interior;
    }
  }
  EXPECT_GT(inner, 0u);
  EXPECT_EQ(inner_interior, inner);
  EXPECT_LT(band.surface(), l.shell.size());  // the interior is left out
}

TEST(NarrowBand, ClassifierCoversTheShellAndLeavesTheDeepInsideInterior) {
  expect_shell_covered_and_deep_interior(box(), deep_in_box);
  expect_shell_covered_and_deep_interior(ball(16), deep_in_ball);
}

TEST(NarrowBand, AsymmetryTestStillCoversTheShell) {
  const Lattice l = ball();
  const auto all = sluice::io::classify_narrow_band(l.xyz, NarrowBandOptions{.diameter = kH});
  const auto asym =
      sluice::io::classify_narrow_band(l.xyz, NarrowBandOptions{.diameter = kH, .f2 = sluice::io::F2Test::Asymmetry});
  EXPECT_LE(asym.surface(), all.surface());
  for (size_t i = 0; i < l.shell.size(); ++i) {
    if (l.shell[i]) EXPECT_TRUE(is_surface(asym.layer[i])) << "shell particle " << i << " missed";
  }
}

TEST(NarrowBand, SprayIsSurface) {
  Lattice l = box();
  // A droplet far from the box, and one just outside a face.
  l.xyz.insert(l.xyz.end(), {50.f, 3.f, -1.f, 0.f, 3.f, -1.f + 12 * kH});
  const auto band = sluice::io::classify_narrow_band(l.xyz, NarrowBandOptions{.diameter = kH});
  const size_t n = band.layer.size();
  EXPECT_EQ(band.layer[n - 2], BandLayer::Isolated);
  EXPECT_EQ(band.layer[n - 1], BandLayer::Isolated);
}

// The dense grid (L1 and L2 by bit operations over its cells, layers in
// particle order) and the hashed one (voxel by voxel) give the same answer.
// A droplet beyond the pool's highest corner leaves the grid's origin, and
// so every voxel, where it was; far away, it makes the box too large for a
// cell array, and the voxels are hashed.
TEST(NarrowBand, DenseAndHashedGridsGiveTheSameBand) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> jitter(-0.3f, 0.3f), spray(0.f, 30.f);
  std::vector<float> pool;
  for (int x = 0; x < 24; ++x)
    for (int y = 0; y < 20; ++y)
      for (int z = 0; z < 16; ++z) {
        if (x > 12 && y > 10) continue;  // a step, so that L1 meets the outside on inner edges too
        pool.insert(pool.end(), {(x + jitter(rng)) * kH, (y + jitter(rng)) * kH, (z + jitter(rng)) * kH});
      }
  for (int k = 0; k < 200; ++k) pool.insert(pool.end(), {spray(rng) * kH, (22.f + spray(rng) / 3) * kH, spray(rng) * kH});
  // Stray coordinates: their cells come from the box's lowest cell either way.
  pool.insert(pool.end(), {NAN, 0.5f, 0.5f, 0.5f, -INFINITY, 0.5f, 0.5f, 0.5f, NAN});
  const auto with_droplet_at = [&](float spacings) {
    std::vector<float> xyz = pool;
    xyz.insert(xyz.end(), {spacings * kH, spacings * kH, spacings * kH});
    return xyz;
  };
  const std::vector<float> near = with_droplet_at(40.f), far = with_droplet_at(5000.f);
  for (const float voxel : {2 * kH, 1.5f * kH}) {
    for (const auto f2 : {sluice::io::F2Test::All, sluice::io::F2Test::Asymmetry}) {
      const NarrowBandOptions o{.diameter = kH, .voxel = voxel, .f2 = f2, .blobs = true};
      const auto dense = sluice::io::classify_narrow_band(near, o), hashed = sluice::io::classify_narrow_band(far, o);
      EXPECT_GT(dense.counts[1], 0u);
      EXPECT_GT(dense.counts[2], 0u);
      EXPECT_GT(dense.counts[3], 20u);  // spray and the droplet
      EXPECT_EQ(dense.layer, hashed.layer);
      EXPECT_EQ(dense.counts, hashed.counts);
      EXPECT_EQ(dense.voxels, hashed.voxels);
      EXPECT_EQ(dense.l1_voxels, hashed.l1_voxels);
      EXPECT_EQ(dense.l2_voxels, hashed.l2_voxels);
      EXPECT_EQ(dense.blob_of, hashed.blob_of);
      ASSERT_EQ(dense.blobs.size(), hashed.blobs.size());
      for (size_t b = 0; b < dense.blobs.size(); ++b) {
        EXPECT_EQ(dense.blobs[b].centroid, hashed.blobs[b].centroid);
        EXPECT_EQ(dense.blobs[b].count, hashed.blobs[b].count);
      }
    }
  }
}

TEST(NarrowBand, VoxelLayersCountFromTheOutside) {
  const Lattice l = box();  // 17 particles a side: voxels of 2h hold 2 along an axis
  const std::vector<uint8_t> layers = sluice::io::voxel_layers(l.xyz, 2 * kH);
  uint8_t deepest = 0;
  for (size_t i = 0; i < layers.size(); ++i) {
    EXPECT_GE(layers[i], 1);
    deepest = std::max(deepest, layers[i]);
    const auto& c = l.cell[i];
    if (std::max({std::abs(c[0]), std::abs(c[1]), std::abs(c[2])}) == 8) EXPECT_EQ(layers[i], 1);
  }
  EXPECT_GE(deepest, 4);
}

TEST(NarrowBand, RejectsANonPositiveDiameter) {
  const std::vector<float> xyz = {0, 0, 0};
  EXPECT_THROW(sluice::io::classify_narrow_band(xyz, NarrowBandOptions{}), sluice::io::Error);
}

}  // namespace
