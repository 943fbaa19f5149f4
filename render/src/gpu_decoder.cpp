// The GPU decoder for frames on the host: plan and upload, the pass
// (decode_pass.h), read-back.
#include "sluice/render/gpu_decoder.h"

#include <cstring>

#include "decode_pass.h"

namespace sluice::render {
namespace {

using Stage = vk::PipelineStageFlagBits2;
using Access = vk::AccessFlagBits2;

constexpr auto kDeviceUsage = vk::BufferUsageFlagBits::eStorageBuffer | vk::BufferUsageFlagBits::eShaderDeviceAddress |
                              vk::BufferUsageFlagBits::eTransferDst | vk::BufferUsageFlagBits::eTransferSrc;

}  // namespace

struct GpuDecoder::Impl {
  detail::ContextImpl& ctx;
  DecodePass pass;
  vk::raii::QueryPool stamps{nullptr};
  bool timestamps = false;
  io::GpuDecodePlan plan;
  uint64_t particles = 0;
  bool attribute = false;
  std::vector<double> pass_ms;  // the last run's passes, mean over its repeats
  Buffer upload, encoded, tile_sums, decoded, values, errors, readback;  // grown to the largest frame seen

  explicit Impl(detail::ContextImpl& c) : ctx(c), pass(c) {
    const auto families = ctx.physical.getQueueFamilyProperties();
    timestamps = ctx.graphics_family < families.size() && families[ctx.graphics_family].timestampValidBits > 0;
  }
};

GpuDecoder::GpuDecoder(Context& context) : impl_(std::make_unique<Impl>(context_impl(context))) {}
GpuDecoder::~GpuDecoder() = default;
const io::GpuDecodePlan& GpuDecoder::plan() const { return impl_->plan; }
std::vector<double> GpuDecoder::last_pass_ms() const { return impl_->pass_ms; }

void GpuDecoder::load(std::span<const std::byte> record, const io::FrameHeader& header, const io::FileHeader& file,
                      const io::GpuPlanOptions& options, bool verify, const io::ErrorLocation& where) {
  Impl& r = *impl_;
  // The new frame replaces the loaded one only once it is planned, staged
  // and uploaded: a frame that throws leaves the last one runnable.
  io::GpuDecodePlan plan;
  io::plan_gpu_decode(record, header, file, options, plan, where);
  const uint64_t bytes = plan.staged_bytes();
  uint64_t particles = 0;
  for (const io::GpuChunkPlan& c : plan.chunks) particles += c.count;

  grow_buffer(r.ctx, r.upload, bytes, vk::BufferUsageFlagBits::eTransferSrc, MemoryKind::Upload);
  const std::span<std::byte> staging(static_cast<std::byte*>(r.upload.mapped), bytes);
  std::memset(staging.data(), 0, bytes);  // the gaps the GPU reads past plane ends: no stale bytes
  io::stage_frame(record, header, plan, staging, verify, where);

  grow_buffer(r.ctx, r.encoded, bytes, kDeviceUsage, MemoryKind::DeviceLocal);
  grow_buffer(r.ctx, r.decoded, std::max<uint64_t>(particles * 8, 16), kDeviceUsage, MemoryKind::DeviceLocal);
  grow_buffer(r.ctx, r.values, std::max<uint64_t>(particles * 2, 16), kDeviceUsage, MemoryKind::DeviceLocal);
  grow_buffer(r.ctx, r.tile_sums, std::max<uint64_t>(plan.tile_chunk.size() * DecodePass::kTileSumBytes, 16), kDeviceUsage,
              MemoryKind::DeviceLocal);
  grow_buffer(r.ctx, r.errors, std::max<uint64_t>(plan.chunks.size() * 4, 16), kDeviceUsage, MemoryKind::DeviceLocal);
  r.ctx.run_once([&](vk::CommandBuffer cmd) { cmd.copyBuffer(*r.upload.buffer, *r.encoded.buffer, vk::BufferCopy(0, 0, bytes)); });
  r.particles = particles;
  r.attribute = !plan.chunks.empty() && (plan.chunks[0].flags & io::kGpuWithAttribute) != 0;
  r.plan = std::move(plan);
}

std::vector<double> GpuDecoder::run(int repeats) {
  Impl& r = *impl_;
  std::vector<double> ms;
  constexpr uint32_t per_run = DecodePass::kPasses + 1;  // before, and after each pass
  const uint32_t stamps = per_run * uint32_t(std::max(repeats, 1));
  if (r.timestamps) r.stamps = vk::raii::QueryPool(r.ctx.device, vk::QueryPoolCreateInfo({}, vk::QueryType::eTimestamp, stamps));
  const DecodeRun run{r.encoded.address,
                      r.encoded.address + r.plan.plans_offset(),
                      r.decoded.address,
                      r.values.address,
                      r.errors.address,
                      r.encoded.address + r.plan.tiles_offset(),
                      r.tile_sums.address,
                      uint32_t(r.plan.tile_chunk.size())};
  r.ctx.run_once([&](vk::CommandBuffer cmd) {
    if (r.timestamps) cmd.resetQueryPool(*r.stamps, 0, stamps);
    for (int k = 0; k < std::max(repeats, 1); ++k) {
      cmd.fillBuffer(*r.errors.buffer, 0, VK_WHOLE_SIZE, 0);
      DecodePass::barrier(cmd);
      if (r.timestamps) cmd.writeTimestamp2(Stage::eAllCommands, *r.stamps, per_run * uint32_t(k));
      r.pass.record(cmd, run, [&](uint32_t pass) {
        if (r.timestamps) cmd.writeTimestamp2(Stage::eAllCommands, *r.stamps, per_run * uint32_t(k) + 1 + pass);
      });
      DecodePass::barrier(cmd);
    }
  });
  if (r.timestamps) {
    std::vector<uint64_t> t(stamps);
    if ((*r.ctx.device).getQueryPoolResults(*r.stamps, 0, stamps, t.size() * 8, t.data(), 8,
                                            vk::QueryResultFlagBits::e64) == vk::Result::eSuccess) {
      const double to_ms = r.ctx.properties.limits.timestampPeriod * 1e-6;
      r.pass_ms.assign(DecodePass::kPasses, 0.0);
      const double runs = double(stamps / per_run);
      for (uint32_t k = 0; k + per_run <= stamps; k += per_run) {
        ms.push_back(double(t[k + DecodePass::kPasses] - t[k]) * to_ms);
        for (uint32_t p = 0; p < DecodePass::kPasses; ++p) r.pass_ms[p] += double(t[k + 1 + p] - t[k + p]) * to_ms / runs;
      }
    }
  }
  return ms;
}

GpuDecodeOutput GpuDecoder::read() const {
  Impl& r = *impl_;
  const uint64_t n = r.particles, chunks = r.plan.chunks.size();
  const uint64_t bytes = n * 8 + (r.attribute ? n * 2 : 0) + chunks * 4;
  grow_buffer(r.ctx, r.readback, std::max<uint64_t>(bytes, 16), vk::BufferUsageFlagBits::eTransferDst, MemoryKind::Readback);
  r.ctx.run_once([&](vk::CommandBuffer cmd) {
    if (n > 0) cmd.copyBuffer(*r.decoded.buffer, *r.readback.buffer, vk::BufferCopy(0, 0, n * 8));
    if (n > 0 && r.attribute) cmd.copyBuffer(*r.values.buffer, *r.readback.buffer, vk::BufferCopy(0, n * 8, n * 2));
    if (chunks > 0) {
      cmd.copyBuffer(*r.errors.buffer, *r.readback.buffer, vk::BufferCopy(0, n * 8 + (r.attribute ? n * 2 : 0), chunks * 4));
    }
    memory_barrier(cmd, Stage::eTransfer, Access::eTransferWrite, Stage::eHost, Access::eHostRead);
  });
  GpuDecodeOutput out;
  const auto* base = static_cast<const std::byte*>(r.readback.mapped);
  out.particles.resize(n);
  std::memcpy(out.particles.data(), base, n * 8);
  if (r.attribute) {
    out.attribute.resize(n);
    std::memcpy(out.attribute.data(), base + n * 8, n * 2);
  }
  const std::byte* errors = base + n * 8 + (r.attribute ? n * 2 : 0);  // not 4-aligned when n is odd
  for (uint64_t c = 0; c < chunks; ++c) {
    uint32_t word = 0;
    std::memcpy(&word, errors + 4 * c, 4);
    out.chunks_with_errors += word != 0 ? 1 : 0;
  }
  return out;
}

}  // namespace sluice::render
