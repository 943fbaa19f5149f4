// Schedules: which frame each entry shows under stop, loop and bounce.
#include <gtest/gtest.h>

#include <vector>

#include "sluice/runtime/clock.h"

using namespace sluice::runtime;

namespace {

std::vector<int64_t> first_frames(const PlaybackSchedule& s, uint64_t n) {
  std::vector<int64_t> out;
  for (uint64_t k = 0; k < n; ++k) out.push_back(s.frame_at(k) ? int64_t(*s.frame_at(k)) : -1);
  return out;
}

}  // namespace

TEST(Schedule, StopEndsAtEitherEnd) {
  PlaybackSchedule s{5, 2, 1, 1, EndMode::Stop};
  EXPECT_EQ(first_frames(s, 5), (std::vector<int64_t>{2, 3, 4, -1, -1}));
  EXPECT_EQ(s.length(), 3u);
  s.direction = -1;
  EXPECT_EQ(first_frames(s, 4), (std::vector<int64_t>{2, 1, 0, -1}));
  EXPECT_EQ(s.length(), 3u);
  s.start = 5;
  EXPECT_TRUE(s.empty());
  EXPECT_EQ(s.length(), 0u);
}

TEST(Schedule, StrideSkipsFrames) {
  const PlaybackSchedule s{10, 1, 1, 3, EndMode::Stop};
  EXPECT_EQ(first_frames(s, 5), (std::vector<int64_t>{1, 4, 7, -1, -1}));
  EXPECT_EQ(s.length(), 3u);
}

TEST(Schedule, LoopWrapsBothWays) {
  PlaybackSchedule s{4, 2, 1, 1, EndMode::Loop};
  EXPECT_EQ(first_frames(s, 7), (std::vector<int64_t>{2, 3, 0, 1, 2, 3, 0}));
  EXPECT_FALSE(s.length().has_value());
  s.direction = -1;
  EXPECT_EQ(first_frames(s, 6), (std::vector<int64_t>{2, 1, 0, 3, 2, 1}));
}

TEST(Schedule, BounceTurnsAroundAtTheEnds) {
  PlaybackSchedule s{4, 1, 1, 1, EndMode::Bounce};
  EXPECT_EQ(first_frames(s, 9), (std::vector<int64_t>{1, 2, 3, 2, 1, 0, 1, 2, 3}));
  s.direction = -1;
  EXPECT_EQ(first_frames(s, 6), (std::vector<int64_t>{1, 0, 1, 2, 3, 2}));
  const PlaybackSchedule one{1, 0, 1, 1, EndMode::Bounce};
  EXPECT_EQ(first_frames(one, 3), (std::vector<int64_t>{0, 0, 0}));
  const PlaybackSchedule two{2, 0, 1, 1, EndMode::Bounce};
  EXPECT_EQ(first_frames(two, 5), (std::vector<int64_t>{0, 1, 0, 1, 0}));
}

TEST(Schedule, EmptyFileHasNoEntries) {
  for (EndMode mode : {EndMode::Stop, EndMode::Loop, EndMode::Bounce}) {
    const PlaybackSchedule s{0, 0, 1, 1, mode};
    EXPECT_TRUE(s.empty()) << end_mode_name(mode);
    EXPECT_EQ(s.length(), 0u);
  }
}
