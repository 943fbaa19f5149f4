#include "sluice/runtime/clock.h"

#include "wrap.h"

namespace sluice::runtime {

using detail::wrap;

const char* end_mode_name(EndMode mode) {
  switch (mode) {
    case EndMode::Stop: return "stop";
    case EndMode::Loop: return "loop";
    case EndMode::Bounce: return "bounce";
  }
  return "?";
}

std::optional<uint64_t> PlaybackSchedule::frame_of(int64_t position) const {
  if (frame_count == 0) return std::nullopt;
  const auto n = static_cast<int64_t>(frame_count);
  switch (end) {
    case EndMode::Stop:
      if (position < 0 || position >= n) return std::nullopt;
      return static_cast<uint64_t>(position);
    case EndMode::Loop:
      return static_cast<uint64_t>(wrap(position, n));
    case EndMode::Bounce: {
      if (n == 1) return 0;
      const int64_t period = 2 * (n - 1);  // 0 .. n-1 .. 1, then again
      const int64_t m = wrap(position, period);
      return static_cast<uint64_t>(m < n ? m : period - m);
    }
  }
  return std::nullopt;
}

std::optional<uint64_t> PlaybackSchedule::frame_at(uint64_t k) const { return frame_of(position_at(k)); }

std::optional<uint64_t> PlaybackSchedule::length() const {
  if (end != EndMode::Stop) return frame_count == 0 ? std::optional<uint64_t>(0) : std::nullopt;
  const auto n = static_cast<int64_t>(frame_count);
  if (start < 0 || start >= n) return 0;
  const int64_t room = direction > 0 ? n - 1 - start : start;  // frames beyond the start
  return static_cast<uint64_t>(room / int64_t(stride > 0 ? stride : 1) + 1);
}

}  // namespace sluice::runtime
