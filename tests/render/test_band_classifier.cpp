// The GPU narrow-band classifier (render/band_classifier.h) against the CPU
// one (io/narrow_band.h), particle by particle: on lattice shapes, on a
// jittered pool with spray and stray coordinates, on the synthetic sloshing
// pool, and on the bundled PySPH frames. Same layer for every particle, the
// same counts, the same voxels, and the same blobs (the same particles in
// each, centroids within float rounding); no validation error.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <vector>

#include "render_test_util.h"
#include "sluice/error.h"
#include "sluice/bench/synth.h"
#include "sluice/import/source.h"
#include "sluice/io/narrow_band.h"
#include "sluice/io/point_set.h"
#include "sluice/render/band_classifier.h"

namespace sluice::render {
namespace {

using testing::ValidationGuard;
using testing::band_classifier;

// Every particle's layer, the counts and the voxels equal; blobs: each GPU
// blob holds exactly the particles of one CPU blob, at the same centroid.
void expect_same_band(std::span<const float> xyz, const io::NarrowBandOptions& o, const char* what) {
  const io::NarrowBand cpu = io::classify_narrow_band(xyz, o);
  const io::NarrowBand gpu = band_classifier().classify(xyz, o);
  std::printf("%s: %zu particles, voxels %s\n", what, cpu.layer.size(), band_classifier().last_hashed() ? "hashed" : "by cell");
  ASSERT_EQ(gpu.layer.size(), cpu.layer.size()) << what;
  size_t differ = 0, first = 0;
  for (size_t i = 0; i < cpu.layer.size(); ++i) {
    if (gpu.layer[i] != cpu.layer[i] && differ++ == 0) first = i;
  }
  EXPECT_EQ(differ, 0u) << what << ": particles classified differently; first " << first << " (cpu "
                        << int(cpu.layer[first]) << ", gpu " << int(gpu.layer[first]) << ")";
  EXPECT_EQ(gpu.counts, cpu.counts) << what;
  EXPECT_EQ(gpu.voxels, cpu.voxels) << what;
  EXPECT_EQ(gpu.l1_voxels, cpu.l1_voxels) << what;
  EXPECT_EQ(gpu.l2_voxels, cpu.l2_voxels) << what;
  EXPECT_EQ(gpu.voxel, cpu.voxel) << what;
  if (!o.blobs) return;
  ASSERT_EQ(gpu.blobs.size(), cpu.blobs.size()) << what;
  ASSERT_EQ(gpu.blob_of.size(), cpu.blob_of.size()) << what;
  std::map<uint32_t, uint32_t> cpu_of_gpu;  // blob correspondence, from their particles
  size_t mismatched = 0;
  for (size_t i = 0; i < cpu.blob_of.size(); ++i) {
    const uint32_t c = cpu.blob_of[i], g = gpu.blob_of[i];
    if ((c == io::NarrowBand::kNoBlob) != (g == io::NarrowBand::kNoBlob)) {
      ++mismatched;
      continue;
    }
    if (c == io::NarrowBand::kNoBlob) continue;
    ASSERT_LT(g, gpu.blobs.size()) << what;
    const auto [it, added] = cpu_of_gpu.emplace(g, c);
    mismatched += it->second != c;
  }
  EXPECT_EQ(mismatched, 0u) << what << ": particles in different blobs";
  EXPECT_EQ(cpu_of_gpu.size(), gpu.blobs.size()) << what << ": every GPU blob holds particles";
  for (const auto& [g, c] : cpu_of_gpu) {
    const io::VoxelBlob &a = gpu.blobs[g], &b = cpu.blobs[c];
    EXPECT_EQ(a.count, b.count) << what << ": blob " << g;
    for (size_t k = 0; k < 3; ++k) {
      // A sum of `count` floats: a few ulps of the coordinates per particle.
      const float tolerance = 4e-7f * float(a.count) * std::max(1.0f, std::abs(b.centroid[k]));
      EXPECT_NEAR(a.centroid[k], b.centroid[k], tolerance) << what << ": blob " << g;
    }
  }
}

std::vector<float> lattice_box(int side, float h) {
  std::vector<float> xyz;
  for (int x = 0; x < side; ++x)
    for (int y = 0; y < side; ++y)
      for (int z = 0; z < side; ++z) xyz.insert(xyz.end(), {float(x) * h + 0.3f, float(y) * h - 2.f, float(z) * h + 5.f});
  return xyz;
}

std::vector<float> lattice_ball(int radius, float h) {
  std::vector<float> xyz;
  for (int x = -radius; x <= radius; ++x)
    for (int y = -radius; y <= radius; ++y)
      for (int z = -radius; z <= radius; ++z) {
        if (x * x + y * y + z * z <= radius * radius) xyz.insert(xyz.end(), {float(x) * h, float(y) * h, float(z) * h});
      }
  return xyz;
}

// A jittered pool, a column standing in it, droplets above, and particles
// with coordinates no solver should write (NaN, infinity).
std::vector<float> jittered_pool_with_spray(float h, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> jitter(-0.3f * h, 0.3f * h), anywhere(0.f, 1.f);
  std::vector<float> xyz;
  const auto add = [&](float x, float y, float z) { xyz.insert(xyz.end(), {x + jitter(rng), y + jitter(rng), z + jitter(rng)}); };
  for (int x = 0; x < 60; ++x)
    for (int y = 0; y < 40; ++y)
      for (int z = 0; z < 20; ++z) add(float(x) * h, float(y) * h, float(z) * h);
  for (int x = 0; x < 10; ++x)
    for (int y = 0; y < 10; ++y)
      for (int z = 20; z < 48; ++z) add(float(x + 40) * h, float(y + 5) * h, float(z) * h);
  for (int k = 0; k < 400; ++k) xyz.insert(xyz.end(), {60 * h * anywhere(rng), 40 * h * anywhere(rng), (22 + 40 * anywhere(rng)) * h});
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  xyz.insert(xyz.end(), {nan, 0.1f, 0.1f, 0.2f, inf, 0.2f, 0.3f, 0.3f, -inf});
  return xyz;
}

TEST(BandClassifierGpu, SameLayersAsTheCpuOnALatticeBoxAndBall) {
  ValidationGuard guard;
  const float h = 0.1f;
  for (const bool blobs : {false, true}) {
    expect_same_band(lattice_box(17, h), {.diameter = h, .blobs = blobs}, "box");
    expect_same_band(lattice_ball(10, h), {.diameter = h, .blobs = blobs}, "ball");
    expect_same_band(lattice_ball(10, h), {.diameter = h, .voxel = 3 * h, .blobs = blobs}, "ball, voxel 3h");
  }
}

TEST(BandClassifierGpu, SameLayersAsTheCpuWithJitterSprayAndStrayCoordinates) {
  ValidationGuard guard;
  const float h = 0.02f;
  for (const uint32_t seed : {1u, 2u, 3u}) {
    const std::vector<float> xyz = jittered_pool_with_spray(h, seed);
    const io::NarrowBand cpu = io::classify_narrow_band(xyz, {.diameter = h});
    ASSERT_GT(cpu.counts[size_t(io::BandLayer::Isolated)], 100u) << "the droplets are isolated";
    ASSERT_GT(cpu.counts[size_t(io::BandLayer::Interior)], xyz.size() / 3 / 4) << "the pool has an inside";
    expect_same_band(xyz, {.diameter = h, .blobs = true}, "pool with spray");
    expect_same_band(xyz, {.diameter = h, .voxel = 1.5f * h, .blobs = true}, "pool with spray, voxel 1.5h");
  }
}

// Droplets far from the pool: the grid has more cells than the table has
// slots, so voxels are placed by hashing their keys (the other tests' grids
// are compact: a voxel's slot is its cell).
TEST(BandClassifierGpu, SameLayersAsTheCpuWhenVoxelsAreHashed) {
  ValidationGuard guard;
  const float h = 0.02f;
  std::vector<float> xyz = jittered_pool_with_spray(h, 4);
  for (int k = 0; k < 20; ++k) xyz.insert(xyz.end(), {(300.f + 7.f * float(k)) * h, -250.f * h + float(k) * h, (260.f - 3.f * float(k)) * h});
  (void)band_classifier().classify(xyz, {.diameter = h});
  EXPECT_TRUE(band_classifier().last_hashed());
  expect_same_band(xyz, {.diameter = h, .blobs = true}, "pool with far droplets");
  (void)band_classifier().classify(lattice_box(17, 0.1f), {.diameter = 0.1f});
  EXPECT_FALSE(band_classifier().last_hashed());
}

TEST(BandClassifierGpu, SameLayersAsTheCpuOnTheSyntheticPool) {
  ValidationGuard guard;
  bench::SynthOptions so;
  so.particles = 300'000;
  so.frames = 30;
  const auto source = bench::synthetic_source(so);
  for (const uint64_t f : {0u, 17u}) {
    const io::ParticleFrame frame = source->read(f);
    expect_same_band(frame.positions, {.diameter = so.spacing, .blobs = true}, "synthetic pool");
  }
}

TEST(BandClassifierGpu, SameLayersAsTheCpuOnTheBundledSample) {
#if !SLUICE_WITH_VTK
  GTEST_SKIP() << "needs the VTK importer to read the sample";
#endif
  ValidationGuard guard;
  const auto source = import::open_source(std::string(SLUICE_SAMPLE_DIR) + "/*.vtu", {});
  for (const uint64_t f : {0u, 6u, 12u}) {
    const io::ParticleFrame frame = source->read(f);
    const float h = io::estimate_spacing(frame.positions);
    expect_same_band(frame.positions, {.diameter = h, .blobs = true}, "bundled sample");
  }
}

TEST(BandClassifierGpu, RefusesWhatItCannotDoAndSaysSo) {
  ValidationGuard guard;
  // Two particles a kilometre apart at a millimetre spacing: 2^20 cells per
  // axis, beyond 32-bit keys. The CPU classifier manages; the GPU refuses.
  const std::vector<float> far = {0, 0, 0, 1000, 1000, 1000};
  EXPECT_EQ(io::classify_narrow_band(far, {.diameter = 0.001f}).surface(), 2u);
  EXPECT_THROW((void)band_classifier().classify(far, {.diameter = 0.001f}), std::runtime_error);
  EXPECT_THROW((void)band_classifier().classify(far, {.diameter = 0}), sluice::render::Error);
  EXPECT_THROW((void)band_classifier().classify(far, {.diameter = 1, .f2 = io::F2Test::Asymmetry}), sluice::render::Error);
  // And it still works afterwards.
  expect_same_band(lattice_box(6, 0.1f), {.diameter = 0.1f}, "box after a refusal");
  EXPECT_TRUE(band_classifier().classify({}, {.diameter = 1}).layer.empty());
}

}  // namespace
}  // namespace sluice::render
