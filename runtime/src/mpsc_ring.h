// A bounded multi-producer single-consumer ring (Vyukov's bounded queue,
// with the consumer side simplified to one thread).
//
// Each cell carries a sequence number that says whose turn it is: a producer
// claims a position with a CAS on the tail, writes the value and then hands
// the cell to the consumer by bumping its sequence; the consumer hands it back
// to producers one lap later. No locks; a producer only retries when another
// producer claimed the same position first.
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
class MpscRing {
  static_assert(std::is_trivially_copyable_v<T>);

 public:
  explicit MpscRing(size_t min_capacity)
      : capacity_(std::bit_ceil(std::max<size_t>(min_capacity, 2))), cells_(std::make_unique<Cell[]>(capacity_)) {
    for (size_t i = 0; i < capacity_; ++i) cells_[i].sequence.store(i, std::memory_order_relaxed);
  }

  size_t capacity() const { return capacity_; }

  // Any thread. False when full.
  bool try_push(const T& value) {
    uint64_t pos = tail_.load(std::memory_order_relaxed);
    while (true) {
      Cell& cell = cells_[pos & (capacity_ - 1)];
      const uint64_t seq = cell.sequence.load(std::memory_order_acquire);
      const auto lag = static_cast<int64_t>(seq - pos);
      if (lag == 0) {
        if (tail_.compare_exchange_weak(pos, pos + 1, std::memory_order_relaxed)) {
          cell.value = value;
          cell.sequence.store(pos + 1, std::memory_order_release);  // the consumer's turn
          return true;
        }
      } else if (lag < 0) {
        return false;  // the consumer has not freed this cell yet: full
      } else {
        pos = tail_.load(std::memory_order_relaxed);  // another producer took it
      }
    }
  }

  // The single consumer. False when empty (or the next value is still being written).
  bool try_pop(T& out) {
    Cell& cell = cells_[head_ & (capacity_ - 1)];
    if (cell.sequence.load(std::memory_order_acquire) != head_ + 1) return false;
    out = cell.value;
    cell.sequence.store(head_ + capacity_, std::memory_order_release);  // producers' turn, next lap
    ++head_;
    return true;
  }

 private:
  struct Cell {
    std::atomic<uint64_t> sequence{0};
    T value{};
  };
  const size_t capacity_;
  std::unique_ptr<Cell[]> cells_;
  alignas(64) std::atomic<uint64_t> tail_{0};
  alignas(64) uint64_t head_ = 0;  // consumer only
};

}  // namespace sluice::runtime
