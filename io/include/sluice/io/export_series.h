// sluice/io/export_series.h: frames of a .sluice file written out one file
// each with export.h's writers, and a .pvd collection for a .vtp series:
// what `sluice export` and the Python module's sluice.export() do.
//
// Frames are decoded, thinned and written in parallel (TBB), a bounded
// number at a time (one per core, fewer for big frames); the progress
// callback and the .pvd follow frame order. Each file is written as
// `path`.partial and renamed when complete (export.h), and the .pvd last,
// so a series cut short never has an index that says it is whole.
//
// Threads: export_series() blocks its caller; the callback runs on one
// thread at a time, in frame order. Errors: io::Error naming the path or
// the frame; OutputsExist before anything is written.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "sluice/io/error.h"
#include "sluice/io/export.h"
#include "sluice/io/reader.h"

namespace sluice::io {

struct SeriesOptions {
  // The output: a file (one frame), a series name (several frames: out.vtp
  // -> out_00002.vtp ... by the file's frame numbers, and out.pvd), or a
  // printf pattern with one integer conversion (frames/shot_%04d.vtp; the
  // collection is then frames/shot.pvd). The extension picks the format.
  std::string out;
  std::vector<uint64_t> frames;         // file frame numbers, in the order written; empty: every frame
  float lod_level = 1;                  // the fraction kept by the stable LOD value (export.h: lod_keeps)
  std::vector<std::string> attributes;  // names; empty: every attribute of the file
  bool force = false;                   // replace outputs that exist
};

// Where each frame goes, and the .pvd that lists them (empty: none).
struct SeriesPlan {
  ExportFormat format = ExportFormat::Vtp;
  std::map<uint64_t, std::string> files;  // by frame number
  std::string pvd;
};
// Throws io::Error for an output whose extension names no format, or a
// pattern without exactly one integer conversion.
SeriesPlan plan_series(const std::string& out, std::span<const uint64_t> frames);

// Outputs that exist and were not to be replaced (SeriesOptions::force):
// `what()` names the first.
class OutputsExist : public Error {
 public:
  explicit OutputsExist(std::vector<std::string> paths);
  const std::vector<std::string>& paths() const noexcept { return paths_; }

 private:
  std::vector<std::string> paths_;
};

struct SeriesProgress {
  uint64_t frames_done = 0, frames = 0;
  uint64_t bytes_in = 0, bytes_out = 0;  // records read, files written
};

struct SeriesSummary {
  SeriesPlan plan;
  uint64_t frames = 0;
  uint64_t particles = 0, kept = 0;  // before and after the LOD level
  uint64_t bytes_in = 0, bytes_out = 0;
};

SeriesSummary export_series(const ContainerReader& reader, const SeriesOptions& options,
                            const std::function<void(const SeriesProgress&)>& progress = {});

}  // namespace sluice::io
