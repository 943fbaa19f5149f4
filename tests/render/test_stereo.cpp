// Both eyes in one pass: a 2-layer target (multiview for the raster passes,
// the dispatch's z for the compute ones, one cull for both eyes) gives each
// eye the picture it gets drawn alone, with the host's depth written per eye;
// with spheres and with anisotropic particles (ellipsoids). And the two
// splat paths draw the ellipsoids alike.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <tuple>

#include "render_test_util.h"
#include "sluice/render/renderer.h"
#include "sluice/render/synthetic.h"
#include "test_host.h"

namespace sluice::render {
namespace {

constexpr uint32_t kW = 200, kH = 150;

// PSNR of the RGB of two RGBA8 images (99: identical).
double psnr(const std::vector<uint32_t>& a, const std::vector<uint32_t>& b) {
  double se = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      const double d = double((a[i] >> (8 * k)) & 255u) - double((b[i] >> (8 * k)) & 255u);
      se += d * d;
    }
  }
  const double mse = se / (double(a.size()) * 3);
  return mse == 0 ? 99.0 : 10 * std::log10(255.0 * 255.0 / mse);
}

// A camera framing the synthetic frame, +z up, at the tests' aspect.
Camera framing(const SyntheticFluid& f) { return Camera::framing(f.scene.bounds, Vec3{0, 0, 1}, float(kW) / kH); }

// The left and right eye: a camera framing the data, moved sideways by
// -/+ half the separation along its right axis.
std::array<View, 2> eyes(const Camera& cam, float separation) {
  const Vec3 forward = normalize(cam.target - cam.eye);
  const Vec3 right = normalize(cross(forward, cam.up));
  std::array<View, 2> v;
  for (int e = 0; e < 2; ++e) {
    Camera c = cam;
    const Vec3 shift = right * ((e == 0 ? -0.5f : 0.5f) * separation);
    c.eye = c.eye + shift;
    c.target = c.target + shift;
    v[size_t(e)] = camera_view(c, {0, 0, kW, kH});
  }
  return v;
}

struct Drawn {
  std::array<std::vector<uint32_t>, 2> color, depth;
  FrameStats stats;
};

// Draws `views` (one per layer) into fresh host images of that many layers,
// colour and D32 depth, and reads every layer back. `in_shading`: images
// that allow storage and copies, so the shading pass tests and writes the
// depth (RenderTarget::depth_transfer); else the present pass does.
Drawn draw_into_host(testing::TestHost& host, Renderer& renderer, std::span<const View> views, const FluidOptions& fluid,
                     const LodOptions& lod, bool in_shading = false, vk::Format depth_format = vk::Format::eD32Sfloat) {
  using U = vk::ImageUsageFlagBits;
  const uint32_t layers = uint32_t(views.size());
  const vk::ImageUsageFlags storage = in_shading ? U::eStorage : vk::ImageUsageFlags{};
  const vk::ImageUsageFlags copy_in = in_shading ? U::eTransferDst : vk::ImageUsageFlags{};
  testing::TestHost::Image color =
      host.image(kW, kH, vk::Format::eR8G8B8A8Unorm, U::eColorAttachment | U::eTransferSrc | storage, layers);
  testing::TestHost::Image depth =
      host.image(kW, kH, depth_format, U::eDepthStencilAttachment | U::eTransferSrc | copy_in, layers);
  RenderTarget t;
  t.width = kW;
  t.height = kH;
  t.color_image = *color.image;
  t.color_view = *color.view;
  t.color_format = VK_FORMAT_R8G8B8A8_UNORM;
  t.color_layout_after = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
  t.depth_image = *depth.image;
  t.depth_view = *depth.view;
  t.depth_format = VkFormat(depth_format);
  t.depth_layout_after = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
  t.layer_count = layers;
  t.color_storage = in_shading;
  t.depth_transfer = in_shading;
  host.submit([&](vk::CommandBuffer c) { renderer.record(c, t, views, fluid, lod); });
  Drawn d;
  for (uint32_t l = 0; l < layers; ++l) {
    d.color[l] = host.read(color, kW, kH, l);
    d.depth[l] = host.read(depth, kW, kH, l);
  }
  d.stats = renderer.last_stats();
  return d;
}

class Stereo : public ::testing::TestWithParam<std::tuple<Splatting, bool>> {};

TEST_P(Stereo, BothEyesInOnePassMatchEachEyeDrawnAlone) {
  testing::TestHost host;
  const auto [splatting, anisotropic] = GetParam();
  {
    Context context(host.handles());
    const SyntheticFluid f = synthetic_fluid(30000);
    RendererOptions options;
    options.anisotropic = anisotropic;
    Renderer renderer(context, f.scene, options);
    upload_synthetic(renderer, f);
    const Camera cam = framing(f);
    const std::array<View, 2> views = eyes(cam, 0.08f * f.scene.bounds.diagonal());
    FluidOptions fluid;
    fluid.splatting = splatting;
    // Draws `layers` eyes starting at `first`.
    const auto draw = [&](uint32_t first, uint32_t layers, const LodOptions& lod) {
      return draw_into_host(host, renderer, std::span(&views[first], layers), fluid, lod);
    };
    for (const bool with_lod : {false, true}) {
      LodOptions lod;
      if (with_lod) {
        lod.mode = LodMode::DensityPreserving;
        lod.level = 0.4f;
      }
      const Drawn both = draw(0, 2, lod);
      const std::array<Drawn, 2> alone{draw(0, 1, lod), draw(1, 1, lod)};
      for (size_t e = 0; e < 2; ++e) {
        const double db = psnr(both.color[e], alone[e].color[0]);
        size_t depth_differs = 0, fluid_pixels = 0;
        for (size_t i = 0; i < both.depth[e].size(); ++i) {
          depth_differs += both.depth[e][i] != alone[e].depth[0][i];
          fluid_pixels += alone[e].depth[0][i] != 0;  // reversed depth: 0 is the far plane
        }
        std::printf("%s, %s, LOD %s, eye %zu: PSNR %.1f dB against the eye alone; depth differs at %zu of %zu fluid pixels\n",
                    to_string(splatting), anisotropic ? "ellipsoids" : "spheres", with_lod ? "density 0.4" : "off", e, db, depth_differs, fluid_pixels);
        ASSERT_GT(fluid_pixels, size_t(kW) * kH / 20) << "the eye sees too little fluid for the comparison to mean much";
        if (!with_lod) {
          // The same particles, the same passes: the same picture.
          EXPECT_GT(db, 60.0);
          EXPECT_LE(depth_differs, fluid_pixels / 1000);
        } else {
          // One LOD decision for both eyes (the larger importance): each eye
          // keeps at least what it keeps alone, and kept splats grow a little
          // less; measured 31.0 and 33.0 dB.
          EXPECT_GT(db, 28.0);
        }
      }
      // The shared draw list holds what either eye keeps alone (in view of
      // either; with LOD, at least as important as for either).
      std::printf("  drawn: both eyes %llu, left alone %llu, right alone %llu\n", (unsigned long long)both.stats.drawn,
                  (unsigned long long)alone[0].stats.drawn, (unsigned long long)alone[1].stats.drawn);
      EXPECT_GE(both.stats.drawn, std::max(alone[0].stats.drawn, alone[1].stats.drawn));
      EXPECT_LE(both.stats.drawn, alone[0].stats.drawn + alone[1].stats.drawn);
    }
  }
  EXPECT_EQ(host.reports.load(), 0) << (host.messages.empty() ? "" : host.messages[0]);
}

INSTANTIATE_TEST_SUITE_P(Render, Stereo,
                         ::testing::Combine(::testing::Values(Splatting::Compute, Splatting::Raster), ::testing::Bool()),
                         [](const ::testing::TestParamInfo<std::tuple<Splatting, bool>>& i) {
                           return std::string(to_string(std::get<0>(i.param))) + (std::get<1>(i.param) ? "_ellipsoids" : "");
                         });

// One picture through both splat paths (compute: per-pixel atomics; raster:
// point sprites and the depth test), mono, spheres and ellipsoids: the same
// fluid pixels and depth (to 1e-5 relative) and nearly the same colour.
TEST(Anisotropic, ComputeAndRasterSplattingDrawTheSameEllipsoids) {
  testing::TestHost host;
  {
    Context context(host.handles());
    const SyntheticFluid f = synthetic_fluid(30000);
    const Camera cam = framing(f);
    const std::array<View, 1> view{camera_view(cam, {0, 0, kW, kH})};
    for (const bool anisotropic : {false, true}) {
      RendererOptions options;
      options.anisotropic = anisotropic;
      Renderer renderer(context, f.scene, options);
      upload_synthetic(renderer, f);
      std::array<Drawn, 2> drawn;
      for (const Splatting s : {Splatting::Compute, Splatting::Raster}) {
        FluidOptions fluid;
        fluid.splatting = s;
        drawn[s == Splatting::Compute ? 0 : 1] = draw_into_host(host, renderer, view, fluid, {});
      }
      size_t both = 0, only_one = 0;
      double worst = 0;
      for (size_t i = 0; i < drawn[0].depth[0].size(); ++i) {
        const uint32_t a = drawn[0].depth[0][i], b = drawn[1].depth[0][i];
        if ((a != 0) != (b != 0)) ++only_one;
        if (a == 0 || b == 0) continue;
        ++both;
        float fa, fb;
        std::memcpy(&fa, &a, 4);
        std::memcpy(&fb, &b, 4);
        worst = std::max(worst, double(std::fabs(fa - fb) / std::max(fa, fb)));
      }
      const double db = psnr(drawn[0].color[0], drawn[1].color[0]);
      std::printf("%s: compute against raster: PSNR %.1f dB; fluid in one only at %zu of %zu pixels; depth at most %.2g apart "
                  "(relative)\n",
                  anisotropic ? "ellipsoids" : "spheres", db, only_one, both, worst);
      ASSERT_GT(both, size_t(kW) * kH / 20);
      // Measured on lavapipe: the same pixels and depths; colour 99 (spheres) and 97.7 dB.
      EXPECT_LE(only_one, both / 1000);
      EXPECT_LT(worst, 1e-5);
      EXPECT_GT(db, 60.0);
    }
  }
  EXPECT_EQ(host.reports.load(), 0) << (host.messages.empty() ? "" : host.messages[0]);
}

// RendererOptions::anisotropic_limit (the apps' --particles auto): a frame
// of more particles than the limit is drawn as spheres, bit for bit; one at
// the limit as ellipsoids.
TEST(Anisotropic, AFrameOverTheLimitIsDrawnAsSpheres) {
  testing::TestHost host;
  {
    Context context(host.handles());
    const SyntheticFluid f = synthetic_fluid(30000);
    const std::array<View, 1> view{camera_view(framing(f), {0, 0, kW, kH})};
    auto draw = [&](bool anisotropic, uint64_t limit) {
      RendererOptions options;
      options.anisotropic = anisotropic;
      options.anisotropic_limit = limit;
      Renderer renderer(context, f.scene, options);
      upload_synthetic(renderer, f);
      return draw_into_host(host, renderer, view, {}, {}).color[0];
    };
    const uint64_t n = f.particles;
    const auto spheres = draw(false, 0), over = draw(true, n - 1);
    const auto ellipsoids = draw(true, n), unlimited = draw(true, 0);
    EXPECT_EQ(over, spheres) << "over the limit";
    EXPECT_EQ(ellipsoids, unlimited) << "at the limit, as without one";
    EXPECT_LT(psnr(ellipsoids, spheres), 60.0) << "the expectation itself: ellipsoids look different";
  }
  EXPECT_EQ(host.reports.load(), 0) << (host.messages.empty() ? "" : host.messages[0]);
}

// Both eyes in one pass into a host's colour and depth: the shading pass's
// own depth test and write (images that allow storage and copies) give the
// present pass's pixels and depth, in each layer.
TEST(Stereo, ShadingWritesTheHostsDepthAsThePresentPassDoes) {
  testing::TestHost host;
  {
    Context context(host.handles());
    const SyntheticFluid f = synthetic_fluid(30000);
    Renderer renderer(context, f.scene);
    upload_synthetic(renderer, f);
    const Camera cam = framing(f);
    const std::array<View, 2> views = eyes(cam, 0.08f * f.scene.bounds.diagonal());
    for (const vk::Format format : {vk::Format::eD32Sfloat, vk::Format::eD24UnormS8Uint}) {
    const Drawn present = draw_into_host(host, renderer, views, FluidOptions{}, {}, false, format);
    const Drawn shading = draw_into_host(host, renderer, views, FluidOptions{}, {}, true, format);
    EXPECT_EQ(present.stats.passes.back().name, "present");
    EXPECT_EQ(shading.stats.passes.back().name, "depth out");
    const bool d24 = format == vk::Format::eD24UnormS8Uint;
    for (size_t e = 0; e < 2; ++e) {
      size_t color_differs = 0, depth_differs = 0, fluid_pixels = 0;
      for (size_t i = 0; i < present.depth[e].size(); ++i) {
        color_differs += present.color[e][i] != shading.color[e][i];
        const uint32_t mask = d24 ? 0x00ffffffu : 0xffffffffu;  // (X8_D24: the top byte is undefined)
        depth_differs += (present.depth[e][i] & mask) != (shading.depth[e][i] & mask);
        fluid_pixels += (present.depth[e][i] & mask) != 0;  // reversed depth: 0 is the far plane
      }
      std::printf("%s, eye %zu: %zu fluid pixels; colour differs at %zu, depth at %zu\n", d24 ? "D24S8" : "D32", e,
                  fluid_pixels, color_differs, depth_differs);
      ASSERT_GT(fluid_pixels, size_t(kW) * kH / 20);
      EXPECT_EQ(color_differs, 0u);
      // The same formula for the depth, compiled into two shaders: at most a
      // rounding step apart, and then only at a few pixels.
      EXPECT_LE(depth_differs, fluid_pixels / 1000);
    }
    }
  }
  EXPECT_EQ(host.reports.load(), 0) << (host.messages.empty() ? "" : host.messages[0]);
}

}  // namespace
}  // namespace sluice::render
