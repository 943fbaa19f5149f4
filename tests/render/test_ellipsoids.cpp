// Anisotropic particles' ellipsoids (BandClassifier::ellipsoids, the pass
// shaders/band_ellipsoids.comp) against what the geometry says: a particle
// with few neighbours is a sphere; inside a cubic lattice it is a sphere;
// in a plane it is flattened along the plane's normal by the largest ratio
// (radii 4^(1/3), 4^(1/3), 4^(1/3) / 4) and stays in it; on a lattice's
// flat top it is drawn at its layer's height; on a dense line it is
// stretched along it (16^(1/3), then 16^(1/3) / 4 twice). The GPU gives each shape
// matrix in half precision; the test finds its axes in double. Tolerance
// 2e-3 on radii (halves: 1e-3 relative on the squared radii), 1e-3 on the
// cosine of axis directions; no validation message.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "render_test_util.h"
#include "sluice/render/band_classifier.h"

namespace sluice::render {
namespace {

using testing::ValidationGuard;
using testing::band_classifier;

struct Axis {
  std::array<double, 3> direction;  // unit
  double radius;                    // in particle radii
};

// Eigenvalues and unit eigenvectors (columns) of a symmetric 3x3 matrix:
// cyclic Jacobi rotations in double, independent of the shader's.
void jacobi(std::array<std::array<double, 3>, 3> a, std::array<double, 3>& values,
            std::array<std::array<double, 3>, 3>& vectors) {
  vectors = {{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
  for (int sweep = 0; sweep < 50; ++sweep) {
    for (int p = 0; p < 2; ++p) {
      for (int q = p + 1; q < 3; ++q) {
        if (std::abs(a[p][q]) < 1e-15) continue;
        const double theta = (a[q][q] - a[p][p]) / (2 * a[p][q]);
        const double t = (theta >= 0 ? 1.0 : -1.0) / (std::abs(theta) + std::sqrt(theta * theta + 1));
        const double c = 1 / std::sqrt(t * t + 1), s = t * c;
        for (int k = 0; k < 3; ++k) {  // a = J^T a J, v = v J
          const double akp = a[k][p], akq = a[k][q];
          a[k][p] = c * akp - s * akq;
          a[k][q] = s * akp + c * akq;
        }
        for (int k = 0; k < 3; ++k) {
          const double apk = a[p][k], aqk = a[q][k];
          a[p][k] = c * apk - s * aqk;
          a[q][k] = s * apk + c * aqk;
        }
        for (int k = 0; k < 3; ++k) {
          const double vkp = vectors[k][p], vkq = vectors[k][q];
          vectors[k][p] = c * vkp - s * vkq;
          vectors[k][q] = s * vkp + c * vkq;
        }
      }
    }
  }
  values = {a[0][0], a[1][1], a[2][2]};
}

// The three axes of a shape matrix A = R S^2 R^T, shortest first.
std::vector<Axis> axes_of(const std::array<float, 6>& e) {
  const std::array<std::array<double, 3>, 3> a{{{e[0], e[1], e[2]}, {e[1], e[3], e[4]}, {e[2], e[4], e[5]}}};
  std::array<double, 3> values{};
  std::array<std::array<double, 3>, 3> vectors{};
  jacobi(a, values, vectors);
  std::vector<Axis> out;
  for (int k = 0; k < 3; ++k) out.push_back({{vectors[0][k], vectors[1][k], vectors[2][k]}, std::sqrt(std::max(values[k], 0.0))});
  std::sort(out.begin(), out.end(), [](const Axis& x, const Axis& y) { return x.radius < y.radius; });
  return out;
}

double alignment(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  return std::abs(a[0] * b[0] + a[1] * b[1] + a[2] * b[2]);
}

// A rotation that takes z to `n` (unit), applied to p.
std::array<float, 3> rotated(std::array<double, 3> p, const std::array<double, 3>& n) {
  // Rodrigues about z x n.
  const double c = n[2], ax = -n[1], ay = n[0];  // axis (unnormalized) = z x n = (-n.y, n.x, 0)
  const double s = std::sqrt(ax * ax + ay * ay);
  if (s < 1e-12) return {float(p[0]), float(p[1]), float(c * p[2])};
  const double kx = ax / s, ky = ay / s;  // unit axis, kz = 0
  const double dot = kx * p[0] + ky * p[1];
  const std::array<double, 3> cross{ky * p[2], -kx * p[2], kx * p[1] - ky * p[0]};
  std::array<float, 3> out{};
  const double along[3] = {kx, ky, 0.0};
  for (int a = 0; a < 3; ++a) out[size_t(a)] = float(p[size_t(a)] * c + cross[size_t(a)] * s + along[a] * dot * (1 - c));
  return out;
}

TEST(Ellipsoids, AParticleWithFewNeighboursIsItsSphere) {
  ValidationGuard guard;
  const float h = 0.1f;
  // One alone, and a cluster of 4 (each has 3 others near: fewer than 6).
  const std::vector<float> xyz{5, 5, 5, 0, 0, 0, h, 0, 0, 0, h, 0, 0, 0, h};
  const auto e = band_classifier().ellipsoids(xyz, h);
  ASSERT_EQ(e.size(), 5u);
  const std::array<float, 6> identity{1, 0, 0, 1, 0, 1};
  const std::array<float, 3> none{0, 0, 0};
  for (size_t i = 0; i < e.size(); ++i) {
    EXPECT_EQ(e[i].shape, identity) << "particle " << i;
    EXPECT_EQ(e[i].shift, none) << "particle " << i;
  }
}

TEST(Ellipsoids, InsideACubicLatticeAParticleIsItsSphere) {
  ValidationGuard guard;
  const float h = 0.1f;
  std::vector<float> xyz;
  for (int x = 0; x < 9; ++x)
    for (int y = 0; y < 9; ++y)
      for (int z = 0; z < 9; ++z) xyz.insert(xyz.end(), {float(x) * h, float(y) * h, float(z) * h});
  const auto e = band_classifier().ellipsoids(xyz, h);
  const size_t centre = (4 * 9 + 4) * 9 + 4;
  for (const Axis& a : axes_of(e[centre].shape)) EXPECT_NEAR(a.radius, 1.0, 2e-3);
  for (float s : e[centre].shift) EXPECT_NEAR(s, 0.0f, 2e-3f * h) << "inside, the neighbours balance";
}

// The drawn centre keeps to the particle's layer: on a lattice's flat top
// a particle stays where it is (the free surface is not pulled in), and one
// raised out of its layer is drawn at its layer's weighted mean height
// along the normal (computed here in double: the weights 1 - q^3 of the
// distance in reaches 2h, times the layer's, full within 0.15 reaches of
// the particle's height along the normal; the next layer, 1.2 h below, is
// out of it); across the normal, by symmetry, it does not move.
TEST(Ellipsoids, OnAFlatTopAParticleIsDrawnAtItsLayersHeight) {
  ValidationGuard guard;
  const float h = 0.1f, raised = 0.2f * h;
  std::vector<float> xyz;
  for (int x = 0; x < 9; ++x)
    for (int y = 0; y < 9; ++y)
      for (int z = 0; z < 5; ++z) xyz.insert(xyz.end(), {float(x) * h, float(y) * h, float(z) * h});
  const size_t top = (4 * 9 + 4) * 5 + 4;
  const auto flat = band_classifier().ellipsoids(xyz, h);
  for (float s : flat[top].shift) EXPECT_NEAR(s, 0.0f, 2e-3f * h) << "on an exact lattice its layer is its height";
  EXPECT_LT(axes_of(flat[top].shape)[0].radius, 0.9) << "and flattened";

  xyz[3 * top + 2] += raised;
  const auto e = band_classifier().ellipsoids(xyz, h);
  double sum_w = 0, sum_height = 0;
  for (size_t j = 0; j < xyz.size() / 3; ++j) {
    double d[3], r2 = 0;
    for (int a = 0; a < 3; ++a) d[a] = double(xyz[3 * j + size_t(a)]) - xyz[3 * top + size_t(a)], r2 += d[a] * d[a];
    const double q = std::sqrt(r2) / (2 * double(h));
    if (q >= 1 || std::abs(d[2]) > 0.15 * 2 * double(h)) continue;  // (no neighbour here is in the fade)
    sum_w += 1 - q * q * q;
    sum_height += (1 - q * q * q) * d[2];
  }
  const double down = sum_height / sum_w;
  EXPECT_LT(down, -0.15 * h) << "the expectation itself: most of the way back to its layer";
  EXPECT_NEAR(e[top].shift[0], 0.0f, 2e-3f * h);
  EXPECT_NEAR(e[top].shift[1], 0.0f, 2e-3f * h);
  EXPECT_NEAR(e[top].shift[2], down, 2e-3 * h);
}

TEST(Ellipsoids, InAPlaneAParticleIsFlattenedAlongItsNormal) {
  ValidationGuard guard;
  const float h = 0.1f;
  const double len = std::sqrt(0.36 + 0.64 + 0.25);
  const std::array<double, 3> normal{0.6 / len, 0.8 / len, 0.5 / len};  // a plane at no axis-aligned angle
  std::vector<float> xyz;
  for (int x = -10; x <= 10; ++x)
    for (int y = -10; y <= 10; ++y) {
      const auto p = rotated({x * double(h), y * double(h), 0.0}, normal);
      xyz.insert(xyz.end(), {p[0] + 1.0f, p[1] + 1.0f, p[2] + 1.0f});
    }
  const auto e = band_classifier().ellipsoids(xyz, h);
  const size_t centre = 10 * 21 + 10;
  const std::vector<Axis> axes = axes_of(e[centre].shape);
  const double flat = std::cbrt(4.0) / 4.0, wide = std::cbrt(4.0);
  EXPECT_NEAR(axes[0].radius, flat, 2e-3);
  EXPECT_NEAR(alignment(axes[0].direction, normal), 1.0, 1e-3) << "the short axis is the plane's normal";
  EXPECT_NEAR(axes[1].radius, wide, 2e-3);
  EXPECT_NEAR(axes[2].radius, wide, 2e-3);
  for (float s : e[centre].shift) EXPECT_NEAR(s, 0.0f, 2e-3f * h) << "in the plane, the neighbours balance";
}

TEST(Ellipsoids, OnADenseLineAParticleIsStretchedAlongIt) {
  ValidationGuard guard;
  const float h = 0.1f;
  const std::array<double, 3> along{0.0, 0.6, 0.8};
  std::vector<float> xyz;
  for (int k = -40; k <= 40; ++k) {
    const double t = k * double(h) / 4;  // 4 a spacing: 14 others within 2h
    xyz.insert(xyz.end(), {float(1 + t * along[0]), float(1 + t * along[1]), float(1 + t * along[2])});
  }
  const auto e = band_classifier().ellipsoids(xyz, h);
  const std::vector<Axis> axes = axes_of(e[40].shape);
  const double r = std::cbrt(16.0);
  EXPECT_NEAR(axes[2].radius, r, 2e-3);
  EXPECT_NEAR(alignment(axes[2].direction, along), 1.0, 1e-3) << "the long axis is the line";
  EXPECT_NEAR(axes[0].radius, r / 4, 2e-3);
  EXPECT_NEAR(axes[1].radius, r / 4, 2e-3);
}

// Each particle's ellipsoid depends on its neighbours, not on the order
// they arrive in the voxels' lists (the scatter's atomics decide that): a
// jittered pool given in reverse order gets the same shapes and shifts,
// bit for bit (the pass sums in fixed point).
TEST(Ellipsoids, TheOrderOfTheParticlesChangesNoBit) {
  ValidationGuard guard;
  const float h = 0.1f;
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> jitter(-0.25f * h, 0.25f * h);
  std::vector<float> xyz;
  for (int x = 0; x < 12; ++x)
    for (int y = 0; y < 12; ++y)
      for (int z = 0; z < 4; ++z)
        xyz.insert(xyz.end(), {float(x) * h + jitter(rng), float(y) * h + jitter(rng), float(z) * h + jitter(rng)});
  const size_t n = xyz.size() / 3;
  std::vector<float> reversed;
  for (size_t i = n; i-- > 0;) reversed.insert(reversed.end(), {xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]});
  const auto forward = band_classifier().ellipsoids(xyz, h);
  const auto backward = band_classifier().ellipsoids(reversed, h);
  ASSERT_EQ(forward.size(), n);
  ASSERT_EQ(backward.size(), n);
  size_t differ = 0, shaped = 0;
  for (size_t i = 0; i < n; ++i) {
    const auto& a = forward[i];
    const auto& b = backward[n - 1 - i];
    differ += std::memcmp(a.shape.data(), b.shape.data(), sizeof a.shape) != 0 ||
              std::memcmp(a.shift.data(), b.shift.data(), sizeof a.shift) != 0;
    shaped += a.shape != std::array<float, 6>{1, 0, 0, 1, 0, 1};
  }
  EXPECT_GT(shaped, n / 2) << "the expectation itself: most particles are shaped";
  EXPECT_EQ(differ, 0u) << "of " << n;
}

}  // namespace
}  // namespace sluice::render
