#include "view_demand.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace sluice::app {

std::string reads_text(const runtime::PipelineStats& s) {
  if (s.frames_read == 0) return "nothing read yet";
  char text[160];
  const double per = double(s.bytes_read) / double(s.frames_read);
  const double share = s.record_bytes > 0 ? 100.0 * double(s.bytes_read) / double(s.record_bytes) : 100.0;
  std::snprintf(text, sizeof text, "read %.1f MB a frame, %.1f%% of the records; %llu of %llu frames by the view", per / 1e6,
                share, (unsigned long long)s.frames_by_demand, (unsigned long long)s.frames_read);
  return text;
}

bool reads_by_view(const std::string& layers, const render::LodOptions& lod, const io::ContainerReader& reader) {
  const bool layered = reader.frame_count() > 0 && reader.index().frames[0].layered();
  return layers != "all" && lod.mode != render::LodMode::Off && layered;
}

runtime::ViewDemand app_demand(std::span<const render::View> views, const render::SceneInfo& scene,
                               const render::FluidOptions& fluid, const render::LodOptions& lod, bool by_view,
                               bool moving, float speed, float horizon_seconds) {
  if (!by_view) return {};
  const float margin = moving ? render::view_margin(scene.bounds.diagonal(), speed, horizon_seconds) : 0.0f;
  return render::view_demand(views, scene, fluid, lod, margin);
}

float CameraSpeed::update(const render::View& view, double seconds) {
  const render::Vec4 eye4 = render::inverse(view.view) * render::Vec4{0, 0, 0, 1};
  const render::Vec3 eye{eye4.x, eye4.y, eye4.z};
  if (seen_ && seconds > at_) {
    const float now = render::length(eye - eye_) / float(seconds - at_);
    // The fastest recent move, decaying by half every 0.25 s.
    speed_ = std::max(now, speed_ * float(std::exp2(-(seconds - at_) / 0.25)));
  }
  seen_ = true;
  eye_ = eye;
  at_ = seconds;
  return speed_;
}

}  // namespace sluice::app
