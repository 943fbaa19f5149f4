#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "bytes.h"
#include "records.h"
#include "sluice/io/lod.h"

namespace sluice::io {
namespace {

void write_aabb(ByteWriter& w, const Aabb& b) {
  for (float v : b.min) w.f32(v);
  for (float v : b.max) w.f32(v);
}

Aabb read_aabb(ByteReader& r) {
  Aabb b;
  for (float& v : b.min) v = r.f32();
  for (float& v : b.max) v = r.f32();
  return b;
}

// A stored box must be finite and ordered, or the canonical empty box.
void check_aabb(const ByteReader& r, const Aabb& b, bool allow_empty, const char* what) {
  if (allow_empty && Aabb{}.min == b.min && Aabb{}.max == b.max) return;
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(b.min[a]) || !std::isfinite(b.max[a])) r.fail(std::string(what) + " bounds are not finite");
    if (b.min[a] > b.max[a]) r.fail(std::string(what) + " bounds have min > max");
  }
}

void check_range(const ByteReader& r, const std::array<float, 2>& range) {
  if (!std::isfinite(range[0]) || !std::isfinite(range[1]) || range[0] > range[1]) {
    r.fail("attribute range is not finite and ordered");
  }
}

// The header's flags word (format 1.2): bits 0-2 up axis, 3-5 how it was
// found, 6-7 the time source; format 1.5: bits 8-13 the position bound's
// exponent; the rest stays 0 for later minor versions.
uint32_t header_flags(const FileHeader& h) {
  return uint32_t(h.up) | uint32_t(h.up_evidence) << 3 | uint32_t(h.time_source) << 6 |
         uint32_t(h.precision_bits & 63) << 8;
}

void read_header_flags(ByteReader& r, FileHeader& h) {
  const uint32_t flags = r.u32();
  const uint32_t up = flags & 7, evidence = (flags >> 3) & 7, time = (flags >> 6) & 3;
  if (up > uint32_t(UpAxis::NegZ)) r.fail("unknown up axis code " + std::to_string(up));
  if (evidence > uint32_t(UpEvidence::Default)) r.fail("unknown up-axis evidence code " + std::to_string(evidence));
  h.up = static_cast<UpAxis>(up);
  h.up_evidence = static_cast<UpEvidence>(evidence);
  h.time_source = static_cast<TimeSource>(time);
  h.precision_bits = static_cast<uint8_t>((flags >> 8) & 63);
}

}  // namespace

float position_bound(const FileHeader& h) {
  if (h.position_coding == PositionCoding::Float32) return 0.0f;
  if (h.precision_bits == 0 || !(h.particle_spacing > 0)) return INFINITY;
  return std::ldexp(h.particle_spacing, -int(h.precision_bits));
}

float chunk_extent_limit(const FileHeader& h) {
  const float bound = position_bound(h);
  return bound > 0 ? bound * 131070.0f : INFINITY;
}

uint8_t precision_bits_for(double fraction) {
  if (!(fraction > 0)) return kDefaultPrecisionBits;
  const int k = int(std::ceil(-std::log2(fraction) - 1e-9));
  return uint8_t(std::clamp(k, 1, 40));
}

int axis_over_bound(const Aabb& box, float bound) {
  for (int a = 0; a < 3; ++a) {
    const float lo = box.min[size_t(a)], hi = box.max[size_t(a)];
    const float big = std::max(std::fabs(lo), std::fabs(hi));
    const double ulp = double(std::nextafter(big, INFINITY) - big);
    if ((double(hi) - double(lo)) / 131070.0 > double(bound) + 2.0 * ulp) return a;
  }
  return -1;
}

const char* time_source_name(TimeSource t) {
  switch (t) {
    case TimeSource::Input: return "input";
    case TimeSource::Step: return "step";
    case TimeSource::FrameNumber: return "frame number";
    default: return "unstated";
  }
}

bool times_stated(const FileHeader& h) { return h.time_source != TimeSource::FrameNumber; }

std::vector<std::byte> serialize_file_header(const FileHeader& h) {
  std::vector<std::byte> out;
  ByteWriter w(out);
  w.bytes(kFileMagic.data(), kFileMagic.size());
  w.u16(h.version_major);
  w.u16(h.version_minor);
  w.u32(0);  // header_bytes, patched below
  w.u8(static_cast<uint8_t>(h.position_coding));
  w.u8(static_cast<uint8_t>(h.lod_source));
  w.u16(static_cast<uint16_t>(h.attributes.size()));
  w.f32(h.particle_spacing);
  w.f32(h.particle_radius);
  w.f32(h.frame_rate);
  w.u32(header_flags(h));
  for (const AttributeInfo& a : h.attributes) {
    w.name(a.name);
    w.f32(a.declared_min);
    w.f32(a.declared_max);
  }
  w.text(h.lod_id_array);
  w.text(h.source);
  const auto total = static_cast<uint32_t>(out.size() + 8);
  std::memcpy(out.data() + 12, &total, 4);
  w.u64(checksum(out));
  return out;
}

std::vector<std::byte> serialize_header_copy(std::span<const std::byte> header) {
  std::vector<std::byte> out;
  out.reserve(4 + header.size());
  ByteWriter w(out);
  w.u32(kHeaderCopyMagic);
  w.bytes(header.data(), header.size());
  return out;
}

uint32_t peek_file_header_bytes(std::span<const std::byte> fixed, const ErrorLocation& where) {
  ByteReader r(fixed, where, "file header");
  std::array<uint8_t, 8> magic{};
  for (auto& m : magic) m = r.u8();
  if (magic != kFileMagic) r.fail("not a .sluice file (bad magic)");
  const uint16_t major = r.u16();
  const uint16_t minor = r.u16();
  if (major < kOldestMajor || major > kFormatMajor) {
    r.fail("format version " + std::to_string(major) + "." + std::to_string(minor) +
           " is not supported by this build (reads " + std::to_string(kOldestMajor) + ".x to " +
           std::to_string(kFormatMajor) + ".x)");
  }
  const uint32_t bytes = r.u32();
  if (bytes < kFileHeaderFixedBytes + 12 || bytes > kMaxHeaderBytes) {
    r.fail("header size " + std::to_string(bytes) + " is out of range");
  }
  return bytes;
}

FileHeader parse_file_header(std::span<const std::byte> bytes, const ErrorLocation& where) {
  const uint32_t total = peek_file_header_bytes(bytes, where);
  ByteReader r(bytes.first(std::min<size_t>(bytes.size(), total)), where, "file header");
  if (bytes.size() < total) r.fail("file is shorter than its header");
  uint64_t stored = 0;
  std::memcpy(&stored, bytes.data() + total - 8, 8);
  if (stored != checksum(bytes.first(total - 8))) r.fail("header checksum mismatch (the header is corrupt)");

  FileHeader h;
  r.skip(8);
  h.version_major = r.u16();
  h.version_minor = r.u16();
  r.u32();
  const uint8_t coding = r.u8();
  if (coding > 1) r.fail("unknown position coding " + std::to_string(coding));
  h.position_coding = static_cast<PositionCoding>(coding);
  const uint8_t lod = r.u8();
  if (lod > 1) r.fail("unknown LOD source " + std::to_string(lod));
  h.lod_source = static_cast<LodSource>(lod);
  const uint16_t attributes = r.u16();
  if (attributes > kMaxAttributes) r.fail("claims " + std::to_string(attributes) + " attributes (limit 32)");
  h.particle_spacing = r.f32();
  h.particle_radius = r.f32();
  h.frame_rate = r.f32();
  read_header_flags(r, h);
  h.attributes.resize(attributes);
  for (AttributeInfo& a : h.attributes) {
    a.name = r.name();
    a.declared_min = r.f32();
    a.declared_max = r.f32();
  }
  h.lod_id_array = r.text();
  h.source = r.text();
  if (r.position() != total - 8) r.fail("header size does not match its contents");
  return h;
}

namespace {

void write_desc(ByteWriter& w, const FrameHeader& f, const ChunkDesc& c, bool fine = false) {
  w.u64(c.offset);
  w.u32(c.compressed_size);
  w.u32(c.particle_count);
  w.u8(static_cast<uint8_t>(c.layer));
  w.u8(static_cast<uint8_t>(c.codec));
  w.u8(c.tier | (fine ? kFinePartFlag : 0));  // format 1.4; reserved (0) before. 3.0: bit 7, a fine part
  w.u8(f.coarse_to_fine ? c.last_tier : c.continues_cell ? 1 : 0);  // 2.0: last tier; 1.4: continues the cell
  write_aabb(w, c.bounds);
  w.u64(c.checksum);
  for (const auto& range : c.attribute_ranges) {
    w.f32(range[0]);
    w.f32(range[1]);
  }
}

// A fine part's record (format 3.0): its record's descriptor but for where
// its bytes lie and the codec.
void write_fine_desc(ByteWriter& w, const FrameHeader& f, const ChunkDesc& c) {
  ChunkDesc fine = c;
  fine.offset = c.fine.offset;
  fine.compressed_size = c.fine.size;
  fine.codec = c.fine.codec;
  fine.checksum = c.fine.checksum;
  write_desc(w, f, fine, true);
}

}  // namespace

std::vector<std::byte> serialize_frame_table(const FrameHeader& f, size_t attribute_count) {
  std::vector<std::byte> out;
  const uint32_t records = f.table_records();
  out.reserve(frame_table_bytes(records, attribute_count));
  ByteWriter w(out);
  w.u32(kFrameMagic);
  w.u32(f.frame_number);
  w.u64(f.frame_bytes);
  w.f64(f.time);
  w.u64(f.particle_count);
  w.u32(records);
  w.u32((f.coarse_to_fine ? kFrameCoarseToFine : 0) | (f.split_positions ? kFrameSplitPositions : 0));  // flags
  write_aabb(w, f.bounds);
  w.u32(static_cast<uint32_t>(attribute_count));
  w.f32(f.blob_voxel);  // format 1.3; reserved (0) before
  // Each layer's records, then (format 3.0) their fine parts in the same order.
  for (size_t first = 0; first < f.chunks.size();) {
    size_t end = first;
    while (end < f.chunks.size() && f.chunks[end].layer == f.chunks[first].layer) write_desc(w, f, f.chunks[end++]);
    for (size_t c = first; c < end; ++c) {
      if (f.chunks[c].fine.split()) write_fine_desc(w, f, f.chunks[c]);
    }
    first = end;
  }
  w.u64(checksum(out));
  return out;
}

namespace {

// Where a layer's records begin in a coarse-to-fine frame: surface (and
// unlayered) first, then blobs, then interior (the order views read them).
int layer_rank(Layer l) {
  switch (l) {
    case Layer::All: return 0;
    case Layer::Surface: return 0;
    case Layer::Blobs: return 1;
    default: return 2;
  }
}

// The rules of a coarse-to-fine table (docs/format.md, "Layout of a frame"):
// layers in their order, tiers rising within a layer, one tier's records
// holding the same tiers, a tier's records never overlapping the next's.
void check_coarse_to_fine(ByteReader& r, const ChunkDesc* before, const ChunkDesc& c) {
  if (c.last_tier < c.tier || c.last_tier >= kLodTiers) {
    r.fail("record holds tiers " + std::to_string(c.tier) + " to " + std::to_string(c.last_tier) +
           " (the last must lie in " + std::to_string(c.tier) + " to " + std::to_string(kLodTiers - 1) + ")");
  }
  if (!before) return;
  if (layer_rank(before->layer) > layer_rank(c.layer) || ((before->layer == Layer::All) != (c.layer == Layer::All))) {
    r.fail(std::string("a ") + layer_name(c.layer) + " record follows a " + layer_name(before->layer) +
           " record (a coarse-to-fine frame holds surface, blobs, interior, in that order)");
  }
  if (before->layer != c.layer) return;
  if (c.tier == before->tier) {
    if (c.last_tier != before->last_tier) r.fail("records of one tier hold different tiers (their last tiers differ)");
  } else if (c.tier <= before->last_tier) {
    r.fail("tier " + std::to_string(c.tier) + " follows a record of tiers " + std::to_string(before->tier) + " to " +
           std::to_string(before->last_tier) + " (tiers must rise within a layer)");
  }
}

}  // namespace

FramePrefix parse_frame_prefix(std::span<const std::byte> fixed, const ErrorLocation& where) {
  ByteReader r(fixed, where, "frame header");
  if (r.u32() != kFrameMagic) r.fail("bad frame magic (not at a frame boundary, or corrupt)");
  FramePrefix p{};
  p.frame_number = r.u32();
  p.frame_bytes = r.u64();
  r.f64();
  r.u64();
  p.chunk_count = r.u32();
  if (p.chunk_count > kMaxChunksPerFrame) r.fail("claims " + std::to_string(p.chunk_count) + " chunks");
  if (p.frame_bytes < frame_table_bytes(p.chunk_count, 0)) r.fail("frame size is smaller than its chunk table");
  return p;
}

FrameHeader parse_frame_table(std::span<const std::byte> record, size_t attribute_count,
                              const ErrorLocation& where) {
  FrameHeader f;
  parse_frame_table(record, attribute_count, where, f);
  return f;
}

namespace {

// A fine part's descriptor must describe its record (format 3.0): the
// same particles, layer, tiers, box and ranges.
void check_fine(ByteReader& r, const ChunkDesc& record, const ChunkDesc& fine) {
  const auto which = [&] {  // only on failure: it allocates, and tables are parsed every frame
    return "fine part (table record " + std::to_string(fine.index) + ") of record " + std::to_string(record.index);
  };
  if (fine.particle_count != record.particle_count || fine.layer != record.layer || fine.tier != record.tier ||
      fine.last_tier != record.last_tier || !(fine.bounds == record.bounds)) {
    r.fail(which() + " does not describe its record (count, layer, tiers or box differ)");
  }
  for (size_t a = 0; a < record.attribute_ranges.size(); ++a) {
    if (fine.attribute_ranges[a] != record.attribute_ranges[a]) r.fail(which() + " does not describe its record (ranges differ)");
  }
}

// Format 3.0: each layer's records are followed by their fine parts, one
// per record, in the same order. Folds each into its record's
// ChunkDesc::fine and leaves only the records in `chunks`. `fine_part[k]`:
// table record k is a fine part (descriptor byte 18 bit 7).
void fold_fine_parts(ByteReader& r, std::vector<ChunkDesc>& chunks, const std::vector<bool>& fine_part) {
  size_t out = 0;
  for (size_t first = 0; first < chunks.size();) {
    size_t records = first;
    while (records < chunks.size() && chunks[records].layer == chunks[first].layer && !fine_part[records]) ++records;
    const size_t count = records - first;
    if (count == 0) r.fail("a fine part (table record " + std::to_string(chunks[first].index) + ") precedes its layer's records");
    if (records + count > chunks.size()) r.fail("a layer's records lack their fine parts (the table ends first)");
    for (size_t k = 0; k < count; ++k) {
      const ChunkDesc& fine = chunks[records + k];
      if (!fine_part[records + k]) {
        r.fail("table record " + std::to_string(fine.index) + " stands where the fine part of record " +
               std::to_string(chunks[first + k].index) + " belongs");
      }
      check_fine(r, chunks[first + k], fine);
      chunks[first + k].fine = {.offset = fine.offset, .size = fine.compressed_size, .codec = fine.codec,
                                .checksum = fine.checksum, .index = fine.index, .dropped = false};
    }
    for (size_t k = 0; k < count; ++k) {
      if (out != first + k) chunks[out] = chunks[first + k];
      ++out;
    }
    first = records + count;
  }
  chunks.resize(out);
}

}  // namespace

void parse_frame_table(std::span<const std::byte> record, size_t attribute_count, const ErrorLocation& where,
                       FrameHeader& f) {
  const FramePrefix prefix = parse_frame_prefix(record, where);
  const uint64_t table = frame_table_bytes(prefix.chunk_count, attribute_count);
  ByteReader r(record, where, "frame header");
  if (table > record.size()) r.fail("frame record is truncated");
  uint64_t stored = 0;
  std::memcpy(&stored, record.data() + table - 8, 8);
  if (stored != checksum(record.first(table - 8))) r.fail("frame header checksum mismatch (corrupt header)");

  r.u32();
  f.frame_number = r.u32();
  f.frame_bytes = r.u64();
  f.time = r.f64();
  f.particle_count = r.u64();
  r.u32();
  const uint32_t flags = r.u32();
  if ((flags & ~(kFrameCoarseToFine | kFrameSplitPositions)) != 0) r.fail("unknown frame flags " + std::to_string(flags));
  f.coarse_to_fine = (flags & kFrameCoarseToFine) != 0;
  f.split_positions = (flags & kFrameSplitPositions) != 0;
  if (f.split_positions && !f.coarse_to_fine) r.fail("positions are split in a frame not ordered coarse to fine");
  f.bounds = read_aabb(r);
  check_aabb(r, f.bounds, true, "frame");
  if (r.u32() != attribute_count) r.fail("attribute count differs from the file header");
  f.blob_voxel = r.f32();
  if (!std::isfinite(f.blob_voxel) || f.blob_voxel < 0) r.fail("blob voxel side is not a finite size");
  f.chunks.resize(prefix.chunk_count);
  thread_local std::vector<bool> fine_part;  // per table record (3.0); kept per thread: no allocation per frame
  fine_part.assign(f.split_positions ? f.chunks.size() : 0, false);
  uint32_t index = 0;
  for (ChunkDesc& c : f.chunks) {
    c.index = index++;
    c.fine = {};
    c.offset = r.u64();
    c.compressed_size = r.u32();
    c.particle_count = r.u32();
    const uint8_t layer = r.u8();
    const uint8_t codec = r.u8();
    const uint8_t tier = r.u8();
    const uint8_t cell = r.u8();
    c.bounds = read_aabb(r);
    c.checksum = r.u64();
    c.attribute_ranges.resize(attribute_count);
    for (auto& range : c.attribute_ranges) {
      range[0] = r.f32();
      range[1] = r.f32();
      check_range(r, range);
    }
    if (layer >= kLayerCount) r.fail("unknown layer " + std::to_string(layer));
    if (codec > uint8_t(ChunkCodec::Packed)) r.fail("unknown chunk codec " + std::to_string(codec));
    c.layer = static_cast<Layer>(layer);
    c.codec = static_cast<ChunkCodec>(codec);
    if (c.particle_count == 0 || c.particle_count > kMaxChunkParticles) {
      r.fail("chunk particle count " + std::to_string(c.particle_count) + " is out of range");
    }
    check_aabb(r, c.bounds, false, "chunk");
    if (c.offset < table || c.offset > f.frame_bytes || c.compressed_size > f.frame_bytes - c.offset) {
      r.fail("chunk payload lies outside the frame record");
    }
    if (c.layer == Layer::Blobs && !(f.blob_voxel > 0)) r.fail("blob chunk in a frame without a blob voxel side");
    const bool fine = f.split_positions && (tier & kFinePartFlag) != 0;
    if (fine) fine_part[c.index] = true;
    const uint8_t t = fine ? uint8_t(tier & ~kFinePartFlag) : tier;
    if (t >= kLodTiers) r.fail("LOD tier " + std::to_string(t) + " is out of range (0 to " + std::to_string(kLodTiers - 1) + ")");
    c.tier = t;
    if (f.coarse_to_fine) {
      c.continues_cell = false;
      c.last_tier = cell;
    } else {
      if (cell > 1) r.fail("unknown cell flags " + std::to_string(cell));
      c.continues_cell = cell == 1;
    }
  }
  if (f.split_positions) fold_fine_parts(r, f.chunks, fine_part);
  uint64_t particles = 0;
  for (ChunkDesc& c : f.chunks) {
    const ChunkDesc* before = &c == f.chunks.data() ? nullptr : &c - 1;
    if (f.coarse_to_fine) {
      check_coarse_to_fine(r, before, c);
    } else if (c.continues_cell &&
               (!before || before->layer != c.layer || before->tier >= c.tier || !(before->bounds == c.bounds))) {
      r.fail("a record continues a cell it does not follow (tiers must rise within one layer and box)");
    }
    particles += c.particle_count;
  }
  if (particles != f.particle_count) r.fail("chunk particle counts do not add up to the frame's");
  if (!f.coarse_to_fine) set_last_tiers(f.chunks);
}

std::vector<std::byte> serialize_index(const FrameIndex& index, size_t attribute_count) {
  std::vector<std::byte> out;
  ByteWriter w(out);
  w.u32(kIndexMagic);
  w.u32(static_cast<uint32_t>(attribute_count));
  w.u64(index.frames.size());
  write_aabb(w, index.bounds);
  for (size_t a = 0; a < attribute_count; ++a) {
    const auto range = a < index.attribute_ranges.size() ? index.attribute_ranges[a] : std::array<float, 2>{0, 0};
    w.f32(range[0]);
    w.f32(range[1]);
  }
  for (const FrameIndexEntry& e : index.frames) {
    w.u64(e.offset);
    w.u64(e.bytes);
    w.f64(e.time);
    w.u64(e.particle_count);
    w.u32(e.chunk_count);
    w.u32(0);
    write_aabb(w, e.bounds);
    for (uint64_t n : e.layer_particles) w.u64(n);
  }
  w.u64(checksum(out));
  return out;
}

FrameIndex parse_index(std::span<const std::byte> bytes, size_t attribute_count, uint64_t file_size,
                       const ErrorLocation& where) {
  ByteReader r(bytes, where, "frame index");
  if (bytes.size() < 8) r.fail("too small");
  uint64_t stored = 0;
  std::memcpy(&stored, bytes.data() + bytes.size() - 8, 8);
  if (stored != checksum(bytes.first(bytes.size() - 8))) r.fail("checksum mismatch (run `sluice recover`)");
  if (r.u32() != kIndexMagic) r.fail("bad magic");
  if (r.u32() != attribute_count) r.fail("attribute count differs from the file header");
  const uint64_t frames = r.u64();
  const uint64_t fixed = 8 + 8 + 24 + 8 * attribute_count + 8;
  if (frames > kMaxFrames || frames * kIndexEntryBytes + fixed != bytes.size()) {
    r.fail("claims " + std::to_string(frames) + " frames, which does not match its size");
  }
  FrameIndex index;
  index.bounds = read_aabb(r);
  check_aabb(r, index.bounds, true, "global");
  index.attribute_ranges.resize(attribute_count);
  for (auto& range : index.attribute_ranges) {
    range[0] = r.f32();
    range[1] = r.f32();
  }
  index.frames.resize(frames);
  uint64_t previous_end = 0;
  for (FrameIndexEntry& e : index.frames) {
    e.offset = r.u64();
    e.bytes = r.u64();
    e.time = r.f64();
    e.particle_count = r.u64();
    e.chunk_count = r.u32();
    r.u32();
    e.bounds = read_aabb(r);
    check_aabb(r, e.bounds, true, "frame");
    uint64_t layered = 0;
    for (uint64_t& n : e.layer_particles) {
      n = r.u64();
      layered += n;
    }
    if (layered != e.particle_count) {
      r.fail("frame " + std::to_string(&e - index.frames.data()) + "'s layer counts do not add up to its particles");
    }
    if (e.offset < previous_end || e.bytes > file_size || e.offset > file_size - e.bytes) {
      r.fail("frame " + std::to_string(&e - index.frames.data()) + " lies outside the file or overlaps");
    }
    previous_end = e.offset + e.bytes;
  }
  return index;
}

std::vector<std::byte> serialize_footer(const Footer& footer) {
  std::vector<std::byte> out;
  ByteWriter w(out);
  w.u64(footer.index_offset);
  w.u64(footer.index_bytes);
  w.bytes(kFooterMagic.data(), kFooterMagic.size());
  return out;
}

bool parse_footer(std::span<const std::byte> bytes, Footer& out) {
  if (bytes.size() != kFooterBytes) return false;
  if (std::memcmp(bytes.data() + 16, kFooterMagic.data(), 8) != 0) return false;
  std::memcpy(&out.index_offset, bytes.data(), 8);
  std::memcpy(&out.index_bytes, bytes.data() + 8, 8);
  return true;
}

FrameIndexEntry index_entry_for(const FrameHeader& frame, uint64_t offset) {
  FrameIndexEntry e;
  e.offset = offset;
  e.bytes = frame.frame_bytes;
  e.time = frame.time;
  e.particle_count = frame.particle_count;
  e.chunk_count = frame.table_records();
  e.bounds = frame.bounds;
  for (const ChunkDesc& c : frame.chunks) e.layer_particles[static_cast<size_t>(c.layer)] += c.particle_count;
  return e;
}

const char* layer_name(Layer l) {
  switch (l) {
    case Layer::All: return "all";
    case Layer::Surface: return "surface";
    case Layer::Interior: return "interior";
    case Layer::Blobs: return "blobs";
  }
  return "?";
}

uint64_t count_in(const FrameHeader& frame, LayerSet set) {
  uint64_t n = 0;
  for (const ChunkDesc& c : frame.chunks) n += set.has(c.layer) ? c.particle_count : 0;
  return n;
}

void keep_layers(FrameHeader& frame, LayerSet set) {
  std::erase_if(frame.chunks, [&](const ChunkDesc& c) { return !set.has(c.layer); });
  frame.particle_count = 0;
  for (const ChunkDesc& c : frame.chunks) frame.particle_count += c.particle_count;
}

uint64_t layers_end(const FrameHeader& frame, LayerSet set, size_t attribute_count) {
  uint64_t end = frame_table_bytes(frame.table_records(), attribute_count);
  for (const ChunkDesc& c : frame.chunks) {
    if (!set.has(c.layer)) continue;
    end = std::max(end, c.offset + c.compressed_size);
    if (c.fine.split()) end = std::max(end, c.fine.offset + c.fine.size);
  }
  return end;
}

void record_parts(const FrameHeader& frame, std::vector<RecordPart>& out) {
  out.clear();
  const std::vector<ChunkDesc>& chunks = frame.chunks;
  for (size_t first = 0; first < chunks.size();) {
    size_t end = first;
    for (; end < chunks.size() && chunks[end].layer == chunks[first].layer; ++end) {
      const ChunkDesc& c = chunks[end];
      out.push_back({c.offset, c.compressed_size, c.checksum, uint32_t(end), false});
    }
    for (size_t k = first; k < end; ++k) {
      const ChunkDesc::Fine& f = chunks[k].fine;
      if (f.read()) out.push_back({f.offset, f.size, f.checksum, uint32_t(k), true});
    }
    first = end;
  }
}

uint64_t FrameIndexEntry::count_in(LayerSet set) const {
  uint64_t n = 0;
  for (int l = 0; l < kLayerCount; ++l) {
    if (set.has(Layer(l))) n += layer_particles[size_t(l)];
  }
  return n;
}

FrameSummary summarize_frame(const FrameHeader& frame) {
  FrameSummary s;
  s.entry = index_entry_for(frame, 0);
  for (const ChunkDesc& c : frame.chunks) {
    if (s.attribute_ranges.empty()) {
      s.attribute_ranges.assign(c.attribute_ranges.begin(), c.attribute_ranges.end());
      continue;
    }
    for (size_t a = 0; a < c.attribute_ranges.size() && a < s.attribute_ranges.size(); ++a) {
      s.attribute_ranges[a][0] = std::min(s.attribute_ranges[a][0], c.attribute_ranges[a][0]);
      s.attribute_ranges[a][1] = std::max(s.attribute_ranges[a][1], c.attribute_ranges[a][1]);
    }
  }
  return s;
}

void IndexBuilder::add(const FrameHeader& frame, uint64_t offset) { add(summarize_frame(frame), offset); }

void IndexBuilder::add(const FrameSummary& frame, uint64_t offset) {
  const bool has_chunks = frame.entry.chunk_count > 0;
  for (size_t a = 0; has_chunks && a < frame.attribute_ranges.size() && a < index_.attribute_ranges.size(); ++a) {
    auto& range = index_.attribute_ranges[a];
    range[0] = have_ranges_ ? std::min(range[0], frame.attribute_ranges[a][0]) : frame.attribute_ranges[a][0];
    range[1] = have_ranges_ ? std::max(range[1], frame.attribute_ranges[a][1]) : frame.attribute_ranges[a][1];
  }
  have_ranges_ = have_ranges_ || has_chunks;
  index_.bounds.extend(frame.entry.bounds);
  FrameIndexEntry entry = frame.entry;
  entry.offset = offset;
  index_.frames.push_back(entry);
}

void set_format_version(FileHeader& h, uint16_t major) {
  if (major == kFormatMajor || major == 2) {
    h.version_major = major;
    h.version_minor = 0;
  } else if (major == 1) {
    h.version_major = 1;
    h.version_minor = kLegacyMinor;
  } else {
    throw std::invalid_argument("format " + std::to_string(major) + ".x cannot be written (3.0, 2.0 or 1.5)");
  }
}

ValueBounds record_value_bounds(const std::vector<ChunkDesc>& records, size_t c) {
  ValueBounds b;
  const ChunkDesc& r = records[c];
  if (r.tier > 0) b.hi = uint16_t(kTierFloor[r.tier - 1] - 1);
  b.lo = uint16_t(kTierFloor[std::min<uint32_t>(std::max(r.last_tier, r.tier), kLodTiers - 1)]);
  return b;
}

void set_last_tiers(std::vector<ChunkDesc>& records) {
  for (size_t c = 0; c < records.size(); ++c) {
    const bool next_in_cell = c + 1 < records.size() && records[c + 1].continues_cell;
    records[c].last_tier = next_in_cell ? uint8_t(records[c + 1].tier - 1) : uint8_t(kLodTiers - 1);
  }
}

}  // namespace sluice::io
