// Splits a frame into spatially coherent chunks.
#pragma once

#include <cstdint>
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
// cells, holding at most `max_particles`. Chunks therefore stay compact boxes
// (their AABBs cull well and quantize finely). Parallel (TBB).
ChunkPlan plan_chunks(std::span<const float> xyz, const Aabb& bounds, uint32_t max_particles);

}  // namespace sluice::io
