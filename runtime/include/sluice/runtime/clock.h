// sluice/runtime/clock.h: time, real or virtual, media time on top of it,
// and the schedule of frames playback shows.
//
// Playback reads time only through Clock, so tests drive it with a
// VirtualClock and get the same result on a loaded machine as on an idle one.
// Units: seconds for time, frames for media positions.
#pragma once

#include <cstdint>
#include <optional>

namespace sluice::runtime {

class Clock {
 public:
  virtual ~Clock() = default;
  // Seconds since an arbitrary epoch; never decreases.
  virtual double now() const = 0;
};

// std::chrono::steady_clock.
class SteadyClock final : public Clock {
 public:
  double now() const override;
};

// Time that moves only when told to. Not thread-safe: the thread that plays
// (the consumer) owns it.
class VirtualClock final : public Clock {
 public:
  explicit VirtualClock(double start = 0) : now_(start) {}
  double now() const override { return now_; }
  void advance(double seconds) {
    if (seconds > 0) now_ += seconds;
  }

 private:
  double now_;
};

// Media position as a function of time: position(t) = p0 + rate * fps * (t -
// t0) while playing, p0 while paused. Positions are unwrapped frame numbers
// (a schedule maps them into the file). Pure arithmetic, no threads.
class PlaybackClock {
 public:
  explicit PlaybackClock(double frames_per_second) : fps_(frames_per_second > 0 ? frames_per_second : 30.0) {}

  double position(double now) const { return playing_ ? position_ + rate_ * fps_ * (now - anchor_) : position_; }
  bool playing() const { return playing_; }
  double rate() const { return rate_; }
  double frames_per_second() const { return fps_; }
  // Seconds of real time per frame of media at the current rate (infinite at rate 0).
  double seconds_per_frame() const;

  void play(double now);
  void pause(double now);
  // Keeps the position continuous across the change.
  void set_rate(double now, double rate);
  // Moves the position; playing or paused stays as it was.
  void jump(double now, double position);

 private:
  double fps_;
  double rate_ = 1.0;
  double position_ = 0;  // at anchor_
  double anchor_ = 0;
  bool playing_ = false;
};

// The schedule: which frames the pipeline fetches, in order.
//
// A schedule is the sequence of frames playback will show from a starting
// point: entry k is the frame at unwrapped position start + direction *
// stride * k, mapped into the file by the end mode. Loop and bounce make the
// sequence endless; Stop ends it at the first or last frame. The pipeline
// fetches entries 0, 1, 2, ... and delivers them in that order; a seek, a
// reversal or a new stride is a new schedule (and a new generation).

enum class EndMode : uint8_t {
  Stop,    // play to the last frame (or the first, in reverse) and stop there
  Loop,    // wrap around: ..., N-2, N-1, 0, 1, ...
  Bounce,  // turn around at either end: ..., N-2, N-1, N-2, ..., 1, 0, 1, ...
};

const char* end_mode_name(EndMode mode);

struct PlaybackSchedule {
  uint64_t frame_count = 0;  // frames in the file
  int64_t start = 0;         // unwrapped position of entry 0 (a frame number for Stop)
  int direction = 1;         // +1 forward, -1 reverse
  uint32_t stride = 1;       // frames between entries (> 1 at rates the display cannot show)
  EndMode end = EndMode::Stop;

  // Unwrapped position of entry k; frame_at maps it into the file.
  int64_t position_at(uint64_t k) const { return start + int64_t(direction) * int64_t(stride) * int64_t(k); }
  // The frame entry k shows, or nullopt past the end of a Stop schedule.
  std::optional<uint64_t> frame_at(uint64_t k) const;
  // The frame an unwrapped position shows under this end mode (nullopt:
  // outside the file, for Stop).
  std::optional<uint64_t> frame_of(int64_t position) const;
  bool empty() const { return !frame_at(0).has_value(); }
  // Number of entries, or nullopt if endless.
  std::optional<uint64_t> length() const;
};

}  // namespace sluice::runtime
