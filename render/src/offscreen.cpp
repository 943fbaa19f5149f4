// OffscreenTarget: an RGBA8 image (and optionally D32 depth) of its own, a
// command buffer and a fence; one record() per render(), submitted and
// waited for.
#include "sluice/render/offscreen.h"

#include <cstring>
#include <stdexcept>

#include "vk_common.h"

namespace sluice::render {

struct OffscreenTarget::Impl {
  Context::Impl& ctx;
  bool with_depth = false;
  Texture color, depth;
  Buffer readback;
  vk::raii::CommandPool pool{nullptr};
  vk::raii::CommandBuffer cmd{nullptr};
  vk::raii::Fence fence{nullptr};
  bool submitted = false;
  bool rendered = false;

  Impl(Context::Impl& c, bool d) : ctx(c), with_depth(d) {}
  void wait() {
    if (!submitted) return;
    while (ctx.device.waitForFences(*fence, VK_TRUE, UINT64_MAX) == vk::Result::eTimeout) {
    }
    submitted = false;
  }
  void create(uint32_t width, uint32_t height) {
    if (width == 0 || height == 0) throw std::invalid_argument("offscreen target: size must be at least 1x1");
    using U = vk::ImageUsageFlagBits;
    color = create_texture(ctx, {width, height}, vk::Format::eR8G8B8A8Unorm, U::eColorAttachment | U::eTransferSrc);
    if (with_depth) depth = create_texture(ctx, {width, height}, vk::Format::eD32Sfloat, U::eDepthStencilAttachment);
    readback = create_buffer(ctx, vk::DeviceSize(width) * height * 4, vk::BufferUsageFlagBits::eTransferDst, MemoryKind::Readback);
    rendered = false;
  }
};

OffscreenTarget::OffscreenTarget(Context& context, uint32_t width, uint32_t height, bool depth)
    : impl_(std::make_unique<Impl>(context_impl(context), depth)) {
  Impl& o = *impl_;
  o.create(width, height);
  o.pool = vk::raii::CommandPool(o.ctx.device, vk::CommandPoolCreateInfo(vk::CommandPoolCreateFlagBits::eResetCommandBuffer,
                                                                         o.ctx.graphics_family));
  o.cmd = std::move(vk::raii::CommandBuffers(o.ctx.device,
                                             vk::CommandBufferAllocateInfo(*o.pool, vk::CommandBufferLevel::ePrimary, 1))[0]);
  o.fence = vk::raii::Fence(o.ctx.device, vk::FenceCreateInfo());
}

OffscreenTarget::~OffscreenTarget() {
  if (impl_) impl_->wait();
}

void OffscreenTarget::resize(uint32_t width, uint32_t height) {
  Impl& o = *impl_;
  if (width == o.color.extent.width && height == o.color.extent.height) return;
  o.wait();
  o.create(width, height);
}

uint32_t OffscreenTarget::width() const { return impl_->color.extent.width; }
uint32_t OffscreenTarget::height() const { return impl_->color.extent.height; }

FrameStats OffscreenTarget::render(Renderer& renderer, const Camera& camera, const FluidOptions& options, const LodOptions& lod) {
  const View view = camera_view(camera, Viewport{0, 0, width(), height()});
  return render(renderer, std::span<const View>(&view, 1), options, lod);
}

FrameStats OffscreenTarget::render(Renderer& renderer, std::span<const View> views, const FluidOptions& options,
                                   const LodOptions& lod, bool background) {
  Impl& o = *impl_;
  o.wait();
  RenderTarget target;
  target.width = width();
  target.height = height();
  target.color_image = static_cast<VkImage>(*o.color.image);
  target.color_view = static_cast<VkImageView>(*o.color.view);
  target.color_format = VK_FORMAT_R8G8B8A8_UNORM;
  target.color_layout_before = VK_IMAGE_LAYOUT_UNDEFINED;
  target.color_layout_after = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
  if (o.with_depth) {
    target.depth_image = static_cast<VkImage>(*o.depth.image);
    target.depth_view = static_cast<VkImageView>(*o.depth.view);
    target.depth_format = VK_FORMAT_D32_SFLOAT;
    target.depth_layout_before = VK_IMAGE_LAYOUT_UNDEFINED;
  }
  target.background = background;
  vk::CommandBuffer cmd = *o.cmd;
  cmd.reset();
  cmd.begin(vk::CommandBufferBeginInfo(vk::CommandBufferUsageFlagBits::eOneTimeSubmit));
  const FrameSync sync = renderer.record(static_cast<VkCommandBuffer>(cmd), target, views, options, lod);
  // The image to the readback buffer while we are at it: a copy is cheap
  // next to the frame and read_rgba8() then needs no second submission.
  const vk::BufferImageCopy region(0, 0, 0, vk::ImageSubresourceLayers(vk::ImageAspectFlagBits::eColor, 0, 0, 1), {},
                                   vk::Extent3D(o.color.extent, 1));
  cmd.copyImageToBuffer(*o.color.image, vk::ImageLayout::eTransferSrcOptimal, *o.readback.buffer, region);
  memory_barrier(cmd, vk::PipelineStageFlagBits2::eCopy, vk::AccessFlagBits2::eTransferWrite, vk::PipelineStageFlagBits2::eHost,
                 vk::AccessFlagBits2::eHostRead);
  cmd.end();
  const vk::CommandBufferSubmitInfo cb(cmd);
  const vk::SemaphoreSubmitInfo wait(vk::Semaphore(sync.upload_semaphore), sync.upload_value,
                                     vk::PipelineStageFlags2(sync.wait_stages));
  o.ctx.device.resetFences(*o.fence);
  o.ctx.graphics_queue.submit2(vk::SubmitInfo2({}, wait, cb), *o.fence);
  o.submitted = true;
  o.rendered = true;
  o.wait();
  return renderer.last_stats();
}

std::vector<uint8_t> OffscreenTarget::read_rgba8() {
  Impl& o = *impl_;
  o.wait();
  const size_t bytes = size_t(width()) * height() * 4;
  std::vector<uint8_t> out(bytes, 0);
  if (o.rendered) std::memcpy(out.data(), o.readback.mapped, bytes);
  return out;
}

}  // namespace sluice::render
