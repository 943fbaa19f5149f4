// Internal: the narrow-band classifier's passes (shaders/band_*.comp; their
// layouts in band.glsl), recorded into a caller's command buffer over
// positions already in device memory. BandClassifier feeds it positions
// from the host; the renderer feeds it frames that arrive without layers.
#pragma once

#include <functional>

#include "vk_common.h"

namespace sluice::render {

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

struct BandRun {
  uint64_t n = 0;                // particles, at most BandPasses::kMaxParticles
  vk::DeviceAddress xyz = 0;     // float x, y, z per particle
  vk::DeviceAddress attr = 0;    // float per particle whose mean each blob takes; 0: none
  float diameter = 0;            // h (> 0)
  float voxel = 0;               // d (> 0)
  bool blobs = false;
  // The classification's own passes (L1, L2, particles); off where only
  // the ellipsoids are wanted.
  bool layers = true;
  // Where each particle's ellipsoid goes (band_ellipsoids.comp: its shape
  // matrix and centre shift as 9 halves in 5 words, 20 n bytes); 0: none.
  vk::DeviceAddress shapes = 0;
  // A bit per entry (32-bit words), 1: a blob among the positions, not a
  // particle: no ellipsoid, no neighbour; 0: every entry is a particle.
  vk::DeviceAddress marks = 0;
};

class BandPasses {
 public:
  // 5 x capacity (2n rounded up to a power of two) slot indices fit 32 bits.
  static constexpr uint64_t kMaxParticles = uint64_t(1) << 28;

  explicit BandPasses(detail::ContextImpl& ctx);

  // Grows the scratch and result buffers to `n` particles (contents lost).
  // The old buffers go to `retire` when given (a recorded run may still use
  // them), else they are freed at once.
  void reserve(uint64_t n, bool blobs, const std::function<void(Buffer&&)>& retire = {});

  // Records the fills and the passes for `run` (after reserve(run.n,
  // run.blobs)); `after(name)` runs after each step, for timestamps. The
  // results stay in the buffers below until the next run executes, ordered
  // by a barrier that makes them visible to compute shaders and transfers.
  void record(vk::CommandBuffer cmd, const BandRun& run, const std::function<void(const char*)>& after = {}) const;

  // Orders compute and transfer work after the compute and transfer writes
  // before it (between the passes, and around them).
  static void barrier(vk::CommandBuffer cmd);

  // Every step's name, in the order record() reports them.
  static constexpr const char* kSteps[] = {"fills", "bounds", "grid", "insert", "voxels", "L1",
                                           "L2", "scatter", "particles", "blobs", "ellipsoids"};

  // Results: Params; per particle (5 n words) LAYER at 3n and BLOB_OF at 4n;
  // blobs (vec4: centroid, count bits) and their mean attributes (float).
  Buffer params, particles, blobs, blob_attr;
  static constexpr uint64_t kLayerWord = 3, kBlobOfWord = 4;  // multiples of n, in words

 private:
  detail::ContextImpl& ctx_;
  vk::raii::PipelineLayout layout_{nullptr};
  std::vector<vk::raii::Pipeline> pipelines_;
  Buffer table_;
  uint64_t reserved_ = 0;
  bool reserved_blobs_ = false;
};

}  // namespace sluice::render
