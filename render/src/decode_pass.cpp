// The GPU decoder's dispatches: two passes of one workgroup per tile, in batches of the
// guaranteed maximum workgroup count.
#include "decode_pass.h"

#include <algorithm>

#include "shaders.h"

namespace sluice::render {
namespace {

using Stage = vk::PipelineStageFlagBits2;
using Access = vk::AccessFlagBits2;

// Mirrors Push in decode.comp.
struct DecodePush {
  uint64_t encoded, plans, particles, attribute, errors, tile_chunks, tile_sums;
  uint32_t tile_base;
  uint32_t pass;
};
static_assert(sizeof(DecodePush) == 64);

constexpr uint32_t kMaxGroups = 65535;  // the guaranteed maxComputeWorkGroupCount[0]

}  // namespace

DecodePass::DecodePass(detail::ContextImpl& ctx) {
  const vk::PushConstantRange range(vk::ShaderStageFlagBits::eCompute, 0, sizeof(DecodePush));
  layout_ = vk::raii::PipelineLayout(ctx.device, vk::PipelineLayoutCreateInfo({}, {}, range));
  pipeline_ = compute_pipeline(ctx.device, layout_, Shader::Decode);
}

void DecodePass::barrier(vk::CommandBuffer cmd) {
  memory_barrier(cmd, Stage::eComputeShader | Stage::eTransfer, Access::eShaderWrite | Access::eTransferWrite,
                 Stage::eComputeShader | Stage::eTransfer | Stage::eVertexShader | Stage::eDrawIndirect,
                 Access::eShaderRead | Access::eShaderWrite | Access::eTransferRead | Access::eTransferWrite |
                     Access::eIndirectCommandRead);
}

void DecodePass::record(vk::CommandBuffer cmd, const DecodeRun& run, const std::function<void(uint32_t)>& after) const {
  if (run.tiles == 0) return;
  cmd.bindPipeline(vk::PipelineBindPoint::eCompute, *pipeline_);
  DecodePush push{run.encoded, run.plans, run.particles, run.attribute, run.errors, run.tile_chunks, run.tile_sums, 0, 0};
  for (uint32_t pass = 0; pass < kPasses; ++pass) {
    if (pass > 0) barrier(cmd);
    push.pass = pass;
    for (uint32_t base = 0; base < run.tiles; base += kMaxGroups) {
      push.tile_base = base;
      cmd.pushConstants<DecodePush>(*layout_, vk::ShaderStageFlagBits::eCompute, 0, push);
      cmd.dispatch(std::min(kMaxGroups, run.tiles - base), 1, 1);
    }
    if (after) after(pass);
  }
}

}  // namespace sluice::render
