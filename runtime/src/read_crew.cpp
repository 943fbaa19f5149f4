#include "read_crew.h"
#include "sluice/error.h"

#include <chrono>
#include <stdexcept>
#include <utility>

namespace sluice::runtime::detail {
namespace {

constexpr uint64_t kLow = 0xffffffffu;

}  // namespace

void ReadCrew::start(int helpers) {
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
  Round* first = &rounds_[0];
  Round* second = &rounds_[1];
  if (second->order.load(std::memory_order_relaxed) < first->order.load(std::memory_order_relaxed)) std::swap(first, second);
  return take(*first) || take(*second);
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
  if (in_flight() >= kRounds) throw Error("ReadCrew::begin: every round is in flight");
  if (count > kLow) throw Error("ReadCrew::begin: 2^32 pieces or more");
  Round& round = rounds_[begun_ % kRounds];
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
  Round& round = rounds_[joined_ % kRounds];
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
