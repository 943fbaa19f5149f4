// The narrow-band passes recorded into one command buffer (band_passes.h).
#include "band_passes.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>

#include "shaders.h"

namespace sluice::render {
namespace {

using Stage = vk::PipelineStageFlagBits2;
using Access = vk::AccessFlagBits2;

// Mirrors Push in band.glsl.
struct BandPush {
  uint64_t xyz, attr, params, table, particles, blobs, blob_attr;
  uint32_t n, mask;
  float inverse, side;
  uint32_t n1;
  float reach2;
  uint32_t with_blobs;
  uint32_t step;
  uint64_t shapes, marks;
};
static_assert(sizeof(BandPush) == 104);

constexpr std::array kPasses{Shader::BandBounds, Shader::BandGrid,  Shader::BandInsert,
                             Shader::BandVoxels, Shader::BandL1,    Shader::BandL2,
                             Shader::BandScatter, Shader::BandParticles, Shader::BandBlobs, Shader::BandEllipsoids};
constexpr uint32_t kMaxGroups = 65535;  // the guaranteed maxComputeWorkGroupCount[0]
constexpr uint32_t kEmpty = std::numeric_limits<uint32_t>::max();

uint32_t groups_for(uint64_t items) { return uint32_t(std::clamp<uint64_t>((items + 255) / 256, 1, kMaxGroups)); }
uint64_t capacity_for(uint64_t n) { return std::bit_ceil(std::max<uint64_t>(2 * n, 256)); }

}  // namespace

void BandPasses::barrier(vk::CommandBuffer cmd) {
  memory_barrier(cmd, Stage::eComputeShader | Stage::eTransfer, Access::eShaderWrite | Access::eTransferWrite,
                 Stage::eComputeShader | Stage::eTransfer, Access::eShaderRead | Access::eShaderWrite | Access::eTransferRead);
}

BandPasses::BandPasses(detail::ContextImpl& ctx) : ctx_(ctx) {
  const vk::PushConstantRange range(vk::ShaderStageFlagBits::eCompute, 0, sizeof(BandPush));
  layout_ = vk::raii::PipelineLayout(ctx.device, vk::PipelineLayoutCreateInfo({}, {}, range));
  for (const Shader s : kPasses) pipelines_.push_back(compute_pipeline(ctx.device, layout_, s));
}

void BandPasses::reserve(uint64_t n, bool with_blobs, const std::function<void(Buffer&&)>& retire) {
  if (n <= reserved_ && (reserved_blobs_ || !with_blobs) && *params.buffer) return;
  n = std::max(n, reserved_);
  with_blobs = with_blobs || reserved_blobs_;
  constexpr auto usage = vk::BufferUsageFlagBits::eStorageBuffer | vk::BufferUsageFlagBits::eShaderDeviceAddress |
                         vk::BufferUsageFlagBits::eTransferDst | vk::BufferUsageFlagBits::eTransferSrc;
  for (Buffer* b : {&params, &table_, &particles, &blobs, &blob_attr}) {
    if (retire && *b->buffer) retire(std::move(*b));
    *b = Buffer{};  // freed before the larger ones are allocated
  }
  params = create_buffer(ctx_, sizeof(BandParams), usage, MemoryKind::DeviceLocal);
  table_ = create_buffer(ctx_, capacity_for(n) * 5 * 4, usage, MemoryKind::DeviceLocal);
  particles = create_buffer(ctx_, n * 5 * 4, usage, MemoryKind::DeviceLocal);
  if (with_blobs) {
    blobs = create_buffer(ctx_, n * 16, usage, MemoryKind::DeviceLocal);
    blob_attr = create_buffer(ctx_, n * 4, usage, MemoryKind::DeviceLocal);
  }
  reserved_ = n;
  reserved_blobs_ = with_blobs;
}

void BandPasses::record(vk::CommandBuffer cmd, const BandRun& run, const std::function<void(const char*)>& after) const {
  const uint64_t n = run.n, capacity = capacity_for(n);
  BandPush push{};
  push.xyz = run.xyz;
  push.attr = run.blobs ? run.attr : 0;
  push.params = params.address;
  push.table = table_.address;
  push.particles = particles.address;
  push.blobs = run.blobs ? blobs.address : 0;
  push.blob_attr = run.blobs ? blob_attr.address : 0;
  push.n = uint32_t(n);
  push.mask = uint32_t(capacity - 1);
  // io::classify_narrow_band's expressions, in float.
  push.inverse = 1.0f / run.voxel;
  push.side = run.voxel;
  const double n1 = std::pow(double(run.voxel) / run.diameter, 3);
  push.n1 = uint32_t(std::min(std::floor(n1), double(kEmpty)));
  const float reach = std::min(2 * run.diameter, run.voxel);
  push.reach2 = reach * reach;
  push.with_blobs = run.blobs ? 1 : 0;
  push.shapes = run.shapes;
  push.marks = run.marks;

  BandParams initial{};
  std::fill(std::begin(initial.lo), std::end(initial.lo), kEmpty);
  cmd.updateBuffer(*params.buffer, 0, sizeof initial, &initial);
  cmd.fillBuffer(*table_.buffer, 0, capacity * 4, kEmpty);             // KEY
  cmd.fillBuffer(*table_.buffer, capacity * 4, capacity * 4, 0);       // COUNT
  cmd.fillBuffer(*table_.buffer, capacity * 12, capacity * 8, 0);      // L1MARK, L2MARK
  if (run.blobs) cmd.fillBuffer(*particles.buffer, kBlobOfWord * n * 4, n * 4, kEmpty);
  barrier(cmd);
  if (after) after(kSteps[0]);
  cmd.pushConstants<BandPush>(*layout_, vk::ShaderStageFlagBits::eCompute, 0, push);
  for (size_t p = 0; p < pipelines_.size(); ++p) {
    const Shader s = kPasses[p];
    const bool classifying = s == Shader::BandL1 || s == Shader::BandL2 || s == Shader::BandParticles;
    const bool wanted = s == Shader::BandBlobs ? run.blobs
                        : s == Shader::BandEllipsoids ? run.shapes != 0
                        : classifying ? run.layers
                                      : true;
    if (wanted) {
      cmd.bindPipeline(vk::PipelineBindPoint::eCompute, *pipelines_[p]);
      // Passes loop over their items in rounds, so any group count covers
      // them; over the slots for BandVoxels, one for BandGrid. The
      // ellipsoids take three steps (band_ellipsoids.comp).
      const uint32_t groups = s == Shader::BandGrid ? 1 : groups_for(s == Shader::BandVoxels ? capacity : n);
      for (uint32_t step = 0; step < (s == Shader::BandEllipsoids ? 3u : 1u); ++step) {
        if (step > 0) {
          push.step = step;
          cmd.pushConstants<BandPush>(*layout_, vk::ShaderStageFlagBits::eCompute, 0, push);
        }
        cmd.dispatch(groups, 1, 1);
        barrier(cmd);
      }
    }
    if (after) after(kSteps[p + 1]);
  }
}

}  // namespace sluice::render
