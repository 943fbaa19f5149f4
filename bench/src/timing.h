// Timing a benchmark's pass: repeated until it has run long enough.
#pragma once

#include <chrono>

namespace sluice::bench {

// Runs `pass` until `min_seconds` have gone by (at least once); returns the
// seconds per pass.
template <class F>
double seconds_per_pass(double min_seconds, F&& pass) {
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  int passes = 0;
  double elapsed = 0;
  do {
    pass();
    ++passes;
    elapsed = std::chrono::duration<double>(Clock::now() - start).count();
  } while (elapsed < min_seconds);
  return elapsed / passes;
}

}  // namespace sluice::bench
