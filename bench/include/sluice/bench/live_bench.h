// sluice/bench/live_bench.h: `sluice bench live`, frames pushed from memory
// (stream::LiveSource) at 1M..10M particles: CPU time to chunk, quantize and
// encode them (TBB workers), to decode them into staging, the GPU copy and the
// render, per frame; optionally with the recording written.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace sluice::bench {

struct LiveBenchOptions {
  std::vector<uint64_t> sizes{1'000'000, 10'000'000};  // particles per frame
  int frames = 6;                                      // distinct frames pushed, each 3 times (medians)
  uint32_t width = 1920, height = 1080;
  std::string device;
  std::string record;  // also record to this .sluice file (overwritten)
};

void run_live_bench(const LiveBenchOptions& options);

}  // namespace sluice::bench
