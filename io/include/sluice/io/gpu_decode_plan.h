// sluice/io/gpu_decode_plan.h: what a GPU needs to decode a frame record's
// chunks itself (render/shaders/decode.comp), and the CPU's share of it.
//
// A chunk of a Quantized16 file is 8 + 2 x attributes byte planes (codec.h).
// The GPU decodes planes that are stored or bit-packed (packed_plane.h)
// straight from the record's bytes; planes compressed with zstd (which a
// GPU decodes badly: one entropy stream per plane) are inflated on the CPU
// into an area appended after the record ("the mixed rule"). The plan says,
// per chunk and plane, where the GPU finds it and how it is coded, after
// checking every size against the record, so that the GPU never reads
// outside the bytes it is given whatever the file holds.
//
// The encoded area a plan refers to: the record's bytes (as read: a prefix
// holding the chunks of the header, see keep_layers) at offset 0, then
// `inflated_bytes` of CPU-inflated planes at `inflated_offset`, then at
// least kGpuReadPadding bytes of anything (the GPU reads whole words).
//
// Plain functions over caller-owned memory; thread-safe.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "sluice/io/codec.h"
#include "sluice/error.h"
#include "sluice/io/format.h"

namespace sluice::io {

// Planes the GPU decodes per chunk: the 6 bytes of the Morton deltas, the
// LOD value's 2 bytes, the colour attribute's 2 delta bytes. Split
// positions (format 3.0): planes 0-1 the fine part's (the codes' low 16
// bits), 2-5 bytes 0-3 of the deltas of their high 32 bits.
inline constexpr int kGpuPlanes = 10;
// GpuChunkPlan::flags.
inline constexpr uint32_t kGpuWithAttribute = 1;  // planes 8 and 9 hold the colour attribute
inline constexpr uint32_t kGpuSplit = 2;          // positions split (format 3.0)
inline constexpr uint32_t kGpuFine = 4;           // ... and planes 0-1 hold the fine part; without: kCoarseFill
inline constexpr uint64_t kGpuReadPadding = 16;
// Particles per workgroup of the decoder (its tiles: 256 threads x 8).
inline constexpr uint32_t kGpuTile = 2048;

// One plane as the GPU reads it (std430, 16 bytes). Mirrored in decode.comp.
struct GpuPlane {
  uint32_t offset = 0;        // byte offset of the plane in the encoded area (packed: its width byte)
  uint32_t escapes = 0;       // packed: byte offset of its escape list
  uint32_t escape_count = 0;  // packed: escapes stored (the GPU checks the codes it finds against it)
  uint32_t width = 0;         // 0: stored (n bytes); 1..7: bit-packed at that width
};

// One chunk (std430, 176 bytes). Mirrored in decode.comp.
struct GpuChunkPlan {
  uint32_t first = 0;      // index of the chunk's first particle in the frame
  uint32_t count = 0;      // particles
  uint32_t flags = 0;      // kGpuWithAttribute, kGpuSplit, kGpuFine
  uint32_t first_tile = 0;      // the chunk's tiles (kGpuTile particles each) are first_tile, first_tile + 1, ...
  GpuPlane planes[kGpuPlanes];
};
static_assert(sizeof(GpuChunkPlan) == 176);

// Where one zstd plane goes: inflated on the CPU into the encoded area.
struct InflateJob {
  uint64_t source = 0;  // byte offset of the zstd frame in the record
  uint32_t size = 0;    // its bytes
  uint32_t plane_bytes = 0;  // what it must inflate to (the chunk's particle count)
  uint64_t target = 0;  // byte offset in the encoded area
  uint32_t chunk = 0;   // for errors
  uint32_t plane = 0;
};

struct GpuDecodePlan {
  std::vector<GpuChunkPlan> chunks;  // one per chunk of the header, in order
  std::vector<InflateJob> inflate;   // zstd planes, chunk by chunk
  std::vector<uint32_t> chunk_inflate;  // chunks + 1: chunk c's jobs are inflate[chunk_inflate[c], chunk_inflate[c + 1])
  uint64_t record_bytes = 0;         // bytes of the record the plan reads (a prefix of it)
  uint64_t inflated_offset = 0;      // record_bytes rounded up to 16
  uint64_t inflated_bytes = 0;       // the CPU-inflated planes
  uint64_t encoded_bytes() const { return inflated_offset + inflated_bytes + kGpuReadPadding; }
  std::vector<uint32_t> tile_chunk;  // per tile of the frame: its chunk
  // Where the chunk plans and the tiles' chunks go when they travel with
  // the encoded area (one buffer: the area, the plans, the tile table), and
  // that buffer's size.
  uint64_t plans_offset() const { return (encoded_bytes() + 15) & ~uint64_t(15); }
  uint64_t tiles_offset() const { return plans_offset() + chunks.size() * sizeof(GpuChunkPlan); }
  uint64_t staged_bytes() const { return tiles_offset() + tile_chunk.size() * 4; }
  // Planes by how they reach the GPU (statistics, bench).
  uint64_t stored_planes = 0, packed_planes = 0, zstd_planes = 0;
};

// An upper bound of GpuDecodePlan::staged_bytes() for a record of
// `record_bytes` holding `chunks` chunks of `particles` in all, of whose
// planes `inflated_bytes` are inflated on the CPU (each rounded up to 16):
// the area can be sized before the record's tables are read.
inline uint64_t staged_bytes_bound(uint64_t record_bytes, uint64_t chunks, uint64_t particles, uint64_t inflated_bytes) {
  return record_bytes + 15 + inflated_bytes + kGpuReadPadding + 15 + chunks * sizeof(GpuChunkPlan) +
         4 * (particles / kGpuTile + chunks);
}

struct GpuPlanOptions {
  int color_attribute = -1;  // attribute index decoded into planes 8-9; < 0: none
};

// Whether files with this header can be decoded on the GPU (Quantized16
// positions; Float32 positions are decoded on the CPU).
bool gpu_decodable(const FileHeader& file);

// Reads the plane tables of `header`'s chunks in `record` (possibly cut to
// some layers) and builds the plan into `plan` (reusing its memory): a few
// bytes per plane, no checksums (stage_chunk checks them). Throws io::Error
// at `where` (chunk filled in) on any inconsistency: a plane beyond its
// payload, a packed width outside 1..7, a packed plane shorter than its
// values, trailing bytes, a record of 4 GiB or more (the GPU's offsets are
// 32-bit: such frames are decoded on the CPU).
void plan_gpu_decode(std::span<const std::byte> record, const FrameHeader& header, const FileHeader& file,
                     const GpuPlanOptions& options, GpuDecodePlan& plan, const ErrorLocation& where);

// The same plan in steps, for a reader that plans each chunk as it brings
// it in (runtime's pieces relayed to device memory) and no longer holds
// the record afterwards. plan_gpu_frame() lays out the frame from `header`
// alone: every chunk's first particle and tiles, record_bytes, no planes
// yet and nothing inflated. plan_gpu_chunk() then reads chunk c's plane
// table from its `payload` (the chunk's compressed_size bytes; chunks may
// be planned from different threads at once) and returns false, leaving
// the chunk's planes unfinished, if a plane is zstd: such a frame needs
// plan_gpu_decode() over the whole record (its planes are inflated into the
// area). finish_gpu_plan() counts the planes once every chunk is planned.
// Errors as plan_gpu_decode().
void plan_gpu_frame(const FrameHeader& header, const FileHeader& file, const GpuPlanOptions& options, GpuDecodePlan& plan,
                    const ErrorLocation& where);
bool plan_gpu_chunk(std::span<const std::byte> payload, const FrameHeader& header, const FileHeader& file,
                    const GpuPlanOptions& options, size_t c, GpuDecodePlan& plan, const ErrorLocation& where);
// The same for chunk c's fine part (format 3.0; GPU planes 0-1), from its
// `payload` (fine.size bytes); a chunk's record and fine part may be
// planned from different threads at once.
bool plan_gpu_fine(std::span<const std::byte> payload, const FrameHeader& header, size_t c, GpuDecodePlan& plan,
                   const ErrorLocation& where);
void finish_gpu_plan(GpuDecodePlan& plan);

// The CPU's share of chunk `c`: checks its checksum (when `verify`), copies
// its payload to the same offset of `encoded` (unless `record` already is
// encoded's prefix) and inflates its zstd planes there. `encoded` holds at
// least plan.encoded_bytes() bytes. Throws io::Error at `where` (chunk
// filled in). Chunks may be staged from different threads at once.
void stage_chunk(std::span<const std::byte> record, const FrameHeader& header, const GpuDecodePlan& plan, size_t c,
                 std::span<std::byte> encoded, bool verify, const ErrorLocation& where);

// Every chunk (TBB, in parallel), then the plans and the tile table
// (write_tables) when `encoded` has room for them (staged_bytes()).
void stage_frame(std::span<const std::byte> record, const FrameHeader& header, const GpuDecodePlan& plan,
                 std::span<std::byte> encoded, bool verify, const ErrorLocation& where);

// Writes the chunk plans and the tile table at their offsets of `staged`
// (staged_bytes() bytes).
void write_tables(const GpuDecodePlan& plan, std::span<std::byte> staged);

// The chunk plans and then the tile table, from the start of `out` (at
// least table_block_bytes()): the tables alone, for an area that lives
// elsewhere (they belong at plans_offset() of it).
inline uint64_t table_block_bytes(const GpuDecodePlan& plan) {
  return plan.chunks.size() * sizeof(GpuChunkPlan) + plan.tile_chunk.size() * 4;
}
void write_table_block(const GpuDecodePlan& plan, std::span<std::byte> out);

}  // namespace sluice::io
