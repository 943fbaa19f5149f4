// sluice/render/synthetic.h: particles that do not come from a file: the
// tests' analytic scenes and the benchmark's synthetic fluid of any size.
//
// Threads: the functions stage into a Renderer and commit; call them from the
// renderer's thread (they use TBB internally).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "sluice/render/renderer.h"

namespace sluice::render {

// A scene description for positions `xyz` (x,y,z interleaved) with the given
// rest spacing; one attribute "value" with range [attr_min, attr_max].
SceneInfo scene_for_points(std::span<const float> xyz, float spacing, float attr_min = 0, float attr_max = 1);

// Quantizes consecutive runs of up to `chunk_particles` particles against
// their own AABB (as the container does), stages them with their LOD values
// and optional attribute, and commits. Callers keep runs spatially coherent
// for chunk culling to work.
void upload_points(Renderer& renderer, std::span<const float> xyz, std::span<const uint16_t> lod,
                   std::span<const float> attribute = {}, uint32_t chunk_particles = 65536);

// A synthetic liquid of about `target` particles in a 2 x 1 x 1 tank (z up):
// a pool with waves and a collapsing column, particles on a jittered grid
// with spacing chosen to hit the target. Chunks are 32^3 grid cells, each
// laid out as a file lays it out (`tiers`): its particles by LOD tier
// (io/lod.h), a chunk row per tier with its values' bounds, Morton order
// within a tier; else one row in Morton order. LOD values hash the grid index
// (stable); the attribute is the depth below the surface, 0..1.
struct SyntheticFluid {
  SceneInfo scene;
  float spacing = 0;
  uint64_t particles = 0;  // exact count the grid gives
  uint32_t chunks = 0;  // chunk rows: a block's non-empty tiers
  bool tiers = true;
};
SyntheticFluid synthetic_fluid(uint64_t target, bool tiers = true);
// Generates it straight into the renderer's staging (parallel) and commits.
void upload_synthetic(Renderer& renderer, const SyntheticFluid& fluid);
// The same particles as world x,y,z (unquantized), e.g. for another renderer.
std::vector<float> synthetic_points(const SyntheticFluid& fluid);

}  // namespace sluice::render
