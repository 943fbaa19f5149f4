// A progress bar on stderr: bar, count, rates and ETA, redrawn in place on a
// terminal at most 10 times a second; on a pipe or file, a line per 10% at
// most once a second, and the final line.
// Thread-safe: update() may be called from any thread.
#pragma once

#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>

namespace sluice::app {

class ProgressBar {
 public:
  ProgressBar(std::string unit, uint64_t total, bool quiet = false);
  // Sets progress to `done` units; `bytes_in`/`bytes_out` so far give MB/s.
  void update(uint64_t done, uint64_t bytes_in = 0, uint64_t bytes_out = 0);
  // Prints a warning above the bar without garbling it.
  void warn(const std::string& line) { print("warning: " + line); }
  // Prints a line (stats, notes) above the bar without garbling it.
  void print(const std::string& line);
  void finish();
  double elapsed() const;

 private:
  void draw(bool final);

  std::string unit_;
  uint64_t total_;
  bool quiet_, tty_;
  std::mutex mutex_;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now(), last_draw_{};
  uint64_t done_ = 0, in_ = 0, out_ = 0;
  int last_decile_ = -1;
  uint64_t last_done_ = UINT64_MAX;
  bool drawn_ = false;
};

}  // namespace sluice::app
