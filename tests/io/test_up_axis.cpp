// Up-axis detection on frames built here, where the answer is known, and on
// frames where there is none to find (io/include/sluice/io/up_axis.h).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "sluice/io/up_axis.h"

using namespace sluice::io;

namespace {

constexpr float kSpacing = 0.02f;

// A block of particles, `along` x `across` x `tall` cells of kSpacing,
// jittered; `tall` runs along z.
std::vector<float> block(int along, int across, int tall, uint32_t seed = 3) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> jitter(-0.1f * kSpacing, 0.1f * kSpacing);
  std::vector<float> xyz;
  for (int i = 0; i < along; ++i) {
    for (int j = 0; j < across; ++j) {
      for (int k = 0; k < tall; ++k) {
        xyz.insert(xyz.end(), {(i + 0.5f) * kSpacing + jitter(rng), (j + 0.5f) * kSpacing + jitter(rng),
                               (k + 0.5f) * kSpacing + jitter(rng)});
      }
    }
  }
  return xyz;
}

ShapeGrid grid_of(const std::vector<float>& xyz) {
  ShapeGrid g;
  for (size_t i = 0; i < xyz.size(); i += 3) g.box.extend(xyz[i], xyz[i + 1], xyz[i + 2]);
  g.cell = 2 * kSpacing;
  return g;
}

// Frames of `first` moved by `move(x, y, z, frame)`, measured on frame 0's grid.
template <class Move>
std::vector<FrameShape> frames(const std::vector<float>& first, int count, Move move) {
  const ShapeGrid grid = grid_of(first);
  std::vector<FrameShape> out;
  for (int f = 0; f < count; ++f) {
    std::vector<float> xyz = first;
    for (size_t i = 0; i < xyz.size(); i += 3) move(xyz[i], xyz[i + 1], xyz[i + 2], f);
    out.push_back(measure_shape(xyz, &grid));
  }
  return out;
}

TEST(UpAxis, ShapeQuantilesIgnoreSpray) {
  std::vector<float> xyz = block(20, 10, 5);
  for (int i = 0; i < 3; ++i) xyz.insert(xyz.end(), {0.2f, 0.1f, 9.0f});  // three droplets far above
  const FrameShape s = measure_shape(xyz);
  EXPECT_NEAR(s.high[2], 5 * kSpacing, kSpacing);
  EXPECT_NEAR(s.low[0], 0, kSpacing);
  EXPECT_NEAR(s.high[0], 20 * kSpacing, kSpacing);
}

TEST(UpAxis, ACollapsingColumnFallsAlongMinusZ) {
  const auto shapes = frames(block(10, 10, 25), 6, [](float& x, float&, float& z, int f) {
    const float s = 0.02f * float(f * f);  // the top falls, the floor stays, the front runs out
    z *= 1 - s;
    x *= 1 + 2 * s;
  });
  const auto found = up_from_motion(shapes, kSpacing);
  ASSERT_TRUE(found);
  EXPECT_EQ(found->up, UpAxis::PosZ);
  EXPECT_EQ(found->evidence, UpEvidence::Motion);
}

TEST(UpAxis, ASplashOntoAFloorIsAFall) {
  // Particles fall along -y onto a floor at y = 0 and pile up there.
  const auto shapes = frames(block(8, 8, 8), 5, [](float&, float& y, float&, int f) {
    y = std::max(0.5f * kSpacing + 0.002f * y, y - 0.02f * float(f * f));
  });
  const auto found = up_from_motion(shapes, kSpacing);
  ASSERT_TRUE(found);
  EXPECT_EQ(found->up, UpAxis::PosY);
}

TEST(UpAxis, MovingAsAWholeIsNoFall) {
  // A drift or a sway moves both ends of every column: no floor, no evidence.
  EXPECT_FALSE(up_from_motion(frames(block(8, 8, 8), 5, [](float&, float& y, float&, int f) { y -= 0.01f * float(f * f); }),
                              kSpacing));
  EXPECT_FALSE(up_from_motion(
      frames(block(16, 8, 8), 5, [](float& x, float&, float& z, int f) { x -= z * 0.2f * float(f); }), kSpacing));
}

TEST(UpAxis, StillOrSideways_NoFall) {
  EXPECT_FALSE(up_from_motion(frames(block(10, 10, 10), 6, [](float&, float&, float&, int) {}), kSpacing));
  // A front running out along the floor with the top staying: not a fall.
  EXPECT_FALSE(up_from_motion(frames(block(10, 10, 10), 6, [](float& x, float&, float&, int f) { x *= 1 + 0.05f * f; }),
                              kSpacing));
  // One frame is not motion.
  EXPECT_FALSE(up_from_motion(frames(block(10, 10, 10), 1, [](float&, float&, float&, int) {}), kSpacing));
}

TEST(UpAxis, ASloshIsNoFall) {
  // A standing wave: the top rises on one side and falls on the other, so
  // the rows across near the top empty on one side and their ends jump.
  const auto shapes = frames(block(30, 8, 10), 8, [](float& x, float&, float& z, int f) {
    // The first sloshing mode: cos(pi x / L) across the tank.
    z *= 1 + 0.3f * std::sin(0.3f * float(f)) * std::cos(3.14159265f * x / (30 * kSpacing));
  });
  EXPECT_FALSE(up_from_motion(shapes, kSpacing));
}

TEST(UpAxis, HydrostaticPressurePointsDown) {
  const std::vector<float> xyz = block(12, 12, 12);
  std::mt19937 rng(5);
  std::normal_distribution<float> noise(0, 300);
  std::vector<float> p, random;
  for (size_t i = 0; i < xyz.size(); i += 3) {
    p.push_back(1000 * 9.81f * (0.24f - xyz[i]) + noise(rng));  // grows toward -x: x is up
    random.push_back(noise(rng));
  }
  const auto found = up_from_pressure(xyz, p, "p");
  ASSERT_TRUE(found);
  EXPECT_EQ(found->up, UpAxis::PosX);
  EXPECT_FALSE(up_from_pressure(xyz, random, "p"));  // no trend: nothing to find
}

TEST(UpAxis, AFlatLayerIsThinAlongUp) {
  const auto flat = up_from_shape(measure_shape(block(40, 30, 4)));
  ASSERT_TRUE(flat);
  EXPECT_EQ(flat->up, UpAxis::PosZ);
  EXPECT_FALSE(up_from_shape(measure_shape(block(10, 10, 10))));  // a cube lies no way
}

TEST(UpAxis, PressureArraysBestFirst) {
  const std::vector<std::string> arrays = {"velocity", "rho", "p"};
  EXPECT_EQ(pick_pressure_array(arrays), "p");
  EXPECT_EQ(pick_pressure_array(std::vector<std::string>{"velocity"}), "");
}

}  // namespace
