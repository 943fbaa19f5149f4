// sluice/bench/io_bench.h: `sluice bench io`, sluice's container against
// VTK's XML reader on the same frames.
#pragma once

#include <string>

namespace sluice::bench {

struct IoBenchOptions {
  std::string input;          // simulation output, as `sluice convert` takes it
  int max_threads = 0;        // 0: all cores
  double min_seconds = 1.0;   // each timing repeats until it has run this long
  std::string work_dir;       // where the converted files go (default: a temp dir, removed after)
  // The VTK copies of the frames (legacy binary, .vtu raw and zlib) hold
  // each frame this many times, side by side: solver-sized files from a
  // small sample.
  int tile = 1;
};

// Runs the benchmark and prints its tables to stdout. Throws io::Error on bad input.
void run_io_bench(const IoBenchOptions& options);

}  // namespace sluice::bench
