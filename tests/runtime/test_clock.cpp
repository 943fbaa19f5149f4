// Media time as a function of (virtual) time.
#include <gtest/gtest.h>

#include "sluice/runtime/clock.h"

using namespace sluice::runtime;

TEST(PlaybackClock, AdvancesOnlyWhilePlaying) {
  PlaybackClock c(30);
  EXPECT_DOUBLE_EQ(c.position(5), 0);
  c.play(1.0);
  EXPECT_DOUBLE_EQ(c.position(2.0), 30);
  c.pause(2.5);
  EXPECT_DOUBLE_EQ(c.position(10), 45);
  c.play(20);
  EXPECT_DOUBLE_EQ(c.position(21), 75);
}

TEST(PlaybackClock, RateChangesKeepThePositionContinuous) {
  PlaybackClock c(10);
  c.play(0);
  c.set_rate(1.0, -2.0);  // at position 10
  EXPECT_DOUBLE_EQ(c.position(1.0), 10);
  EXPECT_DOUBLE_EQ(c.position(1.5), 0);
  EXPECT_DOUBLE_EQ(c.seconds_per_frame(), 0.05);
  c.jump(2.0, 100);
  EXPECT_DOUBLE_EQ(c.position(2.1), 98);
  c.set_rate(3.0, 0);
  EXPECT_DOUBLE_EQ(c.position(50), c.position(3.0));
}

TEST(VirtualClock, MovesOnlyForward) {
  VirtualClock v(1.0);
  v.advance(0.5);
  v.advance(-3);
  EXPECT_DOUBLE_EQ(v.now(), 1.5);
}
