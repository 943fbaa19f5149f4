// The eyes' views as the XR module builds them (placement.h), drawn by the
// renderer: the parallax between the eyes is the eye separation seen at the
// data's depth.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "render_test_util.h"
#include "sluice/render/offscreen.h"
#include "sluice/render/synthetic.h"
#include "sluice/xr/placement.h"

namespace sluice::xr {
namespace {

// Centroid x (pixels, from the left edge of the half) of the fluid's pixels
// in one half of a side-by-side image.
double centroid_x(const std::vector<uint8_t>& rgba, uint32_t width, uint32_t height, uint32_t x0, uint32_t half) {
  double sum = 0, count = 0;
  for (uint32_t y = 0; y < height; ++y) {
    for (uint32_t x = x0; x < x0 + half; ++x) {
      if (rgba[(size_t(y) * width + x) * 4 + 3] == 0) continue;  // no fluid
      sum += double(x - x0) + 0.5;
      count += 1;
    }
  }
  return count > 0 ? sum / count : -1;
}

TEST(StereoViews, ParallaxMatchesTheEyeSeparationAtTheDataDepth) {
  render::testing::ValidationGuard guard;
  render::Context& context = render::testing::context();
  // A ball of particles 2 data units across; the placement makes a data unit
  // 10 cm and puts the ball 2 m in front of the eyes.
  std::vector<float> xyz;
  const float spacing = 0.1f, radius = 1.0f;
  const int n = int(std::lround(radius / spacing));
  for (int i = -n; i <= n; ++i) {
    for (int j = -n; j <= n; ++j) {
      for (int k = -n; k <= n; ++k) {
        if (i * i + j * j + k * k <= n * n) {
          xyz.insert(xyz.end(), {float(i) * spacing, float(j) * spacing, float(k) * spacing});
        }
      }
    }
  }
  const render::SceneInfo scene = render::scene_for_points(xyz, spacing);
  render::Renderer renderer(context, scene);
  render::upload_points(renderer, xyz, std::vector<uint16_t>(xyz.size() / 3, 0));

  Placement placement;
  placement.scale = 0.1f;
  placement.pose.position = {0, 1.5f, -2.0f};  // the ball's centre, 2 m in front of the eyes
  const float ipd = 0.064f;
  const Fov fov{-0.5f, 0.5f, 0.4f, -0.4f};
  const uint32_t w = 640, h = 512;
  std::array<render::View, 2> views;
  for (int e = 0; e < 2; ++e) {
    const Pose eye{{}, {(e == 0 ? -0.5f : 0.5f) * ipd, 1.5f, 0}};
    views[size_t(e)] = eye_view(eye, fov, placement, 0.05f, 100.0f, {uint32_t(e) * w, 0, w, h});
  }
  render::OffscreenTarget target(context, 2 * w, h);
  render::FluidOptions fluid;
  target.render(renderer, views, fluid, {}, false);
  const std::vector<uint8_t> rgba = target.read_rgba8();
  const double left = centroid_x(rgba, 2 * w, h, 0, w), right = centroid_x(rgba, 2 * w, h, w, w);
  ASSERT_GT(left, 0);
  ASSERT_GT(right, 0);
  // Pinhole: disparity = focal length in pixels * separation / depth.
  const double focal = double(w) / (std::tan(double(fov.right)) - std::tan(double(fov.left)));
  const double expected = focal * ipd / 2.0;
  // Tolerance 0.3 px (1.6%): the disc is about 60 pixels across; measured on
  // lavapipe 18.93 px against 18.74. A 2% error in the eye separation, or
  // swapped eyes, fails it.
  EXPECT_NEAR(left - right, expected, 0.3) << "left " << left << " right " << right;
  // Each eye sees the ball's centre where its own projection puts it.
  EXPECT_NEAR(left, w / 2.0 + expected / 2, 0.3);
  EXPECT_NEAR(right, w / 2.0 - expected / 2, 0.3);
  std::printf("disparity %.3f px, expected %.3f (left %.3f, right %.3f)\n", left - right, expected, left, right);
}

}  // namespace
}  // namespace sluice::xr
