// Chunk encoding and decoding. Layout of a chunk's filtered payload (before
// zstd), n particles, planes of n bytes each (docs/format.md, "Chunk payload"):
//   Quantized16: 6 planes: bytes 0..5 of the delta of successive 48-bit Morton
//                codes (particles sorted by code, so deltas are small);
//   Float32:     12 planes: bytes 0..3 of x, then of y, then of z;
//   then 2 planes: low and high byte of the LOD value;
//   then per attribute 2 planes: low and high byte of the delta of successive
//   16-bit quantized values.
#include "sluice/io/codec.h"

#include <tbb/parallel_for.h>
#include <zstd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "bytes.h"
#include "chunking.h"
#include "morton.h"
#include "records.h"

namespace sluice::io {

struct DecodeScratch::State {
  ZSTD_DCtx* zstd = ZSTD_createDCtx();
  std::vector<std::byte> raw;
  ~State() { ZSTD_freeDCtx(zstd); }
};

DecodeScratch::DecodeScratch() : state_(std::make_unique<State>()) {}
DecodeScratch::~DecodeScratch() = default;

namespace {

struct EncodedChunk {
  ChunkDesc desc;
  std::vector<std::byte> payload;
  uint64_t raw_bytes = 0;
};

uint16_t quantize(double value, double lo, double inv_step) {
  const double q = std::nearbyint((value - lo) * inv_step);
  return static_cast<uint16_t>(std::clamp(q, 0.0, 65535.0));
}

double inverse_step(float lo, float hi) {
  const double extent = double(hi) - double(lo);
  return extent > 0 ? 65535.0 / extent : 0.0;
}

void put_planes(std::byte* planes, size_t n, size_t i, uint64_t value, int bytes) {
  for (int b = 0; b < bytes; ++b) planes[size_t(b) * n + i] = std::byte(uint8_t(value >> (8 * b)));
}

ZSTD_CCtx* thread_compressor() {
  struct Holder {
    ZSTD_CCtx* ctx = ZSTD_createCCtx();
    ~Holder() { ZSTD_freeCCtx(ctx); }
  };
  thread_local Holder holder;
  return holder.ctx;
}

EncodedChunk encode_chunk(const FrameInput& in, std::span<const uint32_t> members, PositionCoding coding,
                          const EncodeOptions& options) {
  const size_t n = members.size();
  const size_t attributes = in.attributes.size();
  EncodedChunk out;
  ChunkDesc& desc = out.desc;
  desc.particle_count = static_cast<uint32_t>(n);
  for (uint32_t p : members) desc.bounds.extend(in.positions[3 * p], in.positions[3 * p + 1], in.positions[3 * p + 2]);

  // Widen the top of the box until the decoder's float arithmetic maps the
  // largest code inside it: then every decoded particle lies in the box.
  for (int a = 0; a < 3; ++a) {
    while (dequantize(65535, desc.bounds.min[a], desc.bounds.max[a]) > desc.bounds.max[a]) {
      desc.bounds.max[a] = std::nextafter(desc.bounds.max[a], std::numeric_limits<float>::infinity());
    }
  }

  // Order the chunk by its own 48-bit Morton code so code deltas are non-negative.
  std::array<double, 3> inv{};
  for (int a = 0; a < 3; ++a) inv[a] = inverse_step(desc.bounds.min[a], desc.bounds.max[a]);
  std::vector<std::pair<uint64_t, uint32_t>> sorted(n);
  for (size_t i = 0; i < n; ++i) {
    const float* xyz = &in.positions[3 * size_t(members[i])];
    const uint64_t code = morton_encode(quantize(xyz[0], desc.bounds.min[0], inv[0]),
                                        quantize(xyz[1], desc.bounds.min[1], inv[1]),
                                        quantize(xyz[2], desc.bounds.min[2], inv[2]));
    sorted[i] = {code, members[i]};
  }
  std::sort(sorted.begin(), sorted.end());

  const uint64_t raw_size = raw_chunk_bytes(coding, n, attributes);
  std::vector<std::byte> raw(raw_size);
  std::byte* planes = raw.data();
  if (coding == PositionCoding::Quantized16) {
    uint64_t previous = 0;
    for (size_t i = 0; i < n; ++i) {
      put_planes(planes, n, i, sorted[i].first - previous, 6);
      previous = sorted[i].first;
    }
    planes += 6 * n;
  } else {
    for (size_t i = 0; i < n; ++i) {
      for (int a = 0; a < 3; ++a) {
        uint32_t bits;
        std::memcpy(&bits, &in.positions[3 * size_t(sorted[i].second) + a], 4);
        put_planes(planes + size_t(4 * a) * n, n, i, bits, 4);
      }
    }
    planes += 12 * n;
  }
  for (size_t i = 0; i < n; ++i) put_planes(planes, n, i, in.lod[sorted[i].second], 2);
  planes += 2 * n;

  desc.attribute_ranges.resize(attributes);
  for (size_t a = 0; a < attributes; ++a) {
    const std::span<const float> values = in.attributes[a];
    float lo = values[sorted[0].second], hi = lo;
    for (const auto& s : sorted) {
      lo = std::min(lo, values[s.second]);
      hi = std::max(hi, values[s.second]);
    }
    desc.attribute_ranges[a] = {lo, hi};
    const double inv_a = inverse_step(lo, hi);
    uint16_t previous = 0;
    for (size_t i = 0; i < n; ++i) {
      const uint16_t q = quantize(values[sorted[i].second], lo, inv_a);
      put_planes(planes, n, i, uint16_t(q - previous), 2);
      previous = q;
    }
    planes += 2 * n;
  }

  out.raw_bytes = raw_size;
  out.payload.resize(ZSTD_compressBound(raw_size));
  const size_t written = ZSTD_compressCCtx(thread_compressor(), out.payload.data(), out.payload.size(), raw.data(),
                                           raw.size(), options.zstd_level);
  if (ZSTD_isError(written) || written >= raw_size) {
    out.payload = std::move(raw);  // incompressible: store as is
    desc.codec = ChunkCodec::Stored;
  } else {
    out.payload.resize(written);
    desc.codec = ChunkCodec::Zstd;
  }
  desc.compressed_size = static_cast<uint32_t>(out.payload.size());
  desc.checksum = checksum(out.payload);
  return out;
}

void check_input(const FrameInput& in, const FileHeader& header) {
  const ErrorLocation where{};
  if (in.positions.size() % 3 != 0) throw Error(where, "positions are not x,y,z triples");
  const size_t n = in.positions.size() / 3;
  if (in.lod.size() != n) throw Error(where, "LOD array length differs from the particle count");
  if (in.attributes.size() != header.attributes.size()) {
    throw Error(where, "frame has " + std::to_string(in.attributes.size()) + " attributes, the file declares " +
                           std::to_string(header.attributes.size()));
  }
  for (size_t a = 0; a < in.attributes.size(); ++a) {
    if (in.attributes[a].size() != n) throw Error(where, "attribute '" + header.attributes[a].name + "' has the wrong length");
    for (float v : in.attributes[a]) {
      if (!std::isfinite(v)) throw Error(where, "attribute '" + header.attributes[a].name + "' has a non-finite value");
    }
  }
  for (float v : in.positions) {
    if (!std::isfinite(v)) throw Error(where, "a particle position is not finite");
  }
}

}  // namespace

EncodedFrame encode_frame(const FrameInput& in, const FileHeader& header, const EncodeOptions& options) {
  check_input(in, header);
  const size_t n = in.positions.size() / 3;
  EncodedFrame frame;
  FrameHeader& fh = frame.header;
  fh.time = in.time;
  fh.particle_count = n;
  for (size_t i = 0; i < n; ++i) fh.bounds.extend(in.positions[3 * i], in.positions[3 * i + 1], in.positions[3 * i + 2]);

  const uint32_t limit = std::clamp<uint32_t>(options.chunk_particles, 1, kMaxChunkParticles);
  const ChunkPlan plan = plan_chunks(in.positions, fh.bounds, limit);
  std::vector<EncodedChunk> chunks(plan.chunks.size());
  tbb::parallel_for(size_t(0), chunks.size(), [&](size_t c) {
    const auto& r = plan.chunks[c];
    chunks[c] = encode_chunk(in, std::span(plan.order).subspan(r.begin, r.end - r.begin), header.position_coding,
                             options);
  });

  const size_t attributes = header.attributes.size();
  uint64_t offset = frame_table_bytes(chunks.size(), attributes);
  for (EncodedChunk& c : chunks) {
    c.desc.offset = offset;
    offset += c.desc.compressed_size;
    frame.raw_bytes += c.raw_bytes;
    fh.chunks.push_back(c.desc);
  }
  fh.frame_bytes = offset;
  frame.record = serialize_frame_table(fh, attributes);
  frame.record.reserve(offset);
  for (const EncodedChunk& c : chunks) frame.record.insert(frame.record.end(), c.payload.begin(), c.payload.end());
  return frame;
}

void set_frame_number(EncodedFrame& frame, uint32_t frame_number, size_t attribute_count) {
  frame.header.frame_number = frame_number;
  const std::vector<std::byte> table = serialize_frame_table(frame.header, attribute_count);
  std::copy(table.begin(), table.end(), frame.record.begin());
}

void decode_chunk(std::span<const std::byte> record, const ChunkDesc& chunk, const FileHeader& header,
                  const ChunkDestination& out, DecodeScratch& scratch, const ErrorLocation& where) {
  const size_t n = chunk.particle_count;
  const size_t attributes = header.attributes.size();
  const PositionCoding coding = header.position_coding;
  if (chunk.offset > record.size() || chunk.compressed_size > record.size() - chunk.offset) {
    throw Error(where, "chunk payload lies outside the frame record");
  }
  if (out.particles.size() < n * decoded_particle_bytes(coding)) {
    throw Error(where, "destination buffer is smaller than the chunk");
  }
  const std::span<const std::byte> payload = record.subspan(chunk.offset, chunk.compressed_size);
  const uint64_t stored = checksum(payload);
  if (stored != chunk.checksum) throw Error(where, "chunk checksum mismatch (the chunk's bytes are corrupt)");

  const uint64_t raw_size = raw_chunk_bytes(coding, n, attributes);
  const std::byte* raw = nullptr;
  if (chunk.codec == ChunkCodec::Stored) {
    if (payload.size() != raw_size) throw Error(where, "stored chunk has the wrong size");
    raw = payload.data();
  } else {
    DecodeScratch::State& s = scratch.state();
    if (s.raw.size() < raw_size) s.raw.resize(raw_size);
    const size_t got = ZSTD_decompressDCtx(s.zstd, s.raw.data(), raw_size, payload.data(), payload.size());
    if (ZSTD_isError(got)) throw Error(where, std::string("zstd: ") + ZSTD_getErrorName(got));
    if (got != raw_size) throw Error(where, "chunk decompressed to " + std::to_string(got) + " bytes, expected " +
                                                std::to_string(raw_size));
    raw = s.raw.data();
  }

  const auto* planes = reinterpret_cast<const uint8_t*>(raw);
  const uint8_t* lod_lo = planes + (coding == PositionCoding::Quantized16 ? 6 : 12) * n;
  const uint8_t* lod_hi = lod_lo + n;
  if (coding == PositionCoding::Quantized16) {
    const uint8_t *b0 = planes, *b1 = b0 + n, *b2 = b1 + n, *b3 = b2 + n, *b4 = b3 + n, *b5 = b4 + n;
    auto* dst = reinterpret_cast<uint64_t*>(out.particles.data());
    uint64_t code = 0;
    for (size_t i = 0; i < n; ++i) {
      code += uint64_t(b0[i]) | uint64_t(b1[i]) << 8 | uint64_t(b2[i]) << 16 | uint64_t(b3[i]) << 24 |
              uint64_t(b4[i]) << 32 | uint64_t(b5[i]) << 40;
      const uint64_t x = compact_bits_by_3(code), y = compact_bits_by_3(code >> 1), z = compact_bits_by_3(code >> 2);
      const uint64_t lod = uint64_t(lod_lo[i]) | uint64_t(lod_hi[i]) << 8;
      const uint64_t packed = (x & 0xffff) | (y & 0xffff) << 16 | (z & 0xffff) << 32 | lod << 48;
      std::memcpy(dst + i, &packed, 8);
    }
  } else {
    auto* dst = reinterpret_cast<uint32_t*>(out.particles.data());
    for (size_t i = 0; i < n; ++i) {
      for (size_t a = 0; a < 3; ++a) {
        const uint8_t* p = planes + 4 * a * n;
        dst[4 * i + a] = uint32_t(p[i]) | uint32_t(p[n + i]) << 8 | uint32_t(p[2 * n + i]) << 16 |
                         uint32_t(p[3 * n + i]) << 24;
      }
      dst[4 * i + 3] = uint32_t(lod_lo[i]) | uint32_t(lod_hi[i]) << 8;
    }
  }
  const uint8_t* attr = lod_hi + n;
  for (size_t a = 0; a < attributes && a < out.attributes.size(); ++a, attr += 2 * n) {
    uint16_t* dst = out.attributes[a];
    if (dst == nullptr) continue;
    uint16_t q = 0;
    for (size_t i = 0; i < n; ++i) {
      q = uint16_t(q + (attr[i] | attr[n + i] << 8));
      dst[i] = q;
    }
  }
}

}  // namespace sluice::io
