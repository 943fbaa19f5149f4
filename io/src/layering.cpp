#include "layering.h"

#include <algorithm>

#include "sluice/io/narrow_band.h"

namespace sluice::io {

FrameInput BlobRecords::input() const {
  FrameInput in;
  in.positions = positions;
  in.lod = counts;
  for (const auto& a : attributes) in.attributes.emplace_back(a);
  return in;
}

LayeredFrame split_layers(const FrameInput& in, float spacing, float voxel, F2Test f2) {
  NarrowBandOptions options;
  options.diameter = spacing;
  options.voxel = voxel;
  options.f2 = f2;
  options.blobs = true;
  const NarrowBand band = classify_narrow_band(in.positions, options);
  LayeredFrame out;
  out.voxel = band.voxel;
  const size_t n = band.layer.size();
  out.surface.reserve(band.surface());
  out.interior.reserve(n - band.surface());
  for (size_t i = 0; i < n; ++i) (is_surface(band.layer[i]) ? out.surface : out.interior).push_back(uint32_t(i));

  // Attribute sums per blob, in double: a blob's mean is what its particles
  // would have shown on average.
  const size_t attributes = in.attributes.size();
  std::vector<double> sums(band.blobs.size() * attributes, 0.0);
  for (const uint32_t i : out.interior) {
    const uint32_t b = band.blob_of[i];
    for (size_t a = 0; a < attributes; ++a) sums[b * attributes + a] += in.attributes[a][i];
  }
  BlobRecords& r = out.blobs;
  r.attributes.assign(attributes, {});
  for (size_t b = 0; b < band.blobs.size(); ++b) {
    const VoxelBlob& blob = band.blobs[b];
    for (uint32_t left = blob.count; left > 0;) {
      const uint32_t count = std::min<uint32_t>(left, 65535);
      left -= count;
      r.positions.insert(r.positions.end(), blob.centroid.begin(), blob.centroid.end());
      r.counts.push_back(uint16_t(count));
      for (size_t a = 0; a < attributes; ++a) r.attributes[a].push_back(float(sums[b * attributes + a] / blob.count));
    }
  }
  return out;
}

}  // namespace sluice::io
