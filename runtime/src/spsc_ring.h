// A bounded single-producer single-consumer ring on two atomic counters.
//
// One thread pushes, one thread pops; neither ever blocks the other. The
// consumer may also look at any element already pushed (peek), which the
// pipeline uses to find the newest ready frame without taking the older ones.
// Positions only grow (64-bit: they never wrap in practice); a position maps
// to a cell by masking, so the capacity is a power of two.
#pragma once

#include <algorithm>
#include <atomic>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <type_traits>

namespace sluice::runtime {

template <class T>
class SpscRing {
  static_assert(std::is_trivially_copyable_v<T>, "cells are copied without synchronisation of their own");

 public:
  explicit SpscRing(size_t min_capacity)
      : capacity_(std::bit_ceil(std::max<size_t>(min_capacity, 2))), cells_(std::make_unique<T[]>(capacity_)) {}

  size_t capacity() const { return capacity_; }

  // Producer. False when full.
  bool try_push(const T& value) {
    const uint64_t tail = tail_.load(std::memory_order_relaxed);
    if (tail - head_cache_ == capacity_) {
      head_cache_ = head_.load(std::memory_order_acquire);
      if (tail - head_cache_ == capacity_) return false;
    }
    cells_[tail & (capacity_ - 1)] = value;
    tail_.store(tail + 1, std::memory_order_release);  // publishes the cell
    return true;
  }

  // Consumer: the i-th element from the front, or nullptr if fewer were
  // pushed. The pointer stays valid until the consumer pops past it.
  const T* peek(size_t i = 0) {
    const uint64_t head = head_.load(std::memory_order_relaxed);
    if (head + i >= tail_cache_) {
      tail_cache_ = tail_.load(std::memory_order_acquire);
      if (head + i >= tail_cache_) return nullptr;
    }
    return &cells_[(head + i) & (capacity_ - 1)];
  }

  // Consumer. False when empty.
  bool try_pop(T& out) {
    const T* front = peek(0);
    if (!front) return false;
    out = *front;
    head_.store(head_.load(std::memory_order_relaxed) + 1, std::memory_order_release);  // frees the cell
    return true;
  }

  // Consumer: elements pushed and not yet popped.
  size_t size() {
    tail_cache_ = tail_.load(std::memory_order_acquire);
    return static_cast<size_t>(tail_cache_ - head_.load(std::memory_order_relaxed));
  }

 private:
  const size_t capacity_;
  std::unique_ptr<T[]> cells_;
  // Each side's counter and its cached copy of the other's sit on their own
  // cache lines so the two threads do not share a line they write.
  alignas(64) std::atomic<uint64_t> head_{0};  // written by the consumer
  uint64_t tail_cache_ = 0;                    // consumer's last view of tail_
  alignas(64) std::atomic<uint64_t> tail_{0};  // written by the producer
  uint64_t head_cache_ = 0;                    // producer's last view of head_
};

}  // namespace sluice::runtime
