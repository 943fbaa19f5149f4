// Internal: a frame split into the narrow band's layers for encoding
// (format 1.3): surface particles, interior particles, and the interior's
// voxel blobs as records of their own.
#pragma once

#include <cstdint>
#include <vector>

#include "sluice/io/codec.h"

namespace sluice::io {

// The blobs as a frame of records: centroid positions, the particle count
// as the LOD value, each attribute's mean over the blob's particles.
struct BlobRecords {
  std::vector<float> positions;
  std::vector<uint16_t> counts;
  std::vector<std::vector<float>> attributes;
  FrameInput input() const;
};

struct LayeredFrame {
  std::vector<uint32_t> surface;   // particle indices of `in`
  std::vector<uint32_t> interior;
  BlobRecords blobs;
  float voxel = 0;                 // side of the blobs' voxels
};

// Classifies `in` (particle diameter `spacing`, voxel side `voxel`, 0: 2 x
// spacing, F2 test `f2`) and gathers the interior into blobs. A blob holding
// more than 65535 particles is written as several at the same centroid.
LayeredFrame split_layers(const FrameInput& in, float spacing, float voxel, F2Test f2);

}  // namespace sluice::io
