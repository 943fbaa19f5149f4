// sluice/import/convert.h: simulation output -> .sluice in one call, as
// `sluice convert` does it and as `play` and `render` do it for their cache.
//
// convert() opens the input (a file, glob, .pvd or directory), reads frame 0
// for the header (spacing, radius, id array, precision), decides the times
// (the input's own, a step given, or frame numbers) and the up axis (given,
// else the fall over the first frames, else pressure growing with depth,
// else a flat layer, else +z: io/up_axis.h), then reads, encodes and writes
// every frame in parallel (TBB, at most jobs + 1 frames in memory).
//
// Output: written to `output + ".partial"` and renamed to `output` when
// complete, so a run cut off never leaves a file that looks whole. One
// writer per output (io/writer.h): a second conversion into the same
// file stops with an error naming the first.
//
// Threads: convert() blocks its caller; the observer's functions run on one
// thread at a time (not necessarily the caller's), in frame order.
// Errors: io::Error naming the input (file and frame) on bad input or bad
// options; ConvertStopped when a frame could not be read or the output
// could not be written, after keeping what was converted.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "sluice/import/source.h"
#include "sluice/io/codec.h"
#include "sluice/import/isolation.h"
#include "sluice/error.h"
#include "sluice/io/format.h"
#include "sluice/io/narrow_band.h"

namespace sluice::import {

// A frame convert_frames() left out (ConvertOptions::skip_bad), and why.
struct SkippedFrame {
  uint64_t frame = 0;  // in the source
  std::string name;    // the source's name of the frame (its files)
  std::string error;   // the io::Error's full text
};

struct ConvertOptions {
  std::string input;  // file, glob, .pvd or directory
  // Point-data arrays carried for colouring, in this order ("rho", ...).
  std::vector<std::string> attributes;
  bool all_attributes = false;  // carry every point array of the first frame (up to io::kMaxAttributes)
  std::string id_array;         // empty: found (detect_id_array)
  bool no_ids = false;          // LOD values follow the particle order
  bool lossless = false;        // float32 positions instead of 16-bit quantized
  float spacing = 0, radius = 0;  // world units; 0: estimated (spacing), spacing / 2 (radius)
  // The largest position error, relative to the spacing, rounded down to a
  // power of two (io::FileHeader::precision_bits); 0: 1/1024.
  double precision = 0;
  // > 0: particles more than this many spacings outside the rest of their
  // frame are left out (noted); otherwise they are kept and noted.
  float drop_outliers = 0;
  double fps = 0;  // playback frames/s; also the time step 1/fps for inputs without times (0: unset)
  double dt = 0;   // seconds between frames for inputs without times (0: unset)
  std::optional<io::UpAxis> up;  // given: overrides detection
  uint32_t chunk = 65536;        // most particles per chunk
  int level = 3;                 // zstd level
  io::PlaneCoding planes = io::PlaneCoding::Packed;
  bool lod_tiers = true;  // chunks as LOD tiers (io::EncodeOptions::lod_tiers)
  // The container's major version: 3 (frames ordered coarse to fine,
  // positions in two parts), 2 (coarse to fine, positions whole) or 1
  // (format 1.5: each cell's tiers together, for readers older than 2.0).
  uint16_t format_major = io::kFormatMajor;
  // Classify the narrow band: surface, interior and blob layers (format
  // 1.3). Quantized positions only: lossless files stay one layer.
  bool layers = true;
  float band_voxel = 0;  // 0: twice the spacing
  io::F2Test band_f2 = io::F2Test::All;
  int jobs = 0;  // threads; 0: every core
  // A frame that cannot be read is left out and listed (otherwise the
  // conversion stops there, keeping the frames before it).
  bool skip_bad = false;
  IsolationPolicy isolation;
};

// What a note is about: callers that print notes may add their own advice
// (the sluice command names its flags).
enum class Notice : uint8_t {
  Repair,          // the reader repaired a frame (non-finite particles dropped, ...)
  FarParticles,    // a frame has particles far outside the rest
  FarTotal,        // how many far particles in how many frames, once at the end
  TimesGiven,      // the input states its own times: dt is not used
  NoTimes,         // the input states no times: frames are numbered
  UntimedFrames,   // some frames state no time while the others do
  NoIds,           // no id array found: LOD values follow the particle order
  RepeatedIds,     // the id array repeats ids: LOD values follow the particle order
  SpacingLater,    // frame 0 shows no spacing; a later frame's is used
  NoSpacing,       // no frame shows a spacing: the file states none
  Skipped,         // a frame that could not be read was left out (skip_bad)
  Up,              // the up axis found, and why
  UpGiven,         // the up axis given (ConvertOptions::up)
};

struct Note {
  Notice about;
  std::optional<uint64_t> frame;  // the input frame it is about, if one
  std::string text;               // a sentence, without the caller's advice
};

// Decided once frame 0 is read, before any other frame is.
struct ConvertPlan {
  const SourceInfo& source;
  uint64_t frames;                 // in the input
  const io::FileHeader& header;    // the up axis may still change
  bool spacing_given;
};

struct ConvertProgress {
  uint64_t frames_done = 0, frames = 0;     // input frames handled (written or skipped), of all
  uint64_t input_bytes = 0, output_bytes = 0;
};

struct ConvertObserver {
  std::function<void(const ConvertPlan&)> planned;
  std::function<void(const ConvertProgress&)> progressed;  // once per frame written
  std::function<void(const Note&)> noted;
};

struct ConvertSummary {
  uint64_t frames = 0, particles = 0, input_bytes = 0;  // frames written
  uint64_t far_particles = 0, far_frames = 0;          // far outside the rest (kept or dropped)
  std::vector<SkippedFrame> skipped;                  // with skip_bad
  std::chrono::duration<double> elapsed{};
  io::FileHeader header;  // as finally written
};

// The conversion stopped at a frame: `what()` is the frame's error. When
// the output could be finished it holds the frames before (`frames_kept`);
// when writing failed (disk full), `output_complete` is false and the
// `.partial` file holds what was written (io::recover_container rebuilds it).
class ConvertStopped : public io::Error {
 public:
  ConvertStopped(const io::Error& cause, std::string output, uint64_t frames_kept, bool output_complete);
  const std::string& output() const noexcept { return output_; }
  uint64_t frames_kept() const noexcept { return frames_kept_; }
  bool output_complete() const noexcept { return output_complete_; }

 private:
  std::string output_;
  uint64_t frames_kept_;
  bool output_complete_;
};

// Converts `options.input` into `output` (see the top of this file).
ConvertSummary convert(const ConvertOptions& options, const std::string& output, const ConvertObserver& observer = {});

// Playback frame rate when neither the input nor the caller gives one.
inline constexpr double kDefaultFrameRate = 30.0;

}  // namespace sluice::import
