// sluice/xr/controls.h: what the controllers' actions mean for playback and
// for where the data stands. Plain code: the session samples the OpenXR
// actions into an ActionState once per frame (session.h); Controls turns a
// sequence of them into Commands. No OpenXR here, so every gesture has a
// unit test.
//
// The mapping:
//   play_pause (A/X, menu)       press toggles play/pause
//   stick / trackpad x           scrub: hold right/left to step frames, faster further out
//   stick / trackpad y           LOD level up/down while held
//   grab (squeeze, select)       one hand: the data follows the hand (move and rotate);
//                                two hands: move with their midpoint, turn about the
//                                vertical with the line between them, scale with their
//                                distance
// Threads: one thread (the frame loop's).
#pragma once

#include <array>
#include <cstdint>

#include "sluice/xr/placement.h"

namespace sluice::xr {

struct HandState {
  bool grab = false;        // squeeze (or select) held
  bool pose_valid = false;  // the grip pose is tracked this frame
  Pose grip;                // in the room (the reference space)
};

struct ActionState {
  bool play_pause = false;       // held now (the press is found by Controls)
  float scrub = 0;               // -1..1, the stick's or trackpad's x (both hands summed, clamped)
  float lod = 0;                 // -1..1, its y
  std::array<HandState, 2> hands;  // left, right
};

struct ControlOptions {
  float dead_zone = 0.25f;            // of the stick, ignored
  float scrub_frames_per_second = 30;  // at full deflection
  float lod_per_second = 0.5f;        // LOD level change per second at full deflection
  float min_scale = 1e-6f, max_scale = 1e6f;
};

struct Commands {
  bool toggle_play = false;
  int64_t step = 0;       // frames to step (negative: back); pauses the player
  float lod_delta = 0;    // change of the LOD level (the caller clamps)
  bool moved = false;     // the placement changed this update
};

class Controls {
 public:
  explicit Controls(const Placement& initial, const ControlOptions& options = {});

  // One frame: the actions' state and the seconds since the previous update.
  Commands update(const ActionState& state, double seconds);
  const Placement& placement() const { return placement_; }

 private:
  void start_grab(const ActionState& state);

  ControlOptions options_;
  Placement placement_;
  bool play_was_held_ = false;
  double scrub_frames_ = 0;  // fractional frames not stepped yet
  // The grab: which hands hold, and their poses and the placement when it began.
  std::array<bool, 2> holding_{false, false};
  std::array<Pose, 2> hand_start_;
  Placement start_;
};

}  // namespace sluice::xr
