// sluice/io/lod.h: the per-particle LOD value.
//
// A 16-bit value, uniformly distributed over 0..65535, that a particle keeps
// in every frame: the renderer drops a particle when its value is above the
// LOD threshold, so a given threshold drops the same particles every frame
// and nothing flickers during playback.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

namespace sluice::io {

// Hash of a stable particle id (XXH3, top 16 bits).
uint16_t lod_value_from_id(uint64_t id);

// LOD values for a frame: from `ids` when non-empty, else from the particle's
// index (stable only if the source keeps its particle order).
std::vector<uint16_t> lod_values(std::span<const uint64_t> ids, uint64_t count);

}  // namespace sluice::io
