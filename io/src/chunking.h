// Splits a frame into spatially coherent chunks.
#pragma once

#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "sluice/io/types.h"

namespace sluice::io {

struct ChunkPlan {
  std::vector<uint32_t> order;  // particle indices, Morton order over the frame bounds
  struct Range {
    uint32_t begin, end;        // into `order`
  };
  std::vector<Range> chunks;
};

// Sorts particles along a 63-bit Morton curve over `bounds` and cuts the curve
// at octree cell boundaries: a chunk is an octree cell, or a run of sibling
// cells, holding at most `max_particles` and whose particles' box is at most
// `max_extent` wide on every axis (what keeps the quantization error within
// the file's bound, format.h). Particles that share a Morton code (far
// smaller than the bounds) are cut in halves along their widest axis until
// both limits hold. Chunks therefore stay compact boxes (their AABBs cull
// well and quantize finely). Parallel (TBB).
ChunkPlan plan_chunks(std::span<const float> xyz, const Aabb& bounds, uint32_t max_particles,
                      float max_extent = std::numeric_limits<float>::infinity());

}  // namespace sluice::io
