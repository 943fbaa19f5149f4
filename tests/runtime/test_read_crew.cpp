// The read crew: every piece exactly once per run, across many runs and
// helper counts; a throwing piece ends the run and reaches the caller.
#include <gtest/gtest.h>

#include <atomic>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

#include "read_crew.h"

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
    if (helpers == 0) EXPECT_EQ(distinct_threads_seen.load(), 1);
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
