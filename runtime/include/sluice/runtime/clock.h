// sluice/runtime/clock.h: time, real or virtual, and media time on top of it.
//
// Playback reads time only through Clock, so tests drive it with a
// VirtualClock and get the same result on a loaded machine as on an idle one.
// Units: seconds for time, frames for media positions.
#pragma once

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

}  // namespace sluice::runtime
