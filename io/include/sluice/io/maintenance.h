// sluice/io/maintenance.h: checking a `.sluice` file and rebuilding one that
// was cut short.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>


namespace sluice::io {

// Called with (frames done, frames total) as work progresses.
using ProgressFn = std::function<void(uint64_t, uint64_t)>;

struct VerifyReport {
  uint64_t frames = 0;
  uint64_t chunks = 0;
  uint64_t particles = 0;  // layers all, surface and interior
  uint64_t blobs = 0;      // voxel blobs (layer 3), not particles
  uint64_t bytes = 0;
  // The file's position bound (position_bound(): 0 lossless, infinity not
  // stated), checked against every chunk's box.
  float position_bound = 0;
  std::vector<std::string> problems;  // each names file, frame and chunk
  bool ok() const { return problems.empty(); }
};

// Checks every checksum (header, index, frame tables, chunks), that every
// chunk's box is narrow enough for the file's position bound, and decodes
// every chunk. Does not stop at the first problem. Throws io::Error only when
// the file cannot be opened at all (bad header, no index).
VerifyReport verify_container(const std::filesystem::path& path, const ProgressFn& progress = {});

struct RecoveryReport {
  uint64_t frames = 0;         // frames kept
  uint64_t bytes_kept = 0;     // of the kept frames' records
  uint64_t bytes_dropped = 0;  // of the input's other bytes but the header (damaged frames, old index and footer)
  std::vector<std::string> dropped;  // each damaged frame left out, with its error and byte range
  bool header_rebuilt = false;       // the header was damaged and its copy used
  std::string stopped_because;       // why the scan ended ("end of file" when it read to the end)
};

// Scans the frame records that follow the header and keeps every complete
// frame whose checksums hold: past a damaged frame the scan goes on at the
// next record that checks out (frames after it are renumbered to close the
// gap, their times kept). A damaged header is rebuilt from the copy format
// 1.5 writers put after it. The result goes to `output` through
// `output.recovering`, renamed when whole; with `output` equal to `input`
// and nothing dropped, the tail is cut and the index appended in place.
// Throws io::Error when neither the header nor its copy is readable.
RecoveryReport recover_container(const std::filesystem::path& input, const std::filesystem::path& output,
                                 const ProgressFn& progress = {});

}  // namespace sluice::io
