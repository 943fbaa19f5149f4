// Internal: turning camera and options into the per-frame uniforms. Plain
// C++ (no Vulkan) so it is cheap to compile and easy to test.
#pragma once

#include "gpu_types.h"
#include "sluice/render/camera.h"
#include "sluice/render/frame.h"
#include "sluice/render/options.h"
#include "sluice/render/draw.h"
#include "sluice/render/options.h"

namespace sluice::render {

struct ViewSetup {
  uint32_t width = 0, height = 0;             // output
  uint32_t thick_width = 0, thick_height = 0; // thickness buffer
  float max_point_size = 64;                  // device limit, pixels
  bool write_aux = false;
};

Globals make_globals(const SceneInfo& scene, const View& view, const FluidOptions& options,
                     const LodOptions& lod, const ViewSetup& setup);

// Depth passes run filtered / thickness passes run filtered for this mode.
bool depth_filtered(const FluidOptions& o);
bool thickness_filtered(const FluidOptions& o);

}  // namespace sluice::render
