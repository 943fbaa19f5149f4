// Internal: the state behind sluice::render::Renderer, shared by renderer.cpp
// (lifetime, record()), passes.cpp (one function per pass), targets.cpp
// (screen-space targets) and upload.cpp (staging, copies).
#pragma once

#include <array>
#include <deque>
#include <functional>

#include "gpu_types.h"
#include "decode_pass.h"
#include "frame_band.h"
#include "frame_set.h"
#include "sluice/render/context.h"
#include "sluice/render/draw.h"
#include "sluice/render/frame.h"
#include "sluice/render/image_io.h"
#include "sluice/render/options.h"
#include "vk_common.h"

namespace sluice::render {

constexpr uint32_t kMaxViews = 4;
// Every stage that reads the uniforms and push constants.
constexpr auto kAllStages = vk::ShaderStageFlagBits::eCompute | vk::ShaderStageFlagBits::eVertex |
                            vk::ShaderStageFlagBits::eFragment;
// Timestamp slots per frame slot: one at the start and one after each pass of each view.
constexpr uint32_t kStampsPerSlot = 64;
// Where a FrameSlot's readback holds its timestamps (16 bytes each).
constexpr vk::DeviceSize kStampsOffset = 256;

// The screen-space targets of one view size (views of a frame share them).
struct Targets {
  vk::Extent2D size, thick_size;
  vk::Format thick_format = vk::Format::eR32G32Sfloat;
  bool half_thickness = true;
  uint32_t layers = 1;                         // eyes drawn in one pass (multiview targets: 2)
  Texture depth_hw;                            // D32, reversed z (point-sprite path)
  Texture depth_raw, depth_a, depth_b;         // R32F linear depth
  Texture thick_raw, thick_a, thick_b;         // thickness, thickness * attribute
  Texture depth_u, thick_u, thick_attr_u;      // R32UI targets of compute splatting
  Texture color;                               // RGBA8 shaded fluid, before present
  Texture aux;                                 // RGBA32F eye normal + depth (debug_surfaces)
  uint64_t generation = 0;                     // bumps on every re-creation
  bool initialized = false;                    // layouts set and cleared (recorded once)
};

// Host-written and host-read resources of one frame in flight.
struct FrameSlot {
  vk::raii::DescriptorSet set{nullptr};
  uint64_t set_generation = UINT64_MAX;  // targets generation the set was written for
  // GpuArgs of the last view, BandParams, then the frame's timestamps as
  // (value, availability) pairs copied by the GPU (kStampsOffset): read
  // from mapped memory, so reading figures never calls into the driver
  // (lavapipe's vkGetQueryPoolResults waits for the device to go idle).
  Buffer readback;
  uint64_t frame = UINT64_MAX;            // record() call that used it last
  std::vector<const char*> stamp_names;   // per timestamp after the first
  uint64_t particles = 0;
  double upload_ms = 0;
  bool decoded_on_gpu = false;
  double decode_ms = 0;
  uint32_t decode_errors = 0;
  bool classified = false;                // its frame classified one: BandParams after the GpuArgs
  uint64_t blob_room = 0;
  bool collected = true;
};

namespace detail {
struct RendererImpl;
}  // namespace detail

struct detail::RendererImpl {
  detail::ContextImpl& ctx;
  SceneInfo scene;
  RendererOptions options;

  vk::raii::DescriptorSetLayout set_layout{nullptr};
  vk::raii::PipelineLayout layout{nullptr};
  vk::raii::DescriptorPool pool{nullptr};
  vk::raii::Sampler sampler{nullptr};
  vk::raii::Sampler nearest_sampler{nullptr};  // texel reads of formats without linear filtering (the host's depth)
  vk::raii::Pipeline cull_chunks{nullptr}, cull_args{nullptr}, cull_particles{nullptr};
  std::array<vk::raii::Pipeline, 2> depth_pass{nullptr, nullptr}, thickness_pass{nullptr, nullptr};  // [eyes - 1]
  vk::raii::Pipeline splat{nullptr}, resolve{nullptr};
  vk::raii::Pipeline splat_ellipsoids{nullptr};  // with options.anisotropic (common.glsl's kEllipsoids)
  vk::raii::Pipeline filter_depth{nullptr}, filter_thickness{nullptr}, composite{nullptr};
  struct PresentPipeline {
    vk::Format color, depth;
    vk::raii::Pipeline pipeline{nullptr};
  };
  std::vector<PresentPipeline> present_pipelines;
  vk::Format thick_format = vk::Format::eR32G32Sfloat;
  Targets targets;
  // Equirectangular environment (sRGB); 1x1 placeholder while the procedural sky is used.
  Texture environment;
  vk::raii::ImageView environment_array{nullptr};  // the same as a 1-layer array: the scene colour's stand-in
  uint64_t environment_generation = 0;
  vk::raii::Sampler environment_sampler{nullptr};
  bool has_environment = false;

  // Uniforms: frames_in_flight * kMaxViews pairs of Globals (one per eye; the
  // second unused in mono), each pair at its dynamic offset.
  Buffer globals;
  vk::DeviceSize globals_stride = 0;
  // Counters and work lists written and read by the GPU only (ordered by
  // barriers on the graphics queue, so frames in flight share them).
  Buffer args, blocks, draws, big;
  // The host's depth of one view (its layers x viewport, 4 bytes a pixel), copied out for
  // the shading pass to test and write, then back (Output::DepthInShading).
  Buffer host_depth;
  std::vector<FrameSlot> slots;
  vk::raii::QueryPool timestamps{nullptr};  // frames_in_flight * kStampsPerSlot
  bool timestamps_valid = false;
  uint64_t frames_recorded = 0;
  FrameStats stats;  // the newest collected

  vk::raii::CommandPool transfer_pool{nullptr};  // before the sets: their command buffers come from it
  vk::raii::CommandPool decode_pool{nullptr};    // graphics family: the sets' decode command buffers
  std::unique_ptr<DecodePass> decode_pass;       // made at the first commit_encoded
  std::vector<FrameSet> sets;  // frames_in_flight + 1
  int shown = -1;              // set record() draws
  int staged = -1;             // set stage_frame() filled
  size_t stride = 8;
  std::unique_ptr<FrameBand> band;  // with options.classify_unlayered or .anisotropic, and a known particle size
  vk::raii::Semaphore upload_done{nullptr};  // timeline: value = uploads submitted (copies, or decodes after them)
  uint64_t upload_value = 0;
  uint64_t last_decode_ticket = 0;           // the upload value the last decode signals (graphics queue)
  vk::raii::Semaphore copy_done{nullptr};    // timeline of the copies of frames committed encoded
  uint64_t copy_value = 0;

  // Objects the GPU may still use, destroyed frames_in_flight record() calls later.
  struct Retired {
    uint64_t after_frame;
    std::function<void()> keep;  // owns the objects through its captures
  };
  std::deque<Retired> retired;

  RendererImpl(detail::ContextImpl& c, const SceneInfo& s, const RendererOptions& o) : ctx(c), scene(s), options(o) {}

  void create_pipelines();
  const vk::raii::Pipeline& present_pipeline(vk::Format color, vk::Format depth);
  // Makes the targets `width` x `height` x `layers` (retiring the old ones).
  void ensure_targets(uint32_t width, uint32_t height, bool half_thickness, uint32_t layers);
  void write_descriptors(FrameSlot& slot);
  void bind_output(FrameSlot& slot, VkImageView view);  // binding 9: where shading writes
  // The caller's colour layers as an array view, for shading straight into them.
  VkImageView array_view_of(const RenderTarget& target);
  // A 2D view of one layer of a caller's image, for this frame's commands.
  VkImageView layer_view(VkImage image, VkFormat format, vk::ImageAspectFlags aspect, uint32_t layer);
  void upload_environment(const Image& equirect);  // empty: a 1x1 placeholder
  // Grows a buffer to at least `size` bytes (contents are lost; the old one is retired).
  void ensure(Buffer& b, vk::DeviceSize size, vk::BufferUsageFlags usage, MemoryKind kind);
  template <class T>
  void retire(T&& object) {
    auto holder = std::make_shared<T>(std::move(object));
    retired.push_back({frames_recorded + options.frames_in_flight, [holder] {}});
  }
  void collect_retired();
  // The newest set whose copy is done, if newer than the shown one.
  void pick_shown_set();
  // A set the next copy may write: not drawn by a frame that may still run.
  int free_set();
  bool set_in_use(const FrameSet& s) const;
  // Reads a slot's figures into `stats` once they are back; `finished`: the
  // caller knows the slot's frame is done.
  void collect_slot(FrameSlot& slot, bool finished);
  // Binding 16: the target's scene colour (a view made for this frame), or the environment.
  // A 2D_ARRAY view of `image`'s layers of the target (base_layer,
  // layer_count) that lives as long as this frame's commands.
  VkImageView frame_array_view(VkImage image, VkFormat format, vk::ImageAspectFlags aspect, const RenderTarget& target);
  void bind_scene_color(FrameSlot& slot, const RenderTarget& target);
  // Binding 17: the host's depth image (depth aspect, the target's layers)
  // when the shading pass reads it in place (`read`), else a placeholder.
  void bind_host_depth(FrameSlot& slot, const RenderTarget& target, bool read);
  std::vector<std::byte> read_texture(const Texture& t, size_t texel_bytes);
};

// The multiview mask that draws `layers` eyes at once (0: no multiview).
constexpr uint32_t view_mask(uint32_t layers) { return layers > 1 ? (1u << layers) - 1u : 0u; }

// Formats the hardware sRGB-encodes on write (no storage, present pass only).
bool is_srgb(vk::Format f);

}  // namespace sluice::render
