// Frames read while the conversion is still deciding how to encode them.
//
// Rank 0 of an MPI conversion, and the serial converter, read frame 0 (and
// more) and decide the header before any other frame is encoded: seconds for
// frames of 10M particles, during which the other cores (or ranks) would
// wait. A ReadAhead opens the input itself, as a conversion opens it
// (open_source), and reads frames [first, first + count) meanwhile; take()
// hands them over once the decisions are made.
//
// The reads run on threads of their own, one a frame, not on TBB's: a
// conversion of one thread (--jobs 1, an MPI rank's usual share) has no
// TBB thread to spare while it decides, and a VTK frame's parsing happens
// in a reader process (isolation.h), so these threads mostly wait.
//
// A frame that fails to read is left out (the conversion reads it again in
// its turn, where the error counts). Threads: construct, take and destroy
// on one thread. Errors: none thrown (an input that does not open reads
// nothing here).
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <thread>
#include <vector>

#include "sluice/import/convert.h"

namespace sluice::import {

class ReadAhead {
 public:
  ReadAhead(const ConvertOptions& o, uint64_t first, uint64_t count);
  ~ReadAhead();  // waits for the reads
  // Waits for the reads.
  void finish();
  ReadAhead(const ReadAhead&) = delete;
  ReadAhead& operator=(const ReadAhead&) = delete;

  struct Taken {
    std::map<uint64_t, io::ParticleFrame> frames;  // by frame index
    // The source they were read from, when `used` is what it was opened
    // with (a caller that needs one need not open the input again). Drop it
    // otherwise: its reader processes (isolation.h) hold memory.
    std::unique_ptr<FrameSource> source;
  };
  // Waits for the reads and hands over the frames read as `used` (the
  // options the conversion opened the input with) reads them: when `used`
  // drops the ids (they repeat), theirs are dropped too; when it differs
  // otherwise, none are handed over. Once only.
  Taken take(const SourceOptions& used);

 private:
  SourceOptions options_;
  std::unique_ptr<FrameSource> source_;
  uint64_t first_ = 0;
  std::vector<std::optional<io::ParticleFrame>> frames_;
  std::vector<std::thread> reads_;  // last: joined before the frames they fill die
};

}  // namespace sluice::import
