// Simulation output -> .sluice, as `sluice convert` does it and as `play` and
// `render` do it for their cache: header from the first frame, times, the up
// axis found from the frames (or given), progress and notes on stderr.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "sluice/io/convert.h"
#include "sluice/io/format.h"
#include "sluice/io/narrow_band.h"

namespace sluice::app {

struct ConversionOptions {
  std::string input;  // file, glob, .pvd or directory
  std::vector<std::string> attributes;
  bool all_attributes = false;  // carry every point array of the first frame (the cache does)
  std::string id_array;
  bool no_ids = false;
  bool lossless = false;
  float spacing = 0, radius = 0;
  // The largest position error, relative to the spacing, rounded down to a
  // power of two (io::FileHeader::precision_bits); 0: 1/1024.
  double precision = 0;
  // > 0: particles more than this many spacings outside the rest of their
  // frame are left out (listed); otherwise they are kept, warned about.
  float drop_outliers = 0;
  double fps = 0;  // playback frames/s; also the time step 1/fps for inputs without times (0: unset)
  double dt = 0;   // seconds between frames for inputs without times (0: unset)
  std::string up;  // "", or x|y|z|-x|-y|-z: overrides detection
  uint32_t chunk = 65536;
  int level = 3;
  bool smallest = false;
  bool lod_tiers = true;       // chunks as LOD tiers (EncodeOptions::lod_tiers)
  bool gpu_decodable = false;  // no zstd planes (io::PlaneCoding::GpuDecodable)
  // Classify the narrow band: surface, interior and blob layers (format
  // 1.3). Quantized positions only: --lossless files stay one layer.
  bool layers = true;
  float band_voxel = 0;  // 0: twice the spacing
  io::F2Test band_f2 = io::F2Test::All;
  int jobs = 0;
  bool quiet = false;
  size_t max_warnings = 20;
  // A frame that cannot be read is left out and listed (otherwise the
  // conversion stops there, keeping the frames before it).
  bool skip_bad = false;
  // Read VTK XML files in this process instead of in worker processes
  // (faster to start; a reader crash on a damaged file then ends sluice).
  bool in_process = false;
  int read_timeout = 120;  // seconds a worker may take for one frame
};

struct ConversionSummary {
  uint64_t frames = 0, particles = 0, input_bytes = 0;  // frames written
  uint64_t far_particles = 0, far_frames = 0;          // far outside the rest (kept or dropped)
  std::vector<io::SkippedFrame> skipped;              // with skip_bad
  double seconds = 0;
  io::FileHeader header;  // as finally written
};

// Converts `o.input` into `output` through `output + ".partial"` (renamed
// when complete, so a cut-off run never leaves a file that looks whole).
// Throws io::Error / std::runtime_error naming the input on bad input. A
// frame that cannot be read stops the conversion with its error after
// `output` has been finished with the frames before it (unless skip_bad).
ConversionSummary convert_input(const ConversionOptions& o, const std::string& output);

// Playback frame rate when neither the input nor the user gives one.
inline constexpr double kDefaultFrameRate = 30.0;

}  // namespace sluice::app
