#include "machine.h"

#include <tbb/info.h>

#include <chrono>
#include <cstring>
#include <fstream>
#include <vector>

namespace sluice::bench {

std::string cpu_model() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
  }
  return "unknown CPU";
}

int core_count() { return tbb::info::default_concurrency(); }

double memcpy_gbps(double min_seconds) {
  const size_t bytes = size_t(256) << 20;
  std::vector<char> a(bytes, 1), b(bytes, 0);
  std::memcpy(b.data(), a.data(), bytes);  // fault the pages in before timing
  const auto start = std::chrono::steady_clock::now();
  double t = 0;
  size_t copies = 0;
  do {
    std::memcpy(b.data(), a.data(), bytes);
    ++copies;
    t = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  } while (t < min_seconds);
  return double(bytes) * double(copies) / t / 1e9;
}

}  // namespace sluice::bench
