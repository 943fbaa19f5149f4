// sluice/render/inspection.h: a renderer's intermediate images, read back
// for tests and tools. Not for a host's frame loop: each call submits a copy
// to the graphics queue and waits for it (no other thread may use that queue
// meanwhile), after the caller waited for the frame it reads.
#pragma once

#include <vector>

#include "sluice/render/renderer.h"

namespace sluice::render {

// Per pixel of the last view: eye-space normal x, y, z and linear depth
// after filtering, depth 0 where there is no fluid. Throws render::Error
// unless the renderer was made with RendererOptions::debug_surfaces.
std::vector<float> read_surface(Renderer& renderer);
// The unfiltered linear depth (distance along the view axis) of the last view.
std::vector<float> read_raw_depth(Renderer& renderer);
// The unfiltered thickness (world units along each pixel's ray) of the last
// view, at the thickness buffer's resolution (half size unless full
// resolution was asked for).
std::vector<float> read_raw_thickness(Renderer& renderer);

}  // namespace sluice::render
