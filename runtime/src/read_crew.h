// The threads that copy records' pieces at once: the reader thread and
// `helpers` threads of their own. Dedicated threads rather than TBB workers
// in a second arena: a read never waits for TBB to move a worker over from
// the decode arena, the hand-off is plain atomics that ThreadSanitizer sees
// (no annotations), and the count of threads reading is exactly what was
// asked. Throughput was the same within run-to-run variation (16 cores, 14
// decode + 2 read: 135.8 frames/s with TBB helpers, 120.4 with these, on two
// boxes that vary by about 15%).
//
// Two rounds may be in flight: a helper done with the older round's pieces
// goes on with the younger one's instead of waiting for the round's
// slowest piece (docs/runtime.md, "Two records in flight").
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <exception>
#include <thread>
#include <vector>

namespace sluice::runtime::detail {

// A borrowed `void(uint64_t)` callable: unlike std::function it never
// allocates (the reader runs a crew round per record). Valid while the
// callable it was made from lives.
class PieceBody {
 public:
  template <class F>
  PieceBody(const F& f)  // NOLINT: implicit, like a function reference
      : object_(&f), call_([](const void* o, uint64_t p) { (*static_cast<const F*>(o))(p); }) {}
  void operator()(uint64_t p) const { call_(object_, p); }

 private:
  const void* object_;
  void (*call_)(const void*, uint64_t);
};

class ReadCrew {
 public:
  static constexpr int kMostRounds = 4;  // rounds() at most

  ReadCrew() = default;
  ~ReadCrew();  // joins the rounds in flight, stops and joins the helpers
  // Starts the helper threads and sets how many rounds may be begun and not
  // yet joined (clamped to 1 .. kMostRounds); once, before the first begin().
  void start(int helpers, int rounds = 2);
  int rounds() const { return most_in_flight_; }
  ReadCrew(const ReadCrew&) = delete;
  ReadCrew& operator=(const ReadCrew&) = delete;

  // A round runs body(p) for every p in [0, count), each exactly once, on the
  // helpers and on the thread that joins it. begin() hands the pieces to the
  // helpers and returns at once; join() takes the pieces of the oldest round
  // in flight left on the calling thread, waits for the helpers' pieces of it
  // and rethrows the round's first exception (after which its pieces not yet
  // started are skipped). Helpers take pieces of the oldest round first.
  // Rounds are joined in the order they began; the callable behind `body`
  // must live until its round is joined. One caller (the reader thread)
  // makes every call. Waiting is on futex words (std::atomic::wait): no
  // mutex. begin() throws std::logic_error with rounds() in flight and
  // std::length_error for 2^32 pieces or more; join() throws
  // std::logic_error with none in flight.
  void begin(uint64_t count, PieceBody body);
  void join();
  // begin() then join(), with no other round in flight (std::logic_error).
  void run(uint64_t count, PieceBody body);
  int in_flight() const { return static_cast<int>(begun_ - joined_); }

  int helpers() const { return static_cast<int>(threads_.size()); }
  // Time spent inside bodies, summed over the threads (nanoseconds; any thread).
  uint64_t busy_ns() const { return busy_ns_.load(std::memory_order_relaxed); }

 private:
  struct alignas(64) Round {
    // count << 32 | next piece to take: one word, so that a piece is taken
    // by one compare-and-swap that also says which round it belongs to.
    std::atomic<uint64_t> claim{0};
    std::atomic<uint64_t> order{0};   // when it began: helpers take the oldest round's pieces first
    std::atomic<uint32_t> done{0};    // pieces finished (run or skipped)
    std::atomic<bool> failed{false};
    // Written by begin() before `claim` (release); read after taking a piece.
    PieceBody body{kNothing};
    std::exception_ptr error;  // written by whoever sets `failed` first
    uint32_t count = 0;        // the caller's copy
  };

  void helper_main();
  bool take_oldest();               // one piece of any round; false if none is left
  bool take(Round& round);          // one piece of this round; false if none is left
  void run_piece(Round& round, uint32_t piece, uint32_t count);

  std::vector<std::thread> threads_;
  std::array<Round, kMostRounds> rounds_;  // the first rounds() in use, cyclically
  int most_in_flight_ = 2;                  // rounds(): set by start(), before the helpers run
  std::atomic<uint64_t> posted_{0};  // bumped for every begin(); idle helpers wait on it
  std::atomic<bool> stopping_{false};
  alignas(64) std::atomic<uint64_t> busy_ns_{0};
  uint64_t begun_ = 0, joined_ = 0;  // the caller's only
  static constexpr auto kNothing = [](uint64_t) {};
};

}  // namespace sluice::runtime::detail
