#include "view_demand.h"

namespace sluice::app {

bool reads_by_view(const std::string& layers, const render::LodOptions& lod) {
  return layers != "all" && lod.mode != render::LodMode::Off;
}

runtime::ViewDemand app_demand(std::span<const render::View> views, const render::SceneInfo& scene,
                               const render::FluidOptions& fluid, const render::LodOptions& lod, bool by_view,
                               bool moving) {
  if (!by_view) return {};
  const float margin = moving ? render::view_margin(scene.bounds.diagonal(), 0, 0) : 0.0f;
  return render::view_demand(views, scene, fluid, lod, margin);
}

}  // namespace sluice::app
