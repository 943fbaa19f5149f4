// sluice/runtime/particle_stream.h: the frames of a sequence in order
// through the prefetch pipeline (read and decoded ahead on worker threads,
// the window sized from memory), each converted to world-unit arrays
// (io/particles.h) by the workers as they decode (DecodeMode::World). What
// the Python module's `for frame in seq` and the ParaView reader's
// animation use.
//
// Ownership: shares the reader, so a stream may outlive whoever opened it.
// Threads: one thread at a time calls the members (the pipeline's consumer
// rule).
#pragma once

#include <cstdint>
#include <memory>
#include <optional>

#include "sluice/io/particles.h"
#include "sluice/io/reader.h"
#include "sluice/runtime/frame_allocator.h"
#include "sluice/runtime/pipeline.h"

namespace sluice::runtime {

struct StreamRange {
  uint64_t start = 0, stop = 0;  // frames [start, stop)
  uint32_t step = 1;
  // After the last frame, go round again from frame 0 (the first `stop`
  // frames, over and over): the stream never ends.
  bool loop = false;
};

struct StreamedFrame {
  uint64_t index = 0;  // frame number in the file
  io::ParticleArrays arrays;
};

// A frame whose arrays lie in the pipeline's buffer, lent without a copy:
// valid while `handle` holds that buffer. Give it back (handle.reset(), or
// destroy it) on the stream's thread, before the stream is destroyed.
struct LentFrame {
  uint64_t index = 0;  // frame number in the file
  double time = 0;     // seconds
  io::ParticleSpans arrays;
  FrameHandle handle;
};

class ParticleStream {
 public:
  // Shares the reader (a stream outlives the sequence it came from).
  // `memory_cap`: bytes the window may hold (0: half the available memory);
  // `max_frames`: frames it may hold (0: as many as fit).
  ParticleStream(std::shared_ptr<const io::ContainerReader> reader, StreamRange range, io::ParticleQuery query,
                 uint64_t memory_cap, uint32_t max_frames = 0);
  ~ParticleStream();
  ParticleStream(const ParticleStream&) = delete;
  ParticleStream& operator=(const ParticleStream&) = delete;

  // The next frame as arrays of its own (a copy of next_lent()'s), or
  // nullopt after the last. Throws io::Error (the frame's, naming file,
  // frame and chunk) when a frame cannot be read. `reuse`: arrays of an
  // earlier frame the caller is done with, whose memory the copy takes over.
  std::optional<StreamedFrame> next(io::ParticleArrays reuse = {});
  // As next(), the arrays lent in place (no copy). The caller may hold up to
  // most_lent() lent frames while it asks for the next; holding more makes
  // the pipeline's wait_next() throw (it could never read ahead).
  std::optional<LentFrame> next_lent();
  uint32_t most_lent() const;
  uint64_t remaining() const;  // UINT64_MAX for a loop
  // The frame next() returns next (meaningless once remaining() is 0).
  uint64_t next_frame() const { return range_.start + taken_ * range_.step; }
  uint32_t window_frames() const;  // the prefetch window as planned
  // The pipeline's figures (bytes read against the records' bytes, ...);
  // empty before the first frame of an empty range. Any thread.
  PipelineStats stats() const;

 private:
  std::shared_ptr<const io::ContainerReader> reader_;
  StreamRange range_;
  io::ParticleQuery query_;
  HostFrameAllocator allocator_;
  std::unique_ptr<Pipeline> pipeline_;
  uint64_t taken_ = 0, count_ = 0;
};

}  // namespace sluice::runtime
