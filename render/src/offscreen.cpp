// OffscreenTarget: an RGBA8 image (and optionally D32 depth) of its own, a
// command buffer, fence and readback buffer per frame in flight.
#include "sluice/render/offscreen.h"

#include <cstring>
#include <stdexcept>

#include "vk_common.h"
#include "sluice/error.h"

namespace sluice::render {

namespace {

struct Slot {
  vk::raii::CommandBuffer cmd{nullptr};
  vk::raii::Fence fence{nullptr};
  Buffer readback;
  bool submitted = false;
};

}  // namespace

struct detail::OffscreenTargetImpl {
  detail::ContextImpl& ctx;
  OffscreenOptions options;
  Texture color, depth;
  vk::raii::CommandPool pool{nullptr};
  std::vector<Slot> slots;
  uint64_t frames = 0;
  bool depth_written = false;  // the depth image holds a frame (keep_depth)
  int last = -1;  // slot of the last frame submitted

  OffscreenTargetImpl(detail::ContextImpl& c, const OffscreenOptions& o) : ctx(c), options(o) {}
  void wait(Slot& s) {
    if (!s.submitted) return;
    ctx.wait(*s.fence);
    s.submitted = false;
  }
  void wait_all() {
    for (Slot& s : slots) wait(s);
  }
  void create(uint32_t width, uint32_t height) {
    if (width == 0 || height == 0) throw Error("offscreen target: size must be at least 1x1");
    using U = vk::ImageUsageFlagBits;
    if (options.layers < 1 || options.layers > 2) throw Error("offscreen target: 1 or 2 layers");
    color = create_texture(ctx, {width, height}, vk::Format::eR8G8B8A8Unorm, U::eColorAttachment | U::eStorage | U::eTransferSrc,
                           options.layers);
    depth_written = false;
    if (options.depth) {
      const vk::ImageUsageFlags copies =
          options.depth_transfer ? U::eTransferSrc | U::eTransferDst | U::eSampled : vk::ImageUsageFlags{};
      depth = create_texture(ctx, {width, height}, vk::Format::eD32Sfloat, U::eDepthStencilAttachment | copies, options.layers);
    }
    for (Slot& s : slots) {
      s.readback = options.read_back ? create_buffer(ctx, vk::DeviceSize(width) * height * 4, vk::BufferUsageFlagBits::eTransferDst,
                                                     MemoryKind::Readback)
                                     : Buffer{};
    }
    last = -1;
  }
};

OffscreenTarget::OffscreenTarget(Context& context, uint32_t width, uint32_t height, const OffscreenOptions& options)
    : impl_(std::make_unique<Impl>(context_impl(context), options)) {
  Impl& o = *impl_;
  if (options.frames_in_flight < 1 || options.frames_in_flight > 8) {
    throw Error("offscreen target: frames_in_flight must be 1..8");
  }
  o.pool = vk::raii::CommandPool(o.ctx.device, vk::CommandPoolCreateInfo(vk::CommandPoolCreateFlagBits::eResetCommandBuffer,
                                                                         o.ctx.graphics_family));
  o.slots.resize(options.frames_in_flight);
  for (Slot& s : o.slots) {
    s.cmd = std::move(vk::raii::CommandBuffers(o.ctx.device,
                                               vk::CommandBufferAllocateInfo(*o.pool, vk::CommandBufferLevel::ePrimary, 1))[0]);
    s.fence = vk::raii::Fence(o.ctx.device, vk::FenceCreateInfo());
  }
  o.create(width, height);
}

OffscreenTarget::~OffscreenTarget() {
  if (impl_) impl_->wait_all();
}

void OffscreenTarget::resize(uint32_t width, uint32_t height) {
  Impl& o = *impl_;
  if (width == o.color.extent.width && height == o.color.extent.height) return;
  o.wait_all();
  o.create(width, height);
}

uint32_t OffscreenTarget::width() const { return impl_->color.extent.width; }
uint32_t OffscreenTarget::height() const { return impl_->color.extent.height; }
void OffscreenTarget::finish() { impl_->wait_all(); }

FrameStats OffscreenTarget::render(Renderer& renderer, const Camera& camera, const FluidOptions& options, const LodOptions& lod) {
  const View view = camera_view(camera, Viewport{0, 0, width(), height()});
  return render(renderer, std::span<const View>(&view, 1), options, lod);
}

FrameStats OffscreenTarget::render(Renderer& renderer, std::span<const View> views, const FluidOptions& options,
                                   const LodOptions& lod, bool background) {
  Impl& o = *impl_;
  if (o.slots.size() > renderer.options().frames_in_flight) {
    throw Error("offscreen target: more frames in flight than the renderer keeps");
  }
  const int index = int(o.frames % o.slots.size());
  Slot& slot = o.slots[size_t(index)];
  o.wait(slot);  // the renderer's contract: this slot's previous frame is done
  RenderTarget target;
  target.width = width();
  target.height = height();
  target.color_image = static_cast<VkImage>(*o.color.image);
  target.color_view = static_cast<VkImageView>(*o.color.view);
  target.color_format = VK_FORMAT_R8G8B8A8_UNORM;
  target.color_layout_before = VK_IMAGE_LAYOUT_UNDEFINED;
  target.color_layout_after = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
  target.color_storage = true;
  if (o.options.depth) {
    target.depth_image = static_cast<VkImage>(*o.depth.image);
    target.depth_view = static_cast<VkImageView>(*o.depth.view);
    target.depth_format = VK_FORMAT_D32_SFLOAT;
    target.depth_layout_before = VK_IMAGE_LAYOUT_UNDEFINED;
    if (o.options.keep_depth && o.depth_written) target.depth_layout_before = target.depth_layout_after;
    o.depth_written = true;
    target.depth_transfer = o.options.depth_transfer;
    target.depth_sampled = o.options.depth_transfer;
  }
  target.background = background;
  target.layer_count = o.options.layers;
  vk::CommandBuffer cmd = *slot.cmd;
  cmd.reset();
  cmd.begin(vk::CommandBufferBeginInfo(vk::CommandBufferUsageFlagBits::eOneTimeSubmit));
  const FrameSync sync = renderer.record(static_cast<VkCommandBuffer>(cmd), target, views, options, lod);
  if (o.options.read_back) {
    // The image to this slot's readback buffer: read_rgba8() then needs no second submission.
    const vk::BufferImageCopy region(0, 0, 0, vk::ImageSubresourceLayers(vk::ImageAspectFlagBits::eColor, 0, 0, 1), {},
                                     vk::Extent3D(o.color.extent, 1));
    cmd.copyImageToBuffer(*o.color.image, vk::ImageLayout::eTransferSrcOptimal, *slot.readback.buffer, region);
    memory_barrier(cmd, vk::PipelineStageFlagBits2::eCopy, vk::AccessFlagBits2::eTransferWrite,
                   vk::PipelineStageFlagBits2::eHost, vk::AccessFlagBits2::eHostRead);
  }
  cmd.end();
  const vk::CommandBufferSubmitInfo cb(cmd);
  const vk::SemaphoreSubmitInfo wait(vk::Semaphore(sync.upload_semaphore), sync.upload_value,
                                     vk::PipelineStageFlags2(sync.wait_stages));
  o.ctx.device.resetFences(*slot.fence);
  o.ctx.submit(o.ctx.graphics_queue, vk::SubmitInfo2({}, wait, cb), *slot.fence);
  slot.submitted = true;
  o.last = index;
  ++o.frames;
  if (o.slots.size() == 1) o.wait(slot);
  return renderer.last_stats();
}

std::vector<uint8_t> OffscreenTarget::read_rgba8() {
  Impl& o = *impl_;
  o.wait_all();
  const size_t bytes = size_t(width()) * height() * 4;
  std::vector<uint8_t> out(bytes, 0);
  if (o.last >= 0 && o.options.read_back) std::memcpy(out.data(), o.slots[size_t(o.last)].readback.mapped, bytes);
  return out;
}

}  // namespace sluice::render
