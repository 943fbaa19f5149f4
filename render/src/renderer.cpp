// The frame: pipelines, screen-space targets, and the command buffer that
// runs cull -> spheres -> filters -> shading with a timestamp per pass.
#include <algorithm>
#include <cstring>
#include <stdexcept>

#include "globals.h"
#include "renderer_impl.h"
#include "shaders.h"

namespace sluice::render {
namespace {

using Stage = vk::PipelineStageFlagBits2;
using Access = vk::AccessFlagBits2;
constexpr auto kAllStages = vk::ShaderStageFlagBits::eCompute | vk::ShaderStageFlagBits::eVertex |
                            vk::ShaderStageFlagBits::eFragment;


vk::raii::ShaderModule module(const vk::raii::Device& device, Shader s) {
  const std::span<const uint32_t> code = spirv(s);
  return vk::raii::ShaderModule(device, vk::ShaderModuleCreateInfo({}, code.size_bytes(), code.data()));
}

vk::raii::Pipeline compute_pipeline(const vk::raii::Device& device, const vk::raii::PipelineLayout& layout, Shader s) {
  const vk::raii::ShaderModule m = module(device, s);
  vk::ComputePipelineCreateInfo info({}, vk::PipelineShaderStageCreateInfo({}, vk::ShaderStageFlagBits::eCompute, *m, "main"),
                                     *layout);
  return vk::raii::Pipeline(device, nullptr, info);
}

// Point sprites into one colour target (and optionally reversed-z depth).
vk::raii::Pipeline sphere_pipeline(const vk::raii::Device& device, const vk::raii::PipelineLayout& layout, Shader fragment,
                                   vk::Format color, bool depth, bool additive) {
  const vk::raii::ShaderModule vs = module(device, Shader::SphereVert);
  const vk::raii::ShaderModule fs = module(device, fragment);
  const std::array stages{vk::PipelineShaderStageCreateInfo({}, vk::ShaderStageFlagBits::eVertex, *vs, "main"),
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
  vk::PipelineRenderingCreateInfo rendering(0, color, depth ? vk::Format::eD32Sfloat : vk::Format::eUndefined);
  vk::GraphicsPipelineCreateInfo info({}, stages, &vertex_input, &assembly, nullptr, &viewport, &raster, &multisample,
                                      &depth_state, &blend_state, &dynamic_state, *layout);
  info.pNext = &rendering;
  return vk::raii::Pipeline(device, nullptr, info);
}

constexpr auto kBufferUsage = vk::BufferUsageFlagBits::eStorageBuffer | vk::BufferUsageFlagBits::eShaderDeviceAddress |
                              vk::BufferUsageFlagBits::eTransferDst;

}  // namespace

void Renderer::Impl::create_pipelines() {
  const auto& device = ctx.device;
  std::vector<vk::DescriptorSetLayoutBinding> bindings{
      {0, vk::DescriptorType::eUniformBuffer, 1, kAllStages}};
  for (uint32_t b = 1; b <= 6; ++b) bindings.emplace_back(b, vk::DescriptorType::eStorageImage, 1, kAllStages);
  bindings.emplace_back(7, vk::DescriptorType::eCombinedImageSampler, 1, kAllStages);
  bindings.emplace_back(8, vk::DescriptorType::eCombinedImageSampler, 1, kAllStages);
  bindings.emplace_back(9, vk::DescriptorType::eStorageImage, 1, kAllStages);
  bindings.emplace_back(10, vk::DescriptorType::eStorageImage, 1, kAllStages);
  for (uint32_t b = 11; b <= 13; ++b) bindings.emplace_back(b, vk::DescriptorType::eStorageImage, 1, kAllStages);
  bindings.emplace_back(14, vk::DescriptorType::eCombinedImageSampler, 1, kAllStages);
  set_layout = vk::raii::DescriptorSetLayout(device, vk::DescriptorSetLayoutCreateInfo({}, bindings));
  vk::PushConstantRange push(kAllStages, 0, sizeof(PushConstants));
  layout = vk::raii::PipelineLayout(device, vk::PipelineLayoutCreateInfo({}, *set_layout, push));
  const std::array sizes{vk::DescriptorPoolSize(vk::DescriptorType::eUniformBuffer, 1),
                         vk::DescriptorPoolSize(vk::DescriptorType::eStorageImage, 11),
                         vk::DescriptorPoolSize(vk::DescriptorType::eCombinedImageSampler, 3)};
  pool = vk::raii::DescriptorPool(device, vk::DescriptorPoolCreateInfo(vk::DescriptorPoolCreateFlagBits::eFreeDescriptorSet, 1, sizes));
  set = std::move(vk::raii::DescriptorSets(device, vk::DescriptorSetAllocateInfo(*pool, *set_layout))[0]);
  sampler = vk::raii::Sampler(device, vk::SamplerCreateInfo({}, vk::Filter::eLinear, vk::Filter::eLinear,
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
  targets.thick_format = (props.optimalTilingFeatures & need) == need ? vk::Format::eR32G32Sfloat : vk::Format::eR16G16Sfloat;

  cull_chunks = compute_pipeline(device, layout, Shader::CullChunks);
  cull_args = compute_pipeline(device, layout, Shader::CullArgs);
  cull_particles = compute_pipeline(device, layout, Shader::CullParticles);
  splat = compute_pipeline(device, layout, Shader::Splat);
  resolve = compute_pipeline(device, layout, Shader::Resolve);
  filter_depth = compute_pipeline(device, layout, Shader::FilterDepth);
  filter_thickness = compute_pipeline(device, layout, Shader::FilterThickness);
  composite = compute_pipeline(device, layout, Shader::Composite);
  depth_pass = sphere_pipeline(device, layout, Shader::SphereDepthFrag, vk::Format::eR32Sfloat, true, false);
  thickness_pass = sphere_pipeline(device, layout, Shader::SphereThicknessFrag, targets.thick_format, false, true);
}

void Renderer::Impl::create_targets(uint32_t width, uint32_t height, bool half) {
  if (*ctx.device) ctx.device.waitIdle();
  using U = vk::ImageUsageFlagBits;
  const auto cleared = U::eTransferDst;  // cleared once at creation
  Targets& t = targets;
  t.size = vk::Extent2D(width, height);
  t.thick_size = half ? vk::Extent2D((width + 1) / 2, (height + 1) / 2) : t.size;
  half_thickness = half;
  t.depth_hw = create_texture(ctx, t.size, vk::Format::eD32Sfloat, U::eDepthStencilAttachment);
  t.depth_raw = create_texture(ctx, t.size, vk::Format::eR32Sfloat, U::eColorAttachment | U::eStorage | U::eTransferSrc | cleared);
  t.depth_a = create_texture(ctx, t.size, vk::Format::eR32Sfloat, U::eStorage | U::eTransferSrc | cleared);
  t.depth_b = create_texture(ctx, t.size, vk::Format::eR32Sfloat, U::eStorage | cleared);
  t.thick_raw = create_texture(ctx, t.thick_size, t.thick_format, U::eColorAttachment | U::eStorage | U::eSampled | cleared);
  t.thick_a = create_texture(ctx, t.thick_size, t.thick_format, U::eStorage | U::eSampled | cleared);
  t.thick_b = create_texture(ctx, t.thick_size, t.thick_format, U::eStorage | cleared);
  t.depth_u = create_texture(ctx, t.size, vk::Format::eR32Uint, U::eStorage | cleared);
  t.thick_u = create_texture(ctx, t.thick_size, vk::Format::eR32Uint, U::eStorage | cleared);
  t.thick_attr_u = create_texture(ctx, t.thick_size, vk::Format::eR32Uint, U::eStorage | cleared);
  t.color = create_texture(ctx, t.size, vk::Format::eR8G8B8A8Unorm, U::eStorage | U::eTransferSrc | cleared);
  t.aux = create_texture(ctx, t.size, vk::Format::eR32G32B32A32Sfloat, U::eStorage | U::eTransferSrc | cleared);
  // Everything the compute passes touch lives in GENERAL; the raster targets
  // move to attachment layouts and back every frame.
  ctx.run_once([&](vk::CommandBuffer c) {
    std::vector<vk::ImageMemoryBarrier2> barriers;
    const std::array all{&t.depth_raw, &t.depth_a, &t.depth_b, &t.thick_raw, &t.thick_a, &t.thick_b,
                         &t.depth_u, &t.thick_u, &t.thick_attr_u, &t.color, &t.aux};
    for (const Texture* x : all) {
      barriers.push_back(image_barrier(*x, vk::ImageLayout::eUndefined, vk::ImageLayout::eGeneral, Stage::eNone, {},
                                       Stage::eAllCommands, Access::eMemoryRead | Access::eMemoryWrite));
    }
    c.pipelineBarrier2(vk::DependencyInfo({}, {}, {}, barriers));
    // Clear so reads before the first frame are defined.
    const vk::ClearColorValue zero(std::array<float, 4>{0, 0, 0, 0});
    const vk::ImageSubresourceRange range(vk::ImageAspectFlagBits::eColor, 0, 1, 0, 1);
    // Compute splatting's depth starts "infinitely far" (all bits set).
    const vk::ClearColorValue far(std::array<uint32_t, 4>{0xffffffffu, 0xffffffffu, 0xffffffffu, 0xffffffffu});
    for (const Texture* x : all) {
      c.clearColorImage(*x->image, vk::ImageLayout::eGeneral, x == &t.depth_u ? far : zero, range);
    }
  });
  write_descriptors();
  ensure(readback, vk::DeviceSize(width) * height * 16, vk::BufferUsageFlagBits::eTransferDst, MemoryKind::Readback);
}

void Renderer::Impl::write_descriptors() {
  const Targets& t = targets;
  vk::DescriptorBufferInfo ubo(*globals.buffer, 0, sizeof(Globals));
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
      vk::WriteDescriptorSet(*set, 0, 0, vk::DescriptorType::eUniformBuffer, {}, ubo),
      vk::WriteDescriptorSet(*set, 1, 0, 1, vk::DescriptorType::eStorageImage, &storage[0]),
      vk::WriteDescriptorSet(*set, 2, 0, 1, vk::DescriptorType::eStorageImage, &storage[1]),
      vk::WriteDescriptorSet(*set, 3, 0, 1, vk::DescriptorType::eStorageImage, &storage[2]),
      vk::WriteDescriptorSet(*set, 4, 0, 1, vk::DescriptorType::eStorageImage, &storage[3]),
      vk::WriteDescriptorSet(*set, 5, 0, 1, vk::DescriptorType::eStorageImage, &storage[4]),
      vk::WriteDescriptorSet(*set, 6, 0, 1, vk::DescriptorType::eStorageImage, &storage[5]),
      vk::WriteDescriptorSet(*set, 7, 0, 1, vk::DescriptorType::eCombinedImageSampler, &sampled[0]),
      vk::WriteDescriptorSet(*set, 8, 0, 1, vk::DescriptorType::eCombinedImageSampler, &sampled[1]),
      vk::WriteDescriptorSet(*set, 9, 0, 1, vk::DescriptorType::eStorageImage, &color),
      vk::WriteDescriptorSet(*set, 10, 0, 1, vk::DescriptorType::eStorageImage, &aux),
      vk::WriteDescriptorSet(*set, 11, 0, 1, vk::DescriptorType::eStorageImage, &uints[0]),
      vk::WriteDescriptorSet(*set, 12, 0, 1, vk::DescriptorType::eStorageImage, &uints[1]),
      vk::WriteDescriptorSet(*set, 13, 0, 1, vk::DescriptorType::eStorageImage, &uints[2]),
      vk::WriteDescriptorSet(*set, 14, 0, 1, vk::DescriptorType::eCombinedImageSampler, &env),
  };
  ctx.device.updateDescriptorSets(writes, {});
}

void Renderer::Impl::ensure(Buffer& b, vk::DeviceSize size, vk::BufferUsageFlags usage, MemoryKind kind) {
  if (*b.buffer && b.size >= size) return;
  if (*ctx.device) ctx.device.waitIdle();
  b = Buffer{};
  // Grow with headroom so a slowly growing sequence does not reallocate every frame.
  const vk::DeviceSize grown = size + size / 8;
  b = create_buffer(ctx, std::max<vk::DeviceSize>(grown, 256), usage, kind);
}

std::vector<std::byte> Renderer::Impl::read_texture(const Texture& t, size_t texel_bytes) {
  const size_t bytes = size_t(t.extent.width) * t.extent.height * texel_bytes;
  ensure(readback, bytes, vk::BufferUsageFlagBits::eTransferDst, MemoryKind::Readback);
  ctx.run_once([&](vk::CommandBuffer c) {
    const auto to_copy = image_barrier(t, vk::ImageLayout::eGeneral, vk::ImageLayout::eTransferSrcOptimal, Stage::eAllCommands,
                                       Access::eMemoryWrite, Stage::eCopy, Access::eTransferRead);
    c.pipelineBarrier2(vk::DependencyInfo({}, {}, {}, to_copy));
    vk::BufferImageCopy region(0, 0, 0, vk::ImageSubresourceLayers(t.aspect, 0, 0, 1), {}, vk::Extent3D(t.extent, 1));
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

Renderer::Renderer(Context& context, const SceneInfo& scene, uint32_t width, uint32_t height)
    : impl_(std::make_unique<Impl>(context.impl(), scene)) {
  Impl& r = *impl_;
  if (width == 0 || height == 0) throw std::invalid_argument("renderer: image size must be at least 1x1");
  const auto& device = r.ctx.device;
  r.globals = create_buffer(r.ctx, sizeof(Globals), vk::BufferUsageFlagBits::eUniformBuffer, MemoryKind::Upload);
  r.args = create_buffer(r.ctx, sizeof(GpuArgs),
                         kBufferUsage | vk::BufferUsageFlagBits::eIndirectBuffer | vk::BufferUsageFlagBits::eTransferSrc,
                         MemoryKind::DeviceLocal);
  r.create_pipelines();
  r.upload_environment({});
  r.create_targets(width, height, true);
  r.command_pool = vk::raii::CommandPool(
      device, vk::CommandPoolCreateInfo(vk::CommandPoolCreateFlagBits::eResetCommandBuffer, r.ctx.graphics_family));
  r.cmd = std::move(vk::raii::CommandBuffers(device, vk::CommandBufferAllocateInfo(*r.command_pool, vk::CommandBufferLevel::ePrimary, 1))[0]);
  r.transfer_pool = vk::raii::CommandPool(
      device, vk::CommandPoolCreateInfo(vk::CommandPoolCreateFlagBits::eResetCommandBuffer, r.ctx.transfer_family));
  r.transfer_cmd = std::move(
      vk::raii::CommandBuffers(device, vk::CommandBufferAllocateInfo(*r.transfer_pool, vk::CommandBufferLevel::ePrimary, 1))[0]);
  r.fence = vk::raii::Fence(device, vk::FenceCreateInfo());
  vk::SemaphoreTypeCreateInfo timeline(vk::SemaphoreType::eTimeline, 0);
  vk::SemaphoreCreateInfo sem;
  sem.pNext = &timeline;
  r.upload_done = vk::raii::Semaphore(device, sem);
  r.timestamps = vk::raii::QueryPool(device, vk::QueryPoolCreateInfo({}, vk::QueryType::eTimestamp, kMaxStamps));
  r.upload_timestamps = vk::raii::QueryPool(device, vk::QueryPoolCreateInfo({}, vk::QueryType::eTimestamp, 2));
}

Renderer::~Renderer() {
  if (impl_ && *impl_->ctx.device) impl_->ctx.device.waitIdle();
}

void Renderer::resize(uint32_t width, uint32_t height) {
  if (width == 0 || height == 0) throw std::invalid_argument("renderer: image size must be at least 1x1");
  if (width == impl_->targets.size.width && height == impl_->targets.size.height) return;
  impl_->create_targets(width, height, impl_->half_thickness);
}
uint32_t Renderer::width() const { return impl_->targets.size.width; }
uint32_t Renderer::height() const { return impl_->targets.size.height; }
const SceneInfo& Renderer::scene() const { return impl_->scene; }

FrameStats Renderer::render(const Camera& camera, const FluidOptions& options, const LodOptions& lod) {
  Impl& r = *impl_;
  if (options.half_resolution_thickness != r.half_thickness) {
    r.create_targets(r.targets.size.width, r.targets.size.height, options.half_resolution_thickness);
  }
  const Targets& t = r.targets;
  ViewSetup view;
  view.width = t.size.width;
  view.height = t.size.height;
  view.thick_width = t.thick_size.width;
  view.thick_height = t.thick_size.height;
  view.max_point_size = r.ctx.properties.limits.pointSizeRange[1];
  view.write_aux = true;
  Globals globals = make_globals(r.scene, camera, options, lod, view);
  globals.light[3] = r.has_environment ? 1.0f : 0.0f;
  std::memcpy(r.globals.mapped, &globals, sizeof globals);

  PushConstants pc;
  pc.particles = r.particles.address;
  pc.chunks = r.chunks.address;
  pc.attributes = r.has_attribute ? r.attributes.address : r.chunks.address;
  pc.blocks = r.blocks.address;
  pc.draws = r.draws.address;
  pc.args = r.args.address;
  pc.big = r.big.address;
  pc.chunk_count = r.chunk_count;
  const bool have_frame = r.chunk_count > 0 && *r.particles.buffer;

  vk::CommandBuffer cmd = *r.cmd;
  cmd.reset();
  cmd.begin(vk::CommandBufferBeginInfo(vk::CommandBufferUsageFlagBits::eOneTimeSubmit));
  cmd.resetQueryPool(*r.timestamps, 0, kMaxStamps);
  std::vector<const char*> stamp_names{""};
  cmd.writeTimestamp2(Stage::eAllCommands, *r.timestamps, 0);
  // A timestamp after everything before it: the time of the pass just recorded.
  const auto stamp = [&](const char* name) {
    cmd.writeTimestamp2(Stage::eAllCommands, *r.timestamps, uint32_t(stamp_names.size()));
    stamp_names.push_back(name);
  };
  const auto push = [&](uint32_t p0 = 0, uint32_t p1 = 0, uint32_t p2 = 0) {
    pc.param0 = p0;
    pc.param1 = p1;
    pc.param2 = p2;
    cmd.pushConstants<PushConstants>(*r.layout, kAllStages, 0, pc);
  };
  const auto compute_to_compute = [&] {
    memory_barrier(cmd, Stage::eComputeShader, Access::eShaderStorageWrite, Stage::eComputeShader,
                   Access::eShaderStorageRead | Access::eShaderStorageWrite);
  };
  cmd.bindDescriptorSets(vk::PipelineBindPoint::eCompute, *r.layout, 0, *r.set, {});
  cmd.bindDescriptorSets(vk::PipelineBindPoint::eGraphics, *r.layout, 0, *r.set, {});

  // Cull: reset the counters, chunks -> blocks -> particles -> draw list.
  const GpuArgs reset{0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 1};
  cmd.updateBuffer<GpuArgs>(*r.args.buffer, 0, reset);
  // The splat targets were reset by the last frame's resolve (or at creation).
  const bool compute_splat = options.splatting == Splatting::Compute ||
                             (options.splatting == Splatting::Auto && r.ctx.info.type != "cpu");
  memory_barrier(cmd, Stage::eCopy, Access::eTransferWrite, Stage::eComputeShader | Stage::eDrawIndirect,
                 Access::eShaderStorageRead | Access::eShaderStorageWrite | Access::eIndirectCommandRead);
  if (have_frame) {
    cmd.bindPipeline(vk::PipelineBindPoint::eCompute, *r.cull_chunks);
    push();
    const uint32_t groups = (r.chunk_count + 63) / 64;
    cmd.dispatch(std::min(groups, 65535u), (groups + 65534) / 65535, 1);
    compute_to_compute();
    cmd.bindPipeline(vk::PipelineBindPoint::eCompute, *r.cull_args);
    push(0);
    cmd.dispatch(1, 1, 1);
    memory_barrier(cmd, Stage::eComputeShader, Access::eShaderStorageWrite, Stage::eComputeShader | Stage::eDrawIndirect,
                   Access::eShaderStorageRead | Access::eShaderStorageWrite | Access::eIndirectCommandRead);
    cmd.bindPipeline(vk::PipelineBindPoint::eCompute, *r.cull_particles);
    cmd.dispatchIndirect(*r.args.buffer, offsetof(GpuArgs, groups_x));
  }
  memory_barrier(cmd, Stage::eComputeShader, Access::eShaderStorageWrite,
                 Stage::eDrawIndirect | Stage::eVertexShader | Stage::eComputeShader,
                 Access::eIndirectCommandRead | Access::eShaderStorageRead | Access::eShaderStorageWrite);
  stamp("cull");

  // Spheres: exact depth, then additive thickness.
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
    cmd.pipelineBarrier2(vk::DependencyInfo({}, {}, {}, to));
    const vk::Rect2D area({0, 0}, target.extent);
    vk::RenderingAttachmentInfo color(*target.view, vk::ImageLayout::eColorAttachmentOptimal, {}, {}, {},
                                      vk::AttachmentLoadOp::eClear, vk::AttachmentStoreOp::eStore,
                                      vk::ClearValue(vk::ClearColorValue(std::array<float, 4>{0, 0, 0, 0})));
    vk::RenderingAttachmentInfo depth_info;
    vk::RenderingInfo info({}, area, 1, 0, color);
    if (depth) {
      depth_info = vk::RenderingAttachmentInfo(*depth->view, vk::ImageLayout::eDepthAttachmentOptimal, {}, {}, {},
                                               vk::AttachmentLoadOp::eClear, vk::AttachmentStoreOp::eDontCare,
                                               vk::ClearValue(vk::ClearDepthStencilValue(0.0f, 0)));
      info.setPDepthAttachment(&depth_info);
    }
    cmd.beginRendering(info);
    if (have_frame) {
      cmd.bindPipeline(vk::PipelineBindPoint::eGraphics, *pipeline);
      cmd.setViewport(0, vk::Viewport(0, 0, float(target.extent.width), float(target.extent.height), 0, 1));
      cmd.setScissor(0, area);
      push(flag);
      cmd.drawIndirect(*r.args.buffer, 0, 1, sizeof(VkDrawIndirectCommand));
    }
    cmd.endRendering();
    const auto back = image_barrier(target, vk::ImageLayout::eColorAttachmentOptimal, vk::ImageLayout::eGeneral,
                                    Stage::eColorAttachmentOutput, Access::eColorAttachmentWrite,
                                    Stage::eComputeShader | Stage::eFragmentShader,
                                    Access::eShaderStorageRead | Access::eShaderSampledRead);
    cmd.pipelineBarrier2(vk::DependencyInfo({}, {}, {}, back));
  };
  const auto groups = [](vk::Extent2D e, uint32_t n) { return std::array<uint32_t, 2>{(e.width + n - 1) / n, (e.height + n - 1) / n}; };
  if (!compute_splat) {
    raster(t.depth_raw, &t.depth_hw, r.depth_pass, 0);
    stamp("depth");
    raster(t.thick_raw, nullptr, r.thickness_pass, 1);
    stamp("thickness");
  } else {
    // Small splats one thread each; large ones listed, then one workgroup each.
    const auto args_then = [&](uint32_t which) {
      cmd.bindPipeline(vk::PipelineBindPoint::eCompute, *r.cull_args);
      push(which);
      cmd.dispatch(1, 1, 1);
      memory_barrier(cmd, Stage::eComputeShader, Access::eShaderStorageWrite, Stage::eComputeShader | Stage::eDrawIndirect,
                     Access::eShaderStorageRead | Access::eShaderStorageWrite | Access::eIndirectCommandRead);
    };
    if (have_frame) {
      args_then(1);
      cmd.bindPipeline(vk::PipelineBindPoint::eCompute, *r.splat);
      push(0);
      cmd.dispatchIndirect(*r.args.buffer, offsetof(GpuArgs, splat_x));
      compute_to_compute();
      args_then(2);
      cmd.bindPipeline(vk::PipelineBindPoint::eCompute, *r.splat);
      push(1);
      cmd.dispatchIndirect(*r.args.buffer, offsetof(GpuArgs, big_x));
      compute_to_compute();
    }
    stamp("splat");
    cmd.bindPipeline(vk::PipelineBindPoint::eCompute, *r.resolve);
    push(0);
    const auto gr = groups(t.size, 16);
    cmd.dispatch(gr[0], gr[1], 1);
    push(1);
    const auto gt = groups(t.thick_size, 16);
    cmd.dispatch(gt[0], gt[1], 1);
    memory_barrier(cmd, Stage::eComputeShader, Access::eShaderStorageWrite, Stage::eComputeShader | Stage::eFragmentShader,
                   Access::eShaderStorageRead | Access::eShaderSampledRead);
    stamp("resolve");
  }

  // Filters: separable passes raw -> B -> A, then A -> B -> A per iteration.
  const auto separable = [&](const vk::raii::Pipeline& pipeline, vk::Extent2D size, int iterations) {
    cmd.bindPipeline(vk::PipelineBindPoint::eCompute, *pipeline);
    const auto g = groups(size, 16);
    for (int i = 0; i < iterations; ++i) {
      push(i == 0 ? 0u : 1u, 2u, 0u);
      cmd.dispatch(g[0], g[1], 1);
      compute_to_compute();
      push(2u, 1u, 1u);
      cmd.dispatch(g[0], g[1], 1);
      compute_to_compute();
    }
  };
  if (depth_filtered(options)) separable(r.filter_depth, t.size, options.surface_filter_iterations);
  stamp("filter");
  if (thickness_filtered(options)) {
    separable(r.filter_thickness, t.thick_size, options.thickness_and_volume_color_filter_iterations);
  }
  stamp("thickness filter");

  // Normals, shading and the environment.
  cmd.bindPipeline(vk::PipelineBindPoint::eCompute, *r.composite);
  push();
  const auto gc = groups(t.size, 8);
  cmd.dispatch(gc[0], gc[1], 1);
  stamp("shade");

  // Counters back to the host for the stats.
  memory_barrier(cmd, Stage::eComputeShader | Stage::eDrawIndirect, Access::eShaderStorageWrite | Access::eIndirectCommandRead,
                 Stage::eCopy, Access::eTransferRead);
  cmd.copyBuffer(*r.args.buffer, *r.readback.buffer, vk::BufferCopy(0, 0, sizeof(GpuArgs)));
  memory_barrier(cmd, Stage::eCopy | Stage::eComputeShader, Access::eTransferWrite | Access::eShaderStorageWrite, Stage::eHost,
                 Access::eHostRead);
  cmd.end();

  const vk::CommandBufferSubmitInfo cb(cmd);
  const vk::SemaphoreSubmitInfo wait(*r.upload_done, r.upload_value, Stage::eAllCommands);
  r.ctx.device.resetFences(*r.fence);
  r.ctx.graphics_queue.submit2(vk::SubmitInfo2({}, wait, cb), *r.fence);
  while (r.ctx.device.waitForFences(*r.fence, VK_TRUE, UINT64_MAX) == vk::Result::eTimeout) {
  }

  FrameStats stats;
  GpuArgs counters;
  std::memcpy(&counters, r.readback.mapped, sizeof counters);
  stats.particles = r.particle_count;
  stats.drawn = have_frame ? counters.vertex_count : 0;
  stats.visible_chunks = have_frame ? counters.visible_chunks : 0;
  const uint32_t count = uint32_t(stamp_names.size());
  std::array<uint64_t, kMaxStamps> stamps{};
  const vk::Result res = (*r.ctx.device).getQueryPoolResults(*r.timestamps, 0, count, count * sizeof(uint64_t), stamps.data(),
                                                             sizeof(uint64_t), vk::QueryResultFlagBits::e64 | vk::QueryResultFlagBits::eWait);
  if (res == vk::Result::eSuccess) {
    const double ns = r.ctx.properties.limits.timestampPeriod;
    for (uint32_t i = 1; i < count; ++i) {
      stats.passes.push_back({stamp_names[i], double(stamps[i] - stamps[i - 1]) * ns * 1e-6});
    }
    stats.gpu_ms = double(stamps[count - 1] - stamps[0]) * ns * 1e-6;
  }
  stats.upload_ms = r.upload_ms;
  return stats;
}

std::vector<uint8_t> Renderer::read_rgba8() {
  const std::vector<std::byte> bytes = impl_->read_texture(impl_->targets.color, 4);
  std::vector<uint8_t> out(bytes.size());
  std::memcpy(out.data(), bytes.data(), bytes.size());
  return out;
}

std::vector<float> Renderer::read_surface() {
  const std::vector<std::byte> bytes = impl_->read_texture(impl_->targets.aux, 16);
  std::vector<float> out(bytes.size() / 4);
  std::memcpy(out.data(), bytes.data(), bytes.size());
  return out;
}

std::vector<float> Renderer::read_raw_depth() {
  const std::vector<std::byte> bytes = impl_->read_texture(impl_->targets.depth_raw, 4);
  std::vector<float> out(bytes.size() / 4);
  std::memcpy(out.data(), bytes.data(), bytes.size());
  return out;
}

}  // namespace sluice::render

namespace sluice::render {

void Renderer::Impl::upload_environment(const Image& equirect) {
  // No image: a 1x1 placeholder so the descriptor stays valid (the shader uses the procedural sky).
  static const Image kPlaceholder{1, 1, {0, 0, 0, 255}};
  const Image& image = equirect.width == 0 || equirect.height == 0 ? kPlaceholder : equirect;
  const uint32_t width = image.width, height = image.height;
  const uint8_t* rgba = image.rgba.data();
  const vk::DeviceSize bytes = vk::DeviceSize(width) * height * 4;
  Buffer staging_env = create_buffer(ctx, bytes, vk::BufferUsageFlagBits::eTransferSrc, MemoryKind::Upload);
  std::memcpy(staging_env.mapped, rgba, bytes);
  if (*ctx.device && *environment.image) ctx.device.waitIdle();  // the old texture may be in use
  environment = create_texture(ctx, {width, height}, vk::Format::eR8G8B8A8Srgb,
                               vk::ImageUsageFlagBits::eSampled | vk::ImageUsageFlagBits::eTransferDst);
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
    throw std::invalid_argument("set_environment: the image's pixels do not match its size");
  }
  const uint32_t limit = r.ctx.properties.limits.maxImageDimension2D;
  if (equirect.width > limit || equirect.height > limit) {
    throw std::invalid_argument("environment image of " + std::to_string(equirect.width) + "x" +
                                std::to_string(equirect.height) + " exceeds the device's largest image (" +
                                std::to_string(limit) + ")");
  }
  r.upload_environment(equirect);
  r.has_environment = has_image;
  r.write_descriptors();
}

}  // namespace sluice::render
