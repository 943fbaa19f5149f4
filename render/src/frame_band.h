// Internal: the narrow band of frames that arrive without layers
// (RendererOptions::classify_unlayered), classified on the GPU when a frame
// set is first drawn: its particles as float positions (band_gather.comp),
// the classifier's passes (band_passes.h), then every particle's surface
// bit and the blobs written after the particles with a chunk row of their
// own (band_apply.comp). The cull pass then skips interior particles.
// The same run gives anisotropic particles (RendererOptions::anisotropic)
// their ellipsoids, for any frame: a shape matrix and centre shift per
// particle (band_ellipsoids.comp) in the set's `shapes`.
#pragma once

#include <memory>

#include "band_passes.h"
#include "gpu_types.h"
#include "sluice/render/frame.h"

namespace sluice::render {

struct FrameSet;

// Blobs a set makes room for after its particles; a frame with more is
// drawn whole. A voxel of side 2h holds about 8 particles, and blobs stand
// for the interior voxels only.
uint64_t blob_room(uint64_t particles);

// Words of a set's surface buffer: a validity word, then one bit per particle.
uint64_t surface_words(uint64_t particles);

// Bytes of a set's shapes buffer: a validity word (1 once its ellipsoids
// are written), h (float), then 5 words per particle (common.glsl's Shapes).
uint64_t shapes_bytes(uint64_t particles);

// The blobs' chunk row, all but its count (which the GPU writes): the box
// and attribute range of the frame's chunks, first = n, kind 1, voxel d.
GpuChunk blob_chunk_row(std::span<const GpuChunk> table, uint64_t particles, float voxel);

class FrameBand {
 public:
  FrameBand(detail::ContextImpl& ctx, float diameter);
  // h (the particle diameter) the frames are classified with; 0: unknown,
  // frames stay whole.
  float diameter() const { return diameter_; }
  float voxel() const { return 2 * diameter_; }

  // What a run gives a set.
  struct Wanted {
    bool classify = false;  // its narrow band (the set uploaded unlayered and band_eligible)
    bool shapes = false;    // its particles' ellipsoids (set.shapes sized by shapes_bytes)
  };
  // Records the run for `set` (uploaded) into `cmd`; `retire` keeps
  // grown-out scratch alive while recorded work may use it.
  void record(vk::CommandBuffer cmd, FrameSet& set, bool float_positions, Wanted wanted,
              const std::function<void(Buffer&&)>& retire);
  // The classifier's Params (BandParams) of the last recorded run.
  const Buffer& params() const { return passes_.params; }

 private:
  detail::ContextImpl& ctx_;
  float diameter_;
  BandPasses passes_;
  vk::raii::PipelineLayout layout_{nullptr};
  vk::raii::Pipeline gather_{nullptr}, apply_{nullptr};
  Buffer xyz_, attr_, marks_;  // scratch, grown to the largest frame
};

}  // namespace sluice::render
