// The narrow band on the GPU: nine compute passes over a table of voxels
// (render/shaders/band.glsl says how it is laid out), recorded into one
// command buffer.
#include "sluice/render/band_classifier.h"

#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

#include "shaders.h"
#include "vk_common.h"

namespace sluice::render {
namespace {

using Stage = vk::PipelineStageFlagBits2;
using Access = vk::AccessFlagBits2;

// Mirrors Params in band.glsl.
struct BandParams {
  uint32_t lo[3];
  uint32_t fits;
  uint32_t hi[3];
  uint32_t voxels;
  float origin[3];
  uint32_t cursor;
  float last_cell[3];
  uint32_t blobs;
  uint32_t dims[3];
  uint32_t l1;
  uint32_t counts[4];
  uint32_t l2;
  uint32_t dense;
  uint32_t cells;
  uint32_t pad;
};
static_assert(sizeof(BandParams) == 112);

// Mirrors Push in band.glsl.
struct BandPush {
  uint64_t xyz, params, keys, counts, starts, marks, slots, lists, voxels, layers, blob_of, blobs;
  uint32_t n, mask;
  float inverse, side;
  uint32_t n1;
  float reach2;
  uint32_t with_blobs;
  uint32_t pad;  // to the 8-byte alignment of the addresses; not in the shader's block
};
static_assert(sizeof(BandPush) == 128);

constexpr std::array kPasses{Shader::BandBounds, Shader::BandGrid,  Shader::BandInsert,
                             Shader::BandVoxels, Shader::BandL1,    Shader::BandL2,
                             Shader::BandScatter, Shader::BandParticles, Shader::BandBlobs};
constexpr std::array<const char*, kPasses.size() + 1> kPassNames{
    "fills", "bounds", "grid", "insert", "voxels", "L1", "L2", "scatter", "particles", "blobs"};
constexpr uint32_t kStamps = uint32_t(kPassNames.size()) + 1;  // before the fills, after each step
constexpr uint32_t kMaxGroups = 65535;  // the guaranteed maxComputeWorkGroupCount[0]
constexpr uint32_t kEmpty = std::numeric_limits<uint32_t>::max();

uint32_t groups_for(uint64_t items) { return uint32_t(std::clamp<uint64_t>((items + 255) / 256, 1, kMaxGroups)); }

}  // namespace

struct BandClassifier::Impl {
  Context::Impl& ctx;
  vk::raii::PipelineLayout layout{nullptr};
  std::vector<vk::raii::Pipeline> pipelines;
  vk::raii::QueryPool stamps{nullptr};
  bool timestamps = false;
  double gpu_ms = -1;
  std::vector<BandClassifier::PassTime> pass_ms;
  bool hashed = false;

  // Grown to the largest frame seen, never shrunk.
  Buffer upload, xyz, params, keys, counts, starts, marks, slots, lists, voxels, layers, blob_of, blobs, readback;

  explicit Impl(Context::Impl& c) : ctx(c) {
    const vk::PushConstantRange range(vk::ShaderStageFlagBits::eCompute, 0, sizeof(BandPush));
    layout = vk::raii::PipelineLayout(ctx.device, vk::PipelineLayoutCreateInfo({}, {}, range));
    for (const Shader s : kPasses) {
      const std::span<const uint32_t> code = spirv(s);
      const vk::raii::ShaderModule m(ctx.device, vk::ShaderModuleCreateInfo({}, code.size_bytes(), code.data()));
      const vk::ComputePipelineCreateInfo info(
          {}, vk::PipelineShaderStageCreateInfo({}, vk::ShaderStageFlagBits::eCompute, *m, "main"), *layout);
      pipelines.emplace_back(ctx.device, nullptr, info);
    }
    const auto families = ctx.physical.getQueueFamilyProperties();
    timestamps = ctx.graphics_family < families.size() && families[ctx.graphics_family].timestampValidBits > 0;
    stamps = vk::raii::QueryPool(ctx.device, vk::QueryPoolCreateInfo({}, vk::QueryType::eTimestamp, kStamps));
  }

  void ensure(Buffer& b, vk::DeviceSize size, vk::BufferUsageFlags usage, MemoryKind kind) {
    if (b.size >= size && *b.buffer) return;
    b = Buffer{};  // free before allocating the larger one
    b = create_buffer(ctx, size, usage, kind);
  }

  void ensure_all(uint64_t n, uint64_t capacity, bool with_blobs) {
    constexpr auto storage = vk::BufferUsageFlagBits::eStorageBuffer | vk::BufferUsageFlagBits::eShaderDeviceAddress |
                             vk::BufferUsageFlagBits::eTransferDst | vk::BufferUsageFlagBits::eTransferSrc;
    ensure(upload, n * 12, vk::BufferUsageFlagBits::eTransferSrc, MemoryKind::Upload);
    ensure(xyz, n * 12, storage, MemoryKind::DeviceLocal);
    ensure(params, sizeof(BandParams), storage, MemoryKind::DeviceLocal);
    ensure(keys, capacity * 4, storage, MemoryKind::DeviceLocal);
    ensure(counts, capacity * 4, storage, MemoryKind::DeviceLocal);
    ensure(starts, capacity * 4, storage, MemoryKind::DeviceLocal);
    ensure(marks, capacity * 8, storage, MemoryKind::DeviceLocal);
    ensure(slots, n * 4, storage, MemoryKind::DeviceLocal);
    ensure(lists, n * 4, storage, MemoryKind::DeviceLocal);
    ensure(voxels, n * 4, storage, MemoryKind::DeviceLocal);
    ensure(layers, n * 4, storage, MemoryKind::DeviceLocal);
    if (with_blobs) {
      ensure(blob_of, n * 4, storage, MemoryKind::DeviceLocal);
      ensure(blobs, n * 16, storage, MemoryKind::DeviceLocal);
    }
    // Params, layers, blob_of; blobs go through it in a second copy.
    ensure(readback, sizeof(BandParams) + n * (with_blobs ? 16 : 4), vk::BufferUsageFlagBits::eTransferDst,
           MemoryKind::Readback);
  }

  void between_passes(vk::CommandBuffer cmd) const {
    memory_barrier(cmd, Stage::eComputeShader | Stage::eTransfer, Access::eShaderWrite | Access::eTransferWrite,
                   Stage::eComputeShader | Stage::eTransfer,
                   Access::eShaderRead | Access::eShaderWrite | Access::eTransferRead);
  }

  void record(vk::CommandBuffer cmd, const BandPush& push, uint64_t n, uint64_t capacity, bool with_blobs) {
    cmd.copyBuffer(*upload.buffer, *xyz.buffer, vk::BufferCopy(0, 0, n * 12));
    memory_barrier(cmd, Stage::eTransfer, Access::eTransferWrite, Stage::eComputeShader | Stage::eTransfer,
                   Access::eShaderRead | Access::eTransferWrite);
    if (timestamps) {
      cmd.resetQueryPool(*stamps, 0, kStamps);
      cmd.writeTimestamp2(Stage::eAllCommands, *stamps, 0);
    }
    BandParams initial{};
    std::fill(std::begin(initial.lo), std::end(initial.lo), kEmpty);
    cmd.updateBuffer(*params.buffer, 0, sizeof initial, &initial);
    cmd.fillBuffer(*keys.buffer, 0, capacity * 4, kEmpty);
    cmd.fillBuffer(*counts.buffer, 0, capacity * 4, 0);
    cmd.fillBuffer(*marks.buffer, 0, capacity * 8, 0);
    if (with_blobs) cmd.fillBuffer(*blob_of.buffer, 0, n * 4, kEmpty);
    between_passes(cmd);
    if (timestamps) cmd.writeTimestamp2(Stage::eAllCommands, *stamps, 1);
    cmd.pushConstants<BandPush>(*layout, vk::ShaderStageFlagBits::eCompute, 0, push);
    for (size_t p = 0; p < pipelines.size(); ++p) {
      const Shader s = kPasses[p];
      if (s != Shader::BandBlobs || with_blobs) {
        cmd.bindPipeline(vk::PipelineBindPoint::eCompute, *pipelines[p]);
      // Passes loop over their items in rounds, so any group count covers
      // them; over the slots for BandVoxels, one for BandGrid.
        const uint32_t groups = s == Shader::BandGrid ? 1 : groups_for(s == Shader::BandVoxels ? capacity : n);
        cmd.dispatch(groups, 1, 1);
        between_passes(cmd);
      }
      if (timestamps) cmd.writeTimestamp2(Stage::eAllCommands, *stamps, uint32_t(p) + 2);
    }
    cmd.copyBuffer(*params.buffer, *readback.buffer, vk::BufferCopy(0, 0, sizeof(BandParams)));
    cmd.copyBuffer(*layers.buffer, *readback.buffer, vk::BufferCopy(0, sizeof(BandParams), n * 4));
    if (with_blobs) cmd.copyBuffer(*blob_of.buffer, *readback.buffer, vk::BufferCopy(0, sizeof(BandParams) + n * 4, n * 4));
    memory_barrier(cmd, Stage::eTransfer, Access::eTransferWrite, Stage::eHost, Access::eHostRead);
  }
};

BandClassifier::BandClassifier(Context& context) : impl_(std::make_unique<Impl>(context_impl(context))) {}
BandClassifier::~BandClassifier() = default;
double BandClassifier::last_gpu_ms() const { return impl_->gpu_ms; }
std::vector<BandClassifier::PassTime> BandClassifier::last_pass_ms() const { return impl_->pass_ms; }
bool BandClassifier::last_hashed() const { return impl_->hashed; }

io::NarrowBand BandClassifier::classify(std::span<const float> xyz, const io::NarrowBandOptions& o) {
  if (!(o.diameter > 0)) throw std::invalid_argument("BandClassifier: the particle diameter must be positive");
  if (o.f2 != io::F2Test::All) throw std::invalid_argument("BandClassifier: only F2Test::All runs on the GPU");
  Impl& r = *impl_;
  const float h = o.diameter;
  io::NarrowBand out;
  out.voxel = o.voxel > 0 ? o.voxel : 2 * h;
  const uint64_t n = xyz.size() / 3;
  if (n >= (uint64_t(1) << 31)) throw std::invalid_argument("BandClassifier: more than 2^31 particles");
  out.layer.assign(n, io::BandLayer::Interior);
  if (n == 0) return out;
  const uint64_t capacity = std::bit_ceil(std::max<uint64_t>(2 * n, 256));

  r.ensure_all(n, capacity, o.blobs);
  std::memcpy(r.upload.mapped, xyz.data(), n * 12);
  BandPush push{};
  push.xyz = r.xyz.address;
  push.params = r.params.address;
  push.keys = r.keys.address;
  push.counts = r.counts.address;
  push.starts = r.starts.address;
  push.marks = r.marks.address;
  push.slots = r.slots.address;
  push.lists = r.lists.address;
  push.voxels = r.voxels.address;
  push.layers = r.layers.address;
  push.blob_of = o.blobs ? r.blob_of.address : 0;
  push.blobs = o.blobs ? r.blobs.address : 0;
  push.n = uint32_t(n);
  push.mask = uint32_t(capacity - 1);
  // The CPU classifier's expressions, in float.
  push.inverse = 1.0f / out.voxel;
  push.side = out.voxel;
  const double n1 = std::pow(double(out.voxel) / h, 3);
  push.n1 = uint32_t(std::min(std::floor(n1), double(kEmpty)));
  const float reach = std::min(2 * h, out.voxel);
  push.reach2 = reach * reach;
  push.with_blobs = o.blobs ? 1 : 0;
  r.ctx.run_once([&](vk::CommandBuffer cmd) { r.record(cmd, push, n, capacity, o.blobs); });

  if (r.timestamps) {
    std::array<uint64_t, kStamps> t{};
    r.gpu_ms = -1;
    r.pass_ms.clear();
    if ((*r.ctx.device).getQueryPoolResults(*r.stamps, 0, kStamps, sizeof t, t.data(), sizeof(uint64_t),
                                            vk::QueryResultFlagBits::e64) == vk::Result::eSuccess) {
      const double to_ms = r.ctx.properties.limits.timestampPeriod * 1e-6;
      r.gpu_ms = double(t[kStamps - 1] - t[0]) * to_ms;
      for (size_t k = 0; k < kPassNames.size(); ++k) r.pass_ms.push_back({kPassNames[k], double(t[k + 1] - t[k]) * to_ms});
    }
  }
  BandParams params;
  std::memcpy(&params, r.readback.mapped, sizeof params);
  r.hashed = params.dense == 0;
  if (!params.fits) {
    throw std::runtime_error("BandClassifier: the particles' box holds " + std::to_string(params.dims[0]) + " x " +
                             std::to_string(params.dims[1]) + " x " + std::to_string(params.dims[2]) +
                             " voxels, more than 32-bit keys address; classify on the CPU");
  }
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
      cmd.copyBuffer(*r.blobs.buffer, *r.readback.buffer, vk::BufferCopy(0, 0, std::max<uint64_t>(blobs, 1) * 16));
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

}  // namespace sluice::render
