// sluice/runtime/schedule.h: which frames the pipeline fetches, in order.
//
// A schedule is the sequence of frames playback will show from a starting
// point: entry k is the frame at unwrapped position start + direction *
// stride * k, mapped into the file by the end mode. Loop and bounce make the
// sequence endless; Stop ends it at the first or last frame. The pipeline
// fetches entries 0, 1, 2, ... and delivers them in that order; a seek, a
// reversal or a new stride is a new schedule (and a new generation).
#pragma once

#include <cstdint>
#include <optional>

namespace sluice::runtime {

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
