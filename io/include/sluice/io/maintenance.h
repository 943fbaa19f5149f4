// sluice/io/maintenance.h: checking a `.sluice` file, rebuilding one that
// was cut short, and rewriting one in another layout.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "sluice/io/codec.h"
#include "sluice/io/reader.h"

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

// Relayout: a `.sluice` file rewritten in another layout
// (`sluice convert old.sluice -o new.sluice`): a format 1.x file as 2.0
// (frames ordered coarse to fine), or back to 1.5 for older readers.
//
// Each frame's particles (surface and interior, with their LOD values and
// attributes) are decoded and encoded again for the new layout: the narrow
// band, its blobs, the cells and the tiers are rebuilt as `sluice convert`
// builds them from solver output. The header (spacing, radius, precision,
// up axis, times, attributes, LOD source) is kept but for the version.
// Float32 positions come through bit for bit. Quantized positions are
// quantized again in the new cells: each within the file's stated bound of
// the position the input held, so within twice that bound of the solver's
// (docs/format.md, "Rewriting a file in another layout").
//
// Output: written to `output + ".partial"` under an io::OutputLock and
// renamed to `output` when whole, so a run cut off never leaves a file that
// looks whole.
// Threads: blocks its caller; frames are decoded and encoded on TBB workers,
// `progress` is called from one thread at a time, in frame order.
// Errors: io::Error naming the input's file, frame and chunk on damage (no
// output is left), or the output on a write failure.

struct RelayoutOptions {
  uint16_t format_major = kFormatMajor;  // 3, 2, or 1 (format 1.5)
  // How planes are coded; unset: as the input's first frame (GpuDecodable
  // when every chunk of it decodes on the GPU, else Packed).
  std::optional<PlaneCoding> planes;
  uint32_t chunk_particles = 65536;
  int zstd_level = 3;
};

struct RelayoutReport {
  uint64_t frames = 0, particles = 0;
  uint64_t input_bytes = 0, output_bytes = 0;  // the files' sizes
  EncodeOptions encode;                        // as used (layers and tiers follow the input)
};

// The encoding `input` was written with, as far as its first frame shows:
// layers (and the blobs' voxel), LOD tiers, plane coding (see
// RelayoutOptions::planes). `options` supplies the rest.
EncodeOptions encoding_of(const ContainerReader& input, const RelayoutOptions& options);

// Rewrites every frame of `input` into `output` (which must differ from it)
// with options.format_major's layout. See "Relayout" above.
RelayoutReport relayout_container(const std::filesystem::path& input, const std::filesystem::path& output,
                                  const RelayoutOptions& options, const ProgressFn& progress = {});

}  // namespace sluice::io
