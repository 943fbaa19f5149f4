// The steps of a conversion shared by the serial converter (convert.cpp)
// and the MPI one (convert_mpi.cpp), so both decide and tell the same:
//   prepare_conversion  the decisions before the frames: header, times,
//                       spacing, provisional up axis (reads frame 0);
//   FrameTally          what the written frames tell, in frame order:
//                       notes, progress, the shapes that decide the up axis;
//   tell_totals, settle_up   the notes and the up axis once frames end.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include "sluice/import/convert.h"
#include "sluice/import/frames.h"

namespace sluice::import {

// The input as the conversion reads it: its source, frame `from` (the first
// that reads) and the frames skipped before it.
struct Opened {
  std::unique_ptr<FrameSource> source;
  SourceOptions options;
  std::optional<io::ParticleFrame> first;
  uint64_t from = 0;
  std::vector<SkippedFrame> skipped;
};

struct Prepared {
  Opened in;
  io::FileHeader header;      // the up axis provisional (provisional_up)
  FramesSettings settings;
  io::FrameShape first_shape;  // of the first frame with particles (extent only)
};

// Opens the input as a conversion reads it (the options' id array and
// attributes, every array with all_attributes); sets `options` to what it
// was opened with. Throws io::Error (also for an input without frames).
std::unique_ptr<FrameSource> open_source(const ConvertOptions& o, SourceOptions& options);

// Opens the input and decides what the frames are encoded with. Tells the
// observer the plan and the notes about the whole input. Throws io::Error.
Prepared prepare_conversion(const ConvertOptions& o, const ConvertObserver& observer);

// What every frame is encoded with: from the options, the header and the
// box of the first frame with particles (the up axis's shape grid).
FramesSettings frames_settings(const ConvertOptions& o, const io::FileHeader& header, const io::Aabb& shape_box);

// The header changed while frames are written (the up axis): rewrite it.
using HeaderChanged = std::function<void(const io::FileHeader&)>;

// What the frames tell as they are written: notes, progress, the shapes
// that decide the up axis, and the header's up axis once the first frames
// show a fall (so a file cut short, and recovered, keeps it). Called once
// per frame written, in frame order, on one thread at a time.
class FrameTally {
 public:
  // `bytes_written`: the output's size so far, for progress.
  FrameTally(const ConvertOptions& o, const Opened& in, io::FileHeader& header, const FramesSettings& settings,
             const ConvertObserver& observer, HeaderChanged header_changed, std::function<uint64_t()> bytes_written);
  void operator()(const FrameConverted& p);

  uint64_t far_particles = 0, far_frames = 0, untimed = 0;
  std::vector<io::FrameShape> first_frames;
  io::FrameShape last_shape;

 private:
  const ConvertOptions& o_;
  const Opened& in_;
  io::FileHeader& header_;
  const FramesSettings& settings_;
  const ConvertObserver& observer_;
  HeaderChanged header_changed_;
  std::function<uint64_t()> bytes_written_;
  bool early_up_ = false;
  uint64_t input_bytes_ = 0;
};

// The notes counted over the frames, once at the end.
void tell_totals(const ConvertOptions& o, const FrameTally& tally, const std::vector<SkippedFrame>& skipped,
                 const ConvertObserver& observer);

// The up axis once every frame is written: given, or found from the first
// frames' fall, the pressure at the end, the shape at the end, else +z
// (io/up_axis.h). Sets it in `header` and tells `header_changed`.
void settle_up(const ConvertOptions& o, const Opened& in, const FrameTally& tally, const io::FrameShape& first_shape,
               io::FileHeader& header, const HeaderChanged& header_changed, const ConvertObserver& observer);

}  // namespace sluice::import
