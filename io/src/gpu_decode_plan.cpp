// Plans for the GPU decoder: the chunk payloads' plane tables read and
// checked on the CPU (a few bytes per plane), zstd planes inflated here.
#include "sluice/io/gpu_decode_plan.h"
#include "sluice/io/gpu_decode_reference.h"

#include <tbb/parallel_for.h>
#include <zstd.h>

#include <cstring>
#include <functional>
#include <stdexcept>
#include <string>

#include "bytes.h"
#include "morton.h"
#include "packed_plane.h"
#include "plane_table.h"

namespace sluice::io {

// decode.comp sums a plane's bytes over a chunk in 32 bits.
static_assert(uint64_t(kMaxChunkParticles) * 255 < (uint64_t(1) << 32));
namespace {

constexpr uint64_t kMax32 = UINT32_MAX;

uint64_t groups_of(uint64_t n) { return (n + 7) / 8; }

// A packed plane's width, values and escapes, checked as unpack_plane does.
// `bytes` holds the record's bytes from `base` on (the whole record, or one
// chunk's payload as a read thread holds it).
GpuPlane packed_plane(std::span<const std::byte> bytes, uint64_t base, const PlaneSource& s, uint64_t n, size_t p,
                      const ErrorLocation& where) {
  const std::string what = "plane " + std::to_string(p);
  if (s.size == 0) throw Error(where, what + ": packed plane is empty");
  const uint32_t width = uint32_t(bytes[s.at - base]);
  if (width < 1 || width > uint32_t(kMaxPackedWidth)) {
    throw Error(where, what + ": packed width " + std::to_string(width) + " is not 1..7");
  }
  const uint64_t packed_bytes = groups_of(n) * width;
  if (s.size - 1 < packed_bytes) throw Error(where, what + ": packed plane is shorter than its values");
  if (n == 0 && s.size != 1) throw Error(where, what + ": an empty packed plane stores escapes");
  GpuPlane g;
  g.offset = uint32_t(s.at);
  g.width = width;
  g.escapes = uint32_t(s.at + 1 + packed_bytes);
  g.escape_count = uint32_t(s.size - 1 - packed_bytes);
  return g;
}

uint64_t round16(uint64_t v) { return (v + 15) & ~uint64_t(15); }

// Where a zstd plane goes: sets `out` and returns true, or returns false
// (the caller cannot inflate it).
using PlaneSink = std::function<bool(GpuPlane& out, const PlaneSource& s, size_t p)>;

// GPU plane `out` for plane p, as located (`s`); false if a zstd plane
// was refused by `zstd`.
bool gpu_plane(std::span<const std::byte> bytes, uint64_t base, const PlaneSource& s, uint64_t n, size_t p,
               const PlaneSink& zstd, GpuPlane& out, const ErrorLocation& at) {
  switch (s.kind) {
    case PlaneSource::Stored: out = {uint32_t(s.at), 0, 0, 0}; return true;
    case PlaneSource::Packed: out = packed_plane(bytes, base, s, n, p, at); return true;
    case PlaneSource::Zstd: return zstd(out, s, p);
  }
  return true;
}

// The GPU planes of chunk `chunk` from its plane table, in GpuChunkPlan
// order; `bytes` holds the record from byte `base` on, the chunk's payload
// included. False if a zstd plane was refused by `zstd`.
bool plan_planes(std::span<const std::byte> bytes, uint64_t base, const ChunkDesc& chunk, const FileHeader& file,
                 const GpuPlanOptions& options, GpuChunkPlan& g, const PlaneSink& zstd, const ErrorLocation& at) {
  thread_local std::vector<PlaneSource> sources;
  const size_t attributes = file.attributes.size();
  // Split: the record holds 2 planes fewer; the fine part's go to GPU planes 0-1.
  const size_t fine = chunk.fine.split() ? 2 : 0;
  const size_t planes = raw_chunk_bytes(file.position_coding, 1, attributes) - fine;
  const bool attribute = options.color_attribute >= 0 && size_t(options.color_attribute) < attributes;
  const uint64_t n = chunk.particle_count;
  if (chunk.offset < base || chunk.offset - base > bytes.size() || chunk.compressed_size > bytes.size() - (chunk.offset - base)) {
    throw Error(at, "a chunk payload lies outside the frame record");
  }
  read_plane_table(bytes.subspan(chunk.offset - base, chunk.compressed_size), chunk.offset, chunk.codec, n, planes,
                   sources, at);
  const size_t colour = 8 - fine + 2 * size_t(attribute ? options.color_attribute : 0);
  for (int k = int(fine); k < kGpuPlanes; ++k) {
    if (k >= 8 && !attribute) break;
    const size_t p = k < 8 ? size_t(k) - fine : colour + size_t(k - 8);
    if (!gpu_plane(bytes, base, sources[p], n, p, zstd, g.planes[k], at)) return false;
  }
  return true;
}

// GPU planes 0-1 of a split chunk from its fine part's plane table;
// `bytes` holds the record from byte `base` on, the fine part included.
// False if a zstd plane was refused by `zstd`.
bool plan_fine(std::span<const std::byte> bytes, uint64_t base, const ChunkDesc& chunk, GpuChunkPlan& g,
               const PlaneSink& zstd, const ErrorLocation& at) {
  thread_local std::vector<PlaneSource> sources;
  const ChunkDesc::Fine& fine = chunk.fine;
  const uint64_t n = chunk.particle_count;
  if (fine.offset < base || fine.offset - base > bytes.size() || fine.size > bytes.size() - (fine.offset - base)) {
    throw Error(at, "a fine part lies outside the frame record");
  }
  read_plane_table(bytes.subspan(fine.offset - base, fine.size), fine.offset, fine.codec, n, 2, sources, at);
  for (size_t p = 0; p < 2; ++p) {
    if (!gpu_plane(bytes, base, sources[p], n, p, zstd, g.planes[p], at)) return false;
  }
  return true;
}

// Chunk c's plan before its planes: where its particles and tiles go.
void start_chunk(GpuDecodePlan& plan, const ChunkDesc& chunk, size_t c, uint64_t first, bool attribute) {
  GpuChunkPlan& g = plan.chunks[c];
  g = GpuChunkPlan{};
  g.first = uint32_t(first);
  g.count = chunk.particle_count;
  g.flags = (attribute ? kGpuWithAttribute : 0) | (chunk.fine.split() ? kGpuSplit : 0) | (chunk.fine.read() ? kGpuFine : 0);
  g.first_tile = uint32_t(plan.tile_chunk.size());
  plan.tile_chunk.insert(plan.tile_chunk.end(), (uint64_t(chunk.particle_count) + kGpuTile - 1) / kGpuTile, uint32_t(c));
}

// The plan's statistics, from its planes and jobs.
void count_planes(GpuDecodePlan& plan) {
  plan.stored_planes = plan.packed_planes = 0;
  plan.zstd_planes = plan.inflate.size();
  for (const GpuChunkPlan& g : plan.chunks) {
    const int planes = (g.flags & kGpuWithAttribute) ? kGpuPlanes : 8;
    const bool coarse = (g.flags & kGpuSplit) && !(g.flags & kGpuFine);  // planes 0-1 unused
    for (int k = coarse ? 2 : 0; k < planes; ++k) {
      if (g.planes[k].width > 0) ++plan.packed_planes;
      else ++plan.stored_planes;
    }
  }
  plan.stored_planes -= plan.zstd_planes;  // inflated planes read as stored
}

}  // namespace

bool gpu_decodable(const FileHeader& file) { return file.position_coding == PositionCoding::Quantized16; }

namespace {

bool wants_attribute(const FileHeader& file, const GpuPlanOptions& options) {
  return options.color_attribute >= 0 && size_t(options.color_attribute) < file.attributes.size();
}

void check_offsets_fit(const GpuDecodePlan& plan, const ErrorLocation& where) {
  if (plan.encoded_bytes() > kMax32) {
    throw Error(where, "the frame's encoded bytes (" + std::to_string(plan.encoded_bytes()) +
                           ") do not fit the GPU decoder's 32-bit offsets");
  }
}

}  // namespace

void plan_gpu_frame(const FrameHeader& header, const FileHeader& file, const GpuPlanOptions& options, GpuDecodePlan& plan,
                    const ErrorLocation& where) {
  if (!gpu_decodable(file)) throw Error(where, "float32 positions are not decoded on the GPU");
  const bool attribute = wants_attribute(file, options);
  plan.chunks.resize(header.chunks.size());
  plan.inflate.clear();
  plan.chunk_inflate.assign(header.chunks.size() + 1, 0);
  plan.tile_chunk.clear();
  plan.record_bytes = 0;
  plan.inflated_bytes = 0;
  plan.stored_planes = plan.packed_planes = plan.zstd_planes = 0;
  for (const ChunkDesc& c : header.chunks) {
    plan.record_bytes = std::max(plan.record_bytes, c.offset + c.compressed_size);
    if (c.fine.read()) plan.record_bytes = std::max(plan.record_bytes, c.fine.offset + c.fine.size);
  }
  plan.inflated_offset = round16(plan.record_bytes);
  uint64_t first = 0;
  for (size_t c = 0; c < header.chunks.size(); ++c) {
    start_chunk(plan, header.chunks[c], c, first, attribute);
    first += header.chunks[c].particle_count;
    if (first > kMax32) {
      ErrorLocation at = where;
      at.chunk = c;
      throw Error(at, "the frame has 2^32 particles or more");
    }
  }
  check_offsets_fit(plan, where);
}

bool plan_gpu_chunk(std::span<const std::byte> payload, const FrameHeader& header, const FileHeader& file,
                    const GpuPlanOptions& options, size_t c, GpuDecodePlan& plan, const ErrorLocation& where) {
  ErrorLocation at = where;
  at.chunk = c;
  const ChunkDesc& chunk = header.chunks[c];
  if (payload.size() != chunk.compressed_size || c >= plan.chunks.size()) {
    throw Error(at, "plan_gpu_chunk: the payload or the plan does not match the frame");
  }
  const PlaneSink refuse = [](GpuPlane&, const PlaneSource&, size_t) { return false; };
  return plan_planes(payload, chunk.offset, chunk, file, options, plan.chunks[c], refuse, at);
}

bool plan_gpu_fine(std::span<const std::byte> payload, const FrameHeader& header, size_t c, GpuDecodePlan& plan,
                   const ErrorLocation& where) {
  ErrorLocation at = where;
  at.chunk = c;
  if (c >= plan.chunks.size() || c >= header.chunks.size() || !header.chunks[c].fine.read() ||
      payload.size() != header.chunks[c].fine.size) {
    throw Error(at, "plan_gpu_fine: the fine part or the plan does not match the frame");
  }
  const PlaneSink refuse = [](GpuPlane&, const PlaneSource&, size_t) { return false; };
  return plan_fine(payload, header.chunks[c].fine.offset, header.chunks[c], plan.chunks[c], refuse, at);
}

void finish_gpu_plan(GpuDecodePlan& plan) { count_planes(plan); }

void plan_gpu_decode(std::span<const std::byte> record, const FrameHeader& header, const FileHeader& file,
                     const GpuPlanOptions& options, GpuDecodePlan& plan, const ErrorLocation& where) {
  plan_gpu_frame(header, file, options, plan, where);
  if (plan.record_bytes > record.size()) throw Error(where, "a chunk payload lies outside the frame record");
  for (size_t c = 0; c < header.chunks.size(); ++c) {
    ErrorLocation at = where;
    at.chunk = c;
    const ChunkDesc& chunk = header.chunks[c];
    plan.chunk_inflate[c] = uint32_t(plan.inflate.size());
    const PlaneSink inflate = [&](GpuPlane& out, const PlaneSource& s, size_t p) {
      const uint64_t target = plan.inflated_offset + plan.inflated_bytes;
      plan.inflate.push_back({s.at, s.size, uint32_t(chunk.particle_count), target, uint32_t(c), uint32_t(p)});
      out = {uint32_t(target), 0, 0, 0};
      plan.inflated_bytes = round16(plan.inflated_bytes + chunk.particle_count);
      return true;
    };
    plan_planes(record, 0, chunk, file, options, plan.chunks[c], inflate, at);
    if (chunk.fine.read()) plan_fine(record, 0, chunk, plan.chunks[c], inflate, at);
    plan.chunk_inflate[c + 1] = uint32_t(plan.inflate.size());
  }
  count_planes(plan);
  check_offsets_fit(plan, where);
}

void stage_chunk(std::span<const std::byte> record, const FrameHeader& header, const GpuDecodePlan& plan, size_t c,
                 std::span<std::byte> encoded, bool verify, const ErrorLocation& where) {
  struct Holder {
    ZSTD_DCtx* ctx = ZSTD_createDCtx();
    ~Holder() { ZSTD_freeDCtx(ctx); }
  };
  const auto fail = [&](const std::string& why) {
    ErrorLocation at = where;
    at.chunk = c;
    throw Error(at, why);
  };
  if (encoded.size() < plan.encoded_bytes() || c >= plan.chunks.size() || c >= header.chunks.size()) {
    fail("stage_chunk: the encoded area or the plan does not match the frame");
  }
  const ChunkDesc& chunk = header.chunks[c];
  const std::span<const std::byte> payload = record.subspan(chunk.offset, chunk.compressed_size);
  if (verify && checksum(payload) != chunk.checksum) fail("chunk checksum mismatch (the chunk's bytes are corrupt)");
  if (record.data() != encoded.data()) std::memcpy(encoded.data() + chunk.offset, payload.data(), payload.size());
  if (chunk.fine.read()) {
    if (chunk.fine.offset > record.size() || chunk.fine.size > record.size() - chunk.fine.offset) {
      fail("the fine part (table record " + std::to_string(chunk.fine.index) + ") lies outside the frame record");
    }
    const std::span<const std::byte> fine = record.subspan(chunk.fine.offset, chunk.fine.size);
    if (verify && checksum(fine) != chunk.fine.checksum) {
      fail("fine part (table record " + std::to_string(chunk.fine.index) + ") checksum mismatch (its bytes are corrupt)");
    }
    if (record.data() != encoded.data()) std::memcpy(encoded.data() + chunk.fine.offset, fine.data(), fine.size());
  }
  thread_local Holder zstd;
  for (uint32_t j = plan.chunk_inflate[c]; j < plan.chunk_inflate[c + 1]; ++j) {
    const InflateJob& job = plan.inflate[j];
    const size_t got = ZSTD_decompressDCtx(zstd.ctx, encoded.data() + job.target, job.plane_bytes,
                                           record.data() + job.source, job.size);
    if (ZSTD_isError(got)) fail("plane " + std::to_string(job.plane) + ": zstd: " + ZSTD_getErrorName(got));
    if (got != job.plane_bytes) {
      fail("plane " + std::to_string(job.plane) + " decompressed to " + std::to_string(got) + " bytes, expected " +
           std::to_string(job.plane_bytes));
    }
  }
}

void stage_frame(std::span<const std::byte> record, const FrameHeader& header, const GpuDecodePlan& plan,
                 std::span<std::byte> encoded, bool verify, const ErrorLocation& where) {
  tbb::parallel_for(size_t(0), plan.chunks.size(),
                    [&](size_t c) { stage_chunk(record, header, plan, c, encoded, verify, where); });
  if (encoded.size() >= plan.staged_bytes()) write_tables(plan, encoded);
}

void write_tables(const GpuDecodePlan& plan, std::span<std::byte> staged) {
  if (staged.size() < plan.staged_bytes()) throw Error({}, "write_tables: the staged area is too small");
  // A frame may have no chunk at all (every cell out of view): no copy.
  if (!plan.chunks.empty()) {
    std::memcpy(staged.data() + plan.plans_offset(), plan.chunks.data(), plan.chunks.size() * sizeof(GpuChunkPlan));
  }
  if (!plan.tile_chunk.empty()) std::memcpy(staged.data() + plan.tiles_offset(), plan.tile_chunk.data(), plan.tile_chunk.size() * 4);
}

void write_table_block(const GpuDecodePlan& plan, std::span<std::byte> out) {
  const uint64_t plans = plan.chunks.size() * sizeof(GpuChunkPlan);
  if (out.size() < plans + plan.tile_chunk.size() * 4) throw Error({}, "write_table_block: too small");
  if (plans > 0) std::memcpy(out.data(), plan.chunks.data(), plans);
  if (!plan.tile_chunk.empty()) std::memcpy(out.data() + plans, plan.tile_chunk.data(), plan.tile_chunk.size() * 4);
}

namespace {

// Value i of a plane of the encoded area, escapes resolved in order.
struct PlaneReader {
  const uint8_t* base;
  GpuPlane plane;
  uint32_t escape = 0;
  uint8_t next(uint32_t i) {
    if (plane.width == 0) return base[plane.offset + i];
    const uint32_t w = plane.width, code = (1u << w) - 1;
    const uint64_t bit = uint64_t(i) * w;
    const uint8_t* group = base + plane.offset + 1;
    uint32_t bits = 0;
    for (uint32_t b = 0; b < w; ++b) bits |= uint32_t((group[(bit + b) / 8] >> ((bit + b) % 8)) & 1u) << b;
    if (bits != code) return uint8_t(bits);
    return escape < plane.escape_count ? base[plane.escapes + escape++] : uint8_t(code);
  }
};

}  // namespace

void decode_plan_on_cpu(std::span<const std::byte> encoded, const GpuDecodePlan& plan, std::span<uint64_t> particles,
                        std::span<uint16_t> attribute) {
  const auto* base = reinterpret_cast<const uint8_t*>(encoded.data());
  for (const GpuChunkPlan& c : plan.chunks) {
    std::vector<PlaneReader> planes;
    for (const GpuPlane& p : c.planes) planes.push_back({base, p});
    const bool split = (c.flags & kGpuSplit) != 0, fine = (c.flags & kGpuFine) != 0;
    uint64_t code = 0;
    uint16_t value = 0;
    for (uint32_t i = 0; i < c.count; ++i) {
      uint64_t delta = 0;
      for (int b = split ? 2 : 0; b < 6; ++b) delta |= uint64_t(planes[size_t(b)].next(i)) << (8 * b);
      const uint64_t lod = planes[6].next(i) | uint64_t(planes[7].next(i)) << 8;
      code += delta;  // split: the high 32 bits' delta, shifted by 16
      uint64_t low = 0;
      if (split) low = fine ? planes[0].next(i) | uint64_t(planes[1].next(i)) << 8 : kCoarseFill;
      particles[c.first + i] = morton_to_packed16(code | low) | lod << 48;
      if ((c.flags & kGpuWithAttribute) != 0) {
        value = uint16_t(value + (planes[8].next(i) | planes[9].next(i) << 8));
        attribute[c.first + i] = value;
      }
    }
  }
}

}  // namespace sluice::io
