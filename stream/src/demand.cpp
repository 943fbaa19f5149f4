// The renderer's options as a demand (demand.h); globals.cpp sets the same
// values as uniforms for the cull passes.
#include "sluice/stream/demand.h"

#include <algorithm>

namespace sluice::stream {

runtime::ViewDemand view_demand(std::span<const render::View> views, const render::SceneInfo& scene,
                                const render::FluidOptions& fluid, const render::LodOptions& lod, float margin) {
  runtime::ViewDemand d;
  for (const render::View& v : views) {
    if (d.views.size() == d.views.capacity()) break;
    d.views.push_back({v.view.m, v.projection.m, v.viewport.width, v.viewport.height});
  }
  // The position hash orders nothing the file's tiers hold: every tier.
  d.lod = lod.mode != render::LodMode::Off && lod.random == render::LodRandom::Stable;
  d.level = std::clamp(lod.level, 0.0f, 1.0f);
  d.reference_distance = lod.reference_distance > 0 ? lod.reference_distance : std::max(scene.bounds.diagonal(), 1e-6f);
  d.particle_radius = render::effective_radius(fluid, scene);
  const float growth = lod.mode == render::LodMode::DensityPreserving ? std::max(lod.max_splat_scale, 1.0f) : 1.0f;
  d.particle_reach = d.particle_radius * growth;
  d.margin = std::max(margin, 0.0f);
  d.position_error_pixels = std::max(lod.position_error_pixels, 0.0f);
  return d;
}

float view_margin(float diagonal, float speed, float seconds) {
  return std::max(0.05f * diagonal, std::max(speed, 0.0f) * std::max(seconds, 0.0f));
}

}  // namespace sluice::stream
