// sluice/render/frame.h: what the renderer needs to know about the data, and
// the two ways a frame's particles reach the GPU: a frame read from a file
// (FrameUpload, plain data: decoded particles or a plan to decode them on the
// GPU) and staging that a host fills (FrameStaging: live frames).
//
// Particles stay in the container's decoded form on the GPU (8 bytes each for
// Quantized16: u16 x,y,z relative to the chunk AABB and the u16 LOD value;
// 16 for Float32) and are dequantized in the cull shader, so an upload moves
// exactly what decode_chunk() wrote.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <vulkan/vulkan_core.h>

#include "sluice/io/format.h"
#include "sluice/io/gpu_decode_plan.h"
#include "sluice/render/camera.h"

namespace sluice::io {
class ContainerReader;
struct DecodedFrame;
}  // namespace sluice::io

namespace sluice::render {

// Constant over a sequence.
struct SceneInfo {
  Bounds bounds;                 // of every frame
  Vec3 up{0, 0, 1};              // world direction that points up (the file's, format 1.2; +z before)
  float particle_spacing = 0;    // rest spacing (0 if unknown)
  float particle_radius = 0;     // stored radius (0 if unknown)
  io::PositionCoding coding = io::PositionCoding::Quantized16;
  std::vector<std::string> attribute_names;
  std::vector<std::array<float, 2>> attribute_ranges;  // observed over every frame
  uint64_t max_particles = 0;    // the largest frame, for sizing buffers
  uint64_t max_chunks = 0;
};
SceneInfo scene_info(const io::ContainerReader& reader);

// One chunk as the GPU sees it (std430 layout, 64 bytes).
struct GpuChunk {
  float lo[3];
  uint32_t first;   // index of the chunk's first particle in the frame
  float hi[3];
  uint32_t count;
  float attr_lo, attr_hi;  // range the colour attribute is quantized against
  uint32_t kind = 0;       // 0: particles; 1: voxel blobs (io::Layer::Blobs: the LOD value is the count)
  float voxel = 0;         // blobs: side of their voxels (FrameHeader::blob_voxel)
  // Every particle's LOD value lies in [lod_lo, lod_hi] (blobs: their random
  // term u, io::blob_lod_uniform(), below (lod_hi + 1) / 65536; lod_lo says
  // nothing). A file's LOD tiers give them (io/lod.h); the defaults claim
  // nothing. The cull drops a chunk whose largest value no view keeps
  // without reading its particles: a claim that is wrong loses particles.
  uint16_t lod_lo = 0, lod_hi = 65535;
  uint32_t reserved[3] = {0, 0, 0};
};
static_assert(sizeof(GpuChunk) == 64);

// Mapped staging memory for one frame: the allocator interface. Whoever
// decodes (the runtime's workers, or load_frame below) writes each chunk's
// particles straight into `particles` at first*stride, its colour attribute
// into `color_attribute` at `first`, and its row of `chunks`. The spans are
// valid until the next Renderer::commit_frame(); they may be written from any
// thread, each byte by one thread.
struct FrameStaging {
  std::span<std::byte> particles;         // particle_count * stride bytes
  std::span<uint16_t> color_attribute;    // particle_count values, or empty
  std::span<GpuChunk> chunks;             // chunk_count rows
  size_t stride = 8;
};

// Bytes of a frame the renderer copies to the GPU: always readable at `host`;
// when `buffer` is set, the same bytes also lie in that Vulkan buffer (of the
// renderer's Context, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, host-coherent) at
// `offset`, and the GPU copies them from there with no copy on the CPU.
// Either way they must stay untouched until Renderer::upload_complete().
struct UploadBytes {
  std::span<const std::byte> host;
  VkBuffer buffer = VK_NULL_HANDLE;
  uint64_t offset = 0;
};

// A frame read from a file, as Renderer::commit() takes it: plain data,
// borrowed for the call (what a FrameHandle of the streaming runtime holds:
// render::frame_upload() in staging_allocator.h makes one of it).
struct FrameUpload {
  const io::FrameHeader* header = nullptr;  // the chunk table: counts, boxes, layers, attribute ranges
  // First particle of each chunk (the running sum of the counts), checked; empty: from the counts.
  std::span<const uint64_t> chunk_first;
  // Decoded (plan == nullptr): particle_count * io::decoded_particle_bytes()
  // of the scene's coding. Encoded: the staged area plan->staged_bytes()
  // long (io/gpu_decode_plan.h), decoded on the GPU; empty when `resident`.
  UploadBytes particles;
  // Decoded frames: the colour attribute, one 16-bit value a particle, padded
  // to 4 bytes; empty for none. Encoded frames decode it with the plan.
  UploadBytes color;
  int color_attribute = -1;  // its index in the file header (the chunks' ranges); -1: no colour
  const io::GpuDecodePlan* plan = nullptr;
  // An encoded frame already in device memory (a relay filled it): its staged
  // area is this buffer (VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT and
  // TRANSFER_DST, at least staged_bytes() long; the renderer writes the
  // plan's tables into it) at device address `address` (its
  // vkGetBufferDeviceAddress, taken once by its owner), and the decode waits
  // until `semaphore` (a timeline) reaches `value` (0: nothing to wait for).
  struct Resident {
    VkBuffer buffer = VK_NULL_HANDLE;
    VkDeviceAddress address = 0;
    uint64_t bytes = 0;
    VkSemaphore semaphore = VK_NULL_HANDLE;
    uint64_t value = 0;
  } resident;
};

}  // namespace sluice::render
