#include "sluice/runtime/clock.h"

#include <chrono>
#include <cmath>
#include <limits>

namespace sluice::runtime {

double SteadyClock::now() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

double PlaybackClock::seconds_per_frame() const {
  const double speed = std::abs(rate_) * fps_;
  return speed > 0 ? 1.0 / speed : std::numeric_limits<double>::infinity();
}

void PlaybackClock::play(double now) {
  if (playing_) return;
  anchor_ = now;
  playing_ = true;
}

void PlaybackClock::pause(double now) {
  if (!playing_) return;
  position_ = position(now);
  playing_ = false;
}

void PlaybackClock::set_rate(double now, double rate) {
  position_ = position(now);
  anchor_ = now;
  rate_ = rate;
}

void PlaybackClock::jump(double now, double position) {
  position_ = position;
  anchor_ = now;
}

}  // namespace sluice::runtime
