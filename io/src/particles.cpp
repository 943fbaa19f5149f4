#include "sluice/io/particles.h"

#include <tbb/parallel_for.h>


#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <string>

#include "dequantize.h"
#include "file.h"
#include "sluice/io/codec.h"
#include "sluice/error.h"
#include "sluice/io/export.h"
#include "sluice/io/lod.h"

namespace sluice::io {
namespace {

void check_query(const ParticleQuery& query, const FileHeader& file, const ErrorLocation& where) {
  if (!(query.lod_level > 0 && query.lod_level <= 1)) {
    throw Error(where, "LOD level " + std::to_string(query.lod_level) + " is out of range: give a fraction in (0, 1]");
  }
  for (const size_t a : query.attributes) {
    if (a >= file.attributes.size()) {
      throw Error(where, "attribute " + std::to_string(a) + " requested; the file has " + std::to_string(file.attributes.size()));
    }
  }
}

// Whether a blob centred at `p` is kept at `level`: its cell's random term,
// as the renderer draws blobs at importance 1.
bool blob_keeps(const float* p, float voxel, float level) {
  if (!(voxel > 0)) return true;
  int32_t cell[3];
  for (int a = 0; a < 3; ++a) cell[a] = int32_t(std::clamp(std::floor(double(p[a]) / voxel), -2147483648.0, 2147483647.0));
  return 1.0 - blob_lod_uniform(cell[0], cell[1], cell[2]) <= level;
}

// Whether a frame's converted arrays outgrow the caches, so that writing
// them through the caches would only evict and re-read: 16 MiB, about the
// last-level cache of one socket.
bool outgrows_caches(uint64_t particles) { return particles * (3 * sizeof(float) + sizeof(uint16_t) + 1) > (16ull << 20); }

// `out` sized for the frame's particles, reusing its memory.
void size_arrays(const FrameHeader& header, const ParticleQuery& query, ParticleArrays& out) {
  const uint64_t n = header.particle_count;
  out.time = header.time;
  out.bytes_read = 0;
  out.positions.resize(3 * n);
  out.lod.resize(n);
  out.layer.resize(n);
  out.attributes.resize(query.attributes.size());
  for (auto& a : out.attributes) a.resize(n);
}

ParticleSpans spans_of(ParticleArrays& arrays) {
  ParticleSpans s;
  s.count = arrays.count();
  s.positions = arrays.positions.data();
  s.lod = arrays.lod.data();
  s.layer = arrays.layer.data();
  for (auto& a : arrays.attributes) s.attributes.push_back(a.data());
  return s;
}

// Thins `out` to what `level` keeps.
void thin_arrays(ParticleArrays& out, float level, float blob_voxel) {
  const uint64_t kept = thin(spans_of(out), level, blob_voxel);
  out.positions.resize(3 * kept);
  out.lod.resize(kept);
  out.layer.resize(kept);
  for (auto& a : out.attributes) a.resize(kept);
}

// The kept chunks' bytes (and fine parts) of a frame record into `record`
// (the whole record's size, only those ranges filled): one read per run of
// adjacent parts.
uint64_t read_chunks(const ContainerReader& reader, uint64_t frame, const FrameHeader& header, uint64_t table_bytes,
                     std::span<std::byte> record) {
  const FrameIndexEntry& e = reader.index().frames[frame];
  const ErrorLocation where = reader.location(frame);
  thread_local std::vector<RecordPart> parts;
  record_parts(header, parts);
  uint64_t read = 0;
  for (size_t c = 0; c < parts.size();) {
    const uint64_t begin = parts[c].offset;
    uint64_t end = begin + parts[c].size;
    size_t next = c + 1;
    while (next < parts.size() && parts[next].offset == end) end += parts[next++].size;
    if (begin < table_bytes || end > record.size()) {
      throw Error(reader.location(frame, header.chunks[parts[c].chunk].index), "chunk lies outside its record");
    }
    pread_all_or_throw(reader.descriptor(), record.subspan(begin, end - begin), e.offset + begin, where);
    read += end - begin;
    c = next;
  }
  return read;
}

}  // namespace

uint64_t world_particle_bytes(size_t attributes) { return 3 * sizeof(float) + 4 * attributes + sizeof(uint16_t) + 1; }

ParticleSpans world_spans(std::span<std::byte> block, uint64_t count, size_t attributes) {
  if (block.size() < count * world_particle_bytes(attributes) || reinterpret_cast<uintptr_t>(block.data()) % 16 != 0) {
    throw Error({}, "world_spans: the block is too small or not on 16 bytes");
  }
  ParticleSpans s;
  s.count = count;
  std::byte* at = block.data();
  s.positions = reinterpret_cast<float*>(at);
  at += count * 3 * sizeof(float);
  for (size_t a = 0; a < attributes; ++a) {
    s.attributes.push_back(reinterpret_cast<float*>(at));
    at += count * sizeof(float);
  }
  s.lod = reinterpret_cast<uint16_t*>(at);
  s.layer = reinterpret_cast<uint8_t*>(at + count * sizeof(uint16_t));
  return s;
}

void convert_chunk(const ChunkDesc& chunk, std::span<const std::byte> decoded, std::span<const uint16_t* const> streams,
                   PositionCoding coding, std::span<const size_t> attributes, uint64_t frame_particles, uint64_t first,
                   const ParticleSpans& out) {
  const size_t n = chunk.particle_count;
  if (decoded.size() < n * decoded_particle_bytes(coding) || streams.size() != attributes.size() ||
      out.attributes.size() != attributes.size() || first + n > out.count) {
    throw Error({}, "convert_chunk: the chunk's buffers do not match it");
  }
  float* xyz = out.positions + 3 * first;
  uint16_t* lod = out.lod + first;
  if (coding == PositionCoding::Quantized16) {
    // Decoded particles are 4 uint16 (x, y, z, lod): 8-byte aligned.
    const auto* q = reinterpret_cast<const uint16_t*>(decoded.data());
    ChunkScale scale;
    for (int a = 0; a < 3; ++a) {
      scale.lo[a] = chunk.bounds.min[a];
      scale.step[a] = (chunk.bounds.max[a] - chunk.bounds.min[a]) * (1.0f / 65535.0f);
    }
    size_t i = 0;
    if (outgrows_caches(frame_particles) && reinterpret_cast<uintptr_t>(out.positions) % 16 == 0 &&
        reinterpret_cast<uintptr_t>(out.lod) % 8 == 0) {
      // Up to the first particle whose x lies on 16 bytes (its index a multiple of 4).
      const size_t head = std::min<size_t>(n, (4 - first % 4) % 4);
      dequantize_plain(q, 0, head, scale, xyz, lod);
      i = dequantize_streaming(chosen_streaming_kernel(), q, head, n, scale, xyz, lod);
    } else {
      i = dequantize_cached(q, n, scale, xyz, lod);
    }
    dequantize_plain(q, i, n, scale, xyz, lod);
  } else {
    const std::byte* p = decoded.data();
    for (size_t i = 0; i < n; ++i) {
      std::memcpy(&xyz[3 * i], p + 16 * i, 3 * sizeof(float));
      std::memcpy(&lod[i], p + 16 * i + 12, sizeof(uint16_t));
    }
  }
  std::memset(out.layer + first, int(chunk.layer), n);
  for (size_t k = 0; k < attributes.size(); ++k) {
    const auto [lo, hi] = chunk.attribute_ranges[attributes[k]];
    const float step = (hi - lo) * (1.0f / 65535.0f);
    const uint16_t* in = streams[k];
    float* values = out.attributes[k] + first;
    for (size_t i = 0; i < n; ++i) values[i] = lo + float(in[i]) * step;
  }
}

uint64_t thin(const ParticleSpans& out, float level, float blob_voxel) {
  // One decision per possible value, kept per thread for the level last
  // asked for: a stream thins frame after frame at the same level.
  thread_local std::vector<uint8_t> keeps;
  thread_local float keeps_level = -1;
  if (keeps.empty() || keeps_level != level) {
    keeps.resize(65536);
    for (uint32_t v = 0; v < 65536; ++v) keeps[v] = lod_keeps(uint16_t(v), level) ? 1 : 0;
    keeps_level = level;
  }
  uint64_t kept = 0;
  for (uint64_t i = 0; i < out.count; ++i) {
    const bool keep = out.layer[i] == uint8_t(Layer::Blobs) ? blob_keeps(&out.positions[3 * i], blob_voxel, level)
                                                           : keeps[out.lod[i]] != 0;
    if (!keep) continue;
    if (kept != i) {
      std::memmove(&out.positions[3 * kept], &out.positions[3 * i], 3 * sizeof(float));
      out.lod[kept] = out.lod[i];
      out.layer[kept] = out.layer[i];
      for (float* a : out.attributes) a[kept] = a[i];
    }
    ++kept;
  }
  return kept;
}

namespace {

// A buffer of at least `bytes`, uninitialized, kept when large enough.
std::span<std::byte> at_least(std::unique_ptr<std::byte[]>& buffer, uint64_t& held, uint64_t bytes) {
  if (held < bytes) {
    buffer.reset();
    buffer.reset(new std::byte[bytes]);
    held = bytes;
  }
  return {buffer.get(), bytes};
}

}  // namespace

void read_particles(const ContainerReader& reader, uint64_t frame, const ParticleQuery& query, ParticleArrays& out,
                    ParticleScratch& scratch) {
  const FileHeader& file = reader.header();
  check_query(query, file, reader.location(frame));
  FrameHeader header = reader.read_table(frame);
  const uint64_t table_bytes = frame_table_bytes(header.table_records(), file.attributes.size());
  keep_layers(header, query.layers);
  if (query.lod_level < 1) {
    const uint32_t tiers = tiers_for_keep(query.lod_level);
    keep_tiers(header, [&](const ChunkDesc&) { return std::max<uint32_t>(tiers, 1); });
  }
  // The record's whole size, uninitialized: only the chunks read are touched.
  const uint64_t record_bytes = reader.index().frames[frame].bytes;
  const std::span<std::byte> record = at_least(scratch.record, scratch.record_bytes, record_bytes);
  const uint64_t read = read_chunks(reader, frame, header, table_bytes, record);

  const uint64_t n = header.particle_count;
  const std::span<std::byte> decoded =
      at_least(scratch.decoded, scratch.decoded_bytes, std::max<uint64_t>(1, n * decoded_particle_bytes(file.position_coding)));
  std::vector<uint64_t> first(header.chunks.size());
  chunk_starts(header, first);
  scratch.streams.resize(file.attributes.size());
  std::vector<uint16_t*> destinations(file.attributes.size(), nullptr);
  for (const size_t a : query.attributes) {
    if (scratch.streams[a].size() < n) scratch.streams[a].resize(n);
    destinations[a] = scratch.streams[a].data();
  }
  std::vector<std::span<const uint16_t>> wanted;
  for (const size_t a : query.attributes) wanted.emplace_back(scratch.streams[a].data(), n);
  size_arrays(header, query, out);
  // Each chunk decoded and converted at once, while its decoded particles
  // are still in this core's cache.
  const size_t stride = decoded_particle_bytes(file.position_coding);
  const ErrorLocation where = reader.location(frame);
  const ParticleSpans spans = spans_of(out);
  tbb::parallel_for(size_t(0), header.chunks.size(), [&](size_t c) {
    thread_local DecodeScratch decode_scratch;
    thread_local std::vector<uint16_t*> bases;
    const ChunkDesc& chunk = header.chunks[c];
    bases.assign(destinations.size(), nullptr);
    for (size_t a = 0; a < destinations.size(); ++a) {
      if (destinations[a]) bases[a] = destinations[a] + first[c];
    }
    ErrorLocation at = where;
    at.chunk = chunk.index;
    decode_chunk(record, chunk, file, {decoded.subspan(first[c] * stride, size_t(chunk.particle_count) * stride), bases},
                 decode_scratch, at);
    thread_local std::vector<const uint16_t*> streams;
    streams.clear();
    for (const auto& s : wanted) streams.push_back(s.data() + first[c]);
    convert_chunk(chunk, decoded.subspan(first[c] * stride), streams, file.position_coding, query.attributes, n, first[c],
                  spans);
  });
  if (query.lod_level < 1) thin_arrays(out, query.lod_level, header.blob_voxel);
  out.bytes_read = read + std::min<uint64_t>(record_bytes, table_bytes);
}

ParticleArrays read_particles(const ContainerReader& reader, uint64_t frame, const ParticleQuery& query) {
  ParticleArrays out;
  ParticleScratch scratch;
  read_particles(reader, frame, query, out, scratch);
  return out;
}

}  // namespace sluice::io
