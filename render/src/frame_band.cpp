// The narrow band of frames that arrive without layers (frame_band.h).
#include "frame_band.h"

#include <algorithm>
#include <bit>
#include <limits>

#include "frame_set.h"
#include "shaders.h"

namespace sluice::render {
namespace {

// Mirrors Push in band_frame.glsl.
struct FramePush {
  uint64_t particles, chunks, attributes, xyz, attr, params, layers, blobs, blob_attr, surface, marks;
  uint32_t n, chunk_count, room, float_positions, step;
  uint32_t pad;  // to the 8-byte alignment of the addresses; not in the shader's block
};
static_assert(sizeof(FramePush) == 112);

// 2D dispatch of `groups` workgroups (x at most 65535).
void dispatch(vk::CommandBuffer cmd, uint64_t groups) {
  const uint32_t x = uint32_t(std::clamp<uint64_t>(groups, 1, 65535));
  cmd.dispatch(x, uint32_t((std::max<uint64_t>(groups, 1) + x - 1) / x), 1);
}

}  // namespace

uint64_t blob_room(uint64_t particles) { return std::max<uint64_t>(particles / 4, 1024); }
uint64_t surface_words(uint64_t particles) { return 1 + (particles + 31) / 32; }
uint64_t shapes_bytes(uint64_t particles) { return 8 + 20 * particles; }

GpuChunk blob_chunk_row(std::span<const GpuChunk> table, uint64_t particles, float voxel) {
  GpuChunk row{};
  constexpr float kMax = std::numeric_limits<float>::max();
  for (int a = 0; a < 3; ++a) row.lo[a] = kMax, row.hi[a] = -kMax;
  row.attr_lo = kMax;
  row.attr_hi = -kMax;
  for (const GpuChunk& c : table) {
    if (c.count == 0) continue;
    for (int a = 0; a < 3; ++a) row.lo[a] = std::min(row.lo[a], c.lo[a]), row.hi[a] = std::max(row.hi[a], c.hi[a]);
    row.attr_lo = std::min(row.attr_lo, c.attr_lo);
    row.attr_hi = std::max(row.attr_hi, c.attr_hi);
  }
  if (row.lo[0] > row.hi[0]) {  // no particles: an empty row
    for (int a = 0; a < 3; ++a) row.lo[a] = row.hi[a] = 0;
    row.attr_lo = row.attr_hi = 0;
  }
  row.first = uint32_t(particles);
  row.count = 0;
  row.kind = 1;
  row.voxel = voxel;
  return row;
}

FrameBand::FrameBand(detail::ContextImpl& ctx, float diameter) : ctx_(ctx), diameter_(diameter), passes_(ctx) {
  const vk::PushConstantRange range(vk::ShaderStageFlagBits::eCompute, 0, sizeof(FramePush));
  layout_ = vk::raii::PipelineLayout(ctx.device, vk::PipelineLayoutCreateInfo({}, {}, range));
  gather_ = compute_pipeline(ctx.device, layout_, Shader::BandGather);
  apply_ = compute_pipeline(ctx.device, layout_, Shader::BandApply);
}

void FrameBand::record(vk::CommandBuffer cmd, FrameSet& set, bool float_positions, Wanted wanted,
                       const std::function<void(Buffer&&)>& retire) {
  const uint64_t n = set.particle_count;
  const uint64_t mark_words = (n + 31) / 32;  // a layered set's blob rows are among the positions
  constexpr auto usage = vk::BufferUsageFlagBits::eStorageBuffer | vk::BufferUsageFlagBits::eShaderDeviceAddress |
                         vk::BufferUsageFlagBits::eTransferDst;
  grow_buffer(ctx_, xyz_, n * 12, usage, MemoryKind::DeviceLocal, retire);
  if (wanted.classify) grow_buffer(ctx_, attr_, n * 4, usage, MemoryKind::DeviceLocal, retire);
  if (wanted.shapes) grow_buffer(ctx_, marks_, mark_words * 4, usage, MemoryKind::DeviceLocal, retire);
  passes_.reserve(n, wanted.classify, retire);

  const bool attributes = wanted.classify && set.has_attribute;
  FramePush push{};
  push.particles = set.particles.address;
  push.chunks = set.chunks.address;
  push.attributes = attributes ? set.attributes.address : 0;
  push.xyz = xyz_.address;
  push.attr = attributes ? attr_.address : 0;
  push.params = passes_.params.address;
  push.layers = passes_.particles.address + BandPasses::kLayerWord * n * 4;
  push.blobs = passes_.blobs.address;
  push.blob_attr = passes_.blob_attr.address;
  push.surface = set.surface.address;
  push.marks = wanted.shapes ? marks_.address : 0;
  push.n = uint32_t(n);
  push.chunk_count = set.chunk_count;
  push.room = uint32_t(blob_room(n));
  push.float_positions = float_positions ? 1 : 0;

  if (push.marks) {
    cmd.fillBuffer(*marks_.buffer, 0, mark_words * 4, 0);
    BandPasses::barrier(cmd);
  }
  cmd.bindPipeline(vk::PipelineBindPoint::eCompute, *gather_);
  cmd.pushConstants<FramePush>(*layout_, vk::ShaderStageFlagBits::eCompute, 0, push);
  dispatch(cmd, set.chunk_count);
  BandPasses::barrier(cmd);
  // The shapes after the validity word and h.
  passes_.record(cmd, BandRun{.n = n,
                              .xyz = xyz_.address,
                              .attr = attributes ? attr_.address : 0,
                              .diameter = diameter_,
                              .voxel = voxel(),
                              .blobs = wanted.classify,
                              .layers = wanted.classify,
                              .shapes = wanted.shapes ? set.shapes.address + 8 : 0,
                              .marks = push.marks});
  if (wanted.shapes) {
    cmd.fillBuffer(*set.shapes.buffer, 4, 4, std::bit_cast<uint32_t>(diameter_));
    cmd.fillBuffer(*set.shapes.buffer, 0, 4, 1);
    BandPasses::barrier(cmd);
  }
  if (!wanted.classify) return;
  cmd.bindPipeline(vk::PipelineBindPoint::eCompute, *apply_);
  for (uint32_t step : {0u, 1u}) {
    push.step = step;
    cmd.pushConstants<FramePush>(*layout_, vk::ShaderStageFlagBits::eCompute, 0, push);
    dispatch(cmd, step == 0 ? (surface_words(n) - 1 + 255) / 256 : (blob_room(n) + 255) / 256);
    BandPasses::barrier(cmd);
  }
}

}  // namespace sluice::render
