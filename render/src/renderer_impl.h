// Internal: the state behind sluice::render::Renderer, shared by renderer.cpp
// (pipelines, targets, recording a frame) and upload.cpp (staging, copies).
#pragma once

#include <array>

#include "gpu_types.h"
#include "sluice/render/renderer.h"
#include "vk_common.h"

namespace sluice::render {

// Timestamp slots per frame: one at the start and one after each pass.
constexpr uint32_t kMaxStamps = 16;

struct Targets {
  vk::Extent2D size, thick_size;
  vk::Format thick_format = vk::Format::eR32G32Sfloat;
  Texture depth_hw;                            // D32, reversed z
  Texture depth_raw, depth_a, depth_b;         // R32F linear depth
  Texture thick_raw, thick_a, thick_b;         // thickness, thickness * attribute
  Texture depth_u, thick_u, thick_attr_u;      // R32UI targets of compute splatting
  Texture color;                               // RGBA8 output
  Texture aux;                                 // RGBA32F eye normal + depth (tests)
};

struct Renderer::Impl {
  Context::Impl& ctx;
  SceneInfo scene;

  vk::raii::DescriptorSetLayout set_layout{nullptr};
  vk::raii::PipelineLayout layout{nullptr};
  vk::raii::DescriptorPool pool{nullptr};
  vk::raii::DescriptorSet set{nullptr};
  vk::raii::Sampler sampler{nullptr};
  vk::raii::Pipeline cull_chunks{nullptr}, cull_args{nullptr}, cull_particles{nullptr};
  vk::raii::Pipeline depth_pass{nullptr}, thickness_pass{nullptr};
  vk::raii::Pipeline splat{nullptr}, resolve{nullptr};
  vk::raii::Pipeline filter_depth{nullptr}, filter_thickness{nullptr}, composite{nullptr};
  bool half_thickness = true;
  Targets targets;
  // Equirectangular environment (sRGB); 1x1 placeholder while the procedural sky is used.
  Texture environment;
  vk::raii::Sampler environment_sampler{nullptr};
  bool has_environment = false;

  // Per frame: uniforms, counters, readback of counters and images.
  Buffer globals, args, readback;

  // The frame on the GPU (quantized particles, chunk table, colour attribute)
  // and the work lists the cull writes.
  Buffer staging;    // persistently mapped: particles | chunks | attribute
  Buffer particles, chunks, attributes, blocks, draws, big;
  uint64_t particle_count = 0, staged_particles = 0;
  uint32_t chunk_count = 0, staged_chunks = 0;
  size_t stride = 8;
  bool has_attribute = false, staged_attribute = false;

  vk::raii::CommandPool command_pool{nullptr}, transfer_pool{nullptr};
  vk::raii::CommandBuffer cmd{nullptr}, transfer_cmd{nullptr};
  vk::raii::Fence fence{nullptr};
  vk::raii::Semaphore upload_done{nullptr};  // timeline: value = uploads committed
  uint64_t upload_value = 0;
  vk::raii::QueryPool timestamps{nullptr}, upload_timestamps{nullptr};
  bool upload_timed = false;
  double upload_ms = 0;

  Impl(Context::Impl& c, const SceneInfo& s) : ctx(c), scene(s) {}

  void create_pipelines();
  void create_targets(uint32_t width, uint32_t height, bool half_thickness);
  void write_descriptors();
  void upload_environment(const Image& equirect);  // empty: a 1x1 placeholder
  // Grows a device buffer to at least `size` bytes (contents are lost).
  void ensure(Buffer& b, vk::DeviceSize size, vk::BufferUsageFlags usage, MemoryKind kind);
  void wait_uploads();
  struct UploadSource {  // where upload_frame() (upload.cpp) copies a frame from
    vk::Buffer buffer;
    vk::DeviceSize offset = 0;
  };
  std::vector<std::byte> read_texture(const Texture& t, size_t texel_bytes);
};

}  // namespace sluice::render
