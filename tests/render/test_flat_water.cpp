// Flat water as the renderer draws it today (spheres of one radius): how far
// the shaded normals of a resting pool on a jittered lattice lean from the
// plane's, and how strongly a thin sheet's shading repeats at the lattice
// period (the "ribs"). The yardsticks for anisotropic particles (docs/
// render.md, "Flat water"); the thresholds guard today's figures with a
// margin, so a change that makes flat water worse fails here.
//
// Both scenes are rendered with the player's defaults (narrow-range filter,
// 2 iterations, radius = spacing) at 640x480 on the local Vulkan device
// (lavapipe in CI), validation on.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <random>

#include "render_test_util.h"
#include "sluice/render/inspection.h"
#include "sluice/render/renderer.h"
#include "sluice/render/synthetic.h"

namespace sluice::render {
namespace {

using testing::context;
using testing::ValidationGuard;

constexpr uint32_t kW = 640, kH = 480;
constexpr float kSpacing = 0.05f;

struct Particles {
  std::vector<float> xyz;
  std::vector<uint16_t> lod;
};

// `layers` layers of an n x n square lattice below z = 0, each particle moved
// by up to `jitter` spacings on each axis (uniform, seeded).
Particles lattice(int n, int layers, float jitter, uint32_t seed) {
  Particles p;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-jitter * kSpacing, jitter * kSpacing);
  const float half = 0.5f * float(n) * kSpacing;
  for (int k = 0; k < layers; ++k) {
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        p.xyz.insert(p.xyz.end(), {-half + (float(i) + 0.5f) * kSpacing + u(rng),
                                   -half + (float(j) + 0.5f) * kSpacing + u(rng), -float(k) * kSpacing + u(rng)});
        p.lod.push_back(uint16_t(rng() & 0xffff));
      }
    }
  }
  return p;
}

// A pixel of the fluid's top: its world position, its shaded normal's angle
// from +z, and the thickness along its ray.
struct TopPixel {
  Vec3 world;
  double degrees;
  double thickness;  // world units (the thickness buffer's pixel under it)
};

// The pixels whose world point lies within `window` of the origin on x and y
// (away from the edges, where the surface bends).
std::vector<TopPixel> top_pixels(const Particles& p, float window, bool ellipsoids = false) {
  const SceneInfo scene = scene_for_points(p.xyz, kSpacing);
  RendererOptions options = testing::OffscreenRenderer::debug_options();
  options.anisotropic = ellipsoids;
  testing::OffscreenRenderer r(context(), scene, kW, kH, options);
  upload_points(r, p.xyz, p.lod);
  const Camera cam = testing::camera_at({0.4f, -1.7f, 1.3f}, {0, 0, 0});
  FluidOptions o;
  o.display_mode = DisplayMode::FilteredSurfaceNormal;
  o.ground = false;
  r.render(cam, o, {});
  const std::vector<float> surface = r.read_surface();
  const std::vector<float> thickness = read_raw_thickness(r);
  const uint32_t tw = (kW + 1) / 2, th = uint32_t(thickness.size() / tw);  // (half resolution by default)
  const Mat4 view = cam.view();
  const Mat4 to_world = inverse(view);
  const Vec4 up = view * Vec4{0, 0, 1, 0};
  const Vec3 truth = normalize({up.x, up.y, up.z});
  std::vector<TopPixel> out;
  for (uint32_t y = 0; y < kH; ++y) {
    for (uint32_t x = 0; x < kW; ++x) {
      const float* px = &surface[(size_t(y) * kW + x) * 4];
      if (px[3] <= 0) continue;
      const std::array<double, 3> d = testing::pixel_ray(cam, x, y, kW, kH);
      const Vec4 w = to_world * Vec4{float(d[0] * px[3]), float(d[1] * px[3]), float(d[2] * px[3]), 1};
      if (std::fabs(w.x) > window || std::fabs(w.y) > window) continue;
      const Vec3 n = normalize({px[0], px[1], px[2]});
      const double c = std::clamp(double(dot(n, truth)), -1.0, 1.0);
      const size_t t_at = size_t(std::min(y * th / kH, th - 1)) * tw + std::min(x * tw / kW, tw - 1);
      out.push_back({{w.x, w.y, w.z}, std::acos(c) * 180.0 / M_PI, double(thickness[t_at])});
    }
  }
  return out;
}

struct Angles {
  double mean = 0, p95 = 0;
};
Angles angles(std::vector<TopPixel> pixels) {
  Angles a;
  std::vector<double> deg;
  for (const TopPixel& p : pixels) deg.push_back(p.degrees);
  for (double d : deg) a.mean += d / double(deg.size());
  std::nth_element(deg.begin(), deg.begin() + long(deg.size() * 95 / 100), deg.end());
  a.p95 = deg[deg.size() * 95 / 100];
  return a;
}

// The thickness's amplitude at the lattice period along world x, relative
// to its mean: what the volume colour (Beer-Lambert) shows as ribs. The
// pixels binned at spacing / 8 along x (averaging over y), then one DFT term
// at frequency 1 / spacing.
double rib_strength(const std::vector<TopPixel>& pixels, float window) {
  const double bin = kSpacing / 8.0;
  const int bins = int(2 * window / bin);
  std::vector<double> sum(size_t(bins), 0.0), count(size_t(bins), 0.0);
  for (const TopPixel& p : pixels) {
    const int b = std::clamp(int((p.world.x + window) / bin), 0, bins - 1);
    sum[size_t(b)] += p.thickness;
    count[size_t(b)] += 1;
  }
  double mean = 0, filled = 0;
  for (int b = 0; b < bins; ++b) {
    if (count[size_t(b)] == 0) continue;
    mean += sum[size_t(b)] / count[size_t(b)];
    filled += 1;
  }
  mean /= filled;
  std::complex<double> term = 0;
  for (int b = 0; b < bins; ++b) {
    if (count[size_t(b)] == 0) continue;
    const double x = (b + 0.5) * bin;
    term += (sum[size_t(b)] / count[size_t(b)] - mean) * std::exp(std::complex<double>(0, -2 * M_PI * x / kSpacing));
  }
  return 2 * std::abs(term) / filled / mean;
}

TEST(FlatWater, ARestingPoolOnAJitteredLattice) {
  ValidationGuard guard;
  const float window = 0.6f;
  const std::vector<TopPixel> pool = top_pixels(lattice(48, 4, 0.25f, 7), window);
  ASSERT_GT(pool.size(), 20000u);
  const Angles jittered = angles(pool);
  const Angles rough = angles(top_pixels(lattice(48, 4, 0.5f, 7), window));
  const std::vector<TopPixel> exact = top_pixels(lattice(48, 4, 0.0f, 7), window);
  const Angles regular = angles(exact);
  std::printf("pool, spheres, normals from +z over %zu pixels: exact lattice mean %.2f deg (95%%: %.2f); jittered by "
              "0.25 spacing %.2f (%.2f), by 0.5 spacing %.2f (%.2f)\n",
              pool.size(), regular.mean, regular.p95, jittered.mean, jittered.p95, rough.mean, rough.p95);
  // Today's figures with a margin (docs/render.md): spheres cannot reach the
  // issue's 2 degrees on a jittered lattice; ellipsoids do (1.71, below).
  EXPECT_LT(regular.mean, 1.0);
  EXPECT_LT(jittered.mean, 3.2);  // today 2.56
}

// The same pool drawn with anisotropic particles (RendererOptions::
// anisotropic). The target is at most 2 degrees at 0.25 jitter; today's
// ellipsoids give 1.71 against the spheres' 2.56 (docs/render.md says what
// was tried on the way).
TEST(FlatWater, ARestingPoolOfEllipsoidsIsFlatterThanOfSpheres) {
  ValidationGuard guard;
  const float window = 0.6f;
  const Particles pool = lattice(48, 4, 0.25f, 7);
  const std::vector<TopPixel> flat = top_pixels(pool, window, true);
  ASSERT_GT(flat.size(), 20000u);
  const Angles ellipsoids = angles(flat), spheres = angles(top_pixels(pool, window));
  const Angles rough = angles(top_pixels(lattice(48, 4, 0.5f, 7), window, true));
  const Angles regular = angles(top_pixels(lattice(48, 4, 0.0f, 7), window, true));
  std::printf("pool, ellipsoids, normals from +z over %zu pixels: exact lattice mean %.2f deg (95%%: %.2f); jittered by "
              "0.25 spacing %.2f (%.2f; spheres %.2f), by 0.5 spacing %.2f (%.2f)\n",
              flat.size(), regular.mean, regular.p95, ellipsoids.mean, ellipsoids.p95, spheres.mean, rough.mean, rough.p95);
  EXPECT_LT(ellipsoids.mean, spheres.mean);
  EXPECT_LE(ellipsoids.mean, 2.0);  // today 1.71
}

TEST(FlatWater, AThinSheetsThicknessAtTheLatticePeriod) {
  ValidationGuard guard;
  const float window = 0.6f;
  const std::vector<TopPixel> sheet = top_pixels(lattice(48, 2, 0.0f, 7), window);
  const std::vector<TopPixel> slab = top_pixels(lattice(48, 6, 0.0f, 7), window);
  ASSERT_GT(sheet.size(), 20000u);
  const double sheet_ribs = rib_strength(sheet, window), slab_ribs = rib_strength(slab, window);
  std::printf("ribs, spheres: the thickness's amplitude at the lattice period, of its mean: sheet of 2 layers %.2f%%, "
              "slab of 6 layers %.2f%% (%zu and %zu pixels)\n",
              100 * sheet_ribs, 100 * slab_ribs, sheet.size(), slab.size());
  EXPECT_LT(sheet_ribs, 0.035);  // today 2.57%
}

TEST(FlatWater, AThinSheetOfEllipsoidsHasWeakerRibs) {
  ValidationGuard guard;
  const float window = 0.6f;
  const Particles sheet = lattice(48, 2, 0.0f, 7);
  const std::vector<TopPixel> flat = top_pixels(sheet, window, true);
  ASSERT_GT(flat.size(), 20000u);
  const double ellipsoids = rib_strength(flat, window), spheres = rib_strength(top_pixels(sheet, window), window);
  std::printf("ribs, sheet of 2 layers: ellipsoids %.2f%%, spheres %.2f%% of the mean thickness\n", 100 * ellipsoids,
              100 * spheres);
  EXPECT_LT(ellipsoids, spheres);
  EXPECT_LT(ellipsoids, 0.022);  // today 1.93%
}

}  // namespace
}  // namespace sluice::render
