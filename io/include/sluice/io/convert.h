// sluice/io/convert.h: the conversion pipeline, FrameSource -> container.
//
// Frames are read and encoded in parallel (TBB) and written in order; at most
// `max_in_flight` frames are in memory at once, whatever the sequence length.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "sluice/io/codec.h"
#include "sluice/io/import.h"
#include "sluice/io/outliers.h"
#include "sluice/io/up_axis.h"
#include "sluice/io/writer.h"

namespace sluice::io {

struct ConvertProgress {
  uint64_t frame;                            // just written
  uint64_t input_bytes;                      // size of its source file (0 if unknown)
  const std::vector<std::string>& repairs;   // what the importer repaired in it
  const std::optional<FrameShape>& shape;    // measured for the first `shape_frames` frames and the last
  bool time_given;                           // the input stated this frame's time
  const FarReport& far;                      // its far particles
};

struct ConvertSettings {
  EncodeOptions encode;
  size_t max_in_flight = 2;  // frames in memory at once
  // Seconds between frames, for frames whose input states no time: frame i
  // gets i * time_step. 0: they keep the frame number as their time.
  double time_step = 0;
  // Frames (from the first) whose FrameShape is measured for up-axis
  // detection; the last frame's is measured too when this is non-zero.
  uint64_t shape_frames = 16;
  ShapeGrid shape_grid{};  // the grid of FrameShape's columns; an empty box: no columns
  // A frame that cannot be read (io::Error) is left out and listed in
  // ConvertResult::skipped instead of stopping the conversion.
  bool skip_bad = false;
  // > 0: particles more than this far (world units) outside their frame's
  // core box (outliers.h) are left out before the frame is measured and
  // encoded, and reported as dropped.
  float drop_far = 0;
};

struct SkippedFrame {
  uint64_t frame = 0;  // in the source
  std::string name;    // the source's name of the frame (its files)
  std::string error;   // the io::Error's full text
};

struct ConvertResult {
  uint64_t frames = 0;
  uint64_t particles = 0;
  uint64_t input_bytes = 0;
  uint64_t raw_bytes = 0;  // filtered payload before zstd
  std::vector<SkippedFrame> skipped;  // with skip_bad, in frame order
};

// Reads every frame of `source` from `from` on, encodes it for `writer`'s
// header and appends it. `first`, if given, is frame `from` already read (it
// is consumed). `on_frame` runs on one thread at a time, in frame order.
// A frame that fails to read or encode throws its io::Error (naming the
// source file and frame) after every frame before it has been appended, so
// the writer holds exactly the frames before the bad one; with
// `settings.skip_bad` it is listed in the result instead. Does not call
// writer.finish().
ConvertResult convert_frames(const FrameSource& source, std::optional<ParticleFrame> first, ContainerWriter& writer,
                             const ConvertSettings& settings,
                             const std::function<void(const ConvertProgress&)>& on_frame = {}, uint64_t from = 0);

}  // namespace sluice::io
