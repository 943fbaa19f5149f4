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

uint32_t tiers_for_keep(double keep) {
  if (!(keep > 0)) return 0;
  if (keep >= 1) return kLodTiers;
  // The smallest value that may be kept, one lower for rounding.
  const double lowest = 65536.0 * (1.0 - keep * (1.0 + 1e-4)) - 0.5 - 1.0;
  if (lowest <= 0) return kLodTiers;
  return lod_tier(static_cast<uint16_t>(std::min(lowest, 65535.0))) + 1;
}

}  // namespace sluice::io
