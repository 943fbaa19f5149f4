#include "sluice/io/lod.h"

#include <xxhash.h>

#include <algorithm>

namespace sluice::io {

uint16_t lod_value_from_id(uint64_t id) {
  // Seeded so that ids 0,1,2,... do not map to a recognisable pattern.
  return static_cast<uint16_t>(XXH3_64bits_withSeed(&id, sizeof id, 0x5a1c3e) >> 48);
}

std::vector<uint16_t> lod_values(std::span<const uint64_t> ids, uint64_t count) {
  std::vector<uint16_t> out(count);
  for (uint64_t i = 0; i < count; ++i) out[i] = lod_value_from_id(ids.empty() ? i : ids[i]);
  return out;
}

double blob_lod_uniform(int32_t cx, int32_t cy, int32_t cz) {
  uint32_t h = uint32_t(cx) * 73856093u ^ uint32_t(cy) * 19349663u ^ uint32_t(cz) * 83492791u;
  h ^= h >> 16;
  h *= 0x7feb352du;
  h ^= h >> 15;
  h *= 0x846ca68bu;
  h ^= h >> 16;
  return (double(h >> 8) + 0.5) * (1.0 / 16777216.0);
}

double blob_lod_uniform_bound(float x, float y, float z, float voxel, double margin) {
  const float p[3] = {x, y, z};
  int32_t lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    const double c = double(p[a]) / double(voxel);
    const double f = std::floor(c);
    lo[a] = hi[a] = static_cast<int32_t>(f);
    if (c - f < margin) lo[a] -= 1;
    if (f + 1 - c < margin) hi[a] += 1;
  }
  double best = 0;
  for (int32_t i = lo[0]; i <= hi[0]; ++i) {
    for (int32_t j = lo[1]; j <= hi[1]; ++j) {
      for (int32_t k = lo[2]; k <= hi[2]; ++k) best = std::max(best, blob_lod_uniform(i, j, k));
    }
  }
  return best;
}

uint32_t tiers_for_keep(double keep) {
  if (!(keep > 0)) return 0;
  if (keep >= 1) return kLodTiers;
  // The smallest value that may be kept, one lower for rounding.
  const double lowest = 65536.0 * (1.0 - keep * (1.0 + 1e-4)) - 0.5 - 1.0;
  if (lowest <= 0) return kLodTiers;
  return lod_tier(static_cast<uint16_t>(std::min(lowest, 65535.0))) + 1;
}

}  // namespace sluice::io
