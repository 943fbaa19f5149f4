// sluice/io/relayout.h: a `.sluice` file rewritten in another layout
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
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>

#include "sluice/io/codec.h"
#include "sluice/io/maintenance.h"
#include "sluice/io/reader.h"

namespace sluice::io {

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
// with options.format_major's layout. See the file comment.
RelayoutReport relayout_container(const std::filesystem::path& input, const std::filesystem::path& output,
                                  const RelayoutOptions& options, const ProgressFn& progress = {});

}  // namespace sluice::io
