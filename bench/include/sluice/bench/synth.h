// sluice/bench/synth.h: synthetic fluid sequences for scale runs.
//
// Frames are generated on the fly (nothing is read), encoded in parallel and
// written in order, with a bounded number of frames in memory, by the same
// pipeline as `sluice convert`. Particles keep their id from frame to frame,
// so LOD values are stable and the data compresses like real solver output
// (jittered, not a perfect lattice).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "sluice/io/codec.h"
#include "sluice/io/format.h"
#include "sluice/import/source.h"

namespace sluice::bench {

enum class SynthMotion {
  Slosh,    // a block of water sloshing in a tank (first standing-wave mode)
  Lattice,  // a jittered lattice drifting through space
};

struct SynthOptions {
  uint64_t particles = 1'000'000;
  uint64_t frames = 100;
  std::string output;                  // .sluice path (written as OUTPUT.partial, renamed when done)
  SynthMotion motion = SynthMotion::Slosh;
  float frame_rate = 30.f;
  float spacing = 0.01f;               // rest spacing, world units
  bool speed_attribute = false;        // add a "speed" attribute stream
  bool lossless = false;               // float32 positions instead of 16-bit quantized
  uint32_t chunk_particles = 65536;
  int zstd_level = 1;
  io::PlaneCoding planes = io::PlaneCoding::Packed;  // EncodeOptions::planes
  bool lod_tiers = true;               // chunks written as LOD tiers (EncodeOptions::lod_tiers)
  uint16_t format_major = io::kFormatMajor;  // 3: coarse to fine, positions in two parts; 2: coarse to fine; 1: format 1.5 (io::set_format_version)
  // The file's position bound, spacing x 2^-precision_bits (io::FileHeader).
  uint8_t precision_bits = io::kDefaultPrecisionBits;
  bool layers = true;                  // narrow band: surface, blob and interior chunks (EncodeOptions::layers)
  int jobs = 0;                        // frames encoded at once; 0: one per core
  uint32_t seed = 1;
};

// The sequence as a FrameSource (read(i) may be called from several threads).
std::unique_ptr<import::FrameSource> synthetic_source(const SynthOptions& options);

struct SynthResult {
  uint64_t frames = 0;
  uint64_t particles = 0;  // in all frames
  uint64_t bytes = 0;      // of the file written
};

// Writes the file. `on_frame(frames_done, bytes_written)` runs in frame order
// on one thread at a time. Throws io::Error.
SynthResult write_synthetic(const SynthOptions& options,
                            const std::function<void(uint64_t frames_done, uint64_t bytes_written)>& on_frame = {});

}  // namespace sluice::bench
