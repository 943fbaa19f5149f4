// One frame of a conversion, read and encoded: what convert_frames (serial)
// and convert_mpi (each rank) do to every frame before writing it.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "sluice/import/frames.h"

namespace sluice::import {

struct FrameWork {
  uint64_t frame = 0;
  uint64_t input_bytes = 0;  // its source file's size (0 if unknown)
  std::vector<std::string> repairs;
  std::optional<io::FrameShape> shape;  // for the first settings.shape_frames frames and the last
  bool time_given = false;
  io::EncodedFrame encoded;
  io::FarReport far;
  std::optional<io::Error> error;  // it could not be read or encoded: nothing else is set
};

// Reads frame `f` of `source` (or takes `read`, frame f already read) and
// encodes it for `header`. Errors come back in the value, naming the frame's
// file, never thrown. Thread-safe (source.read is).
FrameWork convert_frame(const FrameSource& source, std::optional<io::ParticleFrame> read, uint64_t f,
                        const io::FileHeader& header, const FramesSettings& settings);

// convert_frames (frames.h) with frames already read: `read` holds some
// frames by index (from ReadAhead, and frame `from`); the rest are read in
// their turn.
FramesResult convert_frames_from(const FrameSource& source, std::map<uint64_t, io::ParticleFrame> read,
                                 io::ContainerWriter& writer, const FramesSettings& settings,
                                 const std::function<void(const FrameConverted&)>& on_frame, uint64_t from);

}  // namespace sluice::import
