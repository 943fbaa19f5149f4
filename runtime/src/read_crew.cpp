#include "read_crew.h"
#include "sluice/error.h"

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <utility>

namespace sluice::runtime::detail {
namespace {

constexpr uint64_t kLow = 0xffffffffu;

}  // namespace

void ReadCrew::start(int helpers, int rounds) {
  most_in_flight_ = std::clamp(rounds, 1, kMostRounds);
  for (int i = 0; i < helpers; ++i) threads_.emplace_back([this] { helper_main(); });
}

ReadCrew::~ReadCrew() {
  while (in_flight() > 0) {
    try {
      join();
    } catch (...) {  // nobody is left to tell
    }
  }
  stopping_.store(true, std::memory_order_release);
  posted_.fetch_add(1, std::memory_order_release);
  posted_.notify_all();
  for (auto& t : threads_) t.join();
}

void ReadCrew::run_piece(Round& round, uint32_t piece, uint32_t count) {
  if (!round.failed.load(std::memory_order_relaxed)) {
    const auto started = std::chrono::steady_clock::now();
    try {
      round.body(piece);
    } catch (...) {
      if (!round.failed.exchange(true, std::memory_order_acq_rel)) round.error = std::current_exception();
    }
    const auto ns = std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - started);
    busy_ns_.fetch_add(static_cast<uint64_t>(ns.count()), std::memory_order_relaxed);
  }
  // The last piece may let the caller reuse the round at once: nothing of it
  // is touched after this but the notification (a spurious wake at worst).
  if (round.done.fetch_add(1, std::memory_order_acq_rel) + 1 == count) round.done.notify_all();
}

bool ReadCrew::take(Round& round) {
  uint64_t claim = round.claim.load(std::memory_order_acquire);
  while ((claim & kLow) < (claim >> 32)) {
    // A stale word cannot take a piece of the wrong round: the swap succeeds
    // only if the word still says the same count and next piece, and then
    // that piece is the round's now (its body is read after the swap).
    if (round.claim.compare_exchange_weak(claim, claim + 1, std::memory_order_acq_rel, std::memory_order_acquire)) {
      run_piece(round, static_cast<uint32_t>(claim & kLow), static_cast<uint32_t>(claim >> 32));
      return true;
    }
  }
  return false;
}

bool ReadCrew::take_oldest() {
  // The rounds by when they began, from one reading of their `order` (a
  // round begun meanwhile sorts by the value read: at worst a piece of a
  // younger round goes first once).
  std::array<std::pair<uint64_t, Round*>, kMostRounds> by_age{};
  const size_t n = size_t(most_in_flight_);
  for (size_t r = 0; r < n; ++r) {  // insertion: four at most
    std::pair<uint64_t, Round*> next{rounds_[r].order.load(std::memory_order_relaxed), &rounds_[r]};
    size_t at = r;
    for (; at > 0 && by_age[at - 1].first > next.first; --at) by_age[at] = by_age[at - 1];
    by_age[at] = next;
  }
  for (size_t r = 0; r < n; ++r) {
    if (take(*by_age[r].second)) return true;
  }
  return false;
}

void ReadCrew::helper_main() {
  for (;;) {
    const uint64_t seen = posted_.load(std::memory_order_acquire);
    if (stopping_.load(std::memory_order_acquire)) return;
    while (take_oldest()) {
    }
    posted_.wait(seen, std::memory_order_acquire);
  }
}

void ReadCrew::begin(uint64_t count, PieceBody body) {
  if (in_flight() >= most_in_flight_) throw Error("ReadCrew::begin: every round is in flight");
  if (count > kLow) throw Error("ReadCrew::begin: 2^32 pieces or more");
  Round& round = rounds_[begun_ % uint64_t(most_in_flight_)];
  round.count = static_cast<uint32_t>(count);
  round.body = body;
  round.error = nullptr;
  round.failed.store(false, std::memory_order_relaxed);
  round.done.store(0, std::memory_order_relaxed);
  round.order.store(begun_, std::memory_order_relaxed);
  round.claim.store(count << 32, std::memory_order_release);
  ++begun_;
  posted_.fetch_add(1, std::memory_order_release);
  posted_.notify_all();
}

void ReadCrew::join() {
  if (in_flight() == 0) throw Error("ReadCrew::join: no round in flight");
  Round& round = rounds_[joined_ % uint64_t(most_in_flight_)];
  while (take(round)) {
  }
  for (uint32_t done; (done = round.done.load(std::memory_order_acquire)) != round.count;) {
    round.done.wait(done, std::memory_order_acquire);
  }
  ++joined_;
  if (round.error) std::rethrow_exception(std::exchange(round.error, nullptr));
}

void ReadCrew::run(uint64_t count, PieceBody body) {
  if (in_flight() > 0) throw Error("ReadCrew::run: a round is in flight");
  begin(count, body);
  join();
}

}  // namespace sluice::runtime::detail
