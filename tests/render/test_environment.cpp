// The environment image: with no fluid and no ground, every pixel is the
// equirectangular image's colour for the pixel's view direction, through the
// renderer's output curve. The image is split into four flat quadrants, so
// looking up, down, along +y and along -y each has a known colour.
#include <gtest/gtest.h>

#include <zlib.h>

#include <cmath>
#include <cstdio>
#include <fstream>

#include "render_test_util.h"
#include "sluice/error.h"
#include "sluice/render/image_io.h"
#include "sluice/render/renderer.h"
#include "sluice/render/synthetic.h"

namespace sluice::render {
namespace {

using testing::context;
using testing::ValidationGuard;

constexpr uint32_t kW = 64, kH = 48;

// 8 x 16 texels: blue-ish above the horizon, green-ish below; red 255 in the
// right half of the azimuth range (u >= 0.5), 0 in the left half.
Image quadrant_environment() {
  Image img{8, 16, std::vector<uint8_t>(8 * 16 * 4)};
  for (uint32_t y = 0; y < 16; ++y) {
    for (uint32_t x = 0; x < 8; ++x) {
      uint8_t* p = &img.rgba[(y * 8 + x) * 4];
      p[0] = x >= 4 ? 255 : 0;
      p[1] = y < 8 ? 60 : 180;
      p[2] = y < 8 ? 200 : 60;
      p[3] = 255;
    }
  }
  return img;
}

// sRGB texel -> linear (the sampler) -> the composite's output curve.
double through_renderer(uint8_t c) {
  const double s = c / 255.0;
  const double linear = s <= 0.04045 ? s / 12.92 : std::pow((s + 0.055) / 1.055, 2.4);
  return 255.0 * std::pow(std::clamp(linear / (1.0 + 0.12 * linear), 0.0, 1.0), 1.0 / 2.2);
}

Camera horizontal_camera(float direction_y) {
  Camera c;
  c.eye = {0, -3 * direction_y, 0.5f};
  c.target = {0, 0, 0.5f};
  c.up = {0, 0, 1};
  c.fov_deg = 40;
  c.near = 0.05f;
  return c;
}

void expect_pixel(const std::vector<uint8_t>& img, uint32_t x, uint32_t y, uint8_t r, uint8_t g, uint8_t b,
                  const char* what) {
  const uint8_t* p = &img[(y * kW + x) * 4];
  EXPECT_NEAR(p[0], through_renderer(r), 3.0) << what << " red";
  EXPECT_NEAR(p[1], through_renderer(g), 3.0) << what << " green";
  EXPECT_NEAR(p[2], through_renderer(b), 3.0) << what << " blue";
}

TEST(Environment, BackgroundIsTheImageInTheViewDirection) {
  ValidationGuard guard;
  SceneInfo scene = scene_for_points(std::vector<float>{0, 0, 0, 1, 1, 1}, 0.1f);
  testing::OffscreenRenderer r(context(), scene, kW, kH);
  upload_points(r, {}, {});
  r.set_environment(quadrant_environment());
  FluidOptions o;
  o.ground = false;

  // Along +y: azimuth 90 degrees from +x, u = 0.75 (red 255).
  r.render(horizontal_camera(+1), o, {});
  std::vector<uint8_t> img = r.read_rgba8();
  expect_pixel(img, kW / 2, 2, 255, 60, 200, "+y, above the horizon");
  expect_pixel(img, kW / 2, kH - 3, 255, 180, 60, "+y, below the horizon");

  // Along -y: u = 0.25 (red 0).
  r.render(horizontal_camera(-1), o, {});
  img = r.read_rgba8();
  expect_pixel(img, kW / 2, 2, 0, 60, 200, "-y, above the horizon");
  expect_pixel(img, kW / 2, kH - 3, 0, 180, 60, "-y, below the horizon");

  // Back to the procedural sky: no longer the image's colours.
  r.set_environment({});
  r.render(horizontal_camera(+1), o, {});
  img = r.read_rgba8();
  EXPECT_GT(std::abs(int(img[(2 * kW + kW / 2) * 4]) - int(through_renderer(255))), 20);
}

TEST(Environment, RejectsAnImageWhosePixelsDoNotMatchItsSize) {
  SceneInfo scene = scene_for_points(std::vector<float>{0, 0, 0, 1, 1, 1}, 0.1f);
  testing::OffscreenRenderer r(context(), scene, 16, 16);
  EXPECT_THROW(r.set_environment(Image{4, 4, std::vector<uint8_t>(10)}), sluice::render::Error);
}

}  // namespace
}  // namespace sluice::render

namespace sluice::render {
namespace {

// A PNG of a signature, an IHDR chunk claiming `width` x `height` and an
// empty IDAT (libpng reads the header up to the first IDAT).
std::string png_claiming(uint32_t width, uint32_t height) {
  auto be32 = [](std::string& out, uint32_t v) {
    for (int s = 24; s >= 0; s -= 8) out.push_back(char((v >> s) & 0xff));
  };
  std::string ihdr = "IHDR";
  be32(ihdr, width);
  be32(ihdr, height);
  ihdr += std::string("\x08\x06\x00\x00\x00", 5);  // 8-bit RGBA, no interlace
  std::string png = "\x89PNG\r\n\x1a\n";
  be32(png, 13);
  png += ihdr;
  be32(png, uint32_t(crc32(0, reinterpret_cast<const Bytef*>(ihdr.data()), uInt(ihdr.size()))));
  be32(png, 0);
  png += "IDAT";
  be32(png, uint32_t(crc32(0, reinterpret_cast<const Bytef*>("IDAT"), 4)));
  return png;
}

TEST(Environment, APngClaimingGigapixelsIsRefusedBeforeAllocating) {
  const std::string path = ::testing::TempDir() + "sluice_huge_claim.png";
  {
    std::ofstream out(path, std::ios::binary);
    out << png_claiming(200000, 200000);  // 160 GB of RGBA if believed
  }
  try {
    read_png(path);
    FAIL() << "a 200000x200000 claim was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("200000x200000"), std::string::npos) << e.what();
  }
  std::remove(path.c_str());
}

}  // namespace
}  // namespace sluice::render
