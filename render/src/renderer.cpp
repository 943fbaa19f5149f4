// The renderer's lifetime: pipelines, descriptor sets, frame slots, retired
// objects, stats; record() hands each view to the passes (passes.cpp).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "globals.h"
#include "renderer_state.h"
#include "sluice/render/renderer.h"
#include "passes.h"
#include "shaders.h"
#include "sluice/error.h"

namespace sluice::render {
namespace {

using Stage = vk::PipelineStageFlagBits2;
using Access = vk::AccessFlagBits2;


vk::raii::ShaderModule module(const vk::raii::Device& device, Shader s) {
  const std::span<const uint32_t> code = spirv(s);
  return vk::raii::ShaderModule(device, vk::ShaderModuleCreateInfo({}, code.size_bytes(), code.data()));
}

// Point sprites into one colour target (and optionally reversed-z depth);
// `ellipsoids`: common.glsl's kEllipsoids, as compute_pipeline's.
vk::raii::Pipeline sphere_pipeline(const vk::raii::Device& device, const vk::raii::PipelineLayout& layout, Shader fragment,
                                   vk::Format color, bool depth, bool additive, uint32_t view_mask, bool ellipsoids) {
  const vk::raii::ShaderModule vs = module(device, Shader::SphereVert);
  const vk::raii::ShaderModule fs = module(device, fragment);
  const vk::Bool32 value = ellipsoids ? VK_TRUE : VK_FALSE;
  const vk::SpecializationMapEntry entry(0, 0, sizeof value);
  const vk::SpecializationInfo specialization(1, &entry, sizeof value, &value);
  const std::array stages{vk::PipelineShaderStageCreateInfo({}, vk::ShaderStageFlagBits::eVertex, *vs, "main", &specialization),
                          vk::PipelineShaderStageCreateInfo({}, vk::ShaderStageFlagBits::eFragment, *fs, "main")};
  vk::PipelineVertexInputStateCreateInfo vertex_input;
  vk::PipelineInputAssemblyStateCreateInfo assembly({}, vk::PrimitiveTopology::ePointList);
  vk::PipelineViewportStateCreateInfo viewport({}, 1, nullptr, 1, nullptr);
  vk::PipelineRasterizationStateCreateInfo raster({}, VK_FALSE, VK_FALSE, vk::PolygonMode::eFill, vk::CullModeFlagBits::eNone,
                                                  vk::FrontFace::eCounterClockwise, VK_FALSE, 0, 0, 0, 1.0f);
  vk::PipelineMultisampleStateCreateInfo multisample({}, vk::SampleCountFlagBits::e1);
  vk::PipelineDepthStencilStateCreateInfo depth_state({}, depth, depth, vk::CompareOp::eGreater);
  vk::PipelineColorBlendAttachmentState blend(additive, vk::BlendFactor::eOne, vk::BlendFactor::eOne, vk::BlendOp::eAdd,
                                              vk::BlendFactor::eOne, vk::BlendFactor::eOne, vk::BlendOp::eAdd,
                                              vk::ColorComponentFlagBits::eR | vk::ColorComponentFlagBits::eG);
  if (!additive) blend.colorWriteMask = vk::ColorComponentFlagBits::eR;
  vk::PipelineColorBlendStateCreateInfo blend_state({}, VK_FALSE, vk::LogicOp::eCopy, blend);
  const std::array dynamic{vk::DynamicState::eViewport, vk::DynamicState::eScissor};
  vk::PipelineDynamicStateCreateInfo dynamic_state({}, dynamic);
  vk::PipelineRenderingCreateInfo rendering(view_mask, color, depth ? vk::Format::eD32Sfloat : vk::Format::eUndefined);
  vk::GraphicsPipelineCreateInfo info({}, stages, &vertex_input, &assembly, nullptr, &viewport, &raster, &multisample,
                                      &depth_state, &blend_state, &dynamic_state, *layout);
  info.pNext = &rendering;
  return vk::raii::Pipeline(device, nullptr, info);
}

constexpr auto kBufferUsage = vk::BufferUsageFlagBits::eStorageBuffer | vk::BufferUsageFlagBits::eShaderDeviceAddress |
                              vk::BufferUsageFlagBits::eTransferDst;

}  // namespace

void detail::RendererImpl::create_pipelines() {
  const auto& device = ctx.device;
  std::vector<vk::DescriptorSetLayoutBinding> bindings{
      {0, vk::DescriptorType::eUniformBufferDynamic, 1, kAllStages}};
  for (uint32_t b = 1; b <= 6; ++b) bindings.emplace_back(b, vk::DescriptorType::eStorageImage, 1, kAllStages);
  bindings.emplace_back(7, vk::DescriptorType::eCombinedImageSampler, 1, kAllStages);
  bindings.emplace_back(8, vk::DescriptorType::eCombinedImageSampler, 1, kAllStages);
  bindings.emplace_back(9, vk::DescriptorType::eStorageImage, 1, kAllStages);
  bindings.emplace_back(10, vk::DescriptorType::eStorageImage, 1, kAllStages);
  for (uint32_t b = 11; b <= 13; ++b) bindings.emplace_back(b, vk::DescriptorType::eStorageImage, 1, kAllStages);
  bindings.emplace_back(14, vk::DescriptorType::eCombinedImageSampler, 1, kAllStages);
  bindings.emplace_back(15, vk::DescriptorType::eStorageImage, 1, kAllStages);
  bindings.emplace_back(16, vk::DescriptorType::eCombinedImageSampler, 1, kAllStages);  // the host's scene colour
  bindings.emplace_back(17, vk::DescriptorType::eCombinedImageSampler, 1, kAllStages);  // the host's depth, read in place
  set_layout = vk::raii::DescriptorSetLayout(device, vk::DescriptorSetLayoutCreateInfo({}, bindings));
  vk::PushConstantRange push(kAllStages, 0, sizeof(PushConstants));
  layout = vk::raii::PipelineLayout(device, vk::PipelineLayoutCreateInfo({}, *set_layout, push));
  const uint32_t n = options.frames_in_flight;
  const std::array sizes{vk::DescriptorPoolSize(vk::DescriptorType::eUniformBufferDynamic, n),
                         vk::DescriptorPoolSize(vk::DescriptorType::eStorageImage, 12 * n),
                         vk::DescriptorPoolSize(vk::DescriptorType::eCombinedImageSampler, 5 * n)};
  pool = vk::raii::DescriptorPool(device, vk::DescriptorPoolCreateInfo(vk::DescriptorPoolCreateFlagBits::eFreeDescriptorSet, n, sizes));
  for (FrameSlot& slot : slots) {
    slot.set = std::move(vk::raii::DescriptorSets(device, vk::DescriptorSetAllocateInfo(*pool, *set_layout))[0]);
  }
  sampler = vk::raii::Sampler(device, vk::SamplerCreateInfo({}, vk::Filter::eLinear, vk::Filter::eLinear,
                                                            vk::SamplerMipmapMode::eNearest, vk::SamplerAddressMode::eClampToEdge,
                                                            vk::SamplerAddressMode::eClampToEdge,
                                                            vk::SamplerAddressMode::eClampToEdge));
  nearest_sampler = vk::raii::Sampler(device, vk::SamplerCreateInfo({}, vk::Filter::eNearest, vk::Filter::eNearest,
                                                                    vk::SamplerMipmapMode::eNearest, vk::SamplerAddressMode::eClampToEdge,
                                                                    vk::SamplerAddressMode::eClampToEdge,
                                                                    vk::SamplerAddressMode::eClampToEdge));
  // The environment wraps around in azimuth (u) and clamps at the poles (v).
  environment_sampler = vk::raii::Sampler(
      device, vk::SamplerCreateInfo({}, vk::Filter::eLinear, vk::Filter::eLinear, vk::SamplerMipmapMode::eNearest,
                                    vk::SamplerAddressMode::eRepeat, vk::SamplerAddressMode::eClampToEdge,
                                    vk::SamplerAddressMode::eClampToEdge));

  // Thickness sums need blending on a float format: 32-bit where the device
  // blends it (precision with millions of splats per pixel), else 16-bit.
  const auto props = ctx.physical.getFormatProperties(vk::Format::eR32G32Sfloat);
  const auto need = vk::FormatFeatureFlagBits::eColorAttachmentBlend | vk::FormatFeatureFlagBits::eStorageImage;
  thick_format = (props.optimalTilingFeatures & need) == need ? vk::Format::eR32G32Sfloat : vk::Format::eR16G16Sfloat;

  cull_chunks = compute_pipeline(device, layout, Shader::CullChunks);
  cull_args = compute_pipeline(device, layout, Shader::CullArgs);
  cull_particles = compute_pipeline(device, layout, Shader::CullParticles);
  splat = compute_pipeline(device, layout, Shader::Splat);
  if (options.anisotropic) splat_ellipsoids = compute_pipeline(device, layout, Shader::Splat, true);
  resolve = compute_pipeline(device, layout, Shader::Resolve);
  filter_depth = compute_pipeline(device, layout, Shader::FilterDepth);
  filter_thickness = compute_pipeline(device, layout, Shader::FilterThickness);
  composite = compute_pipeline(device, layout, Shader::Composite);
  // Point sprites into one layer, or into both eyes' layers at once
  // (multiview); spheres only, unless the renderer draws ellipsoids.
  for (uint32_t layers = 1; layers <= 2; ++layers) {
    const uint32_t mask = view_mask(layers);
    depth_pass[layers - 1] = sphere_pipeline(device, layout, Shader::SphereDepthFrag, vk::Format::eR32Sfloat, true, false, mask,
                                             options.anisotropic);
    thickness_pass[layers - 1] = sphere_pipeline(device, layout, Shader::SphereThicknessFrag, targets.thick_format, false,
                                                 true, mask, options.anisotropic);
  }
}


const vk::raii::Pipeline& detail::RendererImpl::present_pipeline(vk::Format color, vk::Format depth) {
  for (const PresentPipeline& p : present_pipelines) {
    if (p.color == color && p.depth == depth) return p.pipeline;
  }
  const auto& device = ctx.device;
  const vk::raii::ShaderModule vs = module(device, Shader::PresentVert);
  const vk::raii::ShaderModule fs = module(device, Shader::PresentFrag);
  const std::array stages{vk::PipelineShaderStageCreateInfo({}, vk::ShaderStageFlagBits::eVertex, *vs, "main"),
                          vk::PipelineShaderStageCreateInfo({}, vk::ShaderStageFlagBits::eFragment, *fs, "main")};
  vk::PipelineVertexInputStateCreateInfo vertex_input;
  vk::PipelineInputAssemblyStateCreateInfo assembly({}, vk::PrimitiveTopology::eTriangleList);
  vk::PipelineViewportStateCreateInfo viewport({}, 1, nullptr, 1, nullptr);
  vk::PipelineRasterizationStateCreateInfo raster({}, VK_FALSE, VK_FALSE, vk::PolygonMode::eFill, vk::CullModeFlagBits::eNone,
                                                  vk::FrontFace::eCounterClockwise, VK_FALSE, 0, 0, 0, 1.0f);
  vk::PipelineMultisampleStateCreateInfo multisample({}, vk::SampleCountFlagBits::e1);
  // Test and compare op are dynamic: they follow the target and the projection.
  vk::PipelineDepthStencilStateCreateInfo depth_state({}, VK_TRUE, VK_TRUE, vk::CompareOp::eAlways);
  vk::PipelineColorBlendAttachmentState blend(VK_FALSE);
  blend.colorWriteMask = vk::ColorComponentFlagBits::eR | vk::ColorComponentFlagBits::eG | vk::ColorComponentFlagBits::eB |
                         vk::ColorComponentFlagBits::eA;
  vk::PipelineColorBlendStateCreateInfo blend_state({}, VK_FALSE, vk::LogicOp::eCopy, blend);
  const std::array dynamic{vk::DynamicState::eViewport, vk::DynamicState::eScissor, vk::DynamicState::eDepthTestEnable,
                           vk::DynamicState::eDepthWriteEnable, vk::DynamicState::eDepthCompareOp};
  vk::PipelineDynamicStateCreateInfo dynamic_state({}, dynamic);
  const bool stencil = depth == vk::Format::eD24UnormS8Uint || depth == vk::Format::eD32SfloatS8Uint ||
                       depth == vk::Format::eD16UnormS8Uint;
  vk::PipelineRenderingCreateInfo rendering(0, color, depth, stencil ? depth : vk::Format::eUndefined);
  vk::GraphicsPipelineCreateInfo info({}, stages, &vertex_input, &assembly, nullptr, &viewport, &raster, &multisample,
                                      &depth_state, &blend_state, &dynamic_state, *layout);
  info.pNext = &rendering;
  present_pipelines.push_back({color, depth, vk::raii::Pipeline(device, nullptr, info)});
  return present_pipelines.back().pipeline;
}

void detail::RendererImpl::ensure(Buffer& b, vk::DeviceSize size, vk::BufferUsageFlags usage, MemoryKind kind) {
  if (*b.buffer && b.size >= size) return;
  retire(std::move(b));
  b = Buffer{};
  // Grow with headroom so a slowly growing sequence does not reallocate every frame.
  const vk::DeviceSize grown = size + size / 8;
  b = create_buffer(ctx, std::max<vk::DeviceSize>(grown, 256), usage, kind);
}

void detail::RendererImpl::collect_retired() {
  while (!retired.empty() && retired.front().after_frame <= frames_recorded) retired.pop_front();
}

void detail::RendererImpl::write_descriptors(FrameSlot& slot) {
  const Targets& t = targets;
  const vk::DescriptorSet set = *slot.set;
  vk::DescriptorBufferInfo ubo(*globals.buffer, 0, 2 * sizeof(Globals));  // both eyes' uniforms
  const vk::ImageLayout gen = vk::ImageLayout::eGeneral;
  const std::array storage{vk::DescriptorImageInfo({}, *t.depth_raw.view, gen), vk::DescriptorImageInfo({}, *t.depth_a.view, gen),
                           vk::DescriptorImageInfo({}, *t.depth_b.view, gen), vk::DescriptorImageInfo({}, *t.thick_raw.view, gen),
                           vk::DescriptorImageInfo({}, *t.thick_a.view, gen), vk::DescriptorImageInfo({}, *t.thick_b.view, gen)};
  const std::array sampled{vk::DescriptorImageInfo(*sampler, *t.thick_raw.view, gen),
                           vk::DescriptorImageInfo(*sampler, *t.thick_a.view, gen)};
  const vk::DescriptorImageInfo color({}, *t.color.view, gen), aux({}, *t.aux.view, gen);
  const std::array uints{vk::DescriptorImageInfo({}, *t.depth_u.view, gen), vk::DescriptorImageInfo({}, *t.thick_u.view, gen),
                         vk::DescriptorImageInfo({}, *t.thick_attr_u.view, gen)};
  const vk::DescriptorImageInfo env(*environment_sampler, *environment.view, vk::ImageLayout::eShaderReadOnlyOptimal);
  const std::array writes{
      vk::WriteDescriptorSet(set, 0, 0, vk::DescriptorType::eUniformBufferDynamic, {}, ubo),
      vk::WriteDescriptorSet(set, 1, 0, 1, vk::DescriptorType::eStorageImage, &storage[0]),
      vk::WriteDescriptorSet(set, 2, 0, 1, vk::DescriptorType::eStorageImage, &storage[1]),
      vk::WriteDescriptorSet(set, 3, 0, 1, vk::DescriptorType::eStorageImage, &storage[2]),
      vk::WriteDescriptorSet(set, 4, 0, 1, vk::DescriptorType::eStorageImage, &storage[3]),
      vk::WriteDescriptorSet(set, 5, 0, 1, vk::DescriptorType::eStorageImage, &storage[4]),
      vk::WriteDescriptorSet(set, 6, 0, 1, vk::DescriptorType::eStorageImage, &storage[5]),
      vk::WriteDescriptorSet(set, 7, 0, 1, vk::DescriptorType::eCombinedImageSampler, &sampled[0]),
      vk::WriteDescriptorSet(set, 8, 0, 1, vk::DescriptorType::eCombinedImageSampler, &sampled[1]),
      vk::WriteDescriptorSet(set, 9, 0, 1, vk::DescriptorType::eStorageImage, &color),
      vk::WriteDescriptorSet(set, 10, 0, 1, vk::DescriptorType::eStorageImage, &aux),
      vk::WriteDescriptorSet(set, 11, 0, 1, vk::DescriptorType::eStorageImage, &uints[0]),
      vk::WriteDescriptorSet(set, 12, 0, 1, vk::DescriptorType::eStorageImage, &uints[1]),
      vk::WriteDescriptorSet(set, 13, 0, 1, vk::DescriptorType::eStorageImage, &uints[2]),
      vk::WriteDescriptorSet(set, 14, 0, 1, vk::DescriptorType::eCombinedImageSampler, &env),
      vk::WriteDescriptorSet(set, 15, 0, 1, vk::DescriptorType::eStorageImage, &color),
  };
  ctx.device.updateDescriptorSets(writes, {});
  slot.set_generation = targets.generation + (environment_generation << 32);
}

void detail::RendererImpl::bind_output(FrameSlot& slot, VkImageView view) {
  // Written every frame, not only when the handle changes: a caller's view
  // destroyed and re-created may come back with the same handle value.
  const vk::DescriptorImageInfo image({}, vk::ImageView(view), vk::ImageLayout::eGeneral);
  ctx.device.updateDescriptorSets(vk::WriteDescriptorSet(*slot.set, 9, 0, 1, vk::DescriptorType::eStorageImage, &image), {});
}

VkImageView detail::RendererImpl::frame_array_view(VkImage image, VkFormat format, vk::ImageAspectFlags aspect,
                                                   const RenderTarget& target) {
  vk::raii::ImageView view(ctx.device, vk::ImageViewCreateInfo({}, vk::Image(image), vk::ImageViewType::e2DArray, vk::Format(format),
                                                               {}, vk::ImageSubresourceRange(aspect, 0, 1, target.base_layer,
                                                                                             target.layer_count)));
  const VkImageView handle = *view;
  retire(std::move(view));  // lives as long as this frame's commands
  return handle;
}

void detail::RendererImpl::bind_scene_color(FrameSlot& slot, const RenderTarget& target) {
  // Without the host's scene the binding holds the environment (never read).
  vk::DescriptorImageInfo image(*sampler, *environment_array, vk::ImageLayout::eShaderReadOnlyOptimal);
  if (target.scene_color_image) {
    image.imageView =
        frame_array_view(target.scene_color_image, target.scene_color_format, vk::ImageAspectFlagBits::eColor, target);
    image.imageLayout = vk::ImageLayout(target.scene_color_layout);
  }
  ctx.device.updateDescriptorSets(
      vk::WriteDescriptorSet(*slot.set, 16, 0, 1, vk::DescriptorType::eCombinedImageSampler, &image), {});
}

void detail::RendererImpl::bind_host_depth(FrameSlot& slot, const RenderTarget& target, bool read) {
  vk::DescriptorImageInfo image(*sampler, *environment_array, vk::ImageLayout::eShaderReadOnlyOptimal);
  if (read) {
    image.sampler = *nearest_sampler;
    image.imageView = frame_array_view(target.depth_image, target.depth_format, vk::ImageAspectFlagBits::eDepth, target);
    image.imageLayout = vk::ImageLayout::eGeneral;
  }
  ctx.device.updateDescriptorSets(
      vk::WriteDescriptorSet(*slot.set, 17, 0, 1, vk::DescriptorType::eCombinedImageSampler, &image), {});
}

VkImageView detail::RendererImpl::layer_view(VkImage image, VkFormat format, vk::ImageAspectFlags aspect, uint32_t layer) {
  vk::raii::ImageView view(ctx.device, vk::ImageViewCreateInfo({}, vk::Image(image), vk::ImageViewType::e2D, vk::Format(format), {},
                                                               vk::ImageSubresourceRange(aspect, 0, 1, layer, 1)));
  const VkImageView handle = *view;
  retire(std::move(view));  // lives as long as this frame's commands
  return handle;
}

VkImageView detail::RendererImpl::array_view_of(const RenderTarget& target) {
  // A view of the caller's layers as the shading pass's storage image (an array, one layer per eye).
  return frame_array_view(target.color_image, target.color_format, vk::ImageAspectFlagBits::eColor, target);
}

std::vector<std::byte> detail::RendererImpl::read_texture(const Texture& t, size_t texel_bytes) {
  const size_t bytes = size_t(t.extent.width) * t.extent.height * texel_bytes;
  Buffer readback = create_buffer(ctx, bytes, vk::BufferUsageFlagBits::eTransferDst, MemoryKind::Readback);
  ctx.run_once([&](vk::CommandBuffer c) {
    const auto to_copy = image_barrier(t, vk::ImageLayout::eGeneral, vk::ImageLayout::eTransferSrcOptimal, Stage::eAllCommands,
                                       Access::eMemoryWrite, Stage::eCopy, Access::eTransferRead);
    c.pipelineBarrier2(vk::DependencyInfo({}, {}, {}, to_copy));
    vk::BufferImageCopy region(0, 0, 0, vk::ImageSubresourceLayers(t.aspect, 0, t.layers - 1, 1), {}, vk::Extent3D(t.extent, 1));
    c.copyImageToBuffer(*t.image, vk::ImageLayout::eTransferSrcOptimal, *readback.buffer, region);
    const auto back = image_barrier(t, vk::ImageLayout::eTransferSrcOptimal, vk::ImageLayout::eGeneral, Stage::eCopy, {},
                                    Stage::eAllCommands, Access::eMemoryRead | Access::eMemoryWrite);
    const vk::MemoryBarrier2 host(Stage::eCopy, Access::eTransferWrite, Stage::eHost, Access::eHostRead);
    c.pipelineBarrier2(vk::DependencyInfo({}, host, {}, back));
  });
  std::vector<std::byte> out(bytes);
  std::memcpy(out.data(), readback.mapped, bytes);
  return out;
}

Renderer::Renderer(Context& context, const SceneInfo& scene, const RendererOptions& options)
    : impl_(std::make_unique<Impl>(context_impl(context), scene, options)) {
  Impl& r = *impl_;
  if (options.frames_in_flight < 1 || options.frames_in_flight > 8) {
    throw Error("renderer: frames_in_flight must be 1..8");
  }
  const auto& device = r.ctx.device;
  const uint32_t n = options.frames_in_flight;
  r.slots.resize(n);
  const vk::DeviceSize align = std::max<vk::DeviceSize>(r.ctx.properties.limits.minUniformBufferOffsetAlignment, 16);
  r.globals_stride = (2 * sizeof(Globals) + align - 1) / align * align;  // a Globals per eye
  r.globals = create_buffer(r.ctx, r.globals_stride * n * kMaxViews, vk::BufferUsageFlagBits::eUniformBuffer, MemoryKind::Upload);
  r.args = create_buffer(r.ctx, sizeof(GpuArgs),
                         kBufferUsage | vk::BufferUsageFlagBits::eIndirectBuffer | vk::BufferUsageFlagBits::eTransferSrc,
                         MemoryKind::DeviceLocal);
  for (FrameSlot& slot : r.slots) {
    static_assert(sizeof(GpuArgs) + sizeof(BandParams) <= kStampsOffset);
    slot.readback = create_buffer(r.ctx, kStampsOffset + 16 * kStampsPerSlot, vk::BufferUsageFlagBits::eTransferDst,
                                  MemoryKind::Readback);
  }
  r.create_pipelines();
  if (options.classify_unlayered || options.anisotropic) {
    const float h = scene.particle_spacing > 0 ? scene.particle_spacing : 2 * scene.particle_radius;
    if (h > 0) r.band = std::make_unique<FrameBand>(r.ctx, h);
  }
  r.upload_environment({});
  r.transfer_pool = vk::raii::CommandPool(
      device, vk::CommandPoolCreateInfo(vk::CommandPoolCreateFlagBits::eResetCommandBuffer, r.ctx.transfer_family));
  r.sets.resize(n + 1);
  for (FrameSet& set : r.sets) {
    set.copy = std::move(
        vk::raii::CommandBuffers(device, vk::CommandBufferAllocateInfo(*r.transfer_pool, vk::CommandBufferLevel::ePrimary, 1))[0]);
    set.stamps = vk::raii::QueryPool(device, vk::QueryPoolCreateInfo({}, vk::QueryType::eTimestamp, 2));
    (*device).resetQueryPool(*set.stamps, 0, 2);
  }
  vk::SemaphoreTypeCreateInfo timeline(vk::SemaphoreType::eTimeline, 0);
  vk::SemaphoreCreateInfo sem;
  sem.pNext = &timeline;
  r.upload_done = vk::raii::Semaphore(device, sem);
  r.copy_done = vk::raii::Semaphore(device, sem);
  const auto families = r.ctx.physical.getQueueFamilyProperties();
  r.timestamps_valid = r.ctx.graphics_family < families.size() && families[r.ctx.graphics_family].timestampValidBits > 0;
  r.timestamps = vk::raii::QueryPool(device, vk::QueryPoolCreateInfo({}, vk::QueryType::eTimestamp, n * kStampsPerSlot));
  (*device).resetQueryPool(*r.timestamps, 0, n * kStampsPerSlot);
}

Renderer::~Renderer() {
  if (!impl_) return;
  // The uploads are this renderer's own submissions: wait for them. Frames
  // the host submitted are the host's to finish before destroying us.
  wait_upload(impl_->upload_value);
  // A timeline value seen on the host is not the end of the queue's work
  // with the semaphore: lavapipe's submit thread still releases the
  // timeline's points after the wait returns, and destroying the semaphores
  // then crashed it (bench stream --gpu under ASan and load, 2 runs of 12).
  // So the queues this renderer submitted to go idle first.
  if (impl_->upload_value > 0) impl_->ctx.wait_idle(impl_->ctx.transfer_queue);
  if (impl_->last_decode_ticket > 0) impl_->ctx.wait_idle(impl_->ctx.graphics_queue);
}

const SceneInfo& Renderer::scene() const { return impl_->scene; }
const RendererOptions& Renderer::options() const { return impl_->options; }

void detail::RendererImpl::collect_slot(FrameSlot& slot, bool finished) {
  if (slot.collected || slot.frame == UINT64_MAX) return;
  // Without timestamps nothing says whether the frame is done: only when
  // the frames-in-flight contract does.
  if (!timestamps_valid && !finished) return;
  const uint32_t count = uint32_t(slot.stamp_names.size()) + 1;
  std::array<uint64_t, kStampsPerSlot> stamps{};
  if (timestamps_valid) {
    // (value, availability) pairs the GPU copied at the end of the frame;
    // the last one available means the frame's copies are all done.
    uint64_t pairs[2 * kStampsPerSlot];
    std::memcpy(pairs, static_cast<const std::byte*>(slot.readback.mapped) + kStampsOffset, 16 * count);
    if (pairs[2 * (count - 1) + 1] == 0) return;  // not back yet (or never submitted)
    for (uint32_t i = 0; i < count; ++i) stamps[i] = pairs[2 * i];
  }
  FrameStats s;
  s.record_index = slot.frame;
  s.particles = slot.particles;
  GpuArgs counters;
  std::memcpy(&counters, slot.readback.mapped, sizeof counters);
  s.drawn = slot.particles > 0 ? counters.vertex_count : 0;
  s.visible_chunks = slot.particles > 0 ? counters.visible_chunks : 0;
  if (timestamps_valid) {
    const double ns = ctx.properties.limits.timestampPeriod;
    for (uint32_t i = 1; i < count; ++i) {
      const double ms = double(stamps[i] - stamps[i - 1]) * ns * 1e-6;
      const char* name = slot.stamp_names[i - 1];
      auto same = std::find_if(s.passes.begin(), s.passes.end(), [&](const PassTime& p) { return p.name == name; });
      if (same == s.passes.end()) {
        s.passes.push_back({name, ms});
      } else {
        same->ms += ms;
      }
    }
    s.gpu_ms = double(stamps[count - 1] - stamps[0]) * ns * 1e-6;
  }
  s.upload_ms = slot.upload_ms;
  s.decoded_on_gpu = slot.decoded_on_gpu;
  s.decode_ms = slot.decode_ms;
  s.decode_errors = slot.decode_errors;
  if (slot.classified) {
    BandParams p;
    std::memcpy(&p, static_cast<const std::byte*>(slot.readback.mapped) + sizeof(GpuArgs), sizeof p);
    FrameStats::Classification& c = s.classification;
    c.ran = true;
    c.grid_fits = p.fits != 0;
    c.surface = uint64_t(p.counts[1]) + p.counts[2] + p.counts[3];
    c.blobs = p.blobs;
    c.blob_room = slot.blob_room;
    c.narrowed = c.grid_fits && c.blobs <= c.blob_room;
    for (int a = 0; a < 3; ++a) c.cells[a] = p.dims[a];
  }
  slot.collected = true;
  if (stats.passes.empty() || s.record_index >= stats.record_index) stats = std::move(s);
}

FrameStats Renderer::last_stats() {
  Impl& r = *impl_;
  for (FrameSlot& slot : r.slots) r.collect_slot(slot, false);
  return r.stats;
}

namespace {
// Whether the views' viewports cover the target exactly, without overlap
// (one view of the whole image, or side by side).
bool views_tile_target(const RenderTarget& target, std::span<const View> views) {
  if (target.layer_count == 2) views = views.first(1);  // both eyes share one viewport
  uint64_t area = 0;
  for (size_t a = 0; a < views.size(); ++a) {
    const Viewport& va = views[a].viewport;
    area += uint64_t(va.width) * va.height;
    for (size_t b = 0; b < a; ++b) {
      const Viewport& vb = views[b].viewport;
      const bool apart = va.x + va.width <= vb.x || vb.x + vb.width <= va.x || va.y + va.height <= vb.y ||
                         vb.y + vb.height <= va.y;
      if (!apart) return false;
    }
  }
  return area == uint64_t(target.width) * target.height;
}
}  // namespace

namespace {

// record()'s contract (renderer.h): a command buffer, 1 to 4 views of one
// size inside the target, a colour image, 1 layer or 2 with two views.
void check_record_arguments(VkCommandBuffer command_buffer, const RenderTarget& target, std::span<const View> views) {
  if (!command_buffer) throw Error("record: no command buffer");
  if (views.empty() || views.size() > kMaxViews) throw Error("record: 1 to 4 views");
  if (!target.color_view || !target.color_image || target.width == 0 || target.height == 0) {
    throw Error("record: the target needs a colour image, its view and its size");
  }
  const uint32_t layers = target.layer_count;
  if (layers != 1 && layers != 2) throw Error("record: targets of 1 layer, or 2 (both eyes in one pass)");
  if (layers == 2 && views.size() != 2) throw Error("record: a 2-layer target takes 2 views, one per layer");
  if (bool(target.depth_view) != bool(target.depth_image)) throw Error("record: a depth image needs its view");
  const Viewport size = views[0].viewport;
  for (const View& v : views) {
    if (v.viewport.width == 0 || v.viewport.height == 0 || v.viewport.width != size.width || v.viewport.height != size.height) {
      throw Error("record: every view needs the same non-empty viewport size");
    }
    if (uint64_t(v.viewport.x) + v.viewport.width > target.width || uint64_t(v.viewport.y) + v.viewport.height > target.height) {
      throw Error("record: a viewport reaches outside the target");
    }
    if (layers == 2 && (v.viewport.x != size.x || v.viewport.y != size.y)) {
      throw Error("record: both eyes of a 2-layer target need the same viewport");
    }
  }
}

}  // namespace

FrameSync Renderer::record(VkCommandBuffer command_buffer, const RenderTarget& target, std::span<const View> views,
                           const FluidOptions& options, const LodOptions& lod) {
  Impl& r = *impl_;
  check_record_arguments(command_buffer, target, views);
  const uint32_t layers = target.layer_count;
  const Viewport size = views[0].viewport;

  r.collect_retired();
  const uint32_t slot_index = uint32_t(r.frames_recorded % r.slots.size());
  FrameSlot& slot = r.slots[slot_index];
  r.collect_slot(slot, true);  // its last use has finished (the frames-in-flight contract)
  // Its timestamps' availability from the last use cleared: set again by this frame's copy.
  std::memset(static_cast<std::byte*>(slot.readback.mapped) + kStampsOffset, 0, 16 * kStampsPerSlot);
  r.pick_shown_set();
  r.ensure_targets(size.width, size.height, options.half_resolution_thickness, layers);
  if (slot.set_generation != r.targets.generation + (r.environment_generation << 32)) r.write_descriptors(slot);
  const Output output = output_path(target);
  const bool direct = output != Output::Present;
  r.bind_output(slot, direct ? r.array_view_of(target) : static_cast<VkImageView>(*r.targets.color.view));
  if (output == Output::DepthInShading) {
    r.ensure(r.host_depth, vk::DeviceSize(size.width) * size.height * layers * 4,
             vk::BufferUsageFlagBits::eStorageBuffer | vk::BufferUsageFlagBits::eShaderDeviceAddress |
                 vk::BufferUsageFlagBits::eTransferSrc | vk::BufferUsageFlagBits::eTransferDst,
             MemoryKind::DeviceLocal);
  }
  r.bind_scene_color(slot, target);
  r.bind_host_depth(slot, target, reads_host_depth_in_place(target, output));
  FrameSet* frame = r.shown >= 0 ? &r.sets[size_t(r.shown)] : nullptr;
  if (frame) frame->last_drawn = r.frames_recorded;

  slot.frame = r.frames_recorded;
  slot.collected = false;
  slot.stamp_names.clear();
  slot.classified = false;
  slot.particles = frame ? frame->particle_count : 0;
  slot.upload_ms = frame ? std::max(frame->upload_ms, 0.0) : 0;
  slot.decoded_on_gpu = frame && frame->decoded_on_gpu;
  slot.decode_ms = slot.decoded_on_gpu ? std::max(frame->decode_ms, 0.0) : 0;
  slot.decode_errors = frame && frame->decoded_on_gpu ? frame->decode_errors_found : 0;

  PassRecorder pass(r, vk::CommandBuffer(command_buffer), slot, slot_index);
  pass.begin_frame(target, output);
  if (frame) pass.prepare(*frame);
  // Mono: each view its own pass over the targets. A 2-layer target: both
  // eyes in one pass (one cull, every screen-space pass over both layers).
  const uint32_t passes = layers == 2 ? 1 : uint32_t(views.size());
  const bool views_tile = output == Output::DepthInShading && views_tile_target(target, views);
  for (uint32_t v = 0; v < passes; ++v) {
    ViewSetup setup;
    setup.width = size.width;
    setup.height = size.height;
    setup.thick_width = r.targets.thick_size.width;
    setup.thick_height = r.targets.thick_size.height;
    setup.max_point_size = r.ctx.properties.limits.pointSizeRange[1];
    setup.write_aux = r.options.debug_surfaces;
    const vk::DeviceSize offset = (vk::DeviceSize(slot_index) * kMaxViews + v) * r.globals_stride;
    for (uint32_t e = 0; e < layers; ++e) {
      Globals globals = make_globals(r.scene, views[v + e], options, lod, setup);
      globals.light[3] = r.has_environment ? 1.0f : 0.0f;
      globals.stereo[0] = layers;
      globals.stereo[1] = target.scene_color_image ? 1u : 0u;
      globals.stereo[2] = target.scene_color_image && !is_srgb(vk::Format(target.scene_color_format)) ? 1u : 0u;
      std::memcpy(static_cast<std::byte*>(r.globals.mapped) + offset + e * sizeof(Globals), &globals, sizeof globals);
    }
    pass.begin_view(uint32_t(offset), frame, layers);
    const bool compute_splat = options.splatting == Splatting::Compute ||
                               (options.splatting == Splatting::Auto && r.ctx.info.type != "cpu");
    pass.cull();
    if (compute_splat) {
      pass.splat();
    } else {
      pass.raster_spheres();
    }
    pass.filters(options);
    if (output == Output::Direct) {
      pass.shade(views[v].viewport, !target.background);
    } else if (output == Output::DepthInShading) {
      pass.shade_with_host_depth(target, views[v], v == 0, views_tile);
    } else {
      pass.shade({}, false);
      pass.present(target, views[v], v == 0);
    }
  }
  pass.end_frame(target, output);
  ++r.frames_recorded;
  FrameSync sync;
  sync.upload_semaphore = static_cast<VkSemaphore>(*r.upload_done);
  sync.upload_value = frame ? frame->ticket : 0;
  return sync;
}

// For render/src only: the free functions of load.h and inspection.h.
detail::RendererImpl& renderer_impl(Renderer& renderer) { return *renderer.impl_; }

}  // namespace sluice::render

namespace sluice::render {

void detail::RendererImpl::upload_environment(const Image& equirect) {
  // No image: a 1x1 placeholder so the descriptor stays valid (the shader uses the procedural sky).
  static const Image kPlaceholder{1, 1, {0, 0, 0, 255}};
  const Image& image = equirect.width == 0 || equirect.height == 0 ? kPlaceholder : equirect;
  const uint32_t width = image.width, height = image.height;
  const uint8_t* rgba = image.rgba.data();
  const vk::DeviceSize bytes = vk::DeviceSize(width) * height * 4;
  Buffer staging_env = create_buffer(ctx, bytes, vk::BufferUsageFlagBits::eTransferSrc, MemoryKind::Upload);
  std::memcpy(staging_env.mapped, rgba, bytes);
  retire(std::move(environment));  // frames in flight may still sample it
  ++environment_generation;
  environment = create_texture(ctx, {width, height}, vk::Format::eR8G8B8A8Srgb,
                               vk::ImageUsageFlagBits::eSampled | vk::ImageUsageFlagBits::eTransferDst);
  if (*environment_array) retire(std::move(environment_array));
  environment_array = vk::raii::ImageView(
      ctx.device, vk::ImageViewCreateInfo({}, *environment.image, vk::ImageViewType::e2DArray, environment.format, {},
                                          vk::ImageSubresourceRange(vk::ImageAspectFlagBits::eColor, 0, 1, 0, 1)));
  ctx.run_once([&](vk::CommandBuffer c) {
    const auto to_dst = image_barrier(environment, vk::ImageLayout::eUndefined, vk::ImageLayout::eTransferDstOptimal,
                                      vk::PipelineStageFlagBits2::eNone, vk::AccessFlagBits2::eNone,
                                      vk::PipelineStageFlagBits2::eCopy, vk::AccessFlagBits2::eTransferWrite);
    c.pipelineBarrier2(vk::DependencyInfo({}, {}, {}, to_dst));
    const vk::BufferImageCopy region(0, 0, 0, vk::ImageSubresourceLayers(vk::ImageAspectFlagBits::eColor, 0, 0, 1), {0, 0, 0},
                                     {width, height, 1});
    c.copyBufferToImage(*staging_env.buffer, *environment.image, vk::ImageLayout::eTransferDstOptimal, region);
    const auto to_read = image_barrier(environment, vk::ImageLayout::eTransferDstOptimal, vk::ImageLayout::eShaderReadOnlyOptimal,
                                       vk::PipelineStageFlagBits2::eCopy, vk::AccessFlagBits2::eTransferWrite,
                                       vk::PipelineStageFlagBits2::eComputeShader, vk::AccessFlagBits2::eShaderSampledRead);
    c.pipelineBarrier2(vk::DependencyInfo({}, {}, {}, to_read));
  });
}

void Renderer::set_environment(const Image& equirect) {
  Impl& r = *impl_;
  const bool has_image = equirect.width > 0 && equirect.height > 0;
  if (has_image && equirect.rgba.size() != size_t(equirect.width) * equirect.height * 4) {
    throw Error("set_environment: the image's pixels do not match its size");
  }
  const uint32_t limit = r.ctx.properties.limits.maxImageDimension2D;
  if (equirect.width > limit || equirect.height > limit) {
    throw Error("environment image of " + std::to_string(equirect.width) + "x" +
                                std::to_string(equirect.height) + " exceeds the device's largest image (" +
                                std::to_string(limit) + ")");
  }
  r.upload_environment(equirect);
  r.has_environment = has_image;
}

}  // namespace sluice::render
