// The passes of a frame, one function each (see passes.h), with a timestamp
// after each.
#include "passes.h"

#include "globals.h"

#include <algorithm>
#include <bit>

namespace sluice::render {
namespace {

using Stage = vk::PipelineStageFlagBits2;
using Access = vk::AccessFlagBits2;

std::array<uint32_t, 2> groups(vk::Extent2D e, uint32_t n) { return {(e.width + n - 1) / n, (e.height + n - 1) / n}; }

bool has_stencil(vk::Format f) {
  return f == vk::Format::eD24UnormS8Uint || f == vk::Format::eD32SfloatS8Uint || f == vk::Format::eD16UnormS8Uint;
}

// A caller's image from one layout to another, ordered against all work on
// the queue before and after (the host's own passes are unknown to us).
// A host image's layers of `target` from one layout to another; by default
// after everything before and before everything after on the queue.
vk::ImageMemoryBarrier2 host_barrier(VkImage image, vk::ImageAspectFlags aspect, const RenderTarget& target, VkImageLayout from,
                                     vk::ImageLayout to, vk::PipelineStageFlags2 src_stage = Stage::eAllCommands,
                                     vk::AccessFlags2 src_access = Access::eMemoryWrite,
                                     vk::PipelineStageFlags2 dst_stage = Stage::eAllCommands,
                                     vk::AccessFlags2 dst_access = Access::eMemoryRead | Access::eMemoryWrite) {
  return vk::ImageMemoryBarrier2(src_stage, src_access, dst_stage, dst_access, vk::ImageLayout(from), to, VK_QUEUE_FAMILY_IGNORED,
                                 VK_QUEUE_FAMILY_IGNORED, vk::Image(image),
                                 vk::ImageSubresourceRange(aspect, 0, 1, target.base_layer, target.layer_count));
}

vk::ImageAspectFlags depth_aspect(VkFormat f) {
  vk::ImageAspectFlags a = vk::ImageAspectFlagBits::eDepth;
  if (has_stencil(vk::Format(f))) a |= vk::ImageAspectFlagBits::eStencil;
  return a;
}

// The host's depth image from GENERAL (where it lives while sluice's
// commands run) into a copy's own layout around that copy, and back: copies
// in GENERAL are slower on some drivers (the validation layer warns).
void relayout_depth(vk::CommandBuffer cmd, const RenderTarget& target, vk::ImageLayout from, vk::ImageLayout to,
                    vk::PipelineStageFlags2 src_stage, vk::AccessFlags2 src_access, vk::PipelineStageFlags2 dst_stage,
                    vk::AccessFlags2 dst_access) {
  const vk::ImageMemoryBarrier2 b = host_barrier(target.depth_image, depth_aspect(target.depth_format), target,
                                                  VkImageLayout(from), to, src_stage, src_access, dst_stage, dst_access);
  cmd.pipelineBarrier2(vk::DependencyInfo({}, {}, {}, b));
}

}  // namespace

bool is_srgb(vk::Format f) {
  switch (f) {
    case vk::Format::eR8G8B8A8Srgb:
    case vk::Format::eB8G8R8A8Srgb:
    case vk::Format::eA8B8G8R8SrgbPack32:
    case vk::Format::eR8G8B8Srgb:
    case vk::Format::eB8G8R8Srgb:
      return true;
    default:
      return false;
  }
}

namespace {
// The copy of the depth aspect holds 4-byte texels of these two kinds: a
// float, or X8_D24 (the shading pass reads and writes both).
bool float_depth(VkFormat f) { return f == VK_FORMAT_D32_SFLOAT || f == VK_FORMAT_D32_SFLOAT_S8_UINT; }
bool d24_depth(VkFormat f) { return f == VK_FORMAT_D24_UNORM_S8_UINT || f == VK_FORMAT_X8_D24_UNORM_PACK32; }
}  // namespace

Output output_path(const RenderTarget& target) {
  const bool shading_writes = target.color_storage && !is_srgb(vk::Format(target.color_format)) &&
                              (target.background || target.color_layout_before != VK_IMAGE_LAYOUT_UNDEFINED);
  if (!shading_writes) return Output::Present;
  if (!target.depth_view) return Output::Direct;
  const bool four_bytes = float_depth(target.depth_format) || d24_depth(target.depth_format);
  return target.depth_transfer && four_bytes ? Output::DepthInShading : Output::Present;
}

bool reads_host_depth_in_place(const RenderTarget& target, Output output) {
  // Float depth only: a 24-bit value read as a normalized float need not
  // come back to the same integer, and the copy back would move it.
  return output == Output::DepthInShading && target.depth_sampled && float_depth(target.depth_format) &&
         target.depth_layout_before != VK_IMAGE_LAYOUT_UNDEFINED;
}

PassRecorder::PassRecorder(detail::RendererImpl& r, vk::CommandBuffer cmd, FrameSlot& slot, uint32_t slot_index)
    : r_(r), cmd_(cmd), slot_(slot), first_stamp_(slot_index * kStampsPerSlot) {}

void PassRecorder::stamp(const char* name) {
  if (!r_.timestamps_valid) return;
  const uint32_t n = uint32_t(slot_.stamp_names.size()) + 1;
  if (n >= kStampsPerSlot) return;
  cmd_.writeTimestamp2(Stage::eAllCommands, *r_.timestamps, first_stamp_ + n);
  slot_.stamp_names.push_back(name);
}

void PassRecorder::push(uint32_t p0, uint32_t p1, uint32_t p2) {
  pc_.param0 = p0;
  pc_.param1 = p1;
  pc_.param2 = p2;
  cmd_.pushConstants<PushConstants>(*r_.layout, kAllStages, 0, pc_);
}

// Storage writes before, storage and sampled reads after: the filter and
// shading passes sample what the splat passes stored (synchronization
// validation reports READ_AFTER_WRITE on thick_a_tex without the sampled read).
void PassRecorder::compute_to_compute() {
  memory_barrier(cmd_, Stage::eComputeShader, Access::eShaderStorageWrite, Stage::eComputeShader,
                 Access::eShaderStorageRead | Access::eShaderStorageWrite | Access::eShaderSampledRead);
}

void PassRecorder::begin_frame(const RenderTarget& target, Output output) {
  const bool direct = output != Output::Present;
  if (r_.timestamps_valid) {
    cmd_.resetQueryPool(*r_.timestamps, first_stamp_, kStampsPerSlot);
    cmd_.writeTimestamp2(Stage::eAllCommands, *r_.timestamps, first_stamp_);
  }
  // Shared targets and work lists: after every earlier frame on the queue.
  memory_barrier(cmd_, Stage::eAllCommands, Access::eMemoryWrite, Stage::eAllCommands, Access::eMemoryRead | Access::eMemoryWrite);
  Targets& t = r_.targets;
  if (!t.initialized) {
    // New targets: every compute image lives in GENERAL; cleared so reads
    // before the first write are defined. Compute splatting's depth starts
    // "infinitely far" (all bits set); the resolve pass resets it after use.
    std::vector<vk::ImageMemoryBarrier2> barriers;
    const std::array all{&t.depth_raw, &t.depth_a, &t.depth_b, &t.thick_raw, &t.thick_a, &t.thick_b,
                         &t.depth_u, &t.thick_u, &t.thick_attr_u, &t.color, &t.aux};
    for (const Texture* x : all) {
      barriers.push_back(image_barrier(*x, vk::ImageLayout::eUndefined, vk::ImageLayout::eGeneral, Stage::eNone, {},
                                       Stage::eClear, Access::eTransferWrite));
    }
    cmd_.pipelineBarrier2(vk::DependencyInfo({}, {}, {}, barriers));
    const vk::ClearColorValue zero(std::array<float, 4>{0, 0, 0, 0});
    const vk::ClearColorValue far(std::array<uint32_t, 4>{0xffffffffu, 0xffffffffu, 0xffffffffu, 0xffffffffu});
    const vk::ImageSubresourceRange range(vk::ImageAspectFlagBits::eColor, 0, 1, 0, VK_REMAINING_ARRAY_LAYERS);
    for (const Texture* x : all) cmd_.clearColorImage(*x->image, vk::ImageLayout::eGeneral, x == &t.depth_u ? far : zero, range);
    memory_barrier(cmd_, Stage::eClear, Access::eTransferWrite, Stage::eAllCommands, Access::eMemoryRead | Access::eMemoryWrite);
    t.initialized = true;
  }
  std::vector<vk::ImageMemoryBarrier2> to;
  to.push_back(host_barrier(target.color_image, vk::ImageAspectFlagBits::eColor, target, target.color_layout_before,
                            direct ? vk::ImageLayout::eGeneral : vk::ImageLayout::eAttachmentOptimal));
  if (target.depth_image) {
    to.push_back(host_barrier(target.depth_image, depth_aspect(target.depth_format), target, target.depth_layout_before,
                              output == Output::DepthInShading ? vk::ImageLayout::eGeneral : vk::ImageLayout::eAttachmentOptimal));
  }
  cmd_.pipelineBarrier2(vk::DependencyInfo({}, {}, {}, to));
}

void PassRecorder::begin_view(uint32_t globals_offset, const FrameSet* frame, uint32_t layers) {
  layers_ = layers;
  const vk::DescriptorSet set = *slot_.set;
  cmd_.bindDescriptorSets(vk::PipelineBindPoint::eCompute, *r_.layout, 0, set, globals_offset);
  cmd_.bindDescriptorSets(vk::PipelineBindPoint::eGraphics, *r_.layout, 0, set, globals_offset);
  pc_ = PushConstants{};
  have_frame_ = frame && frame->chunk_count > 0 && *frame->particles.buffer;
  if (frame && *frame->particles.buffer) {
    pc_.particles = frame->particles.address;
    pc_.chunks = frame->chunks.address;
    pc_.attributes = frame->has_attribute ? frame->attributes.address : frame->chunks.address;
    pc_.chunk_count = frame->chunk_count;
    if (frame->classified) {
      pc_.chunk_count += 1;  // the blobs' row
      pc_.surface = frame->surface.address;
    }
    if (frame->shaped) pc_.shapes = frame->shapes.address;
  }
  pc_.blocks = r_.blocks.address;
  pc_.draws = r_.draws.address;
  pc_.args = r_.args.address;
  pc_.big = r_.big.address;
  // The previous view's passes are done with the shared targets and lists.
  memory_barrier(cmd_, Stage::eAllCommands, Access::eMemoryWrite, Stage::eAllCommands, Access::eMemoryRead | Access::eMemoryWrite);
}

void PassRecorder::prepare(FrameSet& frame) {
  const FrameBand::Wanted wanted{.classify = frame.band_eligible && !frame.classified,
                                 .shapes = frame.shape_eligible && !frame.shaped};
  if (!wanted.classify && !wanted.shapes) return;
  r_.band->record(cmd_, frame, r_.scene.coding == io::PositionCoding::Float32, wanted,
                  [&](Buffer&& b) { r_.retire(std::move(b)); });
  memory_barrier(cmd_, Stage::eComputeShader | Stage::eTransfer, Access::eShaderStorageWrite | Access::eTransferWrite,
                 Stage::eComputeShader | Stage::eVertexShader | Stage::eFragmentShader,
                 Access::eShaderStorageRead | Access::eShaderStorageWrite);
  frame.shaped = frame.shaped || wanted.shapes;
  if (!wanted.classify) {
    stamp("ellipsoids");
    return;
  }
  frame.classified = true;
  // What came of it, for FrameStats::classification.
  memory_barrier(cmd_, Stage::eComputeShader, Access::eShaderStorageWrite, Stage::eCopy, Access::eTransferRead);
  cmd_.copyBuffer(*r_.band->params().buffer, *slot_.readback.buffer, vk::BufferCopy(0, sizeof(GpuArgs), sizeof(BandParams)));
  slot_.classified = true;
  slot_.blob_room = blob_room(frame.particle_count);
  stamp("classify");
}

void PassRecorder::cull() {
  const GpuArgs reset{0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 1};
  cmd_.updateBuffer<GpuArgs>(*r_.args.buffer, 0, reset);
  memory_barrier(cmd_, Stage::eCopy, Access::eTransferWrite, Stage::eComputeShader | Stage::eDrawIndirect,
                 Access::eShaderStorageRead | Access::eShaderStorageWrite | Access::eIndirectCommandRead);
  if (have_frame_) {
    cmd_.bindPipeline(vk::PipelineBindPoint::eCompute, *r_.cull_chunks);
    push();
    const uint32_t n = (pc_.chunk_count + 63) / 64;
    cmd_.dispatch(std::min(n, 65535u), (n + 65534) / 65535, 1);
    compute_to_compute();
    cmd_.bindPipeline(vk::PipelineBindPoint::eCompute, *r_.cull_args);
    push(0);
    cmd_.dispatch(1, 1, 1);
    memory_barrier(cmd_, Stage::eComputeShader, Access::eShaderStorageWrite, Stage::eComputeShader | Stage::eDrawIndirect,
                   Access::eShaderStorageRead | Access::eShaderStorageWrite | Access::eIndirectCommandRead);
    cmd_.bindPipeline(vk::PipelineBindPoint::eCompute, *r_.cull_particles);
    cmd_.dispatchIndirect(*r_.args.buffer, offsetof(GpuArgs, groups_x));
  }
  memory_barrier(cmd_, Stage::eComputeShader, Access::eShaderStorageWrite,
                 Stage::eDrawIndirect | Stage::eVertexShader | Stage::eComputeShader,
                 Access::eIndirectCommandRead | Access::eShaderStorageRead | Access::eShaderStorageWrite);
  stamp("cull");
}

void PassRecorder::splat() {
  const Targets& t = r_.targets;
  // Small splats one thread each; large ones listed, then one workgroup each.
  const auto args_then = [&](uint32_t which) {
    cmd_.bindPipeline(vk::PipelineBindPoint::eCompute, *r_.cull_args);
    push(which);
    cmd_.dispatch(1, 1, 1);
    memory_barrier(cmd_, Stage::eComputeShader, Access::eShaderStorageWrite, Stage::eComputeShader | Stage::eDrawIndirect,
                   Access::eShaderStorageRead | Access::eShaderStorageWrite | Access::eIndirectCommandRead);
  };
  // Frames with ellipsoids through the pipeline that draws them (the
  // spheres' own is leaner: GPU ms in docs/render.md).
  const vk::Pipeline splat_pipeline = pc_.shapes != 0 && *r_.splat_ellipsoids ? *r_.splat_ellipsoids : *r_.splat;
  if (have_frame_) {
    args_then(1);
    cmd_.bindPipeline(vk::PipelineBindPoint::eCompute, splat_pipeline);
    for (uint32_t e = 0; e < layers_; ++e) {  // eyes in turn (splat.comp says why)
      push(0, e);
      cmd_.dispatchIndirect(*r_.args.buffer, offsetof(GpuArgs, splat_x));
      compute_to_compute();
    }
    args_then(2);
    cmd_.bindPipeline(vk::PipelineBindPoint::eCompute, splat_pipeline);
    push(1);
    cmd_.dispatchIndirect(*r_.args.buffer, offsetof(GpuArgs, big_x));
    compute_to_compute();
  }
  stamp("splat");
  // The splat targets into the float targets, and reset for the next view.
  cmd_.bindPipeline(vk::PipelineBindPoint::eCompute, *r_.resolve);
  push(0);
  const auto gr = groups(t.size, 16);
  cmd_.dispatch(gr[0], gr[1], layers_);
  push(1);
  const auto gt = groups(t.thick_size, 16);
  cmd_.dispatch(gt[0], gt[1], layers_);
  memory_barrier(cmd_, Stage::eComputeShader, Access::eShaderStorageWrite, Stage::eComputeShader | Stage::eFragmentShader,
                 Access::eShaderStorageRead | Access::eShaderSampledRead);
  stamp("resolve");
}

void PassRecorder::raster_spheres() {
  const Targets& t = r_.targets;
  const auto raster = [&](const Texture& target, const Texture* depth, const vk::raii::Pipeline& pipeline, uint32_t flag) {
    std::vector<vk::ImageMemoryBarrier2> to{image_barrier(target, vk::ImageLayout::eUndefined, vk::ImageLayout::eColorAttachmentOptimal,
                                                          Stage::eComputeShader | Stage::eFragmentShader,
                                                          Access::eShaderStorageRead | Access::eShaderSampledRead,
                                                          Stage::eColorAttachmentOutput, Access::eColorAttachmentWrite)};
    if (depth) {
      to.push_back(image_barrier(*depth, vk::ImageLayout::eUndefined, vk::ImageLayout::eDepthAttachmentOptimal,
                                 Stage::eEarlyFragmentTests | Stage::eLateFragmentTests, Access::eDepthStencilAttachmentWrite,
                                 Stage::eEarlyFragmentTests | Stage::eLateFragmentTests,
                                 Access::eDepthStencilAttachmentRead | Access::eDepthStencilAttachmentWrite));
    }
    cmd_.pipelineBarrier2(vk::DependencyInfo({}, {}, {}, to));
    const vk::Rect2D area({0, 0}, target.extent);
    vk::RenderingAttachmentInfo color(*target.view, vk::ImageLayout::eColorAttachmentOptimal, {}, {}, {},
                                      vk::AttachmentLoadOp::eClear, vk::AttachmentStoreOp::eStore,
                                      vk::ClearValue(vk::ClearColorValue(std::array<float, 4>{0, 0, 0, 0})));
    vk::RenderingAttachmentInfo depth_info;
    vk::RenderingInfo info({}, area, 1, view_mask(layers_), color);
    if (depth) {
      depth_info = vk::RenderingAttachmentInfo(*depth->view, vk::ImageLayout::eDepthAttachmentOptimal, {}, {}, {},
                                               vk::AttachmentLoadOp::eClear, vk::AttachmentStoreOp::eDontCare,
                                               vk::ClearValue(vk::ClearDepthStencilValue(0.0f, 0)));
      info.setPDepthAttachment(&depth_info);
    }
    cmd_.beginRendering(info);
    if (have_frame_) {
      cmd_.bindPipeline(vk::PipelineBindPoint::eGraphics, *pipeline);
      cmd_.setViewport(0, vk::Viewport(0, 0, float(target.extent.width), float(target.extent.height), 0, 1));
      cmd_.setScissor(0, area);
      push(flag);
      cmd_.drawIndirect(*r_.args.buffer, 0, 1, sizeof(VkDrawIndirectCommand));
    }
    cmd_.endRendering();
    const auto back = image_barrier(target, vk::ImageLayout::eColorAttachmentOptimal, vk::ImageLayout::eGeneral,
                                    Stage::eColorAttachmentOutput, Access::eColorAttachmentWrite,
                                    Stage::eComputeShader | Stage::eFragmentShader,
                                    Access::eShaderStorageRead | Access::eShaderSampledRead);
    cmd_.pipelineBarrier2(vk::DependencyInfo({}, {}, {}, back));
  };
  raster(t.depth_raw, &t.depth_hw, r_.depth_pass[layers_ - 1], 0);
  stamp("depth");
  raster(t.thick_raw, nullptr, r_.thickness_pass[layers_ - 1], 1);
  stamp("thickness");
}

// Separable passes raw -> B -> A, then A -> B -> A per iteration.
void PassRecorder::separable(const vk::raii::Pipeline& pipeline, vk::Extent2D size, int iterations) {
  cmd_.bindPipeline(vk::PipelineBindPoint::eCompute, *pipeline);
  const auto g = groups(size, 16);
  for (int i = 0; i < iterations; ++i) {
    push(i == 0 ? 0u : 1u, 2u, 0u);
    cmd_.dispatch(g[0], g[1], layers_);
    compute_to_compute();
    push(2u, 1u, 1u);
    cmd_.dispatch(g[0], g[1], layers_);
    compute_to_compute();
  }
}

void PassRecorder::filters(const FluidOptions& o) {
  const Targets& t = r_.targets;
  if (depth_filtered(o)) separable(r_.filter_depth, t.size, o.surface_filter_iterations);
  stamp("filter");
  if (thickness_filtered(o)) separable(r_.filter_thickness, t.thick_size, o.thickness_and_volume_color_filter_iterations);
  stamp("thickness filter");
}

void PassRecorder::shade(const Viewport& origin, bool fluid_only) {
  cmd_.bindPipeline(vk::PipelineBindPoint::eCompute, *r_.composite);
  push(origin.x, origin.y, fluid_only ? 1u : 0u);
  const auto g = groups(r_.targets.size, 8);
  cmd_.dispatch(g[0], g[1], layers_);
  memory_barrier(cmd_, Stage::eComputeShader, Access::eShaderStorageWrite, Stage::eFragmentShader, Access::eShaderStorageRead);
  stamp("shade");
}

void PassRecorder::shade_with_host_depth(const RenderTarget& target, const View& view, bool first, bool views_tile) {
  const vk::Image depth(target.depth_image);
  const vk::ImageLayout general = vk::ImageLayout::eGeneral;
  const Viewport& v = view.viewport;
  // The far plane of the view's projection (reversed depth: 0), as the present pass clears to.
  const float far = view.projection.at(2, 3) > 0 ? 0.0f : 1.0f;
  const bool d24 = d24_depth(target.depth_format);
  const bool in_place = reads_host_depth_in_place(target, Output::DepthInShading);
  const vk::BufferImageCopy region(0, 0, 0,
                                   vk::ImageSubresourceLayers(vk::ImageAspectFlagBits::eDepth, 0, target.base_layer, layers_),
                                   vk::Offset3D(int32_t(v.x), int32_t(v.y), 0), vk::Extent3D(v.width, v.height, 1));
  if (target.depth_layout_before == VK_IMAGE_LAYOUT_UNDEFINED) {
    // What an UNDEFINED layout promises: the image at the far plane. The
    // view's region needs no copy out (its copy is filled with the far
    // plane); the image is cleared once where the views leave some of it
    // (a clear of both eyes' 2064x2208 D32 took 0.70 ms on the H100).
    if (first && !views_tile) {
      const vk::ImageSubresourceRange range(vk::ImageAspectFlagBits::eDepth, 0, 1, target.base_layer, layers_);
      cmd_.clearDepthStencilImage(depth, general, vk::ClearDepthStencilValue(far, 0), range);
    }
    const uint32_t far_bits = d24 ? (far > 0 ? 0x00ffffffu : 0u) : std::bit_cast<uint32_t>(far);
    cmd_.fillBuffer(*r_.host_depth.buffer, 0, vk::DeviceSize(v.width) * v.height * layers_ * 4, far_bits);
    memory_barrier(cmd_, Stage::eClear | Stage::eCopy, Access::eTransferWrite, Stage::eComputeShader | Stage::eCopy,
                   Access::eShaderStorageRead | Access::eShaderStorageWrite | Access::eTransferWrite);
  } else if (in_place) {
    // The shading pass reads the image and writes every pixel's depth to
    // the buffer; after the copy back of the view before, if any.
    memory_barrier(cmd_, Stage::eCopy, Access::eTransferWrite, Stage::eComputeShader, Access::eShaderSampledRead);
  } else {
    const vk::ImageLayout source = vk::ImageLayout::eTransferSrcOptimal;
    relayout_depth(cmd_, target, general, source, Stage::eAllCommands, Access::eMemoryWrite, Stage::eCopy,
                   Access::eTransferRead);
    cmd_.copyImageToBuffer(depth, source, *r_.host_depth.buffer, region);
    relayout_depth(cmd_, target, source, general, Stage::eCopy, {}, Stage::eAllCommands, {});
    memory_barrier(cmd_, Stage::eCopy, Access::eTransferWrite, Stage::eComputeShader,
                   Access::eShaderStorageRead | Access::eShaderStorageWrite);
  }
  stamp("depth in");
  pc_.host_depth = r_.host_depth.address;
  // param2: bit 0 background off (pixels without fluid left alone), bit 1
  // the host's depth test, bit 2 its copy is X8_D24 (else float), bit 3 it
  // is read from the image (binding 17) and every pixel's depth written.
  cmd_.bindPipeline(vk::PipelineBindPoint::eCompute, *r_.composite);
  push(v.x, v.y, (target.background ? 0u : 1u) | 2u | (d24 ? 4u : 0u) | (in_place ? 8u : 0u));
  const auto g = groups(r_.targets.size, 8);
  cmd_.dispatch(g[0], g[1], layers_);
  pc_.host_depth = 0;
  stamp("shade");
  memory_barrier(cmd_, Stage::eComputeShader, Access::eShaderStorageWrite, Stage::eCopy, Access::eTransferRead);
  const vk::ImageLayout destination = vk::ImageLayout::eTransferDstOptimal;
  relayout_depth(cmd_, target, general, destination, Stage::eAllCommands, Access::eMemoryWrite, Stage::eCopy,
                 Access::eTransferWrite);
  cmd_.copyBufferToImage(*r_.host_depth.buffer, depth, destination, region);
  relayout_depth(cmd_, target, destination, general, Stage::eCopy, Access::eTransferWrite, Stage::eAllCommands,
                 Access::eMemoryRead | Access::eMemoryWrite);
  stamp("depth out");
}

void PassRecorder::present(const RenderTarget& target, const View& view, bool first) {
  // One layer at a time (a 2-layer target: each eye's layer through a view
  // of its own): a full-screen pass per eye costs little, and lavapipe (Mesa
  // 22.3) leaves the second layer of a multiview pass of this shape unwritten.
  for (uint32_t e = 0; e < layers_; ++e) {
    VkImageView color = target.color_view, depth = target.depth_view;
    if (layers_ > 1) {
      color = r_.layer_view(target.color_image, target.color_format, vk::ImageAspectFlagBits::eColor, target.base_layer + e);
      if (target.depth_view) {
        depth = r_.layer_view(target.depth_image, target.depth_format, depth_aspect(target.depth_format), target.base_layer + e);
      }
    }
    present_layer(target, color, depth, view, first, e);
  }
  stamp("present");
}

void PassRecorder::present_layer(const RenderTarget& target, VkImageView color_view, VkImageView depth_view, const View& view,
                                 bool first, uint32_t eye) {
  const vk::Format depth_format = depth_view ? vk::Format(target.depth_format) : vk::Format::eUndefined;
  const vk::raii::Pipeline& pipeline = r_.present_pipeline(vk::Format(target.color_format), depth_format);
  const vk::Rect2D area({int32_t(view.viewport.x), int32_t(view.viewport.y)}, {view.viewport.width, view.viewport.height});
  const bool clear_color = first && target.color_layout_before == VK_IMAGE_LAYOUT_UNDEFINED;
  const bool clear_depth = first && target.depth_layout_before == VK_IMAGE_LAYOUT_UNDEFINED;
  // The far plane of the view's projection (reversed depth: 0).
  const float depth_b = view.projection.at(2, 3);
  const bool reversed = depth_b > 0;
  vk::RenderingAttachmentInfo color(vk::ImageView(color_view), vk::ImageLayout::eAttachmentOptimal, {}, {}, {},
                                    clear_color ? vk::AttachmentLoadOp::eClear : vk::AttachmentLoadOp::eLoad,
                                    vk::AttachmentStoreOp::eStore,
                                    vk::ClearValue(vk::ClearColorValue(std::array<float, 4>{0, 0, 0, 0})));
  // The first view clears the whole image (what an UNDEFINED layout
  // promises), not only its own viewport; later views load and draw theirs.
  const vk::Rect2D whole({0, 0}, {target.width, target.height});
  const vk::Rect2D render_area = clear_color || clear_depth ? whole : area;
  vk::RenderingInfo info({}, render_area, 1, 0, color);
  vk::RenderingAttachmentInfo depth;
  if (depth_view) {
    depth = vk::RenderingAttachmentInfo(vk::ImageView(depth_view), vk::ImageLayout::eAttachmentOptimal, {}, {}, {},
                                        clear_depth ? vk::AttachmentLoadOp::eClear : vk::AttachmentLoadOp::eLoad,
                                        vk::AttachmentStoreOp::eStore,
                                        vk::ClearValue(vk::ClearDepthStencilValue(reversed ? 0.0f : 1.0f, 0)));
    info.setPDepthAttachment(&depth);
    if (has_stencil(depth_format)) {
      depth.loadOp = vk::AttachmentLoadOp::eLoad;  // stencil keeps the host's; depth cleared below if asked
      info.setPStencilAttachment(&depth);
    }
  }
  cmd_.beginRendering(info);
  if (depth_view && has_stencil(depth_format) && clear_depth) {
    const vk::ClearAttachment clear(vk::ImageAspectFlagBits::eDepth, 0, vk::ClearDepthStencilValue(reversed ? 0.0f : 1.0f, 0));
    cmd_.clearAttachments(clear, vk::ClearRect(render_area, 0, 1));
  }
  cmd_.bindPipeline(vk::PipelineBindPoint::eGraphics, *pipeline);
  cmd_.setViewport(0, vk::Viewport(float(area.offset.x), float(area.offset.y), float(area.extent.width),
                                   float(area.extent.height), 0, 1));
  cmd_.setScissor(0, area);
  cmd_.setDepthTestEnable(depth_view != VK_NULL_HANDLE);
  cmd_.setDepthWriteEnable(depth_view != VK_NULL_HANDLE);
  cmd_.setDepthCompareOp(reversed ? vk::CompareOp::eGreaterOrEqual : vk::CompareOp::eLessOrEqual);
  uint32_t flags = target.background ? 1u : 0u;
  if (is_srgb(vk::Format(target.color_format))) flags |= 2u;
  flags |= eye << 2;
  push(view.viewport.x, view.viewport.y, flags);
  cmd_.draw(3, 1, 0, 0);
  cmd_.endRendering();
}

void PassRecorder::end_frame(const RenderTarget& target, Output output) {
  const bool direct = output != Output::Present;
  memory_barrier(cmd_, Stage::eComputeShader | Stage::eDrawIndirect, Access::eShaderStorageWrite | Access::eIndirectCommandRead,
                 Stage::eCopy, Access::eTransferRead);
  cmd_.copyBuffer(*r_.args.buffer, *slot_.readback.buffer, vk::BufferCopy(0, 0, sizeof(GpuArgs)));
  if (r_.timestamps_valid) {
    // The timestamps beside the counters, with availability: the host reads
    // them from mapped memory without asking the driver (renderer_state.h).
    const uint32_t count = uint32_t(slot_.stamp_names.size()) + 1;
    cmd_.copyQueryPoolResults(*r_.timestamps, first_stamp_, count, *slot_.readback.buffer, kStampsOffset, 16,
                              vk::QueryResultFlagBits::e64 | vk::QueryResultFlagBits::eWait |
                                  vk::QueryResultFlagBits::eWithAvailability);
  }
  memory_barrier(cmd_, Stage::eCopy, Access::eTransferWrite, Stage::eHost, Access::eHostRead);
  std::vector<vk::ImageMemoryBarrier2> after;
  after.push_back(host_barrier(target.color_image, vk::ImageAspectFlagBits::eColor, target,
                               direct ? VK_IMAGE_LAYOUT_GENERAL : VK_IMAGE_LAYOUT_ATTACHMENT_OPTIMAL,
                               vk::ImageLayout(target.color_layout_after)));
  if (target.depth_image) {
    after.push_back(host_barrier(target.depth_image, depth_aspect(target.depth_format), target,
                                 output == Output::DepthInShading ? VK_IMAGE_LAYOUT_GENERAL : VK_IMAGE_LAYOUT_ATTACHMENT_OPTIMAL,
                                 vk::ImageLayout(target.depth_layout_after)));
  }
  cmd_.pipelineBarrier2(vk::DependencyInfo({}, {}, {}, after));
}

}  // namespace sluice::render
