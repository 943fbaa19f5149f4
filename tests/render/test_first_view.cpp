// The first view a new user gets: `sluice play` on the bundled sample opens
// with the whole fluid in the window and clear of the HUD, at several window
// sizes. Found from screenshots, not from the player's own idea of where
// things are: fluid pixels are those that change when the particles are
// culled away, HUD pixels those that change when the HUD is hidden (the
// same view, given back to the player with --camera).
// Runs under a display (xvfb-run in CI).
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "sluice/render/image_io.h"

namespace {

namespace fs = std::filesystem;
using sluice::render::Image;

struct Mask {
  uint32_t width = 0, height = 0;
  std::vector<uint8_t> on;
  uint64_t count = 0;
  uint32_t x0 = UINT32_MAX, y0 = UINT32_MAX, x1 = 0, y1 = 0;  // bounding box of the pixels that are on
};

// Pixels where any channel differs by more than `tolerance` (of 255).
Mask differing(const Image& a, const Image& b, int tolerance) {
  EXPECT_EQ(a.width, b.width);
  EXPECT_EQ(a.height, b.height);
  Mask m{a.width, a.height, std::vector<uint8_t>(size_t(a.width) * a.height), 0};
  for (uint32_t y = 0; y < a.height; ++y) {
    for (uint32_t x = 0; x < a.width; ++x) {
      const size_t i = size_t(y) * a.width + x;
      bool differs = false;
      for (int c = 0; c < 3; ++c) differs = differs || std::abs(int(a.rgba[4 * i + c]) - int(b.rgba[4 * i + c])) > tolerance;
      if (!differs) continue;
      m.on[i] = 1;
      ++m.count;
      m.x0 = std::min(m.x0, x), m.y0 = std::min(m.y0, y), m.x1 = std::max(m.x1, x), m.y1 = std::max(m.y1, y);
    }
  }
  return m;
}

// Runs `sluice play` on the sample and returns its screenshot; `view`
// receives the camera it ended with (its "last view" line).
Image screenshot(const std::string& size, const std::string& name, const std::string& extra, std::string* view = nullptr) {
  const fs::path dir = fs::path(testing::TempDir()) / "first_view";
  fs::create_directories(dir);
  const std::string out = (dir / (name + "_" + size + ".png")).string();
  const std::string command = std::string("\"") + SLUICE_BINARY + "\" play \"" + SLUICE_SAMPLE_DIR +
                              "/dam_break_3d.pvd\" --no-cache --size " + size +
                              " --paused --start 12 --exit-after 3 --screenshot \"" + out + "\" " + extra + " 2>/dev/null";
  FILE* pipe = popen(command.c_str(), "r");
  EXPECT_NE(pipe, nullptr) << command;
  std::string text;
  char buf[4096];
  while (pipe && std::fgets(buf, sizeof buf, pipe)) text += buf;
  EXPECT_EQ(pipe ? pclose(pipe) : -1, 0) << command << "\n" << text;
  if (view) {
    const std::string key = "last view: --camera \"";
    const size_t at = text.find(key);
    EXPECT_NE(at, std::string::npos) << text;
    if (at != std::string::npos) *view = text.substr(at + key.size(), text.find('"', at + key.size()) - at - key.size());
  }
  return sluice::render::read_png(out);
}

void expect_clear_of_hud(const std::string& size) {
  // The default view with the HUD; then the same view without the HUD, and
  // without the HUD and the particles.
  std::string view;
  const Image hud = screenshot(size, "hud", "", &view);
  const std::string same = "--no-hud --camera \"" + view + "\"";
  const Image bare = screenshot(size, "bare", same);
  const Image empty = screenshot(size, "empty", same + " --near-cull 1e30");  // every particle culled
  const Mask fluid = differing(bare, empty, 8);
  const Mask panel = differing(hud, bare, 8);
  const uint64_t pixels = uint64_t(bare.width) * bare.height;
  // (The sample's frame 12 covers about 5% of the small window; its
  // ellipsoids, the default, cover 6% fewer pixels than its spheres.)
  ASSERT_GT(fluid.count, pixels / 25) << "the fluid should fill a good part of the window";
  ASSERT_GT(panel.count, 1000u) << "the HUD should be drawn";
  uint64_t under = 0;
  for (uint32_t y = panel.y0; y <= panel.y1; ++y) {
    for (uint32_t x = panel.x0; x <= panel.x1; ++x) under += fluid.on[size_t(y) * fluid.width + x];
  }
  EXPECT_EQ(under, 0u) << size << ": fluid pixels inside the HUD's rectangle [" << panel.x0 << ", " << panel.x1
                       << "] x [" << panel.y0 << ", " << panel.y1 << "]; fluid spans [" << fluid.x0 << ", "
                       << fluid.x1 << "] x [" << fluid.y0 << ", " << fluid.y1 << "]";
  // The whole fluid is in the window: none of it on the border.
  EXPECT_GT(fluid.x0, 0u) << size;
  EXPECT_GT(fluid.y0, 0u) << size;
  EXPECT_LT(fluid.x1, fluid.width - 1) << size;
  EXPECT_LT(fluid.y1, fluid.height - 1) << size;
}

TEST(FirstView, WholeFluidClearOfTheHudAt1280x720) { expect_clear_of_hud("1280x720"); }
TEST(FirstView, WholeFluidClearOfTheHudInATallWindow) { expect_clear_of_hud("600x800"); }
// Small enough that the panel would cover the fluid of a centred view.
TEST(FirstView, WholeFluidClearOfTheHudInASmallWindow) { expect_clear_of_hud("640x400"); }

}  // namespace
