// Internal: the GPU decoder's pass (shaders/decode.comp), recorded into a
// caller's command buffer over an encoded area and a plan already in device
// memory (io/gpu_decode_plan.h). GpuDecoder feeds it from the host for tests
// and benchmarks; the renderer feeds it frames committed encoded.
#pragma once

#include <functional>

#include "vk_common.h"

namespace sluice::render {

struct DecodeRun {
  vk::DeviceAddress encoded = 0;    // the encoded area (record, inflated planes, padding)
  vk::DeviceAddress plans = 0;      // io::GpuChunkPlan per chunk
  vk::DeviceAddress particles = 0;  // 8 bytes per particle of the frame
  vk::DeviceAddress attribute = 0;  // 2 bytes per particle (chunks whose plan has attribute = 1)
  vk::DeviceAddress errors = 0;     // a word per chunk, set to 1 on error (the caller zeroes it)
  vk::DeviceAddress tile_chunks = 0;  // each tile's chunk (io::GpuDecodePlan::tile_chunk)
  vk::DeviceAddress tile_sums = 0;    // scratch: kTileSumBytes per tile
  uint32_t tiles = 0;
};

class DecodePass {
 public:
  static constexpr uint64_t kTileSumBytes = 2 * 10 * 4;  // per tile: codes and byte sums of 10 planes
  static constexpr uint32_t kPasses = 2;                 // sum the tiles, decode them

  explicit DecodePass(detail::ContextImpl& ctx);
  // Records the dispatches; the caller orders the inputs' writes before and
  // the outputs' reads after (barrier()).
  // `after(pass)` runs after each pass's dispatches (0 .. kPasses - 1), for timestamps.
  void record(vk::CommandBuffer cmd, const DecodeRun& run, const std::function<void(uint32_t)>& after = {}) const;
  // Orders transfers and compute before later compute, transfers, vertex reads.
  static void barrier(vk::CommandBuffer cmd);

 private:
  vk::raii::PipelineLayout layout_{nullptr};
  vk::raii::Pipeline pipeline_{nullptr};
};

}  // namespace sluice::render
