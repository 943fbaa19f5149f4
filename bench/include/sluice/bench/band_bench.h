// sluice/bench/band_bench.h: `sluice bench band`, the narrow-band classifier
// (io/narrow_band.h) on real frames: how fast, how much it keeps, and how
// the exact narrow band spreads over the voxel layers (the statistic of the
// LNM dissertation's tables 1 and 2); with `gpu`, the GPU classifier beside
// the CPU one.
#pragma once

#include <string>

namespace sluice::bench {

struct BandBenchOptions {
  std::string input;         // simulation output, as `sluice convert` takes it
  int max_threads = 0;       // 0: all cores
  double min_seconds = 1.0;  // each timing repeats until it has run this long
  int frames = 3;            // frames measured: the first, the last, and evenly between
  float diameter = 0;        // particle diameter h; 0: the estimated spacing
  uint64_t synth = 0;        // > 0: instead of `input`, one frame of `sluice synth`'s sloshing block of this many particles
  bool exact = true;         // also compare with the exact narrow band (slow: minutes per 10M particles)
  bool gpu = false;          // also classify on the GPU (render/band_classifier.h): speed, and agreement with the CPU
  std::string device;        // Vulkan device for `gpu`: index or part of its name
};

// Prints the tables to stdout. Throws io::Error on bad input.
void run_band_bench(const BandBenchOptions& options);

}  // namespace sluice::bench
