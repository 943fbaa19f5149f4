// sluice/io/codec.h: encoding frames into container records and decoding
// chunks out of them. Pure functions over caller-owned memory: the runtime
// decodes straight into buffers it was handed (e.g. mapped staging memory).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "sluice/error.h"
#include "sluice/io/format.h"
#include "sluice/io/narrow_band.h"
#include "sluice/io/point_set.h"

namespace sluice::io {

// How a chunk's byte planes are coded.
enum class PlaneCoding : uint8_t {
  // Bit-packed where values are small, unless zstd saves a third over
  // packing: decoding 1.4-2x faster for 1-2% more bytes (docs/format.md).
  Packed,
  // zstd wherever it is smaller (`convert --smallest`; files readable by
  // format 1.0 readers).
  Zstd,
  // No plane zstd, each stored or bit-packed: every chunk decodes on the GPU
  // (gpu_decode_plan.h) with no CPU work but the checksum (`convert
  // --gpu-decodable`; the size cost is in docs/format.md).
  GpuDecodable,
  // Every chunk's planes stored as they are (ChunkCodec::Stored, 8 bytes
  // per quantized particle): the fastest to encode and to decode, for
  // frames that are decoded at once and not kept (live frames not recorded).
  Stored,
};

struct EncodeOptions {
  uint32_t chunk_particles = 65536;  // upper bound per chunk; chunks follow octree cells
  int zstd_level = 3;                // 1 (fast) .. 19 (small); decode speed barely changes
  PlaneCoding planes = PlaneCoding::Packed;
  // Classify the narrow band (narrow_band.h) and write the frame as surface
  // chunks, voxel-blob chunks and interior chunks, payloads in that order
  // (format 1.3), so a reader of the surface and blobs reads a prefix of the
  // record. Needs the header's particle spacing (> 0); without it, or for
  // float32 positions, the frame is written as one layer (All).
  bool layers = false;
  // Write each chunk of particles as LOD tiers (format 1.4, lod.h): one
  // record per tier, tier 0 first, all with the chunk's box, so a reader
  // reads only the tiers a view keeps. Tiers under 1,024 particles join the
  // next; a cell whose tiers would take over 8% more bytes (lattice-like
  // data) stays one record. Blob chunks are tiered by their random term
  // (io::blob_lod_uniform_bound: their LOD value is a count). Frames not
  // compressed stay one record per chunk. false: one record per chunk, as
  // format 1.3.
  bool lod_tiers = true;
  float band_voxel = 0;  // voxel side d of the classification and the blobs; 0: twice the particle spacing
  F2Test band_f2 = F2Test::All;  // which particles of a selected L2 voxel are surface (narrow_band.h)
};

// One frame to encode. Spans are borrowed for the duration of the call.
struct FrameInput {
  std::span<const float> positions;                 // x,y,z interleaved; finite
  std::span<const uint16_t> lod;                    // one per particle (see lod.h)
  std::vector<std::span<const float>> attributes;   // one span per header attribute, finite
  double time = 0.0;
};

// A complete frame record, ready to append to a container.
struct EncodedFrame {
  FrameHeader header;             // frame_number is patched by the writer
  std::vector<std::byte> record;  // header, chunk table, payloads
  uint64_t raw_bytes = 0;         // filtered size before zstd, for statistics
  // Particles far outside the rest (point_set.h): in chunks of their own,
  // outside header.bounds.
  FarReport far;
};

// Chunks, quantizes, filters and compresses one frame. Parallel over chunks
// (TBB); thread-safe. Throws io::Error if the input is inconsistent.
EncodedFrame encode_frame(const FrameInput& input, const FileHeader& header, const EncodeOptions& options);

// Rewrites the frame number of an encoded record in place (and its checksum).
void set_frame_number(EncodedFrame& frame, uint32_t frame_number, size_t attribute_count);

// Per-thread reusable decode state (zstd context and a scratch buffer).
// Not thread-safe: use one per thread.
class DecodeScratch {
 public:
  DecodeScratch();
  ~DecodeScratch();
  DecodeScratch(const DecodeScratch&) = delete;
  DecodeScratch& operator=(const DecodeScratch&) = delete;
  struct State;
  State& state() { return *state_; }

 private:
  std::unique_ptr<State> state_;
};

// Where decode_chunk writes one chunk.
struct ChunkDestination {
  // particle_count * decoded_particle_bytes(coding) bytes, see format.h.
  std::span<std::byte> particles;
  // One array of particle_count values per attribute, quantized against the
  // chunk's attribute range; may be empty to skip attributes.
  std::span<uint16_t* const> attributes;
};

// Checks the chunk's checksum, decompresses (never beyond the size its
// particle count implies) and unfilters into `out`. `record` is the whole
// frame record the chunk belongs to. Throws io::Error at `where` (with the
// chunk number filled in by the caller) on any inconsistency.
void decode_chunk(std::span<const std::byte> record, const ChunkDesc& chunk, const FileHeader& header,
                  const ChunkDestination& out, DecodeScratch& scratch, const ErrorLocation& where);

// The first particle of each chunk of a frame (the running sum of the
// chunks' counts) into `out`, which has one entry per chunk. Returns the total.
uint64_t chunk_starts(const FrameHeader& header, std::span<uint64_t> out);

// Decodes every chunk of a frame record in parallel (TBB) into the frame's
// layout: chunk c's particles at particles[starts[c] * stride] and, for each
// attribute a whose base pointer is non-null, its values at attributes[a] +
// starts[c]. `particles` holds particle_count * decoded_particle_bytes()
// bytes; `starts` comes from chunk_starts(). Throws io::Error at `where` with
// the chunk filled in (the first failure wins).
void decode_record(std::span<const std::byte> record, const FrameHeader& header, const FileHeader& file,
                   std::span<const uint64_t> starts, std::span<std::byte> particles, std::span<uint16_t* const> attributes,
                   const ErrorLocation& where);

// World position of a quantized coordinate, exactly as the GPU computes it.
inline float dequantize(uint16_t q, float lo, float hi) {
  return lo + float(q) * ((hi - lo) * (1.0f / 65535.0f));
}

}  // namespace sluice::io
