// The frame a looping position lands on: `value` modulo `period` (> 0),
// never negative (C++'s % keeps the dividend's sign).
#pragma once

#include <cstdint>

namespace sluice::runtime::detail {

inline int64_t wrap(int64_t value, int64_t period) {
  const int64_t r = value % period;
  return r < 0 ? r + period : r;
}

}  // namespace sluice::runtime::detail
