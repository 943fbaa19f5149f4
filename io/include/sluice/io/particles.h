// sluice/io/particles.h: one frame's particles as plain arrays in world
// units, reading only what a LOD level keeps: for scripts (the Python
// module), readers in other tools (the ParaView plugin) and exports.
//
// A LOD level keeps the same particles in every frame (the stable LOD value,
// lod.h): level L keeps a particle when export.h's lod_keeps(value, L), the
// renderer's rule at importance 1. Of each cell only the tiers that can hold
// a kept particle are read (lod.h, "LOD tiers"), so reading at level 0.1
// reads about a tenth of the frame's particle bytes.
//
// Threads: plain functions; concurrent calls are safe (the reader's reads
// are). Decoding and conversion run on TBB workers.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "sluice/io/format.h"
#include "sluice/io/reader.h"

namespace sluice::io {

struct ParticleQuery {
  // Layers to read (format 1.3): every particle, or the surface and the
  // blobs standing in for the interior. Unlayered files hold All chunks,
  // in every set.
  LayerSet layers = LayerSet::particles();
  // The fraction kept by the stable LOD value, in (0, 1]; 1 keeps every
  // particle. Blobs are kept by their own random term (blob_lod_uniform of
  // their cell) against the same level.
  float lod_level = 1;
  // Attributes to convert: indices into the file header's list, in the
  // order the arrays are wanted.
  std::vector<size_t> attributes;
};

// A frame's particles in decoded order (chunk by chunk).
struct ParticleArrays {
  std::vector<float> positions;                // x,y,z interleaved, world units
  std::vector<uint16_t> lod;                   // stable LOD value (blobs: their particle count)
  std::vector<uint8_t> layer;                  // io::Layer of each particle
  std::vector<std::vector<float>> attributes;  // per ParticleQuery::attributes entry, in attribute units
  double time = 0;                             // seconds (FrameHeader::time)
  uint64_t bytes_read = 0;                     // of the frame's record (0: converted from buffers already decoded)

  uint64_t count() const { return lod.size(); }
};

// Reads frame `frame` (its table, then only the wanted layers' and tiers'
// payloads) and converts it. Throws io::Error naming the file, frame and
// chunk on damage, and on an attribute index or level out of range.
ParticleArrays read_particles(const ContainerReader& reader, uint64_t frame, const ParticleQuery& query);

// What read_particles() reads and decodes into before converting: kept
// between calls, a reader of frame after frame allocates (and faults in)
// nothing once it has held the largest frame. One per thread.
struct ParticleScratch {
  std::unique_ptr<std::byte[]> record;
  uint64_t record_bytes = 0;
  std::unique_ptr<std::byte[]> decoded;
  uint64_t decoded_bytes = 0;
  std::vector<std::vector<uint16_t>> streams;
};
// The same into `out`, reusing its vectors' memory (a caller reading frame
// after frame hands back the last frame's arrays, so no page is faulted in
// or cleared again while sizes stay alike), with `scratch`.
void read_particles(const ContainerReader& reader, uint64_t frame, const ParticleQuery& query, ParticleArrays& out,
                    ParticleScratch& scratch);

// A frame's particles in world units in memory someone else owns (a
// pipeline's frame buffer, the vectors of a ParticleArrays): `count`
// particles; arrays as in ParticleArrays.
struct ParticleSpans {
  float* positions = nullptr;      // x,y,z interleaved
  uint16_t* lod = nullptr;
  uint8_t* layer = nullptr;
  std::vector<float*> attributes;  // per ParticleQuery::attributes entry
  uint64_t count = 0;
};

// Bytes per particle of a frame laid out in one block by world_spans().
uint64_t world_particle_bytes(size_t attributes);
// The arrays of `count` particles with `attributes` float arrays in
// `block` (at least count * world_particle_bytes(attributes) bytes, on 16
// bytes; io::Error otherwise): positions, each attribute, LOD values, layers.
ParticleSpans world_spans(std::span<std::byte> block, uint64_t count, size_t attributes);

// One decoded chunk into world units at particle `first` of `out`:
// `decoded` holds the chunk's particles (decoded_particle_bytes(coding)
// each), `streams[i]` the quantized values of file attribute
// `attributes[i]` for the chunk's particles. `frame_particles` (the whole
// frame's count) picks how to write: a frame larger than the caches is
// written with streaming stores. Threads: chunks of one frame may be
// converted concurrently; what they write does not overlap.
void convert_chunk(const ChunkDesc& chunk, std::span<const std::byte> decoded, std::span<const uint16_t* const> streams,
                   PositionCoding coding, std::span<const size_t> attributes, uint64_t frame_particles, uint64_t first,
                   const ParticleSpans& out);

// Keeps, in place and in order, the particles of `spans` that LOD level
// `level` keeps (blobs by blob_lod_uniform of their cell of `blob_voxel`);
// returns how many.
uint64_t thin(const ParticleSpans& spans, float level, float blob_voxel);

}  // namespace sluice::io
