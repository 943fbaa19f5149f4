// sluice/render/frame.h: what the renderer needs to know about the data, and
// the staging interface through which a frame's particles reach the GPU.
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

#include "sluice/io/format.h"
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

}  // namespace sluice::render
