// The lock-free rings: order, capacity and many threads at once.
#include <gtest/gtest.h>

#include <atomic>
#include <thread>
#include <vector>

#include "mpsc_ring.h"
#include "spsc_ring.h"

using namespace sluice::runtime;

TEST(SpscRing, RoundsCapacityUpAndKeepsOrder) {
  SpscRing<int> ring(5);
  EXPECT_EQ(ring.capacity(), 8u);
  for (int i = 0; i < 8; ++i) EXPECT_TRUE(ring.try_push(i));
  EXPECT_FALSE(ring.try_push(8)) << "a full ring must refuse";
  EXPECT_EQ(ring.size(), 8u);
  ASSERT_NE(ring.peek(7), nullptr);
  EXPECT_EQ(*ring.peek(7), 7);
  EXPECT_EQ(ring.peek(8), nullptr);
  for (int i = 0; i < 8; ++i) {
    int v = -1;
    ASSERT_TRUE(ring.try_pop(v));
    EXPECT_EQ(v, i);
  }
  int v;
  EXPECT_FALSE(ring.try_pop(v));
  EXPECT_EQ(ring.peek(0), nullptr);
}

TEST(SpscRing, TwoThreadsPassEveryValueInOrder) {
  SpscRing<uint64_t> ring(64);
  constexpr uint64_t kCount = 200000;
  std::thread producer([&] {
    for (uint64_t i = 0; i < kCount;) {
      if (ring.try_push(i)) ++i;
      else std::this_thread::yield();
    }
  });
  uint64_t expected = 0;
  while (expected < kCount) {
    uint64_t v;
    if (!ring.try_pop(v)) {
      std::this_thread::yield();
      continue;
    }
    ASSERT_EQ(v, expected);
    ++expected;
  }
  producer.join();
}

TEST(MpscRing, RefusesWhenFullAndKeepsFifoOrder) {
  MpscRing<int> ring(4);
  for (int i = 0; i < 4; ++i) EXPECT_TRUE(ring.try_push(i));
  EXPECT_FALSE(ring.try_push(4));
  int v = -1;
  ASSERT_TRUE(ring.try_pop(v));
  EXPECT_EQ(v, 0);
  EXPECT_TRUE(ring.try_push(4));
  for (int i = 1; i <= 4; ++i) {
    ASSERT_TRUE(ring.try_pop(v));
    EXPECT_EQ(v, i);
  }
  EXPECT_FALSE(ring.try_pop(v));
}

TEST(MpscRing, ManyProducersLoseNothing) {
  MpscRing<uint64_t> ring(16);
  constexpr int kProducers = 4;
  constexpr uint64_t kEach = 30000;
  std::vector<std::thread> producers;
  for (int p = 0; p < kProducers; ++p) {
    producers.emplace_back([&, p] {
      for (uint64_t i = 0; i < kEach;) {
        if (ring.try_push(uint64_t(p) << 32 | i)) ++i;
        else std::this_thread::yield();
      }
    });
  }
  std::vector<uint64_t> next(kProducers, 0);
  for (uint64_t received = 0; received < kProducers * kEach;) {
    uint64_t v;
    if (!ring.try_pop(v)) {
      std::this_thread::yield();
      continue;
    }
    const auto p = static_cast<size_t>(v >> 32);
    ASSERT_LT(p, next.size());
    ASSERT_EQ(v & 0xffffffffu, next[p]) << "each producer's values arrive in the order it pushed them";
    ++next[p];
    ++received;
  }
  for (auto& t : producers) t.join();
}
