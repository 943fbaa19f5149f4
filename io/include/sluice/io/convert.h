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
#include "sluice/io/writer.h"

namespace sluice::io {

struct ConvertProgress {
  uint64_t frame;                            // just written
  uint64_t input_bytes;                      // size of its source file (0 if unknown)
  const std::vector<std::string>& repairs;   // what the importer repaired in it
};

struct ConvertResult {
  uint64_t frames = 0;
  uint64_t particles = 0;
  uint64_t input_bytes = 0;
  uint64_t raw_bytes = 0;  // filtered payload before zstd
};

// Reads every frame of `source`, encodes it for `writer`'s header and appends
// it. `first`, if given, is frame 0 already read (it is consumed). `on_frame`
// runs on one thread at a time, in frame order. Errors name the source file
// and frame. Does not call writer.finish().
ConvertResult convert_frames(const FrameSource& source, std::optional<ParticleFrame> first, ContainerWriter& writer,
                             const EncodeOptions& options, size_t max_in_flight,
                             const std::function<void(const ConvertProgress&)>& on_frame = {});

}  // namespace sluice::io
