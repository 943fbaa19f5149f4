// sluice/render/draw.h: what Renderer::record() draws into and gives back:
// the host's target images, the semaphore wait its submission needs, and
// the figures of a recorded frame (GPU times, particles drawn). Plain data.
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstdint>
#include <string>
#include <vector>

namespace sluice::render {

struct PassTime {
  std::string name;  // "cull", "splat", "resolve", "filter", "shade", "present", ...
  double ms = 0;     // GPU time from timestamps, summed over the frame's views
};

struct FrameStats {
  uint64_t record_index = 0;    // which record() call (0-based) these figures are of (not a frame number)
  uint64_t particles = 0;       // in the frame drawn
  uint64_t drawn = 0;           // after frustum, near and LOD culling (the last view)
  uint64_t visible_chunks = 0;  // the last view
  std::vector<PassTime> passes;
  double gpu_ms = 0;            // first to last timestamp of the frame
  double upload_ms = 0;         // GPU time of the copy of the frame drawn
  bool decoded_on_gpu = false;  // the frame drawn was committed encoded (Renderer::commit of a frame kept encoded)
  double decode_ms = 0;         // GPU time of its decode (0 when not decoded on the GPU, or no timestamps)
  uint32_t decode_errors = 0;   // its chunks whose packed planes the GPU found inconsistent
  // RendererOptions::classify_unlayered: what the classification this frame
  // ran (if it ran one: the first draw of a frame without layers) made of it.
  struct Classification {
    bool ran = false;
    bool narrowed = false;   // drawn from surface + blobs; false: drawn whole
    uint64_t surface = 0;    // particles kept (L1 + L2 + isolated)
    uint64_t blobs = 0;      // voxel blobs (drawn only when narrowed: at most blob_room)
    uint64_t blob_room = 0;  // blobs the frame had room for
    uint32_t cells[3] = {};  // the voxel grid; 2^32 cells or more cannot be classified
    bool grid_fits = false;
  } classification;
};

// For logs and the HUD: "classified on the GPU: 5,012 surface + 1,190 blobs"
// or why the frame was drawn whole; "" when no classification ran.
std::string describe(const FrameStats::Classification& c);

// The caller's images. Layouts: the images are in `*_layout_before` when the
// recorded commands start and in `*_layout_after` when they end (sluice
// records the transitions, synchronized with everything before and after on
// the queue). A `before` layout of UNDEFINED discards the contents: colour is
// cleared to transparent black, depth to the far plane.
struct RenderTarget {
  uint32_t width = 0, height = 0;  // extent of the images (every view's viewport lies inside)
  VkImage color_image = VK_NULL_HANDLE;
  // A 2D view of layer base_layer (layer_count 1), or a 2D_ARRAY view of
  // layers base_layer.. base_layer + 1 (layer_count 2); colour attachment usage.
  VkImageView color_view = VK_NULL_HANDLE;
  VkFormat color_format = VK_FORMAT_UNDEFINED;  // *_SRGB formats get linear values (the hardware encodes)
  VkImageLayout color_layout_before = VK_IMAGE_LAYOUT_UNDEFINED;
  VkImageLayout color_layout_after = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
  // The colour image was created with VK_IMAGE_USAGE_STORAGE_BIT and its
  // (non-sRGB) format allows storage. Then, without a depth image, the
  // shading pass writes it directly and the present pass (a full-viewport
  // raster pass, slow on compute-first GPUs) is skipped.
  bool color_storage = false;
  // Optional: the host's depth (its opaque geometry). The fluid is hidden
  // behind it and writes its own depth into it.
  VkImage depth_image = VK_NULL_HANDLE;
  VkImageView depth_view = VK_NULL_HANDLE;      // as color_view: 2D, or 2D_ARRAY of layer_count layers
  VkFormat depth_format = VK_FORMAT_UNDEFINED;  // D16, D32, D24S8, D32S8
  // The depth image was created with VK_IMAGE_USAGE_TRANSFER_SRC_BIT and
  // TRANSFER_DST_BIT, and its format is D32, D32S8 or D24S8. Then, with
  // color_storage, the shading pass tests the fluid against the host's depth
  // and writes colour and depth itself, the depth going back by one copy of
  // the viewport (and out by one first, unless depth_layout_before is
  // UNDEFINED or depth_sampled), and the present pass is skipped: both eyes
  // of 2064x2208 took 0.48 ms this way on the H100 against 2.61 ms through
  // the present pass (docs/measurements.md). The depth image is in GENERAL
  // layout while the recorded commands run; the stencil is left alone.
  bool depth_transfer = false;
  // With depth_transfer, the depth image was also created with
  // VK_IMAGE_USAGE_SAMPLED_BIT: the shading pass reads a D32 or D32S8 depth
  // in place instead of copying it out (0.40 ms of 0.83 for both eyes of
  // 2064x2208 on the H100).
  bool depth_sampled = false;
  VkImageLayout depth_layout_before = VK_IMAGE_LAYOUT_UNDEFINED;
  VkImageLayout depth_layout_after = VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL;
  uint32_t base_layer = 0;  // the first array layer drawn
  // 1: every view into layer base_layer (side by side, each its own pass).
  // 2: stereo in one pass: views[0] into base_layer, views[1] into the next
  // (same viewport), with one cull for both eyes (a particle is kept for
  // both or neither: the larger LOD importance of the two eyes decides),
  // the point-sprite passes through multiview, and every screen-space pass
  // over both layers at once.
  uint32_t layer_count = 1;
  // Draw sluice's sky and ground where the host's depth is still at the far
  // plane (everywhere without a host depth); off: only the fluid is drawn.
  bool background = true;
  // Optional: the host's scene behind the fluid, refracted through it
  // instead of sluice's environment (as engines hand a scene-colour texture
  // to their transparent passes). A copy of the host's opaque colour, not
  // color_image (which sluice writes): the target's size and layers
  // (base_layer.., layer_count), VK_IMAGE_USAGE_SAMPLED_BIT, in
  // scene_color_layout (SHADER_READ_ONLY_OPTIMAL or GENERAL) while the
  // recorded commands run; the host makes its writes visible to compute
  // shader sampled reads before record() (a barrier in its command buffer).
  // *_SRGB formats are read as linear light, others as display
  // (sRGB-encoded) values, as sluice writes UNORM targets.
  VkImage scene_color_image = VK_NULL_HANDLE;
  VkFormat scene_color_format = VK_FORMAT_UNDEFINED;
  VkImageLayout scene_color_layout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
};

// One attachment of a host's target: the image, a view of it, its format
// and its layouts before and after sluice's commands (see RenderTarget).
struct TargetImage {
  VkImage image = VK_NULL_HANDLE;
  VkImageView view = VK_NULL_HANDLE;
  VkFormat format = VK_FORMAT_UNDEFINED;
  VkImageLayout before = VK_IMAGE_LAYOUT_UNDEFINED, after = VK_IMAGE_LAYOUT_UNDEFINED;
};

// A mono target (layer 0) over a host's colour image and, when `depth.image`
// is set, its depth image; every other field as RenderTarget's defaults.
RenderTarget render_target(uint32_t width, uint32_t height, const TargetImage& color, const TargetImage& depth = {});

// What the caller's submission of the recorded command buffer must wait on:
// the timeline semaphore of the uploads, at the value of the copy of the
// frame drawn. It is already signalled when record() returns (only finished
// copies are drawn); the wait orders the transfer queue's writes before the
// reads, as Vulkan's memory model requires. Value 0: nothing to wait for.
struct FrameSync {
  VkSemaphore upload_semaphore = VK_NULL_HANDLE;
  uint64_t upload_value = 0;
  VkPipelineStageFlags2 wait_stages = VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT;
};

}  // namespace sluice::render
