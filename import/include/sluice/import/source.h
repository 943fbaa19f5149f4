// sluice/import/source.h: reading simulation output into ParticleFrames.
//
// A FrameSource is an ordered sequence of frames opened from what the user
// typed: a single file, a `.pvd` series, a numbered series given as a glob
// (`out/fluid_*.vtu`, natural sort), or a directory. VTK formats go through
// VTK's own readers (only when sluice is built with VTK); CSV and XYZ are read
// by sluice itself.
//
// Threads: `read()` may be called concurrently from several threads for
// different frames; each call opens its own reader.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "sluice/io/types.h"

namespace sluice::import {

struct SourceOptions {
  // Point-data arrays to carry as attribute streams, in this order ("rho",
  // "velocity", ...). A vector array is stored as its magnitude.
  std::vector<std::string> attributes;
  // Name of the particle id array; empty: auto-detect (see detect_id_array).
  std::string id_array;
  // Disable id detection: LOD values then come from the particle order.
  bool no_ids = false;
};

// What a source knows before any frame is read.
struct SourceInfo {
  std::string description;          // e.g. "24 files matching out/fluid_*.vtu (VTK XML unstructured grid)"
  std::string id_array;             // the id array in use, empty if none
  std::vector<std::string> arrays;  // point-data arrays present in the first frame
  // Frames are read by a third-party reader (VTK's XML readers), which trusts
  // the file beyond what sluice checks first: a damaged file may still crash
  // or hang it. Callers that must survive that read such frames in a child
  // process (as `sluice convert` does). Legacy VTK, CSV and XYZ are read by
  // sluice's own checked readers.
  bool third_party_reader = false;
};

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  virtual uint64_t frame_count() const = 0;
  virtual const SourceInfo& info() const = 0;
  // The file (or file:piece) frame `i` comes from, for messages.
  virtual std::string frame_name(uint64_t i) const = 0;
  // Reads frame `i`. Throws io::Error naming the file and frame on bad input.
  // Repairs (dropped non-finite particles, ...) are listed in `repairs`.
  virtual io::ParticleFrame read(uint64_t i) const = 0;
};

// Opens `spec` (file, glob, .pvd, directory). Throws io::Error with advice if
// nothing matches or the format is not supported in this build.
std::unique_ptr<FrameSource> open_source(const std::string& spec, const SourceOptions& options);

// Picks the id array among `arrays`: the first of id, ids, Id, ID, Idp, idp,
// gid, particle_id, ParticleId, ParticleID, particleId that is present.
// Returns "" if none.
std::string detect_id_array(const std::vector<std::string>& arrays);

// Expands a glob into files sorted naturally (frame_2 before frame_10).
std::vector<std::string> expand_glob_natural(const std::string& pattern);

// Natural ordering of strings: digit runs compare as numbers.
bool natural_less(const std::string& a, const std::string& b);

}  // namespace sluice::import
