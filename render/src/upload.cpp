// Frames to the GPU: persistently mapped staging that decoders write into,
// then one copy per buffer on the transfer queue (where there is one) into
// one of the renderer's device frame sets, signalling a timeline semaphore;
// frames kept encoded are copied as they are and decoded by a compute
// submission on the graphics queue (decode_pass.h), which signals instead.
// record() draws the newest set whose upload is done.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <stdexcept>

#include "renderer_state.h"
#include "upload.h"
#include "sluice/render/renderer.h"
#include "sluice/io/codec.h"
#include "sluice/io/lod.h"
#include "sluice/io/reader.h"
#include "sluice/error.h"

namespace sluice::render {
namespace {

constexpr auto kDeviceUsage = vk::BufferUsageFlagBits::eStorageBuffer | vk::BufferUsageFlagBits::eShaderDeviceAddress |
                              vk::BufferUsageFlagBits::eTransferDst;

// Staging layout: particles | chunk table | colour attribute, each 16-aligned.
struct StagingLayout {
  vk::DeviceSize particles = 0, chunks = 0, attribute = 0, total = 0;
};
StagingLayout staging_layout(uint64_t particles, uint32_t chunks, size_t stride, bool attribute) {
  const auto align = [](vk::DeviceSize v) { return (v + 15) & ~vk::DeviceSize(15); };
  StagingLayout l;
  l.particles = 0;
  l.chunks = align(particles * stride);
  l.attribute = align(l.chunks + vk::DeviceSize(chunks) * sizeof(GpuChunk));
  l.total = align(l.attribute + (attribute ? particles * 2 : 0));
  return l;
}

}  // namespace

bool Renderer::upload_complete(uint64_t ticket) const {
  return ticket == 0 || impl_->upload_done.getCounterValue() >= ticket;
}

void Renderer::wait_upload(uint64_t ticket) const {
  if (ticket == 0 || upload_complete(ticket)) return;
  const vk::Semaphore sem = *impl_->upload_done;
  const vk::SemaphoreWaitInfo info({}, sem, ticket);
  while (impl_->ctx.device.waitSemaphores(info, UINT64_MAX) == vk::Result::eTimeout) {
  }
}

bool detail::RendererImpl::set_in_use(const FrameSet& s) const {
  // The host guarantees that record() call n - 1 - frames_in_flight has
  // finished by the time call n - 1 was made (n calls made so far).
  return s.last_drawn != UINT64_MAX && s.last_drawn + options.frames_in_flight >= frames_recorded;
}

int detail::RendererImpl::free_set() {
  int best = -1;
  for (int i = 0; i < int(sets.size()); ++i) {
    if (i == shown || set_in_use(sets[size_t(i)])) continue;
    if (best < 0 || sets[size_t(i)].ticket < sets[size_t(best)].ticket) best = i;
  }
  if (best < 0) {
    throw Error("renderer: every frame buffer is in use by frames in flight; commit at most one frame per "
                           "recorded frame (see the frames-in-flight contract in renderer.h)");
  }
  // A newer frame supersedes one whose copy may still run: wait for that copy
  // only (the transfer queue), never for rendering.
  const vk::Semaphore sem = *upload_done;
  const uint64_t ticket = sets[size_t(best)].ticket;
  if (ticket > 0 && upload_done.getCounterValue() < ticket) {
    const vk::SemaphoreWaitInfo info({}, sem, ticket);
    while (ctx.device.waitSemaphores(info, UINT64_MAX) == vk::Result::eTimeout) {
    }
  }
  return best;
}

void detail::RendererImpl::pick_shown_set() {
  const uint64_t done = upload_done.getCounterValue();
  int newest = shown;
  for (int i = 0; i < int(sets.size()); ++i) {
    const FrameSet& s = sets[size_t(i)];
    if (s.ticket == 0 || s.ticket > done) continue;
    if (newest < 0 || s.ticket > sets[size_t(newest)].ticket) newest = i;
  }
  shown = newest;
  if (shown < 0) return;
  FrameSet& s = sets[size_t(shown)];
  if (s.decoded_on_gpu && s.decode_ms < 0) {
    std::array<uint64_t, 2> stamps{};
    s.decode_ms = (*ctx.device).getQueryPoolResults(*s.decode_stamps, 0, 2, sizeof stamps, stamps.data(), sizeof(uint64_t),
                                                    vk::QueryResultFlagBits::e64) == vk::Result::eSuccess
                      ? double(stamps[1] - stamps[0]) * ctx.properties.limits.timestampPeriod * 1e-6
                      : 0;
    const auto* errors = static_cast<const uint32_t*>(s.decode_errors.mapped);
    s.decode_errors_found = uint32_t(std::count_if(errors, errors + s.chunk_count, [](uint32_t e) { return e != 0; }));
  }
  if (s.upload_ms < 0) {
    std::array<uint64_t, 2> stamps{};
    if ((*ctx.device).getQueryPoolResults(*s.stamps, 0, 2, sizeof stamps, stamps.data(), sizeof(uint64_t),
                                          vk::QueryResultFlagBits::e64) == vk::Result::eSuccess) {
      s.upload_ms = double(stamps[1] - stamps[0]) * ctx.properties.limits.timestampPeriod * 1e-6;
    } else {
      s.upload_ms = 0;
    }
  }
}

FrameStaging Renderer::stage_frame(uint64_t particles, uint32_t chunks) {
  Impl& r = *impl_;
  r.staged = r.free_set();
  FrameSet& set = r.sets[size_t(r.staged)];
  r.stride = io::decoded_particle_bytes(r.scene.coding);
  const bool attribute = !r.scene.attribute_names.empty();
  const StagingLayout l = staging_layout(particles, chunks, r.stride, attribute);
  r.ensure(set.staging, l.total, vk::BufferUsageFlagBits::eTransferSrc, MemoryKind::Upload);
  set.particle_count = particles;
  set.chunk_count = chunks;
  set.has_attribute = attribute;
  set.ticket = 0;  // being refilled: never shown until its new copy is done
  set.layering_known = false;
  auto* base = static_cast<std::byte*>(set.staging.mapped);
  FrameStaging s;
  s.stride = r.stride;
  s.particles = {base + l.particles, size_t(particles * r.stride)};
  s.chunks = {reinterpret_cast<GpuChunk*>(base + l.chunks), chunks};
  if (attribute) s.color_attribute = {reinterpret_cast<uint16_t*>(base + l.attribute), size_t(particles)};
  return s;
}

namespace {

struct UploadSource {  // where upload_frame() copies a part of a frame from
  vk::Buffer buffer;
  vk::DeviceSize offset = 0;
};

// A frame committed encoded: its staged area, decoded on the GPU after the
// copy. A resident one (FrameUpload::Resident) is in device memory already:
// only its tables are copied (from `area`, table_block_bytes() of them), into it.
struct EncodedSource {
  UploadSource area;
  const io::GpuDecodePlan* plan = nullptr;
  vk::Buffer resident;  // the resident area, when set
  vk::DeviceAddress resident_address = 0;
  vk::Semaphore relayed;  // what fills it, and the value the decode waits for
  uint64_t relayed_value = 0;
};

// Records the decode of `set`'s staged area into its particle and
// attribute buffers, creating what it needs first (the pass, a command
// buffer, the tile sums sized for `plan`); submits nothing, so a failure
// here leaves no copy in flight.
void record_decode(detail::RendererImpl& r, FrameSet& set, const io::GpuDecodePlan& plan, vk::DeviceAddress encoded) {
  using Stage = vk::PipelineStageFlagBits2;
  using Access = vk::AccessFlagBits2;
  if (!r.decode_pass) {
    r.decode_pass = std::make_unique<DecodePass>(r.ctx);
    r.decode_pool = vk::raii::CommandPool(
        r.ctx.device, vk::CommandPoolCreateInfo(vk::CommandPoolCreateFlagBits::eResetCommandBuffer, r.ctx.graphics_family));
  }
  if (!*set.decode) {
    set.decode = std::move(vk::raii::CommandBuffers(
        r.ctx.device, vk::CommandBufferAllocateInfo(*r.decode_pool, vk::CommandBufferLevel::ePrimary, 1))[0]);
    set.decode_stamps = vk::raii::QueryPool(r.ctx.device, vk::QueryPoolCreateInfo({}, vk::QueryType::eTimestamp, 2));
  }
  r.ensure(set.decode_tiles, std::max<uint64_t>(plan.tile_chunk.size() * DecodePass::kTileSumBytes, 16), kDeviceUsage,
           MemoryKind::DeviceLocal);
  (*r.ctx.device).resetQueryPool(*set.decode_stamps, 0, 2);
  vk::CommandBuffer cmd = *set.decode;
  cmd.reset();
  cmd.begin(vk::CommandBufferBeginInfo(vk::CommandBufferUsageFlagBits::eOneTimeSubmit));
  cmd.writeTimestamp2(Stage::eAllCommands, *set.decode_stamps, 0);
  DecodePass::barrier(cmd);
  const DecodeRun run{encoded,
                      encoded + plan.plans_offset(),
                      set.particles.address,
                      set.attributes.address,
                      set.decode_errors.address,
                      encoded + plan.tiles_offset(),
                      set.decode_tiles.address,
                      uint32_t(plan.tile_chunk.size())};
  r.decode_pass->record(cmd, run);
  DecodePass::barrier(cmd);
  // The error words are read on the host (pick_shown_set).
  memory_barrier(cmd, Stage::eComputeShader, Access::eShaderWrite, Stage::eHost, Access::eHostRead);
  cmd.writeTimestamp2(Stage::eAllCommands, *set.decode_stamps, 1);
  cmd.end();
  std::memset(set.decode_errors.mapped, 0, plan.chunks.size() * 4);  // the set is not in use: no GPU work reads it
}

// Submits the decode record_decode() recorded to the graphics queue, after
// the copy that signals `copy_value` on copy_done (and, for a resident
// frame, the relay's copies into it); returns the upload timeline value the
// decode signals.
uint64_t submit_decode(detail::RendererImpl& r, FrameSet& set, uint64_t copy_value, const EncodedSource& source) {
  using Stage = vk::PipelineStageFlagBits2;
  const vk::CommandBufferSubmitInfo cb(*set.decode);
  // Every stage waits (the first timestamp too, so decode_ms is the decode's).
  const uint64_t relayed = source.resident && source.relayed ? source.relayed_value : 0;
  const std::array waits{vk::SemaphoreSubmitInfo(*r.copy_done, copy_value, Stage::eAllCommands),
                         vk::SemaphoreSubmitInfo(source.relayed, relayed, Stage::eAllCommands)};
  const uint32_t wait_count = relayed > 0 ? 2 : 1;
  const vk::SemaphoreSubmitInfo signal(*r.upload_done, r.upload_value + 1, Stage::eAllCommands);
  r.ctx.submit(r.ctx.graphics_queue,
               vk::SubmitInfo2({}, vk::ArrayProxyNoTemporaries<const vk::SemaphoreSubmitInfo>(wait_count, waits.data()), cb,
                               signal));
  set.decoded_on_gpu = true;
  set.decode_ms = -1;
  set.decode_errors_found = 0;
  return r.upload_value + 1;
}

// Checks the staged chunk table (at `chunks_offset` of set.staging) against
// the frame's particles, decides what the GPU will do with the frame
// (classify it, shape it) and sizes its device buffers and the work lists
// for it. Returns the table.
const GpuChunk* size_set(detail::RendererImpl& r, FrameSet& set, vk::DeviceSize chunks_offset) {
  const uint64_t n = set.particle_count;
  const uint32_t chunks = set.chunk_count;
  // Device buffers sized for this frame; the work lists for its worst case.
  uint64_t blocks = 0;
  const auto* table = reinterpret_cast<const GpuChunk*>(static_cast<const std::byte*>(set.staging.mapped) + chunks_offset);
  for (uint32_t c = 0; c < chunks; ++c) {
    if (uint64_t(table[c].first) + table[c].count > n) {
      set.chunk_count = 0;
      set.particle_count = 0;
      throw Error("staged chunk " + std::to_string(c) + " reaches past the frame's particles");
    }
    blocks += (table[c].count + 255) / 256;
  }
  if (!set.layering_known) {  // staged by a host: unlayered unless it staged blob rows
    set.unlayered = std::none_of(table, table + chunks, [](const GpuChunk& c) { return c.kind == 1; });
  }
  // Frames to classify on the GPU when first drawn: room for blobs after
  // the particles (and their attribute), a chunk row for them, the bits.
  set.classified = false;
  // Every array the classification indexes stays below 4 GB (see band.glsl).
  constexpr uint64_t k4G = uint64_t(1) << 32;
  set.band_eligible = r.band && r.options.classify_unlayered && set.unlayered && n > 0 && n <= BandPasses::kMaxParticles &&
                      (n + blob_room(n)) * r.stride < k4G;
  const uint64_t room = set.band_eligible ? blob_room(n) : 0;
  blocks += (room + 255) / 256;
  const uint64_t rows = chunks + (set.band_eligible ? 1 : 0);
  r.ensure(set.particles, std::max<uint64_t>((n + room) * r.stride, 16), kDeviceUsage, MemoryKind::DeviceLocal);
  r.ensure(set.chunks, std::max<uint64_t>(rows * sizeof(GpuChunk), 16), kDeviceUsage, MemoryKind::DeviceLocal);
  r.ensure(set.attributes, std::max<uint64_t>((n + room) * 2 + 4, 16), kDeviceUsage, MemoryKind::DeviceLocal);
  if (set.band_eligible) r.ensure(set.surface, surface_words(n) * 4, kDeviceUsage, MemoryKind::DeviceLocal);
  // Anisotropic particles: their shapes, once the first draw computes them
  // (the same 4 GB limit: band_ellipsoids indexes them from the start).
  set.shaped = false;
  const uint64_t limit = r.options.anisotropic_limit > 0 ? std::min(r.options.anisotropic_limit, BandPasses::kMaxParticles)
                                                         : BandPasses::kMaxParticles;
  set.shape_eligible = r.band && r.options.anisotropic && n > 0 && n <= limit && shapes_bytes(n) < k4G;
  if (set.shape_eligible) r.ensure(set.shapes, shapes_bytes(n), kDeviceUsage, MemoryKind::DeviceLocal);
  r.ensure(r.blocks, std::max<uint64_t>(blocks * 8, 16), kDeviceUsage, MemoryKind::DeviceLocal);
  r.ensure(r.draws, std::max<uint64_t>((n + room) * 8, 16), kDeviceUsage, MemoryKind::DeviceLocal);
  // Large splats: up to one entry per drawn item and eye (two eyes in one pass).
  r.ensure(r.big, std::max<uint64_t>((n + room) * 4 * 2, 16), kDeviceUsage, MemoryKind::DeviceLocal);
  return table;
}

// Submits the copy recorded in `cmd` to the transfer queue, and for an
// encoded frame the decode after it on the graphics queue; the upload
// timeline's value rises in the order the values are signalled.
void submit_copy(detail::RendererImpl& r, FrameSet& set, vk::CommandBuffer cmd, const EncodedSource* encoded) {
  const vk::CommandBufferSubmitInfo cb(cmd);
  set.decoded_on_gpu = false;
  if (encoded) {
    // The copy signals its own timeline; the decode, on the graphics
    // queue, waits for it and signals the upload timeline (in order).
    ++r.copy_value;
    const vk::SemaphoreSubmitInfo copied(*r.copy_done, r.copy_value, vk::PipelineStageFlagBits2::eAllCommands);
    r.ctx.submit(r.ctx.transfer_queue, vk::SubmitInfo2({}, {}, cb, copied));
    r.upload_value = submit_decode(r, set, r.copy_value, *encoded);
    r.last_decode_ticket = r.upload_value;
  } else {
    // A timeline's values must rise in the order they are signalled: after
    // a decode's signal on the graphics queue, the transfer queue's waits
    // for it first.
    const vk::SemaphoreSubmitInfo after_decode(*r.upload_done, r.last_decode_ticket, vk::PipelineStageFlagBits2::eAllCommands);
    const bool order = r.last_decode_ticket > 0 && r.last_decode_ticket == r.upload_value;
    ++r.upload_value;
    const vk::SemaphoreSubmitInfo signal(*r.upload_done, r.upload_value, vk::PipelineStageFlagBits2::eAllCommands);
    r.ctx.submit(r.ctx.transfer_queue,
                 vk::SubmitInfo2({}, order ? vk::ArrayProxyNoTemporaries<const vk::SemaphoreSubmitInfo>(after_decode)
                                           : vk::ArrayProxyNoTemporaries<const vk::SemaphoreSubmitInfo>(),
                                 cb, signal));
  }
}

// Submits the copy of `set`'s frame (particle_count, chunk_count,
// has_attribute) from the sources into its device buffers, which grow to
// fit; with `encoded`, the copy of its staged area and then its decode.
// The chunk table source must be set.staging at `chunks_offset` (it is
// validated there). Returns the frame's ticket: the value the copy, or for
// an encoded frame the decode, signals on the upload timeline.
uint64_t upload_frame(detail::RendererImpl& r, FrameSet& set, UploadSource particles_src, vk::DeviceSize chunks_offset,
                      UploadSource attribute_src, const EncodedSource* encoded = nullptr) {
  const uint64_t n = set.particle_count;
  const uint32_t chunks = set.chunk_count;
  const GpuChunk* table = size_set(r, set, chunks_offset);

  if (encoded) {
    if (!encoded->resident) r.ensure(set.encoded, encoded->plan->staged_bytes(), kDeviceUsage, MemoryKind::DeviceLocal);
    r.ensure(set.decode_errors, std::max<uint64_t>(uint64_t(chunks) * 4, 16),
             vk::BufferUsageFlagBits::eStorageBuffer | vk::BufferUsageFlagBits::eShaderDeviceAddress, MemoryKind::Readback);
    record_decode(r, set, *encoded->plan, encoded->resident ? encoded->resident_address : set.encoded.address);
  }

  (*r.ctx.device).resetQueryPool(*set.stamps, 0, 2);
  vk::CommandBuffer cmd = *set.copy;
  cmd.reset();
  cmd.begin(vk::CommandBufferBeginInfo(vk::CommandBufferUsageFlagBits::eOneTimeSubmit));
  cmd.writeTimestamp2(vk::PipelineStageFlagBits2::eAllCommands, *set.stamps, 0);
  if (encoded && encoded->resident) {
    cmd.copyBuffer(
        encoded->area.buffer, encoded->resident,
        vk::BufferCopy(encoded->area.offset, encoded->plan->plans_offset(), io::table_block_bytes(*encoded->plan)));
  } else if (encoded) {
    cmd.copyBuffer(encoded->area.buffer, *set.encoded.buffer,
                   vk::BufferCopy(encoded->area.offset, 0, encoded->plan->staged_bytes()));
  } else if (n > 0) {
    cmd.copyBuffer(particles_src.buffer, *set.particles.buffer, vk::BufferCopy(particles_src.offset, 0, n * r.stride));
  }
  if (chunks > 0) {
    cmd.copyBuffer(*set.staging.buffer, *set.chunks.buffer, vk::BufferCopy(chunks_offset, 0, chunks * sizeof(GpuChunk)));
  }
  if (set.band_eligible) {
    // An empty blob row and an invalid surface: until a classification
    // recorded by record() has run (a host may drop a recorded frame), the
    // frame is drawn whole.
    const GpuChunk row = blob_chunk_row({table, chunks}, n, r.band->voxel());
    cmd.updateBuffer<GpuChunk>(*set.chunks.buffer, chunks * sizeof(GpuChunk), row);
    cmd.fillBuffer(*set.surface.buffer, 0, 4, 0);
  }
  if (set.shape_eligible) cmd.fillBuffer(*set.shapes.buffer, 0, 8, 0);  // spheres until its shapes are written
  if (set.has_attribute && n > 0 && !encoded) {
    // Rounded up to 4 bytes: every source has room (streams are padded).
    cmd.copyBuffer(attribute_src.buffer, *set.attributes.buffer,
                   vk::BufferCopy(attribute_src.offset, 0, (n * 2 + 3) & ~uint64_t(3)));
  }
  cmd.writeTimestamp2(vk::PipelineStageFlagBits2::eAllCommands, *set.stamps, 1);
  cmd.end();
  submit_copy(r, set, cmd, encoded);
  set.ticket = r.upload_value;
  set.upload_ms = -1;
  return set.ticket;
}

}  // namespace

void mark_layers(FrameSet& set, const io::FrameHeader& header) {
  set.unlayered = std::all_of(header.chunks.begin(), header.chunks.end(),
                              [](const io::ChunkDesc& c) { return c.layer == io::Layer::All; });
  set.layering_known = true;
}

namespace {

// What a record's LOD tier says of its values (GpuChunk::lod_lo, lod_hi).
// Blobs are written by a bound of their random term: only the top holds.
void lod_bounds(const std::vector<io::ChunkDesc>& chunks, size_t c, GpuChunk& g) {
  const io::ValueBounds b = io::record_value_bounds(chunks, c);
  g.lod_hi = b.hi;
  g.lod_lo = chunks[c].layer == io::Layer::Blobs ? 0 : b.lo;
}

}  // namespace

void fill_chunk_table(const io::FrameHeader& header, std::span<const uint64_t> first, int color_attribute,
                      std::span<GpuChunk> out, const io::ErrorLocation& where) {
  uint64_t total = 0;
  for (size_t c = 0; c < out.size(); ++c) {
    const io::ChunkDesc& d = header.chunks[c];
    GpuChunk& g = out[c];
    g = GpuChunk{};
    for (int a = 0; a < 3; ++a) {
      g.lo[a] = d.bounds.min[size_t(a)];
      g.hi[a] = d.bounds.max[size_t(a)];
    }
    if ((!first.empty() && first[c] != total) || total > UINT32_MAX) {
      throw io::Error(where, "chunk particle counts do not add up to the frame's (or exceed 2^32)");
    }
    g.first = uint32_t(total);
    g.count = d.particle_count;
    if (d.layer == io::Layer::Blobs) {
      g.kind = 1;
      g.voxel = header.blob_voxel;
    }
    lod_bounds(header.chunks, c, g);
    if (color_attribute >= 0 && size_t(color_attribute) < d.attribute_ranges.size()) {
      g.attr_lo = d.attribute_ranges[size_t(color_attribute)][0];
      g.attr_hi = d.attribute_ranges[size_t(color_attribute)][1];
    }
    total += d.particle_count;
  }
  if (total != header.particle_count || total > UINT32_MAX) {
    throw io::Error(where, "chunk particle counts do not add up to the frame's (or exceed 2^32)");
  }
}

uint64_t Renderer::commit_frame() {
  Impl& r = *impl_;
  if (r.staged < 0) throw Error("commit_frame: no staged frame (call stage_frame first)");
  FrameSet& set = r.sets[size_t(r.staged)];
  r.staged = -1;
  const StagingLayout l = staging_layout(set.particle_count, set.chunk_count, r.stride, set.has_attribute);
  const vk::Buffer staging = *set.staging.buffer;
  return upload_frame(r, set, {staging, l.particles}, l.chunks, {staging, set.has_attribute ? l.attribute : 0});
}

namespace {

uint64_t commit_decoded(Renderer& renderer, detail::RendererImpl& r, const FrameUpload& frame) {
  const io::FrameHeader& header = *frame.header;
  const uint64_t n = header.particle_count;
  const uint32_t chunks = uint32_t(header.chunks.size());
  const bool attribute = frame.color_attribute >= 0 && !frame.color.host.empty();
  const size_t stride = io::decoded_particle_bytes(r.scene.coding);
  if (frame.particles.host.size() < n * stride)
    throw Error("commit: the particle bytes are fewer than the frame's particles");
  if (attribute && frame.color.host.size() < n * 2) throw Error("commit: fewer colour values than particles");

  if (!frame.particles.buffer || (attribute && !frame.color.buffer)) {
    // Not in Vulkan memory: through the renderer's own staging.
    FrameStaging s = renderer.stage_frame(n, chunks);
    FrameSet& set = r.sets[size_t(r.staged)];
    fill_chunk_table(header, frame.chunk_first, attribute ? frame.color_attribute : -1, s.chunks,
                     io::ErrorLocation{{}, header.frame_number, {}});
    mark_layers(set, header);
    const bool copy_attribute = attribute && !s.color_attribute.empty();
    tbb::parallel_for(tbb::blocked_range<uint64_t>(0, n, 1 << 18), [&](const tbb::blocked_range<uint64_t>& range) {
      const size_t begin = range.begin(), count = range.size();
      std::memcpy(s.particles.data() + begin * stride, frame.particles.host.data() + begin * stride, count * stride);
      if (copy_attribute) std::memcpy(s.color_attribute.data() + begin, frame.color.host.data() + begin * 2, count * 2);
    });
    set.has_attribute = copy_attribute;
    return renderer.commit_frame();
  }
  // Straight from the caller's buffers: only the chunk table is written here.
  const int index = r.free_set();
  FrameSet& set = r.sets[size_t(index)];
  r.stride = stride;
  r.ensure(set.staging, std::max<uint64_t>(uint64_t(chunks) * sizeof(GpuChunk), 16), vk::BufferUsageFlagBits::eTransferSrc,
           MemoryKind::Upload);
  set.ticket = 0;
  fill_chunk_table(header, frame.chunk_first, attribute ? frame.color_attribute : -1,
                   {static_cast<GpuChunk*>(set.staging.mapped), chunks}, io::ErrorLocation{{}, header.frame_number, {}});
  mark_layers(set, header);
  set.particle_count = n;
  set.chunk_count = chunks;
  set.has_attribute = attribute;
  return upload_frame(r, set, {frame.particles.buffer, frame.particles.offset}, 0,
                      {attribute ? vk::Buffer(frame.color.buffer) : vk::Buffer(), attribute ? frame.color.offset : 0});
}

uint64_t commit_encoded(detail::RendererImpl& r, const FrameUpload& frame) {
  const io::FrameHeader& header = *frame.header;
  const io::GpuDecodePlan& plan = *frame.plan;
  const uint32_t chunks = uint32_t(header.chunks.size());
  if (plan.chunks.size() != chunks) throw Error("commit: one plan per chunk");
  if (r.scene.coding != io::PositionCoding::Quantized16) throw Error("commit: a float32 scene");
  const uint64_t staged = plan.staged_bytes();
  const bool attribute = frame.color_attribute >= 0 && chunks > 0 && (plan.chunks[0].flags & io::kGpuWithAttribute) != 0;
  const bool resident = frame.resident.buffer != VK_NULL_HANDLE;
  if (resident && frame.resident.bytes < staged) throw Error("commit: the resident area is too small");
  if (resident && frame.resident.address == 0) throw Error("commit: a resident area without its device address");
  if (!resident && frame.particles.host.size() < staged) throw Error("commit: the staged area is too small");
  const bool own = !resident && !frame.particles.buffer;  // not in Vulkan memory: through the renderer's staging
  // A resident frame's tables go through the renderer's staging too.
  const uint64_t extra = own ? staged : resident ? io::table_block_bytes(plan) : 0;

  const int index = r.free_set();
  FrameSet& set = r.sets[size_t(index)];
  r.stride = 8;
  const uint64_t table = (uint64_t(chunks) * sizeof(GpuChunk) + 15) & ~uint64_t(15);
  r.ensure(set.staging, std::max<uint64_t>(table + extra, 16), vk::BufferUsageFlagBits::eTransferSrc, MemoryKind::Upload);
  set.ticket = 0;
  auto* base = static_cast<std::byte*>(set.staging.mapped);
  fill_chunk_table(header, frame.chunk_first, attribute ? frame.color_attribute : -1,
                   {reinterpret_cast<GpuChunk*>(base), chunks}, io::ErrorLocation{{}, header.frame_number, {}});
  if (own) std::memcpy(base + table, frame.particles.host.data(), staged);
  if (resident) io::write_table_block(plan, {base + table, size_t(extra)});
  mark_layers(set, header);
  set.particle_count = header.particle_count;
  set.chunk_count = chunks;
  set.has_attribute = attribute;
  EncodedSource source;
  source.area = own || resident ? UploadSource{*set.staging.buffer, table}
                                : UploadSource{frame.particles.buffer, frame.particles.offset};
  source.plan = &plan;
  if (resident) {
    source.resident = frame.resident.buffer;
    source.resident_address = frame.resident.address;
    source.relayed = frame.resident.semaphore;
    source.relayed_value = frame.resident.value;
  }
  return upload_frame(r, set, {}, 0, {}, &source);
}

}  // namespace

uint64_t Renderer::commit(const FrameUpload& frame) {
  if (frame.header == nullptr) throw Error("commit: a frame without its header");
  if (!frame.chunk_first.empty() && frame.chunk_first.size() != frame.header->chunks.size()) {
    throw Error("commit: one first index per chunk");
  }
  return frame.plan ? commit_encoded(*impl_, frame) : commit_decoded(*this, *impl_, frame);
}

}  // namespace sluice::render
