// sluice/render/gpu_decoder.h: container frames decoded by the GPU, from
// the host and back, for tests and benchmarks ("decode alone").
//
// The renderer decodes frames committed encoded (Renderer::commit)
// with the same pass; this class runs it on its own: load() plans a record
// (io/gpu_decode_plan.h: checks, checksums, zstd planes inflated on the CPU)
// and uploads it, run() decodes it on the GPU as often as asked (timed with
// timestamps, the frame already resident), read() brings the particles and
// the colour attribute back: bit for bit what io::decode_chunk writes.
//
// Threads: one call at a time; load(), run() and read() submit to the
// context's graphics queue and wait, so they must not overlap another
// thread's use of that queue.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "sluice/error.h"
#include "sluice/io/format.h"
#include "sluice/io/gpu_decode_plan.h"
#include "sluice/render/context.h"

namespace sluice::render {

struct GpuDecodeOutput {
  std::vector<uint64_t> particles;  // x | y << 16 | z << 32 | lod << 48, the frame's order
  std::vector<uint16_t> attribute;  // the colour attribute (empty when none was asked for)
  uint32_t chunks_with_errors = 0;  // packed planes whose escapes disagree with their count
};

class GpuDecoder {
 public:
  // `context` must outlive the decoder.
  explicit GpuDecoder(Context& context);
  ~GpuDecoder();
  GpuDecoder(const GpuDecoder&) = delete;
  GpuDecoder& operator=(const GpuDecoder&) = delete;

  // Plans `header`'s chunks of `record` (io::plan_gpu_decode), stages them
  // (io::stage_frame: checksums when `verify`, zstd planes inflated) and
  // uploads the encoded area and the plan. Throws io::Error at `where`.
  void load(std::span<const std::byte> record, const io::FrameHeader& header, const io::FileHeader& file,
            const io::GpuPlanOptions& options, bool verify, const io::ErrorLocation& where);
  const io::GpuDecodePlan& plan() const;

  // Decodes the loaded frame `repeats` times; the GPU milliseconds of each
  // run (timestamps; empty without them).
  std::vector<double> run(int repeats = 1);

  // The last run's passes (tile sums, decode), mean
  // milliseconds over its repeats; empty without timestamps.
  std::vector<double> last_pass_ms() const;

  // The last run's output.
  GpuDecodeOutput read() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sluice::render
