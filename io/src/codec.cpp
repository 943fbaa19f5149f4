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
#include <optional>

#include "bytes.h"
#include "chunking.h"
#include "layering.h"
#include "morton.h"
#include "packed_plane.h"
#include "plane_table.h"
#include "quantized_unpack.h"
#include "records.h"
#include "sluice/io/lod.h"
#include "sluice/io/point_set.h"

namespace sluice::io {

struct DecodeScratch::State {
  ZSTD_DCtx* zstd = ZSTD_createDCtx();
  std::vector<std::byte> raw;
  std::vector<const uint8_t*> planes;
  std::vector<std::byte> fill;  // kCoarseFill's low and high bytes, fill_n of each (records without their fine part)
  size_t fill_n = 0;
  struct {
    std::vector<std::byte> raw;  // a fine part's inflated planes
    std::vector<const uint8_t*> planes;
  } fine;
  ~State() { ZSTD_freeDCtx(zstd); }
};

DecodeScratch::DecodeScratch() : state_(std::make_unique<State>()) {}
DecodeScratch::~DecodeScratch() = default;

namespace {

struct EncodedChunk {
  ChunkDesc desc;
  std::vector<std::byte> payload;
  std::vector<std::byte> fine;  // format 3.0: the fine part (desc.fine), placed after its layer's records
  uint64_t raw_bytes = 0;
  uint64_t bytes() const { return payload.size() + fine.size(); }
};

// Format 3.0 writes each quantized record's positions in two parts
// (docs/format.md, "Precision parts"); frames stored for immediate
// decoding (PlaneCoding::Stored) are read whole and gain nothing.
bool splits_positions(const FileHeader& header, const EncodeOptions& options) {
  return header.version_major >= 3 && header.position_coding == PositionCoding::Quantized16 &&
         options.planes != PlaneCoding::Stored;
}

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

// Chunk payload (codecs Zstd and Packed): a table of one u32 per plane, then
// the planes. An entry equal to n: the plane is stored as is (read in place,
// no copy). Codec Packed only: an entry with kPackedPlaneFlag set is a packed
// plane (packed_plane.h) of the remaining size. Any other entry is the size
// of the zstd frame holding the plane.
//
// Each plane takes the cheapest form to decode that is small enough:
// stored when nothing saves kMinPlaneGain of it (noise: LOD values, low
// bytes); zstd only where it saves kZstdGainOverPacked over bit packing
// (structured planes of lattice-like data); bit-packed otherwise (the small
// high bytes of Morton deltas, which zstd's entropy decoder takes about 1 ns
// per byte to decode and unpacking 0.1-0.2).
constexpr double kMinPlaneGain = 0.15;
constexpr double kZstdGainOverPacked = 1.0 / 3.0;
constexpr uint32_t kLeastTierRecord = 1024;

void entry_stored(std::vector<std::byte>& payload, const std::byte* plane, size_t n, size_t p) {
  const auto entry = static_cast<uint32_t>(n);
  std::memcpy(payload.data() + 4 * p, &entry, 4);
  payload.insert(payload.end(), plane, plane + n);
}

void compress_planes(std::vector<std::byte>& raw, size_t n, const EncodeOptions& options,
                     std::vector<std::byte>& payload, ChunkCodec& codec) {
  if (options.planes == PlaneCoding::Stored) {
    payload = std::move(raw);
    codec = ChunkCodec::Stored;
    return;
  }
  const size_t planes = raw.size() / n;
  ZSTD_CCtx* cctx = thread_compressor();
  std::vector<std::byte> frame(ZSTD_compressBound(n));
  payload.assign(4 * planes, std::byte{0});
  bool any_packed = false;
  for (size_t p = 0; p < planes; ++p) {
    const std::byte* plane = raw.data() + p * n;
    const std::span<const uint8_t> values(reinterpret_cast<const uint8_t*>(plane), n);
    size_t zstd_size = 0;
    const bool may_zstd = options.planes != PlaneCoding::GpuDecodable;
    if (may_zstd) {
      zstd_size = ZSTD_compressCCtx(cctx, frame.data(), frame.size(), plane, n, options.zstd_level);
      if (ZSTD_isError(zstd_size)) throw Error({}, std::string("zstd: ") + ZSTD_getErrorName(zstd_size));
    }
    const PackedPlan packed = options.planes != PlaneCoding::Zstd ? plan_packed_plane(values) : PackedPlan{};
    const bool use_zstd = may_zstd &&
                          (packed.width == 0 || double(zstd_size) < double(packed.bytes) * (1.0 - kZstdGainOverPacked));
    if (!use_zstd && packed.width == 0) {  // neither zstd nor packing: stored
      entry_stored(payload, plane, n, p);
      continue;
    }
    const size_t size = use_zstd ? zstd_size : packed.bytes;
    if (double(size) > double(n) * (1.0 - kMinPlaneGain)) {  // too little gain: stored
      entry_stored(payload, plane, n, p);
      continue;
    }
    uint32_t entry = static_cast<uint32_t>(size);
    if (use_zstd) {
      payload.insert(payload.end(), frame.data(), frame.data() + zstd_size);
    } else {
      pack_plane(values, packed.width, payload);
      entry |= kPackedPlaneFlag;
      any_packed = true;
    }
    std::memcpy(payload.data() + 4 * p, &entry, 4);
  }
  codec = any_packed ? ChunkCodec::Packed : ChunkCodec::Zstd;
  if (payload.size() >= raw.size()) {  // nothing shrank: store the planes, no table
    payload = std::move(raw);
    codec = ChunkCodec::Stored;
  }
}

// Finds (and decompresses where needed, into `raw`) every plane of a chunk payload.
void locate_planes(std::span<const std::byte> payload, ChunkCodec codec, size_t n, size_t planes, ZSTD_DCtx* zstd,
                   std::vector<std::byte>& raw, std::vector<const uint8_t*>& out, const ErrorLocation& where) {
  thread_local std::vector<PlaneSource> sources;
  read_plane_table(payload, 0, codec, n, planes, sources, where);
  out.resize(planes);
  if (codec != ChunkCodec::Stored && raw.size() < n * planes) raw.resize(n * planes);
  for (size_t p = 0; p < planes; ++p) {
    const PlaneSource& s = sources[p];
    const std::byte* src = payload.data() + s.at;
    if (s.kind == PlaneSource::Stored) {
      out[p] = reinterpret_cast<const uint8_t*>(src);
      continue;
    }
    const std::string what = "plane " + std::to_string(p);
    std::byte* dst = raw.data() + p * n;
    if (s.kind == PlaneSource::Packed) {
      unpack_plane({src, s.size}, n, reinterpret_cast<uint8_t*>(dst), where, what);
    } else {
      const size_t got = ZSTD_decompressDCtx(zstd, dst, n, src, s.size);
      if (ZSTD_isError(got)) throw Error(where, what + ": zstd: " + ZSTD_getErrorName(got));
      if (got != n) {
        throw Error(where, what + " decompressed to " + std::to_string(got) + " bytes, expected " + std::to_string(n));
      }
    }
    out[p] = reinterpret_cast<const uint8_t*>(dst);
  }
}

// The box of `members`' positions, its top widened until the decoder's
// float arithmetic maps the largest code inside it: then every decoded
// particle lies in the box.
Aabb box_of(const FrameInput& in, std::span<const uint32_t> members) {
  Aabb box;
  for (uint32_t p : members) box.extend(in.positions[3 * p], in.positions[3 * p + 1], in.positions[3 * p + 2]);
  for (int a = 0; a < 3; ++a) {
    while (dequantize(65535, box.min[a], box.max[a]) > box.max[a]) {
      box.max[a] = std::nextafter(box.max[a], std::numeric_limits<float>::infinity());
    }
  }
  return box;
}

// `box` holds every member: the chunk's own, or its cell's when the chunk is
// one LOD tier of a cell (every tier of a cell is quantized in one box, so a
// particle decodes to the same position whichever tiers are read).
EncodedChunk encode_chunk(const FrameInput& in, std::span<const uint32_t> members, const Aabb& box, PositionCoding coding,
                          const EncodeOptions& options, bool split = false) {
  const size_t n = members.size();
  const size_t attributes = in.attributes.size();
  EncodedChunk out;
  ChunkDesc& desc = out.desc;
  desc.particle_count = static_cast<uint32_t>(n);
  desc.bounds = box;  // box_of(): already widened

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

  // Split: the fine planes go to the fine part, not the record.
  const uint64_t raw_size = raw_chunk_bytes(coding, n, attributes) - (split ? 2 * n : 0);
  std::vector<std::byte> raw(raw_size);
  std::byte* planes = raw.data();
  if (split) {
    // The record: the deltas of the codes' high 32 bits (non-negative: the
    // codes are sorted); the fine part: their low 16 bits as they are
    // (noise, stored, on scattered data; lattice-like data codes them small).
    std::vector<std::byte> fine(2 * n);
    uint64_t previous = 0;
    for (size_t i = 0; i < n; ++i) {
      const uint64_t high = sorted[i].first >> kFineCodeBits;
      put_planes(planes, n, i, high - previous, 4);
      put_planes(fine.data(), n, i, sorted[i].first & ((uint64_t{1} << kFineCodeBits) - 1), 2);
      previous = high;
    }
    planes += 4 * n;
    compress_planes(fine, n, options, out.fine, desc.fine.codec);
    desc.fine.size = static_cast<uint32_t>(out.fine.size());
    desc.fine.checksum = checksum(out.fine);
  } else if (coding == PositionCoding::Quantized16) {
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
  compress_planes(raw, n, options, out.payload, desc.codec);
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


// A frame without some of its particles (a copy: the far particles are
// rare, and only frames that have some pay for it).
struct FrameCopy {
  std::vector<float> positions;
  std::vector<uint16_t> lod;
  std::vector<std::vector<float>> attributes;
  FrameInput input;

  FrameCopy(const FrameInput& in, std::span<const uint32_t> dropped) {
    const size_t n = in.positions.size() / 3;
    std::vector<bool> drop(n);
    for (uint32_t i : dropped) drop[i] = true;
    positions.reserve(3 * (n - dropped.size()));
    lod.reserve(n - dropped.size());
    attributes.resize(in.attributes.size());
    for (size_t i = 0; i < n; ++i) {
      if (drop[i]) continue;
      positions.insert(positions.end(), &in.positions[3 * i], &in.positions[3 * i] + 3);
      lod.push_back(in.lod[i]);
      for (size_t a = 0; a < attributes.size(); ++a) attributes[a].push_back(in.attributes[a][i]);
    }
    input.positions = positions;
    input.lod = lod;
    for (const auto& a : attributes) input.attributes.emplace_back(a);
    input.time = in.time;
  }
};

// One layer's records: which of `in`'s particles, in which chunks.
struct Group {
  const FrameInput* in;
  std::vector<uint32_t> order;  // indices into in, chunk by chunk
  std::vector<ChunkPlan::Range> chunks;
  Layer layer;
};

Group plan_group(const FrameInput& in, std::span<const uint32_t> members, Layer layer, uint32_t limit, float extent) {
  std::vector<float> xyz(3 * members.size());
  Aabb box;
  for (size_t k = 0; k < members.size(); ++k) {
    for (int a = 0; a < 3; ++a) xyz[3 * k + a] = in.positions[3 * size_t(members[k]) + a];
    box.extend(xyz[3 * k], xyz[3 * k + 1], xyz[3 * k + 2]);
  }
  ChunkPlan plan = plan_chunks(xyz, box, limit, extent);
  for (uint32_t& i : plan.order) i = members[i];
  return {&in, std::move(plan.order), std::move(plan.chunks), layer};
}

Group plan_all(const FrameInput& in, const Aabb& bounds, uint32_t limit, float extent) {
  ChunkPlan plan = plan_chunks(in.positions, bounds, limit, extent);
  return {&in, std::move(plan.order), std::move(plan.chunks), Layer::All};
}

// One job per record: a chunk, or LOD tiers of it.
struct Job {
  const Group* group;
  ChunkPlan::Range range;
  uint32_t cell;  // the chunk's index in `cells`
  uint8_t tier;
  bool continues_cell;
};
struct Cell {
  Group* group;
  ChunkPlan::Range range;
  Aabb box;
  std::array<uint32_t, kLodTiers + 1> first{};  // tier t: members [first[t], first[t + 1]) of the range
};

// A cell written as tiers costs more bytes than written whole (sparser
// Morton deltas, attribute deltas between less similar neighbours, a zstd
// frame per plane and a table entry per record): on lattice-like data up
// to 2.3x (the bundled dam break's first frame). Where that cost exceeds
// kMostTierCost the cell is written whole, as one record of tier 0: a
// reader then reads all of it when it reads any. The sizes compared are
// those of the default coding whatever the options, so a file's layout
// depends on its data only (--smallest and --gpu-decodable files of the
// same frames hold the same records).
constexpr double kMostTierCost = 0.08;
// Blobs sit on the voxel grid, lattice-like: tiers cost them 10-15%, but
// they are a third of what a player reads (the sloshing pool), so they are
// tiered unless that doubles them.
constexpr double kMostBlobTierCost = 1.0;

bool default_coding(const EncodeOptions& o) { return o.planes == PlaneCoding::Packed; }

std::vector<EncodedChunk> keep_tiers_that_pay(std::vector<EncodedChunk> records, const std::vector<Job>& jobs,
                                              const std::vector<Cell>& cells, const FileHeader& header,
                                              const EncodeOptions& options) {
  const size_t desc = chunk_desc_bytes(header.attributes.size());
  EncodeOptions reference = options;
  reference.planes = PlaneCoding::Packed;
  const bool same = default_coding(options);
  std::vector<uint32_t> count(cells.size(), 0);
  for (const Job& j : jobs) ++count[j.cell];
  std::vector<uint32_t> split;  // cells of more than one record
  for (uint32_t c = 0; c < cells.size(); ++c) {
    if (count[c] > 1) split.push_back(c);
  }
  if (split.empty()) return records;
  // Record sizes in the reference coding.
  std::vector<uint64_t> sizes(records.size());
  tbb::parallel_for(size_t(0), records.size(), [&](size_t r) {
    if (same || count[jobs[r].cell] < 2) {
      sizes[r] = records[r].payload.size();
      return;
    }
    const Job& j = jobs[r];
    sizes[r] = encode_chunk(*j.group->in, std::span(j.group->order).subspan(j.range.begin, j.range.end - j.range.begin),
                            cells[j.cell].box, header.position_coding, reference)
                   .payload.size();
  });
  std::vector<uint64_t> tiered(cells.size(), 0);
  for (size_t r = 0; r < records.size(); ++r) tiered[jobs[r].cell] += sizes[r] + desc;
  std::vector<EncodedChunk> whole(split.size());
  std::vector<uint8_t> chosen(split.size(), 0);
  tbb::parallel_for(size_t(0), split.size(), [&](size_t k) {
    const Cell& cell = cells[split[k]];
    const std::span<const uint32_t> members =
        std::span(cell.group->order).subspan(cell.range.begin, cell.range.end - cell.range.begin);
    whole[k] = encode_chunk(*cell.group->in, members, cell.box, header.position_coding, reference);
    const double most = cell.group->layer == Layer::Blobs ? kMostBlobTierCost : kMostTierCost;
    chosen[k] = double(tiered[split[k]]) > double(whole[k].payload.size() + desc) * (1.0 + most);
    if (chosen[k] && !same) whole[k] = encode_chunk(*cell.group->in, members, cell.box, header.position_coding, options);
    whole[k].desc.layer = cell.group->layer;
  });
  std::vector<int64_t> replacement(cells.size(), -1);
  for (size_t k = 0; k < split.size(); ++k) {
    if (chosen[k]) replacement[split[k]] = int64_t(k);
  }
  std::vector<EncodedChunk> out;
  out.reserve(records.size());
  for (size_t r = 0; r < records.size(); ++r) {
    const int64_t k = replacement[jobs[r].cell];
    if (k < 0) {
      out.push_back(std::move(records[r]));
    } else if (!jobs[r].continues_cell) {
      out.push_back(std::move(whole[size_t(k)]));
    }
  }
  return out;
}


// ---- Format 2.0: a frame ordered coarse to fine (docs/format.md, "Layout of a frame").

// One set of a layer's particles chunked on its own (the bulk; far particles).
struct MemberSet {
  const FrameInput* in;
  std::vector<uint32_t> ids;
  std::vector<uint8_t> tiers;  // of each id
};

// Tiers first ... last written as one record (tiers under kLeastTierRecord
// particles in the layer join the next).
struct TierSpan {
  uint8_t first, last;
};

// A blob's tier is written from its source centroid with twice the reader's
// margin; its records' boxes are kept narrow enough that the decoded
// centroid lies within 0.9e-3 of a side of the source: any cell the GPU may
// find for it is then among those the bound looked at (lod.h).
constexpr double kBlobTierMargin = 2e-3;
constexpr float kBlobBoxVoxels = 100.f;  // 100 / 131070 < 0.9e-3

std::vector<uint8_t> tiers_of(const FrameInput& in, std::span<const uint32_t> ids, Layer layer, float voxel) {
  std::vector<uint8_t> tiers(ids.size());
  tbb::parallel_for(size_t(0), ids.size(), [&](size_t k) {
    const size_t i = ids[k];
    if (layer == Layer::Blobs) {
      const float* p = &in.positions[3 * i];
      tiers[k] = static_cast<uint8_t>(lod_tier_of_uniform(blob_lod_uniform_bound(p[0], p[1], p[2], voxel, kBlobTierMargin)));
    } else {
      tiers[k] = static_cast<uint8_t>(lod_tier(in.lod[i]));
    }
  });
  return tiers;
}

std::vector<TierSpan> tier_spans(const std::vector<MemberSet>& sets) {
  std::array<uint64_t, kLodTiers> count{};
  for (const MemberSet& m : sets) {
    for (uint8_t t : m.tiers) ++count[t];
  }
  std::vector<TierSpan> spans;
  uint32_t t = 0;
  while (t < kLodTiers) {
    uint64_t sum = count[t];
    uint32_t last = t;
    while (last + 1 < kLodTiers && sum < kLeastTierRecord) sum += count[++last];
    if (sum > 0) {
      if (!spans.empty() && sum < kLeastTierRecord) {
        spans.back().last = static_cast<uint8_t>(last);  // a small tail joins the span before
      } else {
        spans.push_back({static_cast<uint8_t>(t), static_cast<uint8_t>(last)});
      }
    }
    t = last + 1;
  }
  return spans;
}

// A layer's records for the given spans: span by span, set by set, each
// span's particles of a set chunked on their own along the Morton curve.
std::vector<EncodedChunk> encode_spans(const std::vector<MemberSet>& sets, const std::vector<TierSpan>& spans, Layer layer,
                                       const FileHeader& header, const EncodeOptions& options, uint32_t limit,
                                       float extent) {
  std::vector<Group> groups;
  std::vector<TierSpan> group_span;
  groups.reserve(spans.size() * sets.size());
  for (const TierSpan& span : spans) {
    for (const MemberSet& m : sets) {
      std::vector<uint32_t> members;
      for (size_t k = 0; k < m.ids.size(); ++k) {
        if (m.tiers[k] >= span.first && m.tiers[k] <= span.last) members.push_back(m.ids[k]);
      }
      if (members.empty()) continue;
      groups.push_back(plan_group(*m.in, members, layer, limit, extent));
      group_span.push_back(span);
    }
  }
  struct Piece {
    size_t group;
    ChunkPlan::Range range;
  };
  std::vector<Piece> pieces;
  for (size_t g = 0; g < groups.size(); ++g) {
    for (const ChunkPlan::Range& r : groups[g].chunks) pieces.push_back({g, r});
  }
  std::vector<EncodedChunk> records(pieces.size());
  tbb::parallel_for(size_t(0), pieces.size(), [&](size_t c) {
    const Group& g = groups[pieces[c].group];
    const std::span<const uint32_t> members =
        std::span(g.order).subspan(pieces[c].range.begin, pieces[c].range.end - pieces[c].range.begin);
    records[c] = encode_chunk(*g.in, members, box_of(*g.in, members), header.position_coding, options,
                              splits_positions(header, options));
    records[c].desc.layer = layer;
    records[c].desc.tier = group_span[pieces[c].group].first;
    records[c].desc.last_tier = group_span[pieces[c].group].last;
  });
  return records;
}

uint64_t bytes_of(const std::vector<EncodedChunk>& records, size_t desc) {
  uint64_t bytes = 0;
  for (const EncodedChunk& r : records) bytes += r.bytes() + desc;
  return bytes;
}

// One layer, tiered where tiers pay: on lattice-like data (the bundled dam
// break's first frames) a tier's sparser particles cost far more bytes than
// the layer written whole, and the layer is then one tier (0 ... 11).
// Judged on the default coding's sizes whatever the options, so that
// `--smallest` and `--gpu-decodable` files of the same frames hold the same
// records.
std::vector<EncodedChunk> encode_layer(std::vector<MemberSet>& sets, Layer layer, const FileHeader& header,
                                       const EncodeOptions& options, uint32_t limit, float extent, float voxel) {
  const std::vector<TierSpan> whole{{0, uint8_t(kLodTiers - 1)}};
  const bool tiered = options.lod_tiers && options.planes != PlaneCoding::Stored;
  if (!tiered) {
    for (MemberSet& m : sets) m.tiers.assign(m.ids.size(), 0);
    return encode_spans(sets, whole, layer, header, options, limit, extent);
  }
  for (MemberSet& m : sets) m.tiers = tiers_of(*m.in, m.ids, layer, voxel);
  const std::vector<TierSpan> spans = tier_spans(sets);
  if (spans.size() <= 1) return encode_spans(sets, whole, layer, header, options, limit, extent);
  EncodeOptions reference = options;
  reference.planes = PlaneCoding::Packed;
  std::vector<EncodedChunk> by_tiers = encode_spans(sets, spans, layer, header, reference, limit, extent);
  std::vector<EncodedChunk> at_once = encode_spans(sets, whole, layer, header, reference, limit, extent);
  const size_t desc = chunk_desc_bytes(header.attributes.size());
  const double most = layer == Layer::Blobs ? kMostBlobTierCost : kMostTierCost;
  const bool pays = double(bytes_of(by_tiers, desc)) <= double(bytes_of(at_once, desc)) * (1.0 + most);
  if (default_coding(options)) return pays ? std::move(by_tiers) : std::move(at_once);
  return encode_spans(sets, pays ? spans : whole, layer, header, options, limit, extent);
}

// The records of a coarse-to-fine frame, in file order.
std::vector<EncodedChunk> encode_coarse_to_fine(const FrameInput& body, const FrameInput& in, const FarParticles& far,
                                                const LayeredFrame* layered, const FrameInput& blobs, float voxel,
                                                const FileHeader& header, const EncodeOptions& options, uint32_t limit,
                                                float extent) {
  std::vector<EncodedChunk> out;
  auto add = [&](std::vector<MemberSet> sets, Layer layer, float layer_extent) {
    std::erase_if(sets, [](const MemberSet& m) { return m.ids.empty(); });
    if (sets.empty()) return;
    std::vector<EncodedChunk> records = encode_layer(sets, layer, header, options, limit, layer_extent, voxel);
    for (EncodedChunk& r : records) out.push_back(std::move(r));
  };
  auto every = [](size_t n) {
    std::vector<uint32_t> ids(n);
    for (uint32_t i = 0; i < n; ++i) ids[i] = i;
    return ids;
  };
  if (layered) {
    add({{&body, layered->surface, {}}, {&in, far.far, {}}}, Layer::Surface, extent);
    add({{&blobs, every(layered->blobs.counts.size()), {}}}, Layer::Blobs, std::min(extent, kBlobBoxVoxels * voxel));
    add({{&body, layered->interior, {}}}, Layer::Interior, extent);
  } else {
    add({{&body, every(body.positions.size() / 3), {}}, {&in, far.far, {}}}, Layer::All, extent);
  }
  return out;
}

// Format 1.x: each cell's tiers together (docs/format.md, "LOD tiers").
std::vector<EncodedChunk> encode_cells(const FrameInput& in, const FrameInput& body, const FarParticles& far,
                                       const LayeredFrame* layered_frame, const FrameInput& blobs, float voxel,
                                       const FileHeader& header, const EncodeOptions& options, uint32_t limit,
                                       float extent) {
  std::vector<Group> groups;
  if (layered_frame) {
    const LayeredFrame& layered = *layered_frame;
    // Payload order: surface, far particles (alone: surface too), blobs,
    // interior (what is read by default first).
    groups.push_back(plan_group(body, layered.surface, Layer::Surface, limit, extent));
    if (!far.far.empty()) groups.push_back(plan_group(in, far.far, Layer::Surface, limit, extent));
    std::vector<uint32_t> every_blob(layered.blobs.counts.size());
    for (uint32_t b = 0; b < every_blob.size(); ++b) every_blob[b] = b;
    groups.push_back(plan_group(blobs, every_blob, Layer::Blobs, limit, extent));
    groups.push_back(plan_group(body, layered.interior, Layer::Interior, limit, extent));
  } else {
    groups.push_back(plan_all(body, far.bulk, limit, extent));
    if (!far.far.empty()) groups.push_back(plan_group(in, far.far, Layer::All, limit, extent));
  }

  // One job per record: a chunk, or one LOD tier of it. Tiers reorder the
  // chunk's members by tier (counting sort, stable) so each is a range.
  std::vector<Cell> cells;
  for (Group& g : groups) {
    for (const auto& r : g.chunks) cells.push_back({&g, r, {}, {}});
  }
  tbb::parallel_for(size_t(0), cells.size(), [&](size_t c) {
    Cell& cell = cells[c];
    const FrameInput& source = *cell.group->in;
    const std::span<uint32_t> members = std::span(cell.group->order).subspan(cell.range.begin, cell.range.end - cell.range.begin);
    cell.box = box_of(source, members);
    // Stored frames (not kept: decoded at once) gain nothing from tiers.
    if (!options.lod_tiers || options.planes == PlaneCoding::Stored) {
      cell.first.fill(uint32_t(members.size()));
      cell.first[0] = 0;
      return;
    }
    std::vector<uint8_t> tiers(members.size());
    if (cell.group->layer == Layer::Blobs) {
      // A blob's random term hashes the world cell of its decoded centroid.
      std::array<double, 3> inv{};
      for (int a = 0; a < 3; ++a) inv[size_t(a)] = inverse_step(cell.box.min[size_t(a)], cell.box.max[size_t(a)]);
      for (size_t k = 0; k < members.size(); ++k) {
        float p[3];
        for (int a = 0; a < 3; ++a) {
          const uint16_t q = quantize(source.positions[3 * size_t(members[k]) + size_t(a)], cell.box.min[size_t(a)], inv[size_t(a)]);
          p[a] = dequantize(q, cell.box.min[size_t(a)], cell.box.max[size_t(a)]);
        }
        tiers[k] = static_cast<uint8_t>(lod_tier_of_uniform(blob_lod_uniform_bound(p[0], p[1], p[2], voxel)));
      }
    } else {
      for (size_t k = 0; k < members.size(); ++k) tiers[k] = static_cast<uint8_t>(lod_tier(source.lod[members[k]]));
    }
    for (uint8_t t : tiers) ++cell.first[t + 1u];
    for (uint32_t t = 0; t < kLodTiers; ++t) cell.first[t + 1] += cell.first[t];
    std::vector<uint32_t> sorted(members.size());
    std::array<uint32_t, kLodTiers> at{};
    std::copy(cell.first.begin(), cell.first.begin() + kLodTiers, at.begin());
    for (size_t k = 0; k < members.size(); ++k) sorted[at[tiers[k]]++] = members[k];
    std::copy(sorted.begin(), sorted.end(), members.begin());
  });
  // Tiers smaller than kLeastTierRecord particles join the tiers after them
  // in one record labelled with the first (a reader that needs that tier
  // reads a little more); a small last record joins the one before. Small
  // records cost more than they save: every plane's zstd frame and table
  // entry, and sparser Morton deltas (docs/format.md, "LOD tiers").
  std::vector<Job> jobs;
  for (uint32_t c = 0; c < cells.size(); ++c) {
    const uint32_t base = cells[c].range.begin;
    const size_t cell_first_job = jobs.size();
    uint32_t t = 0;
    while (t < kLodTiers) {
      const uint32_t begin = cells[c].first[t];
      uint32_t end_tier = t + 1;
      while (end_tier < kLodTiers && cells[c].first[end_tier] - begin < kLeastTierRecord) ++end_tier;
      const uint32_t end = cells[c].first[end_tier];
      if (end > begin) {
        const bool continues = jobs.size() > cell_first_job;
        if (continues && end - begin < kLeastTierRecord) {
          jobs.back().range.end = base + end;  // a small tail: into the record before
        } else {
          jobs.push_back({cells[c].group, {base + begin, base + end}, c, static_cast<uint8_t>(t), continues});
        }
      }
      t = end_tier;
    }
  }
  std::vector<EncodedChunk> records(jobs.size());
  tbb::parallel_for(size_t(0), records.size(), [&](size_t c) {
    const Job& j = jobs[c];
    records[c] = encode_chunk(*j.group->in, std::span(j.group->order).subspan(j.range.begin, j.range.end - j.range.begin),
                              cells[j.cell].box, header.position_coding, options);
    records[c].desc.layer = j.group->layer;
    records[c].desc.tier = j.tier;
    records[c].desc.continues_cell = j.continues_cell;
  });
  return keep_tiers_that_pay(std::move(records), jobs, cells, header, options);
}

// Places the records after the table and serializes the frame: each
// layer's records, then (format 3.0) their fine parts in the same order, as
// serialize_frame_table lists them.
EncodedFrame finish_frame(EncodedFrame frame, std::vector<EncodedChunk> chunks, size_t attributes) {
  FrameHeader& fh = frame.header;
  for (EncodedChunk& c : chunks) {
    fh.particle_count += c.desc.particle_count;
    frame.raw_bytes += c.raw_bytes;
    fh.split_positions = fh.split_positions || c.desc.fine.split();
    fh.chunks.push_back(c.desc);
  }
  uint64_t offset = frame_table_bytes(fh.table_records(), attributes);
  uint32_t index = 0;
  std::vector<const std::vector<std::byte>*> payloads;
  payloads.reserve(fh.table_records());
  for (size_t first = 0; first < chunks.size();) {
    size_t end = first;
    while (end < chunks.size() && chunks[end].desc.layer == chunks[first].desc.layer) {
      ChunkDesc& d = fh.chunks[end];
      d.index = index++;
      d.offset = offset;
      offset += d.compressed_size;
      payloads.push_back(&chunks[end++].payload);
    }
    for (size_t c = first; c < end; ++c) {
      ChunkDesc::Fine& fine = fh.chunks[c].fine;
      if (!fine.split()) continue;
      fine.index = index++;
      fine.offset = offset;
      offset += fine.size;
      payloads.push_back(&chunks[c].fine);
    }
    first = end;
  }
  fh.frame_bytes = offset;
  if (!fh.coarse_to_fine) set_last_tiers(fh.chunks);
  frame.record = serialize_frame_table(fh, attributes);
  frame.record.reserve(offset);
  for (const std::vector<std::byte>* p : payloads) frame.record.insert(frame.record.end(), p->begin(), p->end());
  return frame;
}

}  // namespace

EncodedFrame encode_frame(const FrameInput& in, const FileHeader& header, const EncodeOptions& options) {
  check_input(in, header);
  EncodedFrame frame;
  FrameHeader& fh = frame.header;
  fh.time = in.time;
  // Far particles (point_set.h) are chunked, and kept out of the frame's
  // display bounds and of the narrow band's grid, on their own: among the
  // rest they would widen a chunk's box, and so its quantization step.
  const FarParticles far = find_far_particles(in.positions, header.particle_spacing);
  fh.bounds = far.bulk;
  frame.far = report_far(far, in.positions, false);
  std::optional<FrameCopy> bulk;
  if (!far.far.empty()) bulk.emplace(in, far.far);
  const FrameInput& body = bulk ? bulk->input : in;
  const size_t body_count = body.positions.size() / 3;

  const uint32_t limit = std::clamp<uint32_t>(options.chunk_particles, 1, kMaxChunkParticles);
  const float extent = chunk_extent_limit(header);
  LayeredFrame layered;
  FrameInput blobs;
  const bool layers = options.layers && header.particle_spacing > 0 &&
                      header.position_coding == PositionCoding::Quantized16 && body_count > 0;
  if (layers) {
    layered = split_layers(body, header.particle_spacing, options.band_voxel, options.band_f2);
    blobs = layered.blobs.input();
    fh.blob_voxel = layered.blobs.counts.empty() ? 0.f : layered.voxel;
  }
  std::vector<EncodedChunk> chunks;
  if (header.version_major >= 2) {
    fh.coarse_to_fine = true;
    chunks = encode_coarse_to_fine(body, in, far, layers ? &layered : nullptr, blobs, fh.blob_voxel, header, options,
                                   limit, extent);
  } else {
    chunks = encode_cells(in, body, far, layers ? &layered : nullptr, blobs, fh.blob_voxel, header, options, limit, extent);
  }
  return finish_frame(std::move(frame), std::move(chunks), header.attributes.size());
}


void set_frame_number(EncodedFrame& frame, uint32_t frame_number, size_t attribute_count) {
  frame.header.frame_number = frame_number;
  const std::vector<std::byte> table = serialize_frame_table(frame.header, attribute_count);
  std::copy(table.begin(), table.end(), frame.record.begin());
}

namespace {

// planes[0..1]: the fine part's two planes (checked), or without it bytes
// of kCoarseFill (held in the scratch, past the record's inflated planes).
void locate_fine(std::span<const std::byte> record, const ChunkDesc& chunk, DecodeScratch::State& s,
                 std::vector<const uint8_t*>& planes, const ErrorLocation& where) {
  const size_t n = chunk.particle_count;
  if (chunk.fine.read()) {
    const ChunkDesc::Fine& fine = chunk.fine;
    const auto what = [&] { return "fine part (table record " + std::to_string(fine.index) + ")"; };  // only on error: it allocates
    if (fine.offset > record.size() || fine.size > record.size() - fine.offset) {
      throw Error(where, "the " + what() + " lies outside the frame record");
    }
    const std::span<const std::byte> bytes = record.subspan(fine.offset, fine.size);
    if (checksum(bytes) != fine.checksum) throw Error(where, what() + " checksum mismatch (its bytes are corrupt)");
    // Its planes inflate into a scratch of their own: the record's hold the rest.
    locate_planes(bytes, fine.codec, n, 2, s.zstd, s.fine.raw, s.fine.planes, where);
    planes[0] = s.fine.planes[0];
    planes[1] = s.fine.planes[1];
    return;
  }
  if (s.fill_n != n) {
    s.fill.resize(2 * n);
    std::fill(s.fill.begin(), s.fill.begin() + std::ptrdiff_t(n), std::byte(uint8_t(kCoarseFill & 0xff)));
    std::fill(s.fill.begin() + std::ptrdiff_t(n), s.fill.end(), std::byte(uint8_t(kCoarseFill >> 8)));
    s.fill_n = n;
  }
  planes[0] = reinterpret_cast<const uint8_t*>(s.fill.data());
  planes[1] = planes[0] + n;
}

}  // namespace

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

  const bool split = chunk.fine.split();
  if (split && coding != PositionCoding::Quantized16) throw Error(where, "a record of float32 positions has a fine part");
  DecodeScratch::State& state = scratch.state();
  std::vector<const uint8_t*>& planes = state.planes;
  // Split positions: the record's planes after two for the fine part's.
  const size_t fine_planes = split ? 2 : 0;
  const size_t plane_count = raw_chunk_bytes(coding, 1, attributes) - fine_planes;
  locate_planes(payload, chunk.codec, n, plane_count, state.zstd, state.raw, planes, where);
  if (split) {
    planes.insert(planes.begin(), 2, nullptr);
    locate_fine(record, chunk, state, planes, where);
  }
  const size_t first_lod = coding == PositionCoding::Quantized16 ? 6 : 12;
  const uint8_t* lod_lo = planes[first_lod];
  const uint8_t* lod_hi = planes[first_lod + 1];
  if (split) {
    unpack_split16(planes.data(), n, out.particles.data());
  } else if (coding == PositionCoding::Quantized16) {
    unpack_quantized16(planes.data(), n, out.particles.data());
  } else {
    auto* dst = reinterpret_cast<uint32_t*>(out.particles.data());
    for (size_t i = 0; i < n; ++i) {
      for (size_t a = 0; a < 3; ++a) {
        const uint8_t* const* p = &planes[4 * a];
        dst[4 * i + a] = uint32_t(p[0][i]) | uint32_t(p[1][i]) << 8 | uint32_t(p[2][i]) << 16 | uint32_t(p[3][i]) << 24;
      }
      dst[4 * i + 3] = uint32_t(lod_lo[i]) | uint32_t(lod_hi[i]) << 8;
    }
  }
  for (size_t a = 0; a < attributes && a < out.attributes.size(); ++a) {
    uint16_t* dst = out.attributes[a];
    if (dst == nullptr) continue;
    const uint8_t* lo = planes[first_lod + 2 + 2 * a];
    const uint8_t* hi = planes[first_lod + 3 + 2 * a];
    uint16_t q = 0;
    for (size_t i = 0; i < n; ++i) {
      q = uint16_t(q + (lo[i] | hi[i] << 8));
      dst[i] = q;
    }
  }
}

}  // namespace sluice::io

namespace sluice::io {

uint64_t chunk_starts(const FrameHeader& header, std::span<uint64_t> out) {
  uint64_t first = 0;
  for (size_t c = 0; c < header.chunks.size() && c < out.size(); ++c) {
    out[c] = first;
    first += header.chunks[c].particle_count;
  }
  return first;
}

void decode_record(std::span<const std::byte> record, const FrameHeader& header, const FileHeader& file,
                   std::span<const uint64_t> starts, std::span<std::byte> particles, std::span<uint16_t* const> attributes,
                   const ErrorLocation& where) {
  const size_t stride = decoded_particle_bytes(file.position_coding);
  if (starts.size() != header.chunks.size() || particles.size() < header.particle_count * stride) {
    throw Error(where, "decode_record: the destination does not match the frame");
  }
  tbb::parallel_for(size_t(0), header.chunks.size(), [&](size_t c) {
    thread_local DecodeScratch scratch;
    thread_local std::vector<uint16_t*> bases;
    const ChunkDesc& chunk = header.chunks[c];
    const uint64_t begin = starts[c];
    bases.assign(attributes.size(), nullptr);
    for (size_t a = 0; a < attributes.size(); ++a) {
      if (attributes[a]) bases[a] = attributes[a] + begin;
    }
    const ChunkDestination dest{particles.subspan(begin * stride, size_t(chunk.particle_count) * stride), bases};
    ErrorLocation at = where;  // copied only here: once per chunk of a load, not on the streaming path
    at.chunk = c;
    decode_chunk(record, chunk, file, dest, scratch, at);
  });
}

}  // namespace sluice::io
