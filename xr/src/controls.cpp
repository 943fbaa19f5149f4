// Controller actions to playback commands and placement (see controls.h).
#include "sluice/xr/controls.h"

#include <algorithm>
#include <cmath>

namespace sluice::xr {
namespace {

// The stick beyond the dead zone, rescaled to 0..1 (signed).
float deflection(float v, float dead_zone) {
  const float a = std::min(std::fabs(v), 1.0f);
  if (a <= dead_zone) return 0;
  return std::copysign((a - dead_zone) / (1.0f - dead_zone), v);
}

// The direction from a to b projected on the floor (y dropped).
Vec3 horizontal(Vec3 a, Vec3 b) { return {b.x - a.x, 0, b.z - a.z}; }

}  // namespace

Controls::Controls(const Placement& initial, const ControlOptions& options) : options_(options), placement_(initial) {}

void Controls::start_grab(const ActionState& state) {
  for (int h = 0; h < 2; ++h) {
    holding_[size_t(h)] = state.hands[size_t(h)].grab && state.hands[size_t(h)].pose_valid;
    if (holding_[size_t(h)]) hand_start_[size_t(h)] = state.hands[size_t(h)].grip;
  }
  start_ = placement_;
}

Commands Controls::update(const ActionState& state, double seconds) {
  Commands c;
  seconds = std::clamp(seconds, 0.0, 0.25);  // a long stall must not jump the playback
  c.toggle_play = state.play_pause && !play_was_held_;
  play_was_held_ = state.play_pause;

  const float scrub = deflection(state.scrub, options_.dead_zone);
  if (scrub == 0) {
    scrub_frames_ = 0;
  } else {
    scrub_frames_ += double(scrub) * options_.scrub_frames_per_second * seconds;
    c.step = int64_t(scrub_frames_);  // whole frames; the rest carries over
    scrub_frames_ -= double(c.step);
  }
  c.lod_delta = deflection(state.lod, options_.dead_zone) * options_.lod_per_second * float(seconds);

  // A hand that starts or stops holding restarts the grab from where things
  // are, so nothing jumps when the second hand joins or one lets go.
  std::array<bool, 2> now{};
  for (size_t h = 0; h < 2; ++h) now[h] = state.hands[h].grab && state.hands[h].pose_valid;
  if (now != holding_) start_grab(state);
  const int held = int(holding_[0]) + int(holding_[1]);
  if (held == 1) {
    const size_t h = holding_[0] ? 0 : 1;
    // The data keeps its pose relative to the hand.
    const Pose delta = state.hands[h].grip * inverse(hand_start_[h]);
    placement_.pose = delta * start_.pose;
    placement_.scale = start_.scale;
    c.moved = true;
  } else if (held == 2) {
    const Vec3 a0 = hand_start_[0].position, b0 = hand_start_[1].position;
    const Vec3 a = state.hands[0].grip.position, b = state.hands[1].grip.position;
    const float d0 = render::length(b0 - a0), d = render::length(b - a);
    float k = d0 > 1e-4f ? d / d0 : 1.0f;
    k = std::clamp(start_.scale * k, options_.min_scale, options_.max_scale) / start_.scale;
    // Turn about the vertical by the angle the line between the hands turned.
    const Vec3 h0 = horizontal(a0, b0), h1 = horizontal(a, b);
    Quat yaw;
    if (render::length(h0) > 1e-4f && render::length(h1) > 1e-4f) {
      const float angle = std::atan2(render::cross(h0, h1).y, render::dot(h0, h1));
      yaw = axis_angle({0, 1, 0}, angle);
    }
    const Vec3 m0 = (a0 + b0) * 0.5f, m = (a + b) * 0.5f;
    // p' = m + yaw * k * (p - m0) for every room point p of the data.
    placement_.pose.orientation = normalize(yaw * start_.pose.orientation);
    placement_.pose.position = m + rotate(yaw, k * (start_.pose.position - m0));
    placement_.scale = start_.scale * k;
    c.moved = true;
  }
  return c;
}

}  // namespace sluice::xr
