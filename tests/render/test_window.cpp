// The windowed path under a display (Xvfb in CI): the swapchain shows
// exactly what the renderer made, the HUD draws on top, zero validation
// errors. Skipped only where no display is set; a display GLFW cannot use
// fails.
#include <gtest/gtest.h>
#include <imgui.h>

#include <cstdio>
#include <cstdlib>
#include <memory>

#include "sluice/render/image_io.h"
#include "sluice/render/renderer.h"
#include "sluice/render/synthetic.h"
#include "sluice/desktop/window.h"
#include "sluice/render/offscreen.h"

namespace sluice::render {
namespace {

using desktop::poll_window_events;
using desktop::Window;
using desktop::window_instance_extensions;
using desktop::WindowOptions;

class WindowTest : public ::testing::Test {
 protected:
  void SetUp() override {
    // No display at all (run by hand outside xvfb-run): nothing to test.
    // With one, as CTest runs it, GLFW failing is a failure.
    if (!std::getenv("DISPLAY") && !std::getenv("WAYLAND_DISPLAY")) GTEST_SKIP() << "no display (DISPLAY unset)";
    try {
      extensions_ = window_instance_extensions();
    } catch (const std::exception& e) {
      FAIL() << "a display is set but GLFW failed: " << e.what();
    }
    ContextOptions o;
    o.validation = true;
    o.quiet_validation = true;
    o.instance_extensions = extensions_;
    o.presentation = true;
    context_ = std::make_unique<Context>(o);
  }
  void TearDown() override {
    if (context_ && context_->validation_active()) {
      std::string all;
      for (const std::string& m : context_->validation_messages()) all += m + "\n";
      EXPECT_EQ(context_->validation_errors(), 0u) << all;
    }
  }
  std::vector<std::string> extensions_;
  std::unique_ptr<Context> context_;
};

TEST_F(WindowTest, PresentsTheRenderersImageAndTheHud) {
  WindowOptions wo;
  wo.width = 320;
  wo.height = 240;
  Window window(*context_, wo);
  ASSERT_GT(window.width(), 0u);
  const SyntheticFluid fluid = synthetic_fluid(20000);
  Renderer renderer(*context_, fluid.scene);
  upload_synthetic(renderer, fluid);
  const Camera cam = Camera::framing(fluid.scene.bounds, Vec3{0, 0, 1}, float(window.width()) / float(window.height()));
  const FluidOptions options;
  OffscreenTarget target(*context_, window.width(), window.height());
  const FrameStats stats = target.render(renderer, cam, options, {});
  EXPECT_EQ(stats.drawn, fluid.particles);
  const Image offscreen{target.width(), target.height(), target.read_rgba8()};

  // A few frames without the HUD: the last presented image is the renderer's.
  int presented = 0;
  for (int i = 0; i < 10 && presented < 3; ++i) {
    poll_window_events();
    window.new_ui_frame();
    presented += window.present(renderer, cam, options, {}, false, true) ? 1 : 0;
  }
  ASSERT_EQ(presented, 3);
  const Image shown{window.width(), window.height(), window.read_presented()};
  ASSERT_EQ(shown.rgba.size(), offscreen.rgba.size());
  const double same = psnr(shown, offscreen);
  std::printf("presented frame against the offscreen image: %.1f dB PSNR\n", same);
  EXPECT_GT(same, 50.0);

  // With a HUD window: pixels under it change, the rest stays.
  window.new_ui_frame();
  ImGui::SetNextWindowPos(ImVec2(0, 0));
  ImGui::SetNextWindowSize(ImVec2(120, 60));
  ImGui::Begin("hud");
  ImGui::TextUnformatted("frame 1 / 1");
  ImGui::End();
  ASSERT_TRUE(window.present(renderer, cam, options, {}, true, true));
  const Image hud{window.width(), window.height(), window.read_presented()};
  size_t changed_inside = 0, changed_outside = 0;
  for (uint32_t y = 0; y < hud.height; ++y) {
    for (uint32_t x = 0; x < hud.width; ++x) {
      const size_t i = (size_t(y) * hud.width + x) * 4;
      const bool differs = std::abs(int(hud.rgba[i]) - int(offscreen.rgba[i])) > 2 ||
                           std::abs(int(hud.rgba[i + 2]) - int(offscreen.rgba[i + 2])) > 2;
      ((x < 120 && y < 60) ? changed_inside : changed_outside) += differs;
    }
  }
  EXPECT_GT(changed_inside, 1000u);
  EXPECT_EQ(changed_outside, 0u);
}

}  // namespace
}  // namespace sluice::render
