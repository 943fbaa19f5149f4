// The frames of a sequence in order through the runtime's prefetch pipeline
// (reads and decodes ahead on worker threads, window sized from memory),
// each converted to world-unit arrays. What `for frame in seq` uses.
//
// Threads: one caller at a time (the pipeline's consumer rule); next() may
// run without the Python GIL.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>

#include "sluice/io/particles.h"
#include "sluice/io/reader.h"
#include "sluice/runtime/frame_allocator.h"
#include "sluice/runtime/pipeline.h"

namespace sluice::python {

struct StreamRange {
  uint64_t start = 0, stop = 0;  // frames [start, stop)
  uint32_t step = 1;
};

struct StreamedFrame {
  uint64_t index = 0;  // frame number in the file
  io::ParticleArrays arrays;
};

class FrameStream {
 public:
  // Shares the reader (a stream outlives the sequence it came from).
  // `memory_cap`: bytes the window may hold (0: half the available memory).
  FrameStream(std::shared_ptr<const io::ContainerReader> reader, StreamRange range, io::ParticleQuery query,
              uint64_t memory_cap);
  ~FrameStream();
  FrameStream(const FrameStream&) = delete;
  FrameStream& operator=(const FrameStream&) = delete;

  // The next frame, or nullopt after the last. Throws io::Error (the
  // frame's, naming file, frame and chunk) when a frame cannot be read.
  std::optional<StreamedFrame> next();
  uint64_t remaining() const;
  uint32_t window_frames() const;  // the prefetch window as planned

 private:
  std::shared_ptr<const io::ContainerReader> reader_;
  StreamRange range_;
  io::ParticleQuery query_;
  runtime::HostFrameAllocator allocator_;
  std::unique_ptr<runtime::Pipeline> pipeline_;
  uint64_t taken_ = 0, count_ = 0;
};

}  // namespace sluice::python
