// The narrow band on the GPU for positions on the host: upload, the passes
// (band_passes.h), read-back.
#include "sluice/render/band_classifier.h"

#include <array>
#include <cstring>
#include <stdexcept>

#include "band_passes.h"
#include "half.h"
#include "sluice/error.h"

namespace sluice::render {
namespace {

using Stage = vk::PipelineStageFlagBits2;
using Access = vk::AccessFlagBits2;

constexpr uint32_t kStamps = uint32_t(std::size(BandPasses::kSteps)) + 1;  // before the fills, after each step

}  // namespace

struct BandClassifier::Impl {
  detail::ContextImpl& ctx;
  BandPasses passes;
  vk::raii::QueryPool stamps{nullptr};
  bool timestamps = false;
  double gpu_ms = -1;
  std::vector<BandClassifier::PassTime> pass_ms;
  bool hashed = false;
  Buffer upload, xyz, readback, shapes;  // grown to the largest frame seen

  explicit Impl(detail::ContextImpl& c) : ctx(c), passes(c) {
    const auto families = ctx.physical.getQueueFamilyProperties();
    timestamps = ctx.graphics_family < families.size() && families[ctx.graphics_family].timestampValidBits > 0;
    stamps = vk::raii::QueryPool(ctx.device, vk::QueryPoolCreateInfo({}, vk::QueryType::eTimestamp, kStamps));
  }

  // Grows the buffers to n particles and copies xyz into the staging one.
  void stage(std::span<const float> positions, uint64_t readback_bytes) {
    const uint64_t n = positions.size() / 3;
    grow_buffer(ctx, upload, n * 12, vk::BufferUsageFlagBits::eTransferSrc, MemoryKind::Upload);
    grow_buffer(ctx, xyz, n * 12,
                vk::BufferUsageFlagBits::eStorageBuffer | vk::BufferUsageFlagBits::eShaderDeviceAddress |
                    vk::BufferUsageFlagBits::eTransferDst,
                MemoryKind::DeviceLocal);
    grow_buffer(ctx, readback, readback_bytes, vk::BufferUsageFlagBits::eTransferDst, MemoryKind::Readback);
    std::memcpy(upload.mapped, positions.data(), n * 12);
  }

  // Records the upload and the passes of `run`, with timestamps.
  void record(vk::CommandBuffer cmd, const BandRun& run) {
    cmd.copyBuffer(*upload.buffer, *xyz.buffer, vk::BufferCopy(0, 0, run.n * 12));
    memory_barrier(cmd, Stage::eTransfer, Access::eTransferWrite, Stage::eComputeShader | Stage::eTransfer,
                   Access::eShaderRead | Access::eTransferWrite);
    uint32_t stamp = 0;
    if (timestamps) {
      cmd.resetQueryPool(*stamps, 0, kStamps);
      cmd.writeTimestamp2(Stage::eAllCommands, *stamps, stamp++);
    }
    passes.record(cmd, run, [&](const char*) {
      if (timestamps) cmd.writeTimestamp2(Stage::eAllCommands, *stamps, stamp++);
    });
  }

  // The grid's verdict: throws where the box's voxels outgrow 32-bit keys.
  static void require_fits(const BandParams& params) {
    if (params.fits) return;
    throw Error("BandClassifier: the particles' box holds " + std::to_string(params.dims[0]) + " x " +
                std::to_string(params.dims[1]) + " x " + std::to_string(params.dims[2]) +
                " voxels, more than 32-bit keys address; classify on the CPU");
  }

  void read_timestamps() {
    gpu_ms = -1;
    pass_ms.clear();
    if (!timestamps) return;
    std::array<uint64_t, kStamps> t{};
    if ((*ctx.device).getQueryPoolResults(*stamps, 0, kStamps, sizeof t, t.data(), sizeof(uint64_t),
                                          vk::QueryResultFlagBits::e64) != vk::Result::eSuccess) {
      return;
    }
    const double to_ms = ctx.properties.limits.timestampPeriod * 1e-6;
    gpu_ms = double(t[kStamps - 1] - t[0]) * to_ms;
    for (size_t k = 0; k + 1 < kStamps; ++k) pass_ms.push_back({BandPasses::kSteps[k], double(t[k + 1] - t[k]) * to_ms});
  }
};

BandClassifier::BandClassifier(Context& context) : impl_(std::make_unique<Impl>(context_impl(context))) {}
BandClassifier::~BandClassifier() = default;
double BandClassifier::last_gpu_ms() const { return impl_->gpu_ms; }
std::vector<BandClassifier::PassTime> BandClassifier::last_pass_ms() const { return impl_->pass_ms; }
bool BandClassifier::last_hashed() const { return impl_->hashed; }

io::NarrowBand BandClassifier::classify(std::span<const float> xyz, const io::NarrowBandOptions& o) {
  if (!(o.diameter > 0)) throw Error("BandClassifier: the particle diameter must be positive");
  if (o.f2 != io::F2Test::All) throw Error("BandClassifier: only F2Test::All runs on the GPU");
  Impl& r = *impl_;
  io::NarrowBand out;
  out.voxel = o.voxel > 0 ? o.voxel : 2 * o.diameter;
  const uint64_t n = xyz.size() / 3;
  if (n > BandPasses::kMaxParticles) throw Error("BandClassifier: more than 2^28 particles");
  out.layer.assign(n, io::BandLayer::Interior);
  if (n == 0) return out;

  r.passes.reserve(n, o.blobs);
  // Params, layers, blob_of; the blobs go through it in a second copy.
  r.stage(xyz, sizeof(BandParams) + n * (o.blobs ? 16 : 4));
  const BandRun run{.n = n, .xyz = r.xyz.address, .diameter = o.diameter, .voxel = out.voxel, .blobs = o.blobs};
  r.ctx.run_once([&](vk::CommandBuffer cmd) {
    r.record(cmd, run);
    const vk::Buffer particles = *r.passes.particles.buffer;
    cmd.copyBuffer(*r.passes.params.buffer, *r.readback.buffer, vk::BufferCopy(0, 0, sizeof(BandParams)));
    cmd.copyBuffer(particles, *r.readback.buffer, vk::BufferCopy(BandPasses::kLayerWord * n * 4, sizeof(BandParams), n * 4));
    if (o.blobs) {
      cmd.copyBuffer(particles, *r.readback.buffer,
                     vk::BufferCopy(BandPasses::kBlobOfWord * n * 4, sizeof(BandParams) + n * 4, n * 4));
    }
    memory_barrier(cmd, Stage::eTransfer, Access::eTransferWrite, Stage::eHost, Access::eHostRead);
  });
  r.read_timestamps();

  BandParams params;
  std::memcpy(&params, r.readback.mapped, sizeof params);
  r.hashed = params.dense == 0;
  Impl::require_fits(params);
  const auto* words = reinterpret_cast<const uint32_t*>(static_cast<const std::byte*>(r.readback.mapped) + sizeof params);
  for (uint64_t i = 0; i < n; ++i) out.layer[i] = io::BandLayer(words[i] & 3u);
  for (size_t l = 0; l < 4; ++l) out.counts[l] = params.counts[l];
  out.voxels = params.voxels;
  out.l1_voxels = params.l1;
  out.l2_voxels = params.l2;
  if (o.blobs) {
    out.blob_of.assign(words + n, words + 2 * n);
    const uint64_t blobs = params.blobs;
    r.ctx.run_once([&](vk::CommandBuffer cmd) {
      cmd.copyBuffer(*r.passes.blobs.buffer, *r.readback.buffer, vk::BufferCopy(0, 0, std::max<uint64_t>(blobs, 1) * 16));
      memory_barrier(cmd, Stage::eTransfer, Access::eTransferWrite, Stage::eHost, Access::eHostRead);
    });
    const auto* b = static_cast<const float*>(r.readback.mapped);
    out.blobs.resize(blobs);
    for (uint64_t k = 0; k < blobs; ++k) {
      out.blobs[k].centroid = {b[4 * k], b[4 * k + 1], b[4 * k + 2]};
      std::memcpy(&out.blobs[k].count, &b[4 * k + 3], 4);
    }
  }
  return out;
}

std::vector<BandClassifier::Ellipsoid> BandClassifier::ellipsoids(std::span<const float> xyz, float diameter) {
  if (!(diameter > 0)) throw Error("BandClassifier: the particle diameter must be positive");
  Impl& r = *impl_;
  const uint64_t n = xyz.size() / 3;
  if (n > BandPasses::kMaxParticles) throw Error("BandClassifier: more than 2^28 particles");
  std::vector<Ellipsoid> out(n);
  if (n == 0) return out;
  r.passes.reserve(n, false);
  grow_buffer(r.ctx, r.shapes, n * 20, vk::BufferUsageFlagBits::eStorageBuffer | vk::BufferUsageFlagBits::eShaderDeviceAddress |
                                           vk::BufferUsageFlagBits::eTransferSrc,
              MemoryKind::DeviceLocal);
  r.stage(xyz, sizeof(BandParams) + n * 20);
  const BandRun run{
      .n = n, .xyz = r.xyz.address, .diameter = diameter, .voxel = 2 * diameter, .layers = false, .shapes = r.shapes.address};
  r.ctx.run_once([&](vk::CommandBuffer cmd) {
    r.record(cmd, run);
    cmd.copyBuffer(*r.passes.params.buffer, *r.readback.buffer, vk::BufferCopy(0, 0, sizeof(BandParams)));
    cmd.copyBuffer(*r.shapes.buffer, *r.readback.buffer, vk::BufferCopy(0, sizeof(BandParams), n * 20));
    memory_barrier(cmd, Stage::eTransfer, Access::eTransferWrite, Stage::eHost, Access::eHostRead);
  });
  r.read_timestamps();
  BandParams params;
  std::memcpy(&params, r.readback.mapped, sizeof params);
  Impl::require_fits(params);
  const auto* halves = reinterpret_cast<const uint16_t*>(static_cast<const std::byte*>(r.readback.mapped) + sizeof params);
  for (uint64_t i = 0; i < n; ++i) {
    const uint16_t* h = halves + 10 * i;
    for (size_t k = 0; k < 6; ++k) out[i].shape[k] = half_to_float(h[k]);
    for (size_t k = 0; k < 3; ++k) out[i].shift[k] = half_to_float(h[6 + k]) * diameter;
  }
  return out;
}

}  // namespace sluice::render
