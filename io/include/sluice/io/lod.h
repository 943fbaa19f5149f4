// sluice/io/lod.h: the per-particle LOD value.
//
// A 16-bit value, uniformly distributed over 0..65535, that a particle keeps
// in every frame: the renderer drops a particle when its value is above the
// LOD threshold, so a given threshold drops the same particles every frame
// and nothing flickers during playback.
#pragma once

#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

namespace sluice::io {

// Hash of a stable particle id (XXH3, top 16 bits).
uint16_t lod_value_from_id(uint64_t id);

// LOD values for a frame: from `ids` when non-empty, else from the particle's
// index (stable only if the source keeps its particle order).
std::vector<uint16_t> lod_values(std::span<const uint64_t> ids, uint64_t count);

// LOD tiers (format 1.4, docs/format.md "LOD tiers"). The renderer keeps a
// particle of importance w at level L when u >= 1 - L^(1/w), u = (value +
// 0.5) / 65536 (render/lod.h): what it can keep of a chunk is always the
// particles with the largest values. A chunk is therefore written as up to
// kLodTiers records, tier 0 holding the largest values, so that the
// particles kept at any level are a prefix of tiers: one contiguous byte
// range. Tier t holds the values v with kTierFloor[t] <= v < kTierFloor[t-1]
// (65536 for t = 0): the top 1/64, 1/32, 1/16, 0.1, 0.15, 0.2, 0.25, 0.3,
// 0.4, 0.5, 0.7 and 1 of the values, cumulatively (and 40 values more, the
// reader's rounding margin), so that the levels 0.1-0.5 of a particle of
// importance 1 fall on tier boundaries, a view never reads more than 1.5
// times what it keeps above 1/64, and far views (small importance) read a
// few percent (docs/format.md, "LOD tiers", measured).
inline constexpr uint32_t kLodTiers = 12;
inline constexpr uint32_t kTierFloor[kLodTiers] = {64472, 63448, 61400, 58942, 55666, 52389,
                                                   49112, 45835, 39282, 32728, 19621, 0};

// The tier a value belongs to, 0 .. kLodTiers - 1.
inline uint32_t lod_tier(uint16_t value) {
  uint32_t t = 0;
  while (value < kTierFloor[t]) ++t;
  return t;
}

// The tier of a random term u in [0, 1): the tier of the 16-bit values
// u * 65536 falls among (so a demand's tiers_for_keep() holds it too).
inline uint32_t lod_tier_of_uniform(double u) {
  const double scaled = std::floor(u * 65536.0);
  return lod_tier(static_cast<uint16_t>(scaled < 0 ? 0 : scaled > 65535 ? 65535 : scaled));
}

// A voxel blob's random term (its LOD value is a count, not a hash): an
// integer hash of the world cell of side `voxel` its centroid lies in, as
// the renderer computes it (shaders/cull_particles.comp, cell_hash), 24 bits
// in (0, 1). Stable while the voxel stays occupied.
double blob_lod_uniform(int32_t cx, int32_t cy, int32_t cz);
// The largest blob_lod_uniform() of the cells a decoded centroid may be
// taken to lie in: its own and, on each axis where it lies within 1e-3 of a
// cell's side from a face, the neighbour's too (the GPU's division need not
// round as the host's does). A blob is written in the tier of this value,
// so a reader that reads that tier has it whichever cell the GPU finds.
// `margin` (a fraction of the side): a format 2.0 writer, which knows the
// source centroid and not yet the decoded one, passes 2e-3 and keeps the
// quantization error under 0.9e-3 of the side (docs/format.md).
double blob_lod_uniform_bound(float x, float y, float z, float voxel, double margin = 1e-3);

// How many tiers hold every value v with (v + 0.5) / 65536 >= 1 - keep:
// what a reader must read of a chunk whose particles are kept with
// probability at most `keep` (0..1; values outside are clamped). The bound
// is widened by a relative 1e-4 and one value against float rounding in the
// renderer's test (the tier floors leave room for it). 0 only for keep <= 0.
uint32_t tiers_for_keep(double keep);

}  // namespace sluice::io
