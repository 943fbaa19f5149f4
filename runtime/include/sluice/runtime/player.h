// sluice/runtime/player.h: playback driven by time.
//
// A Player owns a Pipeline and decides, at every display refresh (update()),
// which frame is on screen: the frame nearest the media position (a frame is
// due half a frame before its time, and the clock is anchored at the centre
// of the frame that shows, so refresh jitter never drops or repeats a frame
// when the display keeps pace with the media). Play, pause, rate
// (negative plays in reverse), end modes (stop, loop, bounce), step, seek and
// scrub all map onto a PlaybackSchedule the pipeline prefetches.
//
// Real-time policy, when the due frame is not decoded yet:
//  - HoldLastFrame: keep the last frame on screen and wait for it (a stall);
//    media time waits too, so no frame of the schedule is ever skipped.
//  - SkipToNewest: media time never waits; show the newest decoded frame
//    whose time has come and drop the older ones (drops). A frame that is due
//    and not ready is a stall. Far behind, the schedule restarts at the due
//    frame rather than decode frames that would all be dropped.
// At rates the display cannot show (|rate| * fps > display rate) the schedule
// fetches every n-th frame, n = floor(|rate| * fps / display rate).
//
// Errors: a frame that cannot be read or decoded is reported (pop_error(),
// naming file, frame and chunk) and, by ErrorPolicy, skipped (playback goes
// on; the last good frame stays on screen for its time) or playback stops
// cleanly (state Stopped, reading stops; seek() or play() resume).
//
// Threads: every member except stats() is for the one consumer thread (the
// one that renders). stats() may be called from any thread.
#pragma once

#include <atomic>
#include <cstdint>
#include <deque>
#include <optional>

#include "sluice/runtime/clock.h"
#include "sluice/runtime/pipeline.h"

namespace sluice::runtime {

enum class RealTimePolicy : uint8_t { HoldLastFrame, SkipToNewest };
enum class ErrorPolicy : uint8_t { SkipFrame, Stop };
enum class PlayerState : uint8_t {
  Paused,   // showing one frame (a seek, step or scrub target appears when decoded)
  Playing,
  Ended,    // EndMode::Stop reached the last frame (first, in reverse)
  Stopped,  // a frame failed under ErrorPolicy::Stop
};

const char* state_name(PlayerState state);

struct PlayerOptions {
  double frame_rate = 0;    // media frames per second; 0: the file's (30 if it has none)
  double display_rate = 0;  // display refreshes per second, for the stride; 0: fetch every frame
  double rate = 1.0;        // initial playback rate
  uint64_t start_frame = 0;
  // Play only the file's first `frames` frames (0: all of them): the end,
  // loop and bounce come there, and the pipeline reads nothing past it (a
  // render of frames 3..5 reads no frame 6).
  uint64_t frames = 0;
  EndMode end = EndMode::Stop;
  RealTimePolicy policy = RealTimePolicy::HoldLastFrame;
  ErrorPolicy on_error = ErrorPolicy::SkipFrame;
  PipelineOptions pipeline;
};

struct PlaybackStats {
  PlayerState state = PlayerState::Paused;
  uint64_t frame = 0;          // on screen
  uint64_t frames_shown = 0;   // new frames put on screen
  uint64_t stalls = 0;         // updates at which the due frame was not ready
  uint64_t drops = 0;          // frames passed over because a newer one was due (SkipToNewest)
  uint64_t errors = 0;         // frames that failed
  uint64_t refinements = 0;    // frames on screen read again for a larger demand (paused)
  PipelineStats pipeline;
};

// What update() says: the frame to show now.
struct Tick {
  const FrameHandle* frame = nullptr;  // nullptr before the first frame; valid until the next update()
  bool changed = false;                // a different frame than at the last update()
};

class Player {
 public:
  // Borrowed: reader, allocator and clock outlive the player. Starts paused
  // at options.start_frame (shown by update() once decoded).
  Player(const io::ContainerReader& reader, FrameAllocator& allocator, const Clock& clock, PlayerOptions options = {});
  ~Player();

  // Consumer thread.
  void play();
  void pause();
  void set_rate(double rate);     // frames of media per frame of frame_rate; < 0 plays in reverse
  void set_end_mode(EndMode end);
  void seek(uint64_t frame);      // jump; playing or paused stays as it was
  void step(int64_t frames);      // pause and move by `frames` (clamped, or wrapped when looping)
  void scrub(uint64_t frame);     // pause and show `frame`, prefetching in the direction of the drag

  // Once per display refresh: returns the frame to show. The previous
  // frame's buffers are given back when a new one is shown, so finish
  // reading them (e.g. the staging upload) before calling update() again.
  Tick update();
  // Blocks until update() would find the frame it wants ready (or failed),
  // or returns at once if no frame is due. For tests and as-fast-as-possible
  // runs; a real-time loop just calls update().
  void wait_for_due();

  // What the views draw (demand.h; Pipeline::set_demand): frames read from
  // now on hold only the tiers it needs. While paused, the frame on screen
  // is read again with the tiers it lacks whenever the demand outgrows what
  // it was read with (the camera came closer, the level went up), and shown
  // once read: the picture converges to the full read's.
  void set_demand(const ViewDemand& demand);
  const ViewDemand& demand() const { return demand_; }

  std::optional<FrameError> pop_error();
  PlayerState state() const { return state_; }
  double rate() const { return clock_state_.rate(); }
  EndMode end_mode() const { return end_; }
  uint64_t frame_count() const { return frame_count_; }
  double frame_rate() const { return clock_state_.frames_per_second(); }
  const FrameHandle* shown() const { return shown_.empty() ? nullptr : &shown_; }  // the frame on screen, if any
  const PlaybackSchedule& schedule() const { return schedule_; }
  Pipeline& pipeline() { return pipeline_; }

  // Any thread.
  PlaybackStats stats() const;

 private:
  bool is_due(uint64_t sequence, double now) const;
  double interval_start(int64_t position) const;  // where a frame's time on screen begins
  uint32_t stride_for(double rate) const;
  int direction_for(double rate) const;
  void restart_from(int64_t start, int direction, uint32_t stride, bool anchor_on_show);
  void show(FrameHandle frame, double now);
  bool handle_failure(FrameHandle failed, double now);  // true: playback stopped
  void tick_paused(double now);
  void refine();  // paused: read the frame on screen again if the demand outgrew it
  void tick_hold(double now);
  void tick_skip(double now);
  bool catch_up(double now);
  bool check_end(const NextEntry& next, double now);
  void move_to(uint64_t frame, int direction, double now);
  std::optional<uint64_t> pending_sequence();  // the entry on its way to the screen (seek, step, scrub)
  uint64_t current_frame();                     // that entry's frame, else the one on screen

  const Clock& clock_;
  const PlayerOptions options_;
  const uint64_t frame_count_;
  Pipeline pipeline_;
  PlaybackClock clock_state_;
  PlaybackSchedule schedule_;
  EndMode end_;
  PlayerState state_ = PlayerState::Paused;

  FrameHandle shown_;
  int64_t shown_position_ = 0;             // unwrapped position of the shown frame
  std::optional<uint64_t> shown_sequence_; // its entry, if it belongs to the current schedule
  std::optional<uint64_t> target_;         // paused: the entry to show once decoded
  bool anchor_on_show_ = false;            // the clock starts when the next frame shows (after a seek)
  bool changed_ = false;
  std::deque<FrameError> errors_;

  std::atomic<PlayerState> stat_state_{PlayerState::Paused};
  std::atomic<uint64_t> stat_frame_{0}, stat_shown_{0}, stat_stalls_{0}, stat_drops_{0}, stat_errors_{0};
  std::atomic<uint64_t> stat_refinements_{0};
  ViewDemand demand_;
};

}  // namespace sluice::runtime
