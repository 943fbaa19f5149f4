// The embedding API as a host uses it: a Context built on the host's own
// instance and device, the fluid recorded into the host's command buffer and
// images, occluded by the host's depth both ways (standard and reversed
// depth), asymmetric frusta, several views in one target, frames in flight,
// sRGB targets. Every test fails on a validation error the host's own
// messenger counts (when the layer is installed).
#include <gtest/gtest.h>

#include <cmath>

#include "render_test_util.h"
#include "sluice/error.h"
#include "sluice/render/offscreen.h"
#include "sluice/render/renderer.h"
#include "sluice/render/staging_allocator.h"
#include "sluice/render/synthetic.h"
#include "test_host.h"

namespace sluice::render {
namespace {

using testing::TestHost;
constexpr uint32_t kW = 160, kH = 120;

Camera front_camera() { return testing::camera_looking_along_y(4); }

// Eye -> Vulkan clip with depth 0 at `near` and 1 at `far` (y down).
Mat4 standard_projection(float fov_deg, float aspect, float near, float far) {
  const float f = 1.0f / std::tan(fov_deg * 0.5f * 3.14159265f / 180.0f);
  Mat4 p;
  p.at(0, 0) = f / aspect;
  p.at(1, 1) = -f;
  p.at(2, 2) = far / (near - far);
  p.at(2, 3) = near * far / (near - far);
  p.at(3, 2) = -1;
  return p;
}

// Target depth of a point `d` along the view axis under projection `p`.
float depth_at(const Mat4& p, float d) { return -p.at(2, 2) + p.at(2, 3) / d; }

// Pixel of world point `x` (top-left origin).
std::array<int, 2> pixel_of(const View& v, Vec3 x) {
  const Vec4 c = v.projection * (v.view * Vec4{x.x, x.y, x.z, 1});
  return {int((c.x / c.w * 0.5f + 0.5f) * float(v.viewport.width)) + int(v.viewport.x),
          int((c.y / c.w * 0.5f + 0.5f) * float(v.viewport.height)) + int(v.viewport.y)};
}

void expect_clean(const TestHost& host) {
  if (!host.validation) return;
  std::string all;
  for (const std::string& m : host.messages) all += m + "\n";
  EXPECT_EQ(host.reports.load(), 0) << all;
}

// A host's kW x kH colour image as a target: contents discarded before,
// left ready for the host's read-back after.
RenderTarget color_target(const TestHost::Image& color) {
  RenderTarget t;
  t.width = kW;
  t.height = kH;
  t.color_image = *color.image;
  t.color_view = *color.view;
  t.color_format = static_cast<VkFormat>(color.format);
  t.color_layout_before = VK_IMAGE_LAYOUT_UNDEFINED;
  t.color_layout_after = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
  return t;
}

// How the fluid reaches a host's colour and depth image.
enum class Into {
  PresentPass,    // plain attachments: the raster present pass
  ShadingCopies,  // storage colour, depth that allows copies: the shading pass, the depth copied out and back
  ShadingReads,   // ... and a sampled depth: the shading pass reads it in place, the depth copied back
};

// A host's kW x kH colour and D32 depth images, with the usage `into` needs.
struct HostImages {
  TestHost::Image color, depth;
};
HostImages host_images(TestHost& host, Into into) {
  using U = vk::ImageUsageFlagBits;
  const bool in_shading = into != Into::PresentPass;
  const vk::ImageUsageFlags storage = in_shading ? U::eStorage : vk::ImageUsageFlags{};
  const vk::ImageUsageFlags copy_in = in_shading ? U::eTransferDst : vk::ImageUsageFlags{};
  const vk::ImageUsageFlags sampled = into == Into::ShadingReads ? U::eSampled : vk::ImageUsageFlags{};
  return {host.image(kW, kH, vk::Format::eR8G8B8A8Unorm, U::eColorAttachment | U::eTransferSrc | storage),
          host.image(kW, kH, vk::Format::eD32Sfloat, U::eDepthStencilAttachment | U::eTransferSrc | copy_in | sampled)};
}
// The target over them (as color_target(), the depth discarded before and
// ready for read-back after), with the flags `into` allows.
RenderTarget host_target(const HostImages& images, Into into) {
  RenderTarget t = color_target(images.color);
  t.depth_image = *images.depth.image;
  t.depth_view = *images.depth.view;
  t.depth_format = VK_FORMAT_D32_SFLOAT;
  t.depth_layout_after = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
  t.color_storage = into != Into::PresentPass;
  t.depth_transfer = into != Into::PresentPass;
  t.depth_sampled = into == Into::ShadingReads;
  return t;
}

// Two spheres of radius 0.4 at x = -1 and x = +1, 4 units in front of the camera.
const std::vector<float> kTwoSpheres{-1, 0, 0, 1, 0, 0};
constexpr float kRadius = 0.4f;

FluidOptions opaque() {
  FluidOptions o;
  o.particle_radius = kRadius;
  o.ground = false;
  o.display_mode = DisplayMode::UnfilteredOpaqueSurface;  // exact sphere depth
  return o;
}

// Reversed depth?  Into which way?
class Occlusion : public ::testing::TestWithParam<std::tuple<bool, Into>> {};

TEST_P(Occlusion, HostDepthHidesTheFluidAndTheFluidHidesTheHost) {
  TestHost host;
  {
    Context context(host.handles());
    EXPECT_FALSE(context.owns_device());
    const SceneInfo scene = scene_for_points(kTwoSpheres, kRadius);
    Renderer renderer(context, scene);
    upload_points(renderer, kTwoSpheres, std::vector<uint16_t>(2, 0), {}, 1);

    const auto [reversed, into] = GetParam();
    const bool in_shading = into != Into::PresentPass;
    const Camera cam = front_camera();
    View view = camera_view(cam, {0, 0, kW, kH});
    if (!reversed) view.projection = standard_projection(cam.fov_deg, float(kW) / kH, 0.5f, 20.0f);
    const HostImages images = host_images(host, into);
    const TestHost::Image &color = images.color, &depth = images.depth;
    // The host's geometry: a wall in front of the left sphere (red), one
    // behind the right sphere (blue); the spheres span 3.6 .. 4.4 in depth.
    const float near_wall = depth_at(view.projection, 3.2f), far_wall = depth_at(view.projection, 4.8f);
    const vk::ClearColorValue red(std::array<float, 4>{1, 0, 0, 1}), blue(std::array<float, 4>{0, 0, 1, 1});

    RenderTarget target = host_target(images, into);
    target.color_layout_before = VK_IMAGE_LAYOUT_ATTACHMENT_OPTIMAL;
    target.depth_layout_before = VK_IMAGE_LAYOUT_ATTACHMENT_OPTIMAL;
    target.background = false;
    FrameSync sync;
    host.submit([&](vk::CommandBuffer c) {
      using S = vk::PipelineStageFlagBits2;
      const std::array to{
          vk::ImageMemoryBarrier2(S::eNone, {}, S::eAllCommands, vk::AccessFlagBits2::eMemoryWrite, vk::ImageLayout::eUndefined,
                                  vk::ImageLayout::eAttachmentOptimal, VK_QUEUE_FAMILY_IGNORED, VK_QUEUE_FAMILY_IGNORED,
                                  *color.image, vk::ImageSubresourceRange(vk::ImageAspectFlagBits::eColor, 0, 1, 0, 1)),
          vk::ImageMemoryBarrier2(S::eNone, {}, S::eAllCommands, vk::AccessFlagBits2::eMemoryWrite, vk::ImageLayout::eUndefined,
                                  vk::ImageLayout::eAttachmentOptimal, VK_QUEUE_FAMILY_IGNORED, VK_QUEUE_FAMILY_IGNORED,
                                  *depth.image, vk::ImageSubresourceRange(vk::ImageAspectFlagBits::eDepth, 0, 1, 0, 1))};
      c.pipelineBarrier2(vk::DependencyInfo({}, {}, {}, to));
      vk::RenderingAttachmentInfo ca(*color.view, vk::ImageLayout::eAttachmentOptimal, {}, {}, {}, vk::AttachmentLoadOp::eDontCare,
                                     vk::AttachmentStoreOp::eStore);
      vk::RenderingAttachmentInfo da(*depth.view, vk::ImageLayout::eAttachmentOptimal, {}, {}, {},
                                     vk::AttachmentLoadOp::eDontCare, vk::AttachmentStoreOp::eStore);
      vk::RenderingInfo info({}, vk::Rect2D({0, 0}, {kW, kH}), 1, 0, ca, &da);
      c.beginRendering(info);
      const vk::ClearRect left(vk::Rect2D({0, 0}, {kW / 2, kH}), 0, 1), right(vk::Rect2D({int32_t(kW / 2), 0}, {kW / 2, kH}), 0, 1);
      c.clearAttachments({vk::ClearAttachment(vk::ImageAspectFlagBits::eColor, 0, red),
                          vk::ClearAttachment(vk::ImageAspectFlagBits::eDepth, 0, vk::ClearDepthStencilValue(near_wall, 0))},
                         left);
      c.clearAttachments({vk::ClearAttachment(vk::ImageAspectFlagBits::eColor, 0, blue),
                          vk::ClearAttachment(vk::ImageAspectFlagBits::eDepth, 0, vk::ClearDepthStencilValue(far_wall, 0))},
                         right);
      c.endRendering();
      sync = renderer.record(static_cast<VkCommandBuffer>(c), target, {&view, 1}, opaque(), {});
    });
    // (host.submit waits on no semaphore: upload_points already waited for its copy.)
    const FrameStats stats = renderer.last_stats();
    ASSERT_FALSE(stats.passes.empty());
    EXPECT_EQ(stats.passes.back().name, in_shading ? "depth out" : "present");
    const std::vector<uint32_t> rgba = host.read(color, kW, kH);
    const std::vector<uint32_t> depth_bits = host.read(depth, kW, kH);
    const auto at = [&](int x, int y) { return rgba[size_t(y) * kW + size_t(x)]; };
    const auto depth_px = [&](int x, int y) {
      float d;
      std::memcpy(&d, &depth_bits[size_t(y) * kW + size_t(x)], 4);
      return d;
    };
    const uint32_t kRed = 0xff0000ffu, kBlue = 0xffff0000u;  // RGBA8 little-endian
    size_t left_not_red = 0, right_fluid = 0;
    for (uint32_t y = 0; y < kH; ++y) {
      for (uint32_t x = 0; x < kW; ++x) {
        if (x < kW / 2) left_not_red += at(int(x), int(y)) != kRed;
        else right_fluid += at(int(x), int(y)) != kBlue;
      }
    }
    EXPECT_EQ(left_not_red, 0u) << "the host's wall in front must hide the fluid";
    EXPECT_GT(right_fluid, 700u) << "the fluid in front of the host's wall must hide it";
    const auto c = pixel_of(view, {1, 0, 0});
    EXPECT_NE(at(c[0], c[1]), kBlue);
    // The fluid's depth is written with the host's projection: its nearest
    // point is 3.6 along the view axis.
    const float written = depth_px(c[0], c[1]);
    EXPECT_NEAR(written, depth_at(view.projection, 3.6f), std::fabs(depth_at(view.projection, 3.6f) - depth_at(view.projection, 3.7f)));
    EXPECT_EQ(depth_px(2, 2), near_wall);
    EXPECT_EQ(depth_px(int(kW) - 3, 2), far_wall);
    std::printf("%s depth, %s: %zu fluid pixels over the far wall, depth at the sphere's centre %.5f (expected %.5f)\n",
                reversed ? "reversed" : "standard",
                into == Into::PresentPass ? "present pass" : into == Into::ShadingCopies ? "shading, copies" : "shading reads it",
                right_fluid, written, depth_at(view.projection, 3.6f));
  }
  expect_clean(host);
}

INSTANTIATE_TEST_SUITE_P(Embedding, Occlusion,
                         ::testing::Combine(::testing::Bool(),
                                            ::testing::Values(Into::PresentPass, Into::ShadingCopies, Into::ShadingReads)),
                         [](const ::testing::TestParamInfo<std::tuple<bool, Into>>& i) {
                           const Into into = std::get<1>(i.param);
                           return std::string(std::get<0>(i.param) ? "reversed" : "standard") +
                                  (into == Into::PresentPass     ? "_present_pass"
                                   : into == Into::ShadingCopies ? "_shading_copies_depth"
                                                                 : "_shading_reads_depth");
                         });

double psnr_region(const std::vector<uint8_t>& a, uint32_t aw, uint32_t ax, const std::vector<uint8_t>& b, uint32_t bw,
                   uint32_t bx, uint32_t w, uint32_t h) {
  double se = 0;
  for (uint32_t y = 0; y < h; ++y) {
    for (uint32_t x = 0; x < w; ++x) {
      for (int k = 0; k < 3; ++k) {
        const double d = double(a[(size_t(y) * aw + ax + x) * 4 + k]) - double(b[(size_t(y) * bw + bx + x) * 4 + k]);
        se += d * d;
      }
    }
  }
  const double mse = se / (double(w) * h * 3);
  return mse == 0 ? 99.0 : 10 * std::log10(255.0 * 255.0 / mse);
}

TEST(Embedding, AsymmetricFrustumMatchesTheCropOfAWiderView) {
  testing::ValidationGuard guard;
  Context& context = testing::context();
  const SyntheticFluid f = synthetic_fluid(30000);
  Renderer renderer(context, f.scene);
  upload_synthetic(renderer, f);
  const Camera cam = Camera::framing(f.scene.bounds, Vec3{0, 0, 1}, 2.0f * kW / kH);
  FluidOptions o;
  OffscreenTarget wide(context, 2 * kW, kH), half(context, kW, kH);
  wide.render(renderer, cam, o, {});
  const std::vector<uint8_t> full = wide.read_rgba8();
  // The right half of the wide view through an off-centre projection.
  View right = camera_view(cam, {0, 0, 2 * kW, kH});
  for (int c = 0; c < 4; ++c) right.projection.at(0, c) = 2 * right.projection.at(0, c) - right.projection.at(3, c);
  right.viewport = {0, 0, kW, kH};
  half.render(renderer, {&right, 1}, o, {});
  const std::vector<uint8_t> crop = half.read_rgba8();
  // The screen-space filter sees other neighbours along the cut: leave 12 columns out.
  const double db = psnr_region(full, 2 * kW, kW + 12, crop, kW, 12, kW - 12, kH);
  std::printf("asymmetric frustum against the crop of the wider view: %.1f dB PSNR\n", db);
  EXPECT_GT(db, 40.0);
}

// A host depth image in UNDEFINED layout, one view over its left part only:
// the shading pass's depth test (images that allow storage and copies)
// leaves what the present pass leaves, the view's fluid depth inside it and
// the far plane everywhere else.
TEST(Embedding, AnUndefinedHostDepthOutsideTheViewEndsAtTheFarPlane) {
  TestHost host;
  {
    Context context(host.handles());
    const SyntheticFluid f = synthetic_fluid(20000);
    Renderer renderer(context, f.scene);
    upload_synthetic(renderer, f);
    const uint32_t w = kW * 3 / 4;
    const Camera cam = Camera::framing(f.scene.bounds, Vec3{0, 0, 1}, float(w) / kH);
    const View view = camera_view(cam, {0, 0, w, kH});
    std::array<std::vector<uint32_t>, 2> depth_of, color_of;
    for (const bool in_shading : {false, true}) {
      const Into into = in_shading ? Into::ShadingCopies : Into::PresentPass;
      const HostImages images = host_images(host, into);
      const RenderTarget target = host_target(images, into);
      host.submit([&](vk::CommandBuffer c) { renderer.record(static_cast<VkCommandBuffer>(c), target, {&view, 1}, FluidOptions{}, {}); });
      EXPECT_EQ(renderer.last_stats().passes.back().name, in_shading ? "depth out" : "present");
      depth_of[in_shading] = host.read(images.depth, kW, kH);
      color_of[in_shading] = host.read(images.color, kW, kH);
    }
    size_t fluid = 0, outside_not_far = 0, differs = 0;
    for (uint32_t y = 0; y < kH; ++y) {
      for (uint32_t x = 0; x < kW; ++x) {
        const size_t i = size_t(y) * kW + x;
        differs += depth_of[0][i] != depth_of[1][i] || (x < w && color_of[0][i] != color_of[1][i]);
        if (x >= w) outside_not_far += depth_of[1][i] != 0;  // reversed depth: 0 is the far plane
        else fluid += depth_of[1][i] != 0;
      }
    }
    EXPECT_GT(fluid, size_t(w) * kH / 20);
    EXPECT_EQ(outside_not_far, 0u);
    EXPECT_EQ(differs, 0u);
  }
  expect_clean(host);
}

// OffscreenTarget::keep_depth: the second frame starts from the first's
// depth (read in place, tested against, written back) and draws the same.
TEST(Embedding, AKeptDepthDrawsTheSameFluidAgain) {
  testing::ValidationGuard guard;
  Context& context = testing::context();
  const SyntheticFluid f = synthetic_fluid(20000);
  Renderer renderer(context, f.scene);
  upload_synthetic(renderer, f);
  const Camera cam = Camera::framing(f.scene.bounds, Vec3{0, 0, 1}, float(kW) / kH);
  OffscreenOptions options;
  options.depth = true;
  options.keep_depth = true;
  OffscreenTarget target(context, kW, kH, options);
  target.render(renderer, cam, FluidOptions{}, {});
  const std::vector<uint8_t> first = target.read_rgba8();
  const FrameStats again = target.render(renderer, cam, FluidOptions{}, {});
  EXPECT_EQ(again.passes.back().name, "depth out");
  EXPECT_TRUE(target.read_rgba8() == first);
}

TEST(Embedding, TwoViewsInOneTargetEachMatchASingleView) {
  testing::ValidationGuard guard;
  Context& context = testing::context();
  const SyntheticFluid f = synthetic_fluid(30000);
  Renderer renderer(context, f.scene);
  upload_synthetic(renderer, f);
  const Camera a = Camera::framing(f.scene.bounds, Vec3{0, 0, 1}, float(kW) / kH);
  Camera b = a;
  b.orbit(0.5f, 0.1f);
  const FluidOptions o;
  OffscreenTarget single(context, kW, kH), pair(context, 2 * kW, kH);
  single.render(renderer, a, o, {});
  const std::vector<uint8_t> only_a = single.read_rgba8();
  single.render(renderer, b, o, {});
  const std::vector<uint8_t> only_b = single.read_rgba8();
  const std::array views{camera_view(a, {0, 0, kW, kH}), camera_view(b, {kW, 0, kW, kH})};
  const FrameStats stats = pair.render(renderer, views, o, {});
  const std::vector<uint8_t> both = pair.read_rgba8();
  EXPECT_GT(psnr_region(both, 2 * kW, 0, only_a, kW, 0, kW, kH), 60.0);
  EXPECT_GT(psnr_region(both, 2 * kW, kW, only_b, kW, 0, kW, kH), 60.0);
  // Each pass is timed once per view and reported summed; the offscreen
  // target allows storage, so shading writes it and there is no present pass.
  ASSERT_FALSE(stats.passes.empty());
  EXPECT_EQ(stats.passes.back().name, "shade");
}

TEST(Embedding, FramesInFlightWithoutWaitingShowTheNewestCompleteFrame) {
  TestHost host;
  {
    Context context(host.handles());
    std::vector<float> xyz(kTwoSpheres);
    const SceneInfo scene = scene_for_points(std::vector<float>{-2, -1, -1, 2, 1, 1}, kRadius);
    RendererOptions ro;
    ro.frames_in_flight = 2;
    Renderer renderer(context, scene, ro);
    using U = vk::ImageUsageFlagBits;
    TestHost::Image color = host.image(kW, kH, vk::Format::eR8G8B8A8Unorm, U::eColorAttachment | U::eTransferSrc);
    const RenderTarget target = color_target(color);
    const View view = camera_view(front_camera(), {0, 0, kW, kH});
    // The host's loop: one command buffer and fence per slot; a slot's fence
    // is waited for before its reuse (the frames-in-flight contract).
    struct Slot {
      vk::raii::CommandBuffer cmd{nullptr};
      vk::raii::Fence fence{nullptr};
      bool used = false;
    };
    std::array<Slot, 2> slots;
    for (Slot& s : slots) {
      s.cmd = std::move(vk::raii::CommandBuffers(host.device(), vk::CommandBufferAllocateInfo(*host.pool(), vk::CommandBufferLevel::ePrimary, 1))[0]);
      s.fence = vk::raii::Fence(host.device(), vk::FenceCreateInfo());
    }
    uint64_t last_ticket = 0;
    const int frames = 12;
    for (int i = 0; i < frames; ++i) {
      Slot& s = slots[size_t(i) % slots.size()];
      if (s.used) {
        while (host.device().waitForFences(*s.fence, VK_TRUE, UINT64_MAX) == vk::Result::eTimeout) {
        }
        host.device().resetFences(*s.fence);
      }
      if (i % 3 == 0) {
        // A new frame: the spheres move right by 0.1 per commit.
        for (size_t p = 0; p < xyz.size(); p += 3) xyz[p] = kTwoSpheres[p] + 0.1f * float(i / 3);
        FrameStaging st = renderer.stage_frame(2, 2);
        const std::vector<float> one(xyz);
        for (uint32_t c = 0; c < 2; ++c) {
          GpuChunk& g = st.chunks[c];
          g = GpuChunk{};
          for (int k = 0; k < 3; ++k) g.lo[k] = g.hi[k] = one[c * 3 + size_t(k)];
          g.first = c;
          g.count = 1;
          std::memset(st.particles.data() + c * st.stride, 0, st.stride);
        }
        last_ticket = renderer.commit_frame();
      }
      vk::CommandBuffer cmd = *s.cmd;
      cmd.reset();
      cmd.begin(vk::CommandBufferBeginInfo(vk::CommandBufferUsageFlagBits::eOneTimeSubmit));
      const FrameSync sync = renderer.record(static_cast<VkCommandBuffer>(cmd), target, {&view, 1}, opaque(), {});
      cmd.end();
      const vk::CommandBufferSubmitInfo cb(cmd);
      const vk::SemaphoreSubmitInfo wait(vk::Semaphore(sync.upload_semaphore), sync.upload_value,
                                         vk::PipelineStageFlags2(sync.wait_stages));
      host.queue().submit2(vk::SubmitInfo2({}, wait, cb), *s.fence);
      s.used = true;
    }
    for (Slot& s : slots) {
      while (s.used && host.device().waitForFences(*s.fence, VK_TRUE, UINT64_MAX) == vk::Result::eTimeout) {
      }
    }
    EXPECT_TRUE(renderer.upload_complete(last_ticket));
    const FrameStats stats = renderer.last_stats();
    EXPECT_EQ(stats.record_index, uint64_t(frames - 1));
    EXPECT_EQ(stats.particles, 2u);
    // The last frame shows the spheres at their last positions.
    const std::vector<uint32_t> rgba = host.read(color, kW, kH);
    OffscreenTarget reference(context, kW, kH);
    reference.render(renderer, front_camera(), opaque(), {});
    const std::vector<uint8_t> expect = reference.read_rgba8();
    std::vector<uint8_t> got(rgba.size() * 4);
    std::memcpy(got.data(), rgba.data(), got.size());
    EXPECT_GT(psnr_region(got, kW, 0, expect, kW, 0, kW, kH), 60.0);
  }
  expect_clean(host);
}

// The two ways into a caller's image give the same pixels: shading straight
// into a storage-capable image (OffscreenTarget), and the present pass into
// a plain colour attachment (UNORM: the same 8-bit values; sRGB: the values
// whose encoding they are, within one level).
TEST(Embedding, PresentPassAndDirectShadingAgree) {
  TestHost host;
  {
    Context context(host.handles());
    const SyntheticFluid f = synthetic_fluid(20000);
    Renderer renderer(context, f.scene);
    upload_synthetic(renderer, f);
    const Camera cam = Camera::framing(f.scene.bounds, Vec3{0, 0, 1}, float(kW) / kH);
    OffscreenTarget unorm(context, kW, kH);
    unorm.render(renderer, cam, FluidOptions{}, {});
    const std::vector<uint8_t> expect = unorm.read_rgba8();
    for (const vk::Format format : {vk::Format::eR8G8B8A8Unorm, vk::Format::eR8G8B8A8Srgb}) {
      using U = vk::ImageUsageFlagBits;
      TestHost::Image color = host.image(kW, kH, format, U::eColorAttachment | U::eTransferSrc);
      const RenderTarget target = color_target(color);
      const View view = camera_view(cam, {0, 0, kW, kH});
      FrameSync sync;
      host.submit([&](vk::CommandBuffer c) {
        sync = renderer.record(static_cast<VkCommandBuffer>(c), target, {&view, 1}, FluidOptions{}, {});
      });
      const FrameStats stats = renderer.last_stats();
      ASSERT_FALSE(stats.passes.empty());
      EXPECT_EQ(stats.passes.back().name, "present");
      const std::vector<uint32_t> rgba = host.read(color, kW, kH);
      int worst = 0;
      for (size_t i = 0; i < rgba.size(); ++i) {
        for (int k = 0; k < 3; ++k) {
          worst = std::max(worst, std::abs(int((rgba[i] >> (8 * k)) & 0xff) - int(expect[i * 4 + size_t(k)])));
        }
      }
      EXPECT_LE(worst, format == vk::Format::eR8G8B8A8Unorm ? 0 : 1) << "largest difference in 8-bit levels";
    }
  }
  expect_clean(host);
}

// The host's scene in the refraction: a red wall behind the water (the
// host's scene colour, RenderTarget::scene_color_image) shows red through
// it; without it the water refracts sluice's sky.
TEST(Embedding, TheHostsSceneShowsThroughTheWater) {
  TestHost host;
  {
    Context context(host.handles());
    const SyntheticFluid f = synthetic_fluid(20000);
    Renderer renderer(context, f.scene);
    upload_synthetic(renderer, f);
    const Camera cam = Camera::framing(f.scene.bounds, Vec3{0, 0, 1}, float(kW) / kH);
    const View view = camera_view(cam, {0, 0, kW, kH});
    using U = vk::ImageUsageFlagBits;
    using S = vk::PipelineStageFlagBits2;
    using A = vk::AccessFlagBits2;
    const vk::ImageSubresourceRange all(vk::ImageAspectFlagBits::eColor, 0, 1, 0, 1);
    TestHost::Image wall = host.image(kW, kH, vk::Format::eR8G8B8A8Unorm, U::eSampled | U::eTransferDst);
    host.submit([&](vk::CommandBuffer c) {
      const vk::ImageMemoryBarrier2 to_clear(S::eNone, {}, S::eClear, A::eTransferWrite, vk::ImageLayout::eUndefined,
                                             vk::ImageLayout::eTransferDstOptimal, VK_QUEUE_FAMILY_IGNORED, VK_QUEUE_FAMILY_IGNORED,
                                             *wall.image, all);
      c.pipelineBarrier2(vk::DependencyInfo({}, {}, {}, to_clear));
      c.clearColorImage(*wall.image, vk::ImageLayout::eTransferDstOptimal, vk::ClearColorValue(std::array<float, 4>{1, 0, 0, 1}),
                        all);
      const vk::ImageMemoryBarrier2 to_sample(S::eClear, A::eTransferWrite, S::eComputeShader, A::eShaderSampledRead,
                                              vk::ImageLayout::eTransferDstOptimal, vk::ImageLayout::eShaderReadOnlyOptimal,
                                              VK_QUEUE_FAMILY_IGNORED, VK_QUEUE_FAMILY_IGNORED, *wall.image, all);
      c.pipelineBarrier2(vk::DependencyInfo({}, {}, {}, to_sample));
    });
    FluidOptions water;
    water.ground = false;
    const auto draw = [&](bool with_wall) {
      TestHost::Image color = host.image(kW, kH, vk::Format::eR8G8B8A8Unorm, U::eColorAttachment | U::eTransferSrc);
      RenderTarget target = color_target(color);
      if (with_wall) {
        target.scene_color_image = *wall.image;
        target.scene_color_format = VK_FORMAT_R8G8B8A8_UNORM;
        target.scene_color_layout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
      }
      host.submit([&](vk::CommandBuffer c) { renderer.record(static_cast<VkCommandBuffer>(c), target, {&view, 1}, water, {}); });
      return host.read(color, kW, kH);
    };
    const std::vector<uint32_t> sky = draw(false), red = draw(true);
    // Pixels without fluid are the same sky in both; the fluid's differ.
    size_t fluid = 0;
    std::array<double, 3> through_wall{}, through_sky{};
    for (size_t i = 0; i < sky.size(); ++i) {
      if (sky[i] == red[i]) continue;
      ++fluid;
      for (int k = 0; k < 3; ++k) {
        through_wall[size_t(k)] += double((red[i] >> (8 * k)) & 0xff);
        through_sky[size_t(k)] += double((sky[i] >> (8 * k)) & 0xff);
      }
    }
    ASSERT_GT(fluid, 1000u) << "the water covers too little of the image";
    for (double& c : through_wall) c /= double(fluid);
    for (double& c : through_sky) c /= double(fluid);
    std::printf("%zu water pixels: mean RGB through the wall %.0f %.0f %.0f, through the sky %.0f %.0f %.0f\n", fluid,
                through_wall[0], through_wall[1], through_wall[2], through_sky[0], through_sky[1], through_sky[2]);
    EXPECT_GT(through_wall[0], 1.5 * through_wall[1]) << "red shows through the water";
    EXPECT_GT(through_wall[0], 1.5 * through_wall[2]) << "red shows through the water";
    EXPECT_LT(through_sky[0], through_sky[2]) << "without the host's scene the water refracts the (blue) sky";
  }
  expect_clean(host);
}

TEST(Embedding, HostHandlesAreChecked) {
  EXPECT_THROW(Context(HostVulkan{}), sluice::render::Error);
  const DeviceFeatures f = required_device_features();
  const DeviceFeatures copy = f;  // the copy's chain points into the copy
  EXPECT_EQ(copy.features2.pNext, &copy.vulkan11);
  EXPECT_EQ(copy.vulkan12.pNext, &copy.vulkan13);
  EXPECT_EQ(copy.vulkan13.pNext, nullptr);
  EXPECT_TRUE(copy.vulkan13.dynamicRendering);
  EXPECT_TRUE(copy.vulkan11.multiview);
}

}  // namespace
}  // namespace sluice::render

namespace sluice::render {
namespace {

TEST(Embedding, RecordRefusesTargetsAndViewsThatDoNotFit) {
  TestHost host;
  {
    Context context(host.handles());
    Renderer renderer(context, scene_for_points(kTwoSpheres, kRadius));
    using U = vk::ImageUsageFlagBits;
    TestHost::Image color = host.image(kW, kH, vk::Format::eR8G8B8A8Unorm, U::eColorAttachment | U::eTransferSrc);
    const RenderTarget target = color_target(color);
    const View whole = camera_view(front_camera(), {0, 0, kW, kH});
    host.submit([&](vk::CommandBuffer c) {
      const auto cmd = static_cast<VkCommandBuffer>(c);
      const FluidOptions o;
      EXPECT_THROW(renderer.record(cmd, target, {}, o, {}), sluice::render::Error);  // no view
      View outside = whole;
      outside.viewport.x = 1;  // reaches one pixel past the right edge
      EXPECT_THROW(renderer.record(cmd, target, {&outside, 1}, o, {}), sluice::render::Error);
      const std::array uneven{whole, camera_view(front_camera(), {0, 0, kW / 2, kH})};
      EXPECT_THROW(renderer.record(cmd, target, uneven, o, {}), sluice::render::Error);
      RenderTarget no_view = target;
      no_view.color_view = VK_NULL_HANDLE;
      EXPECT_THROW(renderer.record(cmd, no_view, {&whole, 1}, o, {}), sluice::render::Error);
      RenderTarget layers = target;
      layers.layer_count = 2;
      EXPECT_THROW(renderer.record(cmd, layers, {&whole, 1}, o, {}), sluice::render::Error);
      EXPECT_THROW(renderer.record(VK_NULL_HANDLE, target, {&whole, 1}, o, {}), sluice::render::Error);
    });
    EXPECT_EQ(renderer.last_stats().record_index, 0u);  // nothing was recorded
  }
  expect_clean(host);
}

}  // namespace
}  // namespace sluice::render

namespace sluice::render {
namespace {

// The staging heap's budget for the prefetch window is what the heap can
// still give: it does not grow as the allocator takes more of the heap.
// Without VK_EXT_memory_budget (a host that did not enable it) nothing is
// known about other users; the figure is the heap's size, once.
TEST(StagingBudget, DoesNotGrowWithTheWindow) {
  for (const bool with_extension : {true, false}) {
    TestHost host;
    if (with_extension && !host.memory_budget) continue;
    HostVulkan h = host.handles();
    h.memory_budget_enabled = with_extension;
    Context context(h);
    StagingAllocator staging(context);
    // nullptr where staging lives in system memory (device_budget()'s contract).
    const runtime::DeviceMemoryBudget* budget = staging.device_budget();
    if (budget == nullptr) GTEST_SKIP() << "staging memory is not device memory here";
    const uint64_t before = budget->available_bytes();
    runtime::FrameLayout layout;
    layout.particles = 1 << 20;  // 8 MiB frames
    std::vector<runtime::FrameBuffers> frames;
    for (int i = 0; i < 4; ++i) frames.push_back(staging.allocate(layout));
    const uint64_t after = budget->available_bytes();
    // With the extension the heap's usage grew by what was allocated and the
    // allocator's blocks are added back: about the same figure (other users
    // may move it a little). Without it: exactly the same.
    if (with_extension) {
      EXPECT_LT(after, before + staging.held_bytes() / 2) << "the held blocks are counted once";
    } else {
      EXPECT_EQ(after, before) << "without the extension the held blocks were counted on top of the heap's size";
    }
    for (auto& f : frames) staging.release(f);
  }
}

}  // namespace
}  // namespace sluice::render
