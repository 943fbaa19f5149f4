// Waking a thread that waits on a counter (std::atomic::wait): the
// pipeline's threads sleep on one each (the reader's, the consumer's).
#pragma once

#include <atomic>
#include <cstdint>

namespace sluice::runtime::detail {

// Bumps `counter` and wakes one thread waiting on it.
inline void wake(std::atomic<uint32_t>& counter) {
  counter.fetch_add(1, std::memory_order_release);
  counter.notify_one();
}

}  // namespace sluice::runtime::detail
