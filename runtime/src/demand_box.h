// The latest demand, from any thread to the reader thread: a triple buffer.
// Writers (serialised by a mutex of their own, never taken by the reader)
// fill a spare copy and swap it in; the reader swaps the newest one out when
// there is one, without a lock or an allocation.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <mutex>

#include "sluice/runtime/demand.h"

namespace sluice::runtime::detail {

class DemandBox {
 public:
  explicit DemandBox(const ViewDemand& first) { copies_.fill(first); }

  // Any thread.
  void set(const ViewDemand& demand) {
    const std::lock_guard lock(writers_);
    copies_[write_] = demand;
    write_ = middle_.exchange(write_ | kFresh, std::memory_order_acq_rel) & kIndex;
    serial_.fetch_add(1, std::memory_order_relaxed);
  }
  // The reader thread: the newest demand set; valid until its next call.
  const ViewDemand& latest() {
    if (middle_.load(std::memory_order_relaxed) & kFresh) {
      read_ = middle_.exchange(read_, std::memory_order_acq_rel) & kIndex;
    }
    return copies_[read_];
  }
  uint64_t serial() const { return serial_.load(std::memory_order_relaxed); }  // demands set so far

 private:
  static constexpr uint32_t kIndex = 3, kFresh = 4;
  std::array<ViewDemand, 3> copies_;
  std::mutex writers_;
  uint32_t write_ = 0;              // the writers' spare (under writers_)
  std::atomic<uint32_t> middle_{1}; // the one in between, kFresh when a writer left it there
  uint32_t read_ = 2;               // the reader's
  std::atomic<uint64_t> serial_{0};
};

}  // namespace sluice::runtime::detail
