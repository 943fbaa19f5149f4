// sluice/stream/demand.h: the demand (runtime/demand.h) of views drawn with
// the renderer's options: the same frusta, the same reach of a splat, the
// same cLOD rule and reference distance the cull passes use, so that a frame
// read for it holds every particle the renderer keeps for those views.
#pragma once

#include <span>

#include "sluice/render/frame.h"
#include "sluice/render/options.h"
#include "sluice/render/renderer.h"
#include "sluice/runtime/demand.h"

namespace sluice::stream {

// `views` as render::Renderer::record() takes them (1 to 4). `margin`: how far, in
// world units, the views may move before frames read now are drawn (head
// motion in XR, orbiting on the desktop); boxes grow by it.
runtime::ViewDemand view_demand(std::span<const render::View> views, const render::SceneInfo& scene,
                                const render::FluidOptions& fluid, const render::LodOptions& lod, float margin = 0);

// A margin for a camera that moves at most `speed` (world units per
// second) over `seconds` of prefetch, at least a twentieth of `diagonal`
// (the scene's; docs/measurements.md compares a tenth and a twentieth on
// the picture and the bytes read).
float view_margin(float diagonal, float speed, float seconds);

}  // namespace sluice::stream
