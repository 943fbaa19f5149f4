// What the players read of each frame: only the LOD tiers of the cells
// their views can keep (render/demand.h), unless `--layers all` or
// `--lod off` asks for everything.
#pragma once

#include <span>
#include <string>

#include "sluice/io/reader.h"
#include "sluice/render/demand.h"
#include "sluice/runtime/stats.h"

namespace sluice::app {

// Whether frames are read by the view: not with --layers all or --lod off,
// and not for a file without layers drawn as its narrow band (the GPU
// classifies each frame whole: a frame thinned by the view would give
// another narrow band).
bool reads_by_view(const std::string& layers, const render::LodOptions& lod, const io::ContainerReader& reader);

// The demand of `views` (render::view_demand), or every tier when frames
// are not read by the view. `moving`: the camera may move before frames
// read now are drawn (a window, a headset): boxes grow by `speed` (world
// units per second) times `horizon_seconds`, at least a twentieth of the
// scene's diagonal (render::view_margin); a fixed camera needs none. Set it as the
// pipeline's first demand (PlayerOptions) and, as the views change,
// through Player::set_demand.
// For the HUD and summaries: "read 23.8 MB a frame, 3.2% of the records;
// 120 of 120 frames by the view" (bytes read per frame read and their
// share of those frames' whole records).
std::string reads_text(const runtime::PipelineStats& stats);

runtime::ViewDemand app_demand(std::span<const render::View> views, const render::SceneInfo& scene,
                               const render::FluidOptions& fluid, const render::LodOptions& lod, bool by_view,
                               bool moving, float speed = 0, float horizon_seconds = 0);

// How fast a camera moves, for the margin of a moving view: the largest
// speed of its eye (world units per second) over about the last half
// second. One per player loop; not thread-safe.
class CameraSpeed {
 public:
  // The eye of `view` (the first, for stereo) at `seconds` (a steady clock).
  float update(const render::View& view, double seconds);

 private:
  bool seen_ = false;
  render::Vec3 eye_{};
  double at_ = 0;
  float speed_ = 0;
};

}  // namespace sluice::app
