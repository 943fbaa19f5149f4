// Far particles in a real frame (the bundled PySPH dam break, its sixth file): 1,
// 5 or 50 particles moved to 1e3, 1e6, 1e30, -1e6 or a mix. Every other
// particle must decode within the file's stated bound (plus two float32
// ulps), the far ones too, and the frame's display bounds must frame the
// fluid, not the outliers.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <tuple>

#include "../io/test_util.h"
#include "sluice/import/frames.h"
#include "sluice/import/source.h"
#include "sluice/io/maintenance.h"
#include "sluice/io/point_set.h"
#include "sluice/io/reader.h"

namespace test = sluice::test;
namespace io = sluice::io;
using namespace sluice::io;
using namespace sluice::import;

namespace {

const std::string kFrame = std::string(SLUICE_SAMPLE_DIR) + "/dam_break_3d_fluid_00250.vtu";
constexpr float kSpacing = 0.04f;

float ulp(float v) {
  const float a = std::fabs(v);
  return std::nextafter(a, INFINITY) - a;
}

// Every source particle has a decoded particle within `bound` (+ 2 ulps) on
// each axis, found on a hash grid of cell `kSpacing`; returns the worst miss
// ratio (error / allowed), > 1 when one is out of bound.
double worst_error_ratio(const std::vector<float>& source, const std::vector<float>& decoded, float bound) {
  using Key = std::tuple<int64_t, int64_t, int64_t>;
  const auto key = [](const float* p, int dx, int dy, int dz) {
    const auto cell = [](float v) { return int64_t(std::floor(std::clamp(double(v) / kSpacing, -1e15, 1e15))); };
    return Key{cell(p[0]) + dx, cell(p[1]) + dy, cell(p[2]) + dz};
  };
  std::map<Key, std::vector<size_t>> grid;
  for (size_t i = 0; i < decoded.size() / 3; ++i) grid[key(&decoded[3 * i], 0, 0, 0)].push_back(i);
  double worst = 0;
  for (size_t i = 0; i < source.size() / 3; ++i) {
    const float* p = &source[3 * i];
    double best = INFINITY;
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it = grid.find(key(p, dx, dy, dz));
          if (it == grid.end()) continue;
          for (size_t j : it->second) {
            double ratio = 0;
            for (int a = 0; a < 3; ++a) {
              const double allowed = double(bound) + 2.0 * double(ulp(p[a]));
              ratio = std::max(ratio, std::fabs(double(decoded[3 * j + a]) - double(p[a])) / allowed);
            }
            best = std::min(best, ratio);
          }
        }
    worst = std::max(worst, best);
  }
  return worst;
}

class FarParticlesInARealFrame : public ::testing::TestWithParam<std::tuple<int, float>> {
 protected:
  void SetUp() override {
#ifndef SLUICE_WITH_VTK
    FAIL() << "built without VTK: the sample is .vtu";
#endif
    ASSERT_TRUE(std::filesystem::exists(kFrame)) << kFrame << " is missing (data/ is part of the repository)";
    frame = open_source(kFrame, {})->read(0);
  }
  ParticleFrame frame;
  test::TempDir dir;
};

TEST_P(FarParticlesInARealFrame, EveryOtherParticleKeepsTheBound) {
  const auto [count, value] = GetParam();
  ParticleFrame f = frame;
  const Aabb before = find_far_particles(f.positions, kSpacing).bulk;
  // Spread over the frame; value 0 stands for "mixed": 1e3, 1e6, 1e30, -1e6 in turn on x, y, z.
  const float mixed[] = {1e3f, 1e6f, 1e30f, -1e6f};
  for (int k = 0; k < count; ++k) {
    const size_t i = size_t(37 + k * 101) % f.count();
    if (value != 0) f.positions[3 * i] = value;
    else f.positions[3 * i + size_t(k % 3)] = mixed[k % 4];
  }
  FileHeader h = test::test_header(PositionCoding::Quantized16, false);
  h.particle_spacing = kSpacing;
  h.precision_bits = kDefaultPrecisionBits;
  for (bool layers : {false, true}) {
    SCOPED_TRACE(layers ? "layered" : "one layer");
    const auto path = dir / (std::string("far") + (layers ? "_layers" : "") + ".sluice");
    {
      ContainerWriter w(path, h);
      io::EncodedFrame e = test::encode(f, h, 65536, layers);
      EXPECT_EQ(e.far.count, uint64_t(count));
      w.append(std::move(e));
      w.finish();
    }
    const ContainerReader r(path);
    const std::vector<float> decoded = world_positions(decode_frame(r, 0), PositionCoding::Quantized16);
    ASSERT_EQ(decoded.size(), f.positions.size());
    EXPECT_LE(worst_error_ratio(f.positions, decoded, position_bound(h)), 1.0);
    // The display bounds are the fluid's, not the outliers'.
    const Aabb& shown = r.index().bounds;
    for (int a = 0; a < 3; ++a) {
      EXPECT_GE(shown.min[size_t(a)], before.min[size_t(a)] - 1e-6f);
      EXPECT_LE(shown.max[size_t(a)], before.max[size_t(a)] + 1e-6f);
    }
    EXPECT_TRUE(verify_container(path).ok());
  }
}

INSTANTIATE_TEST_SUITE_P(Outliers, FarParticlesInARealFrame,
                         ::testing::Combine(::testing::Values(1, 5, 50), ::testing::Values(1e3f, 1e6f, 1e30f, -1e6f, 0.0f)));

// Without far particles the bound holds too, and a tighter one when asked.
TEST(PrecisionBound, HoldsOnTheSampleAtEveryPrecision) {
#ifndef SLUICE_WITH_VTK
  FAIL() << "built without VTK: the sample is .vtu";
#endif
  const ParticleFrame f = open_source(kFrame, {})->read(0);
  test::TempDir dir;
  for (uint8_t bits : {uint8_t(8), kDefaultPrecisionBits, uint8_t(16)}) {
    FileHeader h = test::test_header(PositionCoding::Quantized16, false);
    h.particle_spacing = kSpacing;
    h.precision_bits = bits;
    const auto path = dir / ("p" + std::to_string(bits) + ".sluice");
    test::write_file(path, h, {f}, 65536, true);
    const ContainerReader r(path);
    EXPECT_EQ(r.header().precision_bits, bits);
    const std::vector<float> decoded = world_positions(decode_frame(r, 0), PositionCoding::Quantized16);
    EXPECT_LE(worst_error_ratio(f.positions, decoded, position_bound(h)), 1.0) << "2^-" << int(bits);
    EXPECT_TRUE(verify_container(path).ok());
  }
}

// The far-particle finder itself: nothing far in a fluid body, exactly the
// moved particles when some are moved, nothing in tiny frames.
TEST(FindFarParticles, FindsExactlyTheMovedOnes) {
  const ParticleFrame lattice = test::lattice_frame(20000, 0);
  EXPECT_TRUE(find_far_particles(lattice.positions, 0.01f).far.empty());
  ParticleFrame moved = lattice;
  moved.positions[3 * 123 + 1] = 50.f;
  moved.positions[3 * 4567 + 2] = -3e7f;
  const FarParticles far = find_far_particles(moved.positions, 0.01f);
  EXPECT_EQ(far.far, (std::vector<uint32_t>{123, 4567}));
  EXPECT_EQ(far.farthest, 4567u);
  EXPECT_LT(far.bulk.max[1], 1.f);
  EXPECT_GT(far.bulk.min[2], -1.f);
  const std::vector<float> few = {0, 0, 0, 1e9f, 0, 0};
  EXPECT_TRUE(find_far_particles(few, 0.01f).far.empty());
}

}  // namespace
