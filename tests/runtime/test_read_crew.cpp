// The read crew: every piece exactly once per run, across many runs and
// helper counts; a throwing piece ends the run and reaches the caller; with
// two rounds in flight, helpers go on to the younger one while the older
// waits for a straggler, and each round keeps its own error.
#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <chrono>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

#include "read_crew.h"
#include "sluice/error.h"

using sluice::runtime::detail::ReadCrew;

TEST(ReadCrew, RunsEveryPieceExactlyOnceOnSeveralThreads) {
  for (int helpers : {0, 1, 3}) {
    ReadCrew crew;
    crew.start(helpers);
    std::set<std::thread::id> threads;
    std::atomic<int> distinct_threads_seen{0};
    for (uint64_t round = 0; round < 300; ++round) {
      const uint64_t count = round % 17;  // 0 pieces too
      std::vector<std::atomic<int>> hits(count);
      std::vector<std::thread::id> who(count);
      crew.run(count, [&](uint64_t p) {
        hits[p].fetch_add(1);
        who[p] = std::this_thread::get_id();
        if (count > 8) std::this_thread::yield();  // give the helpers a chance to take some
      });
      for (uint64_t p = 0; p < count; ++p) {
        ASSERT_EQ(hits[p].load(), 1) << "piece " << p << " of " << count << ", helpers " << helpers;
        threads.insert(who[p]);  // written before run() returned: no race
      }
    }
    distinct_threads_seen = int(threads.size());
    EXPECT_LE(distinct_threads_seen.load(), helpers + 1);
    if (helpers == 0) {
      EXPECT_EQ(distinct_threads_seen.load(), 1);
    }
  }
}

TEST(ReadCrew, FirstErrorReachesTheCallerAndLaterRunsStillWork) {
  ReadCrew crew;
  crew.start(2);
  std::atomic<int> ran{0};
  EXPECT_THROW(crew.run(1000, [&](uint64_t p) {
                 ran.fetch_add(1);
                 if (p == 5) throw std::runtime_error("short read at piece 5");
               }),
               std::runtime_error);
  EXPECT_GE(ran.load(), 1);  // how many ran depends on timing: the failure only stops pieces not yet begun
  std::atomic<uint64_t> sum{0};
  crew.run(100, [&](uint64_t p) { sum.fetch_add(p); });
  EXPECT_EQ(sum.load(), 4950u);
}

TEST(ReadCrew, HelpersGoOnToTheYoungerRoundWhileTheOlderWaitsForAStraggler) {
  ReadCrew crew;
  crew.start(3);
  std::atomic<bool> release{false};
  std::atomic<int> older_done{0}, younger_done{0};
  const auto older = [&](uint64_t p) {
    if (p == 0) {
      const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(30);  // never forever
      while (!release.load() && std::chrono::steady_clock::now() < until) std::this_thread::yield();
    }
    older_done.fetch_add(1);
  };
  const auto younger = [&](uint64_t) { younger_done.fetch_add(1); };
  crew.begin(4, older);
  crew.begin(64, younger);
  EXPECT_EQ(crew.in_flight(), 2);
  // Nobody joins yet: the helpers alone must finish the younger round while
  // piece 0 of the older one holds a helper.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (younger_done.load() < 64 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  EXPECT_EQ(younger_done.load(), 64) << "the helpers waited for the older round's straggler";
  EXPECT_EQ(older_done.load(), 3);
  release = true;
  crew.join();
  EXPECT_EQ(older_done.load(), 4);
  crew.join();
  EXPECT_EQ(crew.in_flight(), 0);
}

TEST(ReadCrew, EachRoundKeepsItsOwnErrorAndRoundsAreBounded) {
  ReadCrew crew;
  crew.start(2);
  std::atomic<uint64_t> sum{0};
  const auto failing = [&](uint64_t p) {
    if (p == 3) throw std::runtime_error("short read at piece 3");
  };
  const auto adding = [&](uint64_t p) { sum.fetch_add(p); };
  crew.begin(50, failing);
  crew.begin(100, adding);
  EXPECT_THROW(crew.begin(1, adding), sluice::runtime::Error) << "a third round in flight";
  EXPECT_THROW(crew.run(1, adding), sluice::runtime::Error) << "run() with rounds in flight";
  EXPECT_THROW(crew.join(), std::runtime_error);
  crew.join();  // the younger round ran whole, its error slot untouched
  EXPECT_EQ(sum.load(), 4950u);
  EXPECT_THROW(crew.join(), sluice::runtime::Error) << "nothing left to join";
  EXPECT_THROW(crew.begin(uint64_t(1) << 32, adding), sluice::runtime::Error);
  EXPECT_EQ(crew.in_flight(), 0);
}

// With four rounds in flight, helpers finish the three younger rounds while
// a straggler holds the oldest; a fifth is refused; joins go in order.
TEST(ReadCrew, FourRoundsInFlightEachRunWholeByTheHelpers) {
  ReadCrew crew;
  crew.start(3, 4);
  EXPECT_EQ(crew.rounds(), 4);
  std::atomic<bool> release{false};
  std::atomic<int> oldest_done{0};
  std::array<std::atomic<uint64_t>, 3> sums{};
  const auto oldest = [&](uint64_t p) {
    if (p == 0) {
      const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(30);  // never forever
      while (!release.load() && std::chrono::steady_clock::now() < until) std::this_thread::yield();
    }
    oldest_done.fetch_add(1);
  };
  const auto r1 = [&](uint64_t p) { sums[0].fetch_add(p); };
  const auto r2 = [&](uint64_t p) { sums[1].fetch_add(p); };
  const auto r3 = [&](uint64_t p) { sums[2].fetch_add(p); };
  crew.begin(4, oldest);
  crew.begin(100, r1);
  crew.begin(200, r2);
  crew.begin(300, r3);
  EXPECT_EQ(crew.in_flight(), 4);
  EXPECT_THROW(crew.begin(1, r1), sluice::runtime::Error) << "a fifth round in flight";
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (sums[2].load() < 44850u && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  EXPECT_EQ(sums[0].load(), 4950u) << "the helpers reach the second round";
  EXPECT_EQ(sums[1].load(), 19900u) << "and the third";
  EXPECT_EQ(sums[2].load(), 44850u) << "and the fourth, while the oldest waits";
  release = true;
  for (int r = 0; r < 4; ++r) crew.join();
  EXPECT_EQ(oldest_done.load(), 4);
  // The rounds' storage is reused cyclically: another four go through.
  for (int r = 0; r < 4; ++r) crew.begin(10, r1);
  for (int r = 0; r < 4; ++r) crew.join();
  EXPECT_EQ(sums[0].load(), 4950u + 4 * 45u);
  EXPECT_EQ(crew.in_flight(), 0);
}

TEST(ReadCrew, CountsTheTimeSpentInPieces) {
  ReadCrew crew;
  crew.start(1);
  crew.run(4, [](uint64_t) { std::this_thread::sleep_for(std::chrono::milliseconds(5)); });
  EXPECT_GE(crew.busy_ns(), 4u * 5'000'000u);
}
