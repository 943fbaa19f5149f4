// sluice/import/frames.h: the conversion pipeline, FrameSource -> container.
//
// Frames are read and encoded in parallel (TBB) and written in order; at most
// `max_in_flight` frames are in memory at once, whatever the sequence length.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "sluice/io/codec.h"
#include "sluice/import/convert.h"
#include "sluice/import/source.h"
#include "sluice/io/point_set.h"
#include "sluice/io/up_axis.h"
#include "sluice/io/writer.h"

namespace sluice::import {

struct FrameConverted {
  uint64_t frame;                            // just written
  uint64_t input_bytes;                      // size of its source file (0 if unknown)
  const std::vector<std::string>& repairs;   // what the importer repaired in it
  const std::optional<io::FrameShape>& shape;    // measured for the first `shape_frames` frames and the last
  bool time_given;                           // the input stated this frame's time
  const io::FarReport& far;                      // its far particles
};

struct FramesSettings {
  io::EncodeOptions encode;
  size_t max_in_flight = 2;  // frames in memory at once
  // Seconds between frames, for frames whose input states no time: frame i
  // gets i * time_step. 0: they keep the frame number as their time.
  double time_step = 0;
  // Frames (from the first) whose io::FrameShape is measured for up-axis
  // detection; the last frame's is measured too when this is non-zero.
  uint64_t shape_frames = 16;
  io::ShapeGrid shape_grid{};  // the grid of io::FrameShape's columns; an empty box: no columns
  // A frame that cannot be read (io::Error) is left out and listed in
  // FramesResult::skipped instead of stopping the conversion.
  bool skip_bad = false;
  // > 0: particles more than this far (world units) outside their frame's
  // core box (point_set.h) are left out before the frame is measured and
  // encoded, and reported as dropped.
  float drop_far = 0;
};

struct FramesResult {
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
FramesResult convert_frames(const FrameSource& source, std::optional<io::ParticleFrame> first, io::ContainerWriter& writer,
                             const FramesSettings& settings,
                             const std::function<void(const FrameConverted&)>& on_frame = {}, uint64_t from = 0);

}  // namespace sluice::import
