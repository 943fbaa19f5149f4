// Host-only checks: camera math and its text form, the cLOD rule.
#include <gtest/gtest.h>

#include <cmath>

#include "sluice/error.h"
#include "sluice/render/camera.h"
#include "sluice/render/lod.h"
#include "sluice/render/options.h"
#include "sluice/render/renderer.h"

using namespace sluice::render;

TEST(Camera, TextRoundTrip) {
  Camera c;
  c.eye = {1.25f, -3.5f, 2.0f};
  c.target = {0.1f, 0.2f, 0.3f};
  c.up = {0, 0, 1};
  c.fov_deg = 35.5f;
  Camera d;
  d.apply(c.to_string());
  EXPECT_EQ(d.to_string(), c.to_string());
  EXPECT_FLOAT_EQ(d.eye.y, -3.5f);
  EXPECT_FLOAT_EQ(d.fov_deg, 35.5f);
}

TEST(Camera, PartialAndBadStrings) {
  Camera c;
  c.apply("fov=60");
  EXPECT_FLOAT_EQ(c.fov_deg, 60.0f);
  EXPECT_THROW(c.apply("eye=1,2"), sluice::render::Error);
  EXPECT_THROW(c.apply("zoom=3"), sluice::render::Error);
  EXPECT_THROW(c.apply("fov=0"), sluice::render::Error);
  EXPECT_FLOAT_EQ(c.fov_deg, 60.0f);  // failed applies change nothing
}

TEST(Camera, OrbitKeepsDistanceAndPan) {
  Camera c;
  c.eye = {0, -4, 0};
  c.target = {0, 0, 0};
  c.orbit(0.7f, 0.3f);
  EXPECT_NEAR(length(c.eye - c.target), 4.0f, 1e-4f);
  EXPECT_GT(c.eye.z, 0.0f);  // positive pitch goes up
  c.orbit(0, 10.0f);         // clamped short of the pole
  EXPECT_LT(dot(normalize(c.eye - c.target), c.up), 1.0f);
  const Vec3 before = c.target;
  c.pan(0.5f, 0);
  EXPECT_GT(length(c.target - before), 0.1f);
  c.zoom(0.5f);
  EXPECT_NEAR(length(c.eye - c.target), 2.0f, 1e-3f);
}

TEST(Camera, FitContainsBounds) {
  const Bounds box{{-1, -2, 0}, {3, 2, 1}};
  Camera c = Camera::framing(box, Vec3{0, 0, 1}, 16.0f / 9.0f);
  c.fit(box, 16.0f / 9.0f);  // framing() then comes in a little; fit() alone must contain it
  const Mat4 vp = c.projection(16.0f / 9.0f) * c.view();
  for (int i = 0; i < 8; ++i) {
    const Vec4 p = vp * Vec4{i & 1 ? box.max.x : box.min.x, i & 2 ? box.max.y : box.min.y, i & 4 ? box.max.z : box.min.z, 1};
    EXPECT_GT(p.w, 0);
    EXPECT_LE(std::fabs(p.x / p.w), 1.0f);
    EXPECT_LE(std::fabs(p.y / p.w), 1.0f);
  }
}

// The default framing puts every corner of the box inside the free part of
// the image (a HUD covers the rest), for any up direction, and the text form
// keeps the lens shift.
TEST(Camera, FramingKeepsEveryCornerInTheFreePart) {
  const Bounds box{{0.04f, -0.46f, 0.03f}, {1.61f, 0.46f, 0.52f}};  // the bundled dam break's bounds
  const float aspect = 1280.0f / 720.0f;
  const ScreenRect free{0.28f, 0.0f, 1.0f, 1.0f};  // right of a panel 28% wide
  for (const Vec3 up : {Vec3{0, 0, 1}, Vec3{0, 1, 0}, Vec3{0, -1, 0}, Vec3{1, 0, 0}}) {
    const Camera c = Camera::framing(box, up, aspect, 40.0f, free);
    EXPECT_NEAR(dot(c.up, up), 1.0f, 1e-6f);
    const Mat4 vp = c.projection(aspect) * c.view();
    float left = 1, right = 0, top = 1, bottom = 0;
    for (int i = 0; i < 8; ++i) {
      const Vec4 p = vp * Vec4{i & 1 ? box.max.x : box.min.x, i & 2 ? box.max.y : box.min.y, i & 4 ? box.max.z : box.min.z, 1};
      ASSERT_GT(p.w, 0);
      const float x = (p.x / p.w + 1) / 2, y = (p.y / p.w + 1) / 2;  // fractions of the image, y down
      EXPECT_GE(x, free.x0);
      EXPECT_LE(x, free.x1);
      EXPECT_GE(y, free.y0);
      EXPECT_LE(y, free.y1);
      left = std::min(left, x), right = std::max(right, x), top = std::min(top, y), bottom = std::max(bottom, y);
    }
    // Framed tightly, not just somewhere inside: one way it spans most of the free part.
    EXPECT_TRUE(right - left > 0.7f * (free.x1 - free.x0) || bottom - top > 0.7f * (free.y1 - free.y0))
        << left << ".." << right << " x " << top << ".." << bottom;
    Camera back;
    back.apply(c.to_string());
    EXPECT_NEAR(back.shift_x, c.shift_x, 1e-6f);
    EXPECT_NEAR(back.shift_y, c.shift_y, 1e-6f);
  }
}

TEST(Math, ProjectionIsReversedInfinite) {
  const Mat4 p = perspective_reverse_z(1.0f, 1.0f, 0.1f);
  const Vec4 nearp = p * Vec4{0, 0, -0.1f, 1};
  const Vec4 far = p * Vec4{0, 0, -1000.0f, 1};
  EXPECT_NEAR(nearp.z / nearp.w, 1.0f, 1e-6f);
  EXPECT_NEAR(far.z / far.w, 1e-4f, 1e-7f);
  const Mat4 i = inverse(p) * p;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) EXPECT_NEAR(i.at(r, c), r == c ? 1.0f : 0.0f, 1e-5f);
}

TEST(Lod, KeepProbabilityMatchesRule) {
  // level 1 keeps all; level 0 none; importance 1 keeps `level`.
  EXPECT_EQ(lod_keep_probability(1.0f, 0.1f), 1.0f);
  EXPECT_EQ(lod_keep_probability(0.0f, 5.0f), 0.0f);
  EXPECT_NEAR(lod_keep_probability(0.3f, 1.0f), 0.3f, 1e-6f);
  EXPECT_GT(lod_keep_probability(0.3f, 2.0f), 0.3f);
  EXPECT_LT(lod_keep_probability(0.3f, 0.5f), 0.3f);
  // The decision over uniform u reproduces the probability.
  for (float w : {0.4f, 1.0f, 2.5f}) {
    int kept = 0;
    const int n = 65536;
    for (int v = 0; v < n; ++v) kept += lod_keep(0.4f, w, lod_uniform(uint16_t(v)));
    EXPECT_NEAR(double(kept) / n, lod_keep_probability(0.4f, w), 2e-4) << "w " << w;
  }
  for (int v = 0; v < 65536; v += 97) EXPECT_TRUE(lod_keep(1.0f, 0.01f, lod_uniform(uint16_t(v))));
}

TEST(Lod, ImportanceFollowsThesis) {
  EXPECT_FLOAT_EQ(lod_importance(0, 2, 2), 1.0f);
  EXPECT_FLOAT_EQ(lod_importance(1, 2, 2), 0.3f);       // clamped at the corner
  EXPECT_FLOAT_EQ(lod_importance(0.5f, 2, 2), 0.65f);  // 1 - 0.7 * 0.5
  EXPECT_FLOAT_EQ(lod_importance(0, 4, 2), 0.5f);       // twice as far
  EXPECT_NEAR(lod_splat_scale(0.125f, 4), 2.0f, 1e-6f);
  EXPECT_EQ(lod_splat_scale(1e-6f, 4), 4.0f);
  const float h = lod_position_hash(0.1f, 0.2f, 0.3f);
  EXPECT_GE(h, 0.0f);
  EXPECT_LT(h, 1.0f);
}

TEST(Options, Names) {
  EXPECT_EQ(parse_display_mode("TransparentFluidVolume"), DisplayMode::TransparentFluidVolume);
  EXPECT_EQ(parse_display_mode("normals"), DisplayMode::FilteredSurfaceNormal);
  for (const std::string& n : display_mode_names()) EXPECT_EQ(to_string(parse_display_mode(n)), n);
  EXPECT_EQ(parse_filter_method("bilateral"), SurfaceFilterMethod::BilateralGaussian);
  EXPECT_EQ(parse_lod_mode("density"), LodMode::DensityPreserving);
  EXPECT_THROW(parse_display_mode("shiny"), sluice::render::Error);
}

// --particles and the Python module's particles=: the renderer's two fields.
TEST(Options, ParticleLooks) {
  RendererOptions o;
  apply_particles("auto", o);
  EXPECT_TRUE(o.anisotropic);
  EXPECT_EQ(o.anisotropic_limit, kAutoAnisotropicLimit);
  apply_particles("ellipsoids", o);
  EXPECT_TRUE(o.anisotropic);
  EXPECT_EQ(o.anisotropic_limit, 0u);
  apply_particles("spheres", o);
  EXPECT_FALSE(o.anisotropic);
  EXPECT_THROW(apply_particles("cubes", o), sluice::render::Error);
  EXPECT_THROW(apply_particles("", o), sluice::render::Error);
}
