#include "read_crew.h"

namespace sluice::runtime::detail {

void ReadCrew::start(int helpers) {
  for (int i = 0; i < helpers; ++i) threads_.emplace_back([this] { helper_main(); });
}

ReadCrew::~ReadCrew() {
  if (running_) {
    try {
      join();
    } catch (...) {  // nobody is left to tell
    }
  }
  stopping_.store(true, std::memory_order_release);
  round_.fetch_add(1, std::memory_order_release);
  round_.notify_all();
  for (auto& t : threads_) t.join();
}

void ReadCrew::work() {
  for (uint64_t p; (p = next_.fetch_add(1, std::memory_order_relaxed)) < count_;) {
    if (failed_.load(std::memory_order_relaxed)) return;
    try {
      body_(p);
    } catch (...) {
      if (!failed_.exchange(true, std::memory_order_acq_rel)) error_ = std::current_exception();
      return;
    }
  }
}

void ReadCrew::helper_main() {
  uint64_t seen = 0;
  for (;;) {
    round_.wait(seen, std::memory_order_acquire);
    seen = round_.load(std::memory_order_acquire);
    if (stopping_.load(std::memory_order_acquire)) return;
    work();
    if (working_.fetch_sub(1, std::memory_order_acq_rel) == 1) working_.notify_one();
  }
}

void ReadCrew::run(uint64_t count, PieceBody body) {
  begin(count, body);
  join();
}

void ReadCrew::begin(uint64_t count, PieceBody body) {
  count_ = count;
  body_ = body;
  next_.store(0, std::memory_order_relaxed);
  failed_.store(false, std::memory_order_relaxed);
  error_ = nullptr;
  working_.store(helpers(), std::memory_order_relaxed);
  running_ = true;
  round_.fetch_add(1, std::memory_order_release);
  round_.notify_all();
}

void ReadCrew::join() {
  work();
  for (int left; (left = working_.load(std::memory_order_acquire)) != 0;) working_.wait(left, std::memory_order_acquire);
  running_ = false;
  if (error_) std::rethrow_exception(error_);
}

}  // namespace sluice::runtime::detail
