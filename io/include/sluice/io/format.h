// sluice/io/format.h: the `.sluice` container, (docs/format.md).
//
// These are the in-memory forms of the on-disk records. They are parsed from
// and written to bytes explicitly (little-endian), never memcpy'd, so every
// field read from a file is range-checked before it is used.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "sluice/error.h"
#include "sluice/io/types.h"
#include "sluice/io/up_axis.h"

namespace sluice::io {

// InlineVector: a vector of at most N elements held inline, for
// the per-chunk and per-frame lists whose size a format limit bounds
// (attributes: 32), so that filling them again never allocates.

template <class T, size_t N>
class InlineVector {
 public:
  size_t size() const { return count_; }
  bool empty() const { return count_ == 0; }
  static constexpr size_t capacity() { return N; }
  // Throws io::Error beyond N.
  void resize(size_t n, const T& value = T{}) {
    if (n > N) throw io::Error({}, "InlineVector: more than its capacity");
    for (size_t i = count_; i < n; ++i) items_[i] = value;
    count_ = n;
  }
  void assign(size_t n, const T& value) {
    count_ = 0;
    resize(n, value);
  }
  void clear() { count_ = 0; }
  template <class... Args>
  T& emplace_back(Args&&... args) {
    if (count_ == N) throw io::Error({}, "InlineVector: more than its capacity");
    items_[count_] = T(static_cast<Args&&>(args)...);
    return items_[count_++];
  }
  void push_back(const T& value) { emplace_back(value); }
  T& operator[](size_t i) { return items_[i]; }
  const T& operator[](size_t i) const { return items_[i]; }
  T* begin() { return items_.data(); }
  T* end() { return items_.data() + count_; }
  const T* begin() const { return items_.data(); }
  const T* end() const { return items_.data() + count_; }
  T* data() { return items_.data(); }
  const T* data() const { return items_.data(); }

 private:
  std::array<T, N> items_{};
  size_t count_ = 0;
};

// Format 2.0 orders each frame coarse to fine (docs/format.md, "Layout of a
// frame"); 3.0 also stores each record's positions in two parts, the fine
// part apart ("Precision parts"). Readers of this build read 1.x and 2.0
// files too.
inline constexpr uint16_t kFormatMajor = 3;  // what writers write; readers reject majors above it
inline constexpr uint16_t kFormatMinor = 0;  // readers accept any minor of a major they read
inline constexpr uint16_t kOldestMajor = 1;  // the oldest major readers still read
// The last 1.x minor (what `--format 1.5` writes: each cell's tiers together).
inline constexpr uint16_t kLegacyMinor = 5;

// Hard limits. A header that claims more is rejected before any allocation.
inline constexpr uint32_t kMaxHeaderBytes = 1u << 20;
inline constexpr uint32_t kMaxAttributes = 32;
inline constexpr uint32_t kMaxNameBytes = 255;
inline constexpr uint32_t kMaxChunkParticles = 1u << 20;
inline constexpr uint32_t kMaxChunksPerFrame = 1u << 22;
inline constexpr uint64_t kMaxFrames = 1ull << 32;

// How positions are stored in a chunk.
enum class PositionCoding : uint8_t {
  Quantized16 = 0,  // 16 bits per axis relative to the chunk AABB; Morton-delta filter
  Float32 = 1,      // lossless float32; byte-shuffle filter
};

// Where the per-particle LOD value comes from.
enum class LodSource : uint8_t {
  IdHash = 0,         // hash of the source's particle id array: stable across frames
  ParticleOrder = 1,  // hash of the particle's index in the source: stable only if the source keeps its order
};

// Which layer of the narrow band a chunk belongs to. v1 writers that do not
// classify write everything as All; the narrow-band classifier fills the rest.
enum class Layer : uint8_t {
  All = 0,       // unclassified: every particle
  Surface = 1,   // LNM layers L1+L2: particles near the surface
  Interior = 2,  // the rest of the particles
  Blobs = 3,     // voxel blobs (centroid + count) standing in for Interior
};
inline constexpr int kLayerCount = 4;
const char* layer_name(Layer l);

// Which layers a reader wants. Blob chunks stand in for interior chunks, so
// a set holds one or the other; an unlayered file's chunks (All) are in
// every set.
class LayerSet {
 public:
  // Every particle: what a file without layers holds (All, Surface, Interior).
  static constexpr LayerSet particles() { return LayerSet(0b0111); }
  // The narrow band and the blobs: what is drawn by default (All, Surface, Blobs).
  static constexpr LayerSet surface() { return LayerSet(0b1011); }
  bool has(Layer l) const { return (bits_ >> unsigned(l)) & 1u; }
  bool operator==(const LayerSet&) const = default;

 private:
  constexpr explicit LayerSet(uint8_t bits) : bits_(bits) {}
  uint8_t bits_;
};

// Chunk payload compression.
enum class ChunkCodec : uint8_t {
  Zstd = 0,    // planes, each stored or zstd
  Stored = 1,  // planes concatenated, no table
  Packed = 2,  // planes, each stored, zstd or bit-packed (format 1.1)
};

// Format 3.0 (frame flags bit 1): a quantized record's 48-bit Morton codes
// are stored in two parts. The record holds the deltas of their high 32
// bits; its fine part, apart, the low kFineCodeBits: 6 bits of x, 5 of y,
// 5 of z. A reader without the fine part decodes each code with
// kCoarseFill as its low bits (every dropped axis bit pattern at its
// middle): off by at most kCoarseSteps quantization steps on each axis.
inline constexpr uint32_t kFineCodeBits = 16;
inline constexpr uint64_t kCoarseFill = 0xE000;  // x bit 5, y bit 4, z bit 4 of the low 16 bits
inline constexpr std::array<uint32_t, 3> kCoarseSteps = {32, 16, 16};

// Where a file's frame times come from (format 1.2).
enum class TimeSource : uint8_t {
  Unstated = 0,     // a file older than 1.2: times as its converter found them
  Input = 1,        // the input's own times (.pvd, a time field in each file)
  Step = 2,         // frame number x a time step given at conversion (--fps, --dt)
  FrameNumber = 3,  // none known: the time field holds the frame number
};
const char* time_source_name(TimeSource t);

struct FileHeader {
  uint16_t version_major = kFormatMajor;
  uint16_t version_minor = kFormatMinor;
  PositionCoding position_coding = PositionCoding::Quantized16;
  LodSource lod_source = LodSource::IdHash;
  float particle_spacing = 0.f;  // rest spacing in world units; 0 if unknown
  float particle_radius = 0.f;   // render radius in world units; 0 if unknown
  float frame_rate = 0.f;        // nominal frames per second of playback; 0 if unknown
  // Format 1.2, in the flags word (a 1.1 reader ignores it and sees +z up):
  UpAxis up = UpAxis::Unstated;                  // which world direction points up
  UpEvidence up_evidence = UpEvidence::Unstated;  // how that was found
  TimeSource time_source = TimeSource::Unstated;  // what the frames' time fields hold
  // Format 1.5, in the flags word: every quantized position decodes within
  // particle_spacing x 2^-precision_bits of its source on each axis (plus
  // two float32 ulps of the coordinate): the writer keeps every chunk's box
  // at most 131070 times that wide. 0: not stated (older files, no spacing).
  // 1 ... 63. Writers default to kDefaultPrecisionBits.
  uint8_t precision_bits = 0;
  std::vector<AttributeInfo> attributes;
  std::string lod_id_array;      // the id array hashed for LOD values, if any
  std::string source;            // free text: what the file was converted from
};

// Sets the header's version for writing with major `major`: 2 (kFormatMajor:
// frames ordered coarse to fine) or 1 (1.5, kLegacyMinor: each cell's
// tiers together, for readers older than 2.0). Throws std::invalid_argument
// for other majors. encode_frame() lays frames out by the header's major.
void set_format_version(FileHeader& h, uint16_t major);

// Whether the file's frame times are the input's or a step given, not frame
// numbers standing in for times the input did not state.
bool times_stated(const FileHeader& h);

// 1/1024 of the spacing: boxes of at most 128 spacings, about what the
// default 65,536-particle chunks had before the bound (docs/format.md).
inline constexpr uint8_t kDefaultPrecisionBits = 10;

// The precision exponent k for a bound of at most `fraction` of the spacing:
// the smallest k (1 ... 40) with 2^-k <= fraction (`--precision`).
uint8_t precision_bits_for(double fraction);

// The largest error of a decoded position on one axis, world units, not
// counting two ulps of the coordinate: 0 for float32 files, infinity where
// the file states none (FileHeader::precision_bits).
float position_bound(const FileHeader& h);
// The widest a chunk's box may be on any axis to keep position_bound:
// 131070 x the bound (infinity: no limit).
float chunk_extent_limit(const FileHeader& h);
// The first axis (0 x, 1 y, 2 z) along which positions quantized in `box`
// may be off by more than `bound` plus two ulps of the coordinate (float32
// input is no finer); -1 when none: what `verify` checks of every chunk.
int axis_over_bound(const Aabb& box, float bound);

struct ChunkDesc {
  uint64_t offset = 0;           // from the start of the frame record
  uint32_t compressed_size = 0;  // bytes at offset
  uint32_t particle_count = 0;
  Layer layer = Layer::All;
  ChunkCodec codec = ChunkCodec::Zstd;
  // LOD tier (format 1.4, lod.h): the record holds the particles of its
  // cell whose LOD values lie in tier `tier`. A cell is a run of records:
  // one with continues_cell false, then those with it true, tiers rising,
  // same layer and box. Older files: every record its own cell, tier 0.
  uint8_t tier = 0;
  bool continues_cell = false;
  // The last tier whose values the record holds (tier ... last_tier): byte
  // 19 in a coarse-to-fine frame (format 2.0); for 1.x records the tier
  // before the next record of the cell, or 11 (parse_frame_table sets it).
  uint8_t last_tier = 11;
  // Not stored: the record's place in the frame's chunk table as written
  // (parse_frame_table sets it), kept when keep_layers or keep_tiers drop
  // records, so errors name the chunk the file holds.
  uint32_t index = 0;
  // Format 3.0: the record's fine part (the low kFineCodeBits of its
  // Morton codes: 2 planes of particle_count bytes, coded as any payload),
  // written apart: after every record of its layer, in the records' order.
  // size 0: the record's positions are whole (older formats, float32).
  struct Fine {
    uint64_t offset = 0;    // from the start of the frame record
    uint32_t size = 0;      // bytes; 0: none
    ChunkCodec codec = ChunkCodec::Stored;
    uint64_t checksum = 0;  // XXH3-64 of its bytes
    uint32_t index = 0;     // its place in the chunk table as written (errors name it)
    // Left out by a reader (runtime's demand: a view far enough away): the
    // record then decodes at the coarse precision (kCoarseFill).
    bool dropped = false;
    bool split() const { return size > 0; }
    bool read() const { return size > 0 && !dropped; }
  } fine;
  Aabb bounds;                   // every particle of the chunk lies inside (inclusive); the cell's box
  uint64_t checksum = 0;         // XXH3-64 of the compressed bytes
  // Per attribute: the range its 16-bit values are quantized against (held
  // inline: re-parsing a chunk table into the same vector allocates nothing).
  InlineVector<std::array<float, 2>, kMaxAttributes> attribute_ranges;
};

struct FrameHeader {
  uint32_t frame_number = 0;     // position in the file, 0-based
  uint64_t frame_bytes = 0;      // the whole record: header, chunk table, payloads
  double time = 0.0;             // simulation time, seconds
  uint64_t particle_count = 0;
  // The frame's display bounds: every particle's box but for far particles
  // (format 1.5, point_set.h), which lie in chunks of their own outside it.
  // Cameras frame it; chunk boxes, not this, bound what is drawn.
  Aabb bounds;
  // Format 1.3: side of the voxels whose blobs the Blobs chunks hold (world
  // units; 0 when the frame has none). A blob's LOD value is its count.
  float blob_voxel = 0;
  // Format 2.0 (frame flags bit 0): records ordered coarse to fine: by
  // layer (as written), then by tier, then along the Morton curve; every
  // record its own cell. 1.x frames: each cell's tiers together.
  bool coarse_to_fine = false;
  // Format 3.0 (frame flags bit 1): every record's positions in two parts
  // (ChunkDesc::fine); the chunk table lists the fine parts as records too
  // (descriptor byte 18 bit 7), which parse_frame_table folds into `chunks`.
  bool split_positions = false;
  std::vector<ChunkDesc> chunks;
  // Records of the chunk table as written: chunks, and their fine parts.
  uint32_t table_records() const {
    uint32_t n = 0;
    for (const ChunkDesc& c : chunks) n += c.fine.split() ? 2 : 1;
    return n;
  }
};

// Chunk records (particles, and blobs if `set` has them) of `set`'s layers.
uint64_t count_in(const FrameHeader& frame, LayerSet set);
// Drops the chunks of layers not in `set` and recounts the particles: what
// the renderer and tools see of a frame. Payload offsets stay those of the
// whole record.
void keep_layers(FrameHeader& frame, LayerSet set);
// Bytes from the start of the record that hold its table and every payload
// of `set`'s chunks: a reader that wants only those reads this many.
uint64_t layers_end(const FrameHeader& frame, LayerSet set, size_t attribute_count);

// One byte range a reader of a frame reads: a record's payload, or its fine
// part (format 3.0).
struct RecordPart {
  uint64_t offset = 0;    // from the start of the frame record
  uint32_t size = 0;
  uint64_t checksum = 0;  // XXH3-64 of the bytes
  uint32_t chunk = 0;     // the record's place in FrameHeader::chunks
  bool fine = false;      // the record's fine part
};
// The parts of `frame`'s records a reader reads, in table order (each
// layer's records, then the fine parts they read): `out` is cleared first
// and allocates nothing once it has held as many.
void record_parts(const FrameHeader& frame, std::vector<RecordPart>& out);

// The records of the cell whose first record is chunks[first]: returns the
// index one past its last record.
inline size_t cell_end(const std::vector<ChunkDesc>& chunks, size_t first) {
  size_t end = first + 1;
  while (end < chunks.size() && chunks[end].continues_cell) ++end;
  return end;
}
// The LOD values records[c] may hold (docs/format.md, "LOD tiers"): below
// the floor of the tier above its own, at least the floor of its last tier
// (ChunkDesc::last_tier).
struct ValueBounds {
  uint16_t lo = 0, hi = 65535;
};
ValueBounds record_value_bounds(const std::vector<ChunkDesc>& records, size_t c);
// 1.x tables: sets each record's last_tier from the next record of its cell
// (the tier before it), or 11 for a cell's last record.
void set_last_tiers(std::vector<ChunkDesc>& records);

// Keeps, of each cell, the records of tiers below `tiers_of(first record of
// the cell)` (uint32_t; 0 drops the cell) and recounts the particles. The
// records kept stay in file order, so a cell's kept tiers are one
// contiguous byte range of the record. No allocation.
template <class TiersOf>
void keep_tiers(FrameHeader& frame, TiersOf&& tiers_of) {
  std::vector<ChunkDesc>& chunks = frame.chunks;
  size_t out = 0;
  frame.particle_count = 0;
  for (size_t first = 0; first < chunks.size();) {
    const size_t end = cell_end(chunks, first);
    const uint32_t tiers = tiers_of(chunks[first]);
    for (size_t c = first; c < end; ++c) {
      if (chunks[c].tier >= tiers) continue;
      frame.particle_count += chunks[c].particle_count;
      if (out != c) chunks[out] = chunks[c];
      ++out;
    }
    first = end;
  }
  chunks.resize(out);
}

struct FrameIndexEntry {
  uint64_t offset = 0;           // of the frame record, from the start of the file
  uint64_t bytes = 0;
  double time = 0.0;
  uint64_t particle_count = 0;
  uint32_t chunk_count = 0;
  Aabb bounds;
  std::array<uint64_t, kLayerCount> layer_particles{};  // by Layer (for Blobs: blobs)
  // The frame holds classified layers (anything but All).
  bool layered() const { return layer_particles[0] != particle_count; }
  // Chunk records (particles, and blobs if `set` has them) of `set`'s layers.
  uint64_t count_in(LayerSet set) const;
};

struct FrameIndex {
  std::vector<FrameIndexEntry> frames;
  Aabb bounds;                                        // of every frame
  std::vector<std::array<float, 2>> attribute_ranges; // observed over every frame
};

// What the index keeps of one frame: its entry (offset 0 until placed) and
// the range of each attribute over its chunks. Kilobytes where the frame's
// chunk table is megabytes: an MPI conversion's ranks send rank 0 this.
struct FrameSummary {
  FrameIndexEntry entry;
  std::vector<std::array<float, 2>> attribute_ranges;  // empty: the frame has no chunks
};
FrameSummary summarize_frame(const FrameHeader& frame);

// Accumulates the frame index as frames are written or recovered: entries,
// global bounds and the observed range of each attribute. Adding a frame's
// summary gives the index adding the frame gives.
class IndexBuilder {
 public:
  explicit IndexBuilder(size_t attribute_count) { index_.attribute_ranges.assign(attribute_count, {0.f, 0.f}); }
  void add(const FrameHeader& frame, uint64_t offset);
  void add(const FrameSummary& frame, uint64_t offset);
  const FrameIndex& index() const { return index_; }

 private:
  FrameIndex index_;
  bool have_ranges_ = false;  // an attribute range has been seen
};

// Sizes of the fixed parts of the records (see docs/format.md).
inline constexpr size_t kFrameHeaderFixedBytes = 72;
inline constexpr size_t kChunkDescFixedBytes = 52;
inline constexpr size_t kIndexEntryBytes = 96;
inline constexpr size_t kFooterBytes = 24;

inline size_t chunk_desc_bytes(size_t attribute_count) {
  return kChunkDescFixedBytes + 8 * attribute_count;
}
// Header, chunk table and the table checksum: where the first payload starts.
inline uint64_t frame_table_bytes(uint64_t chunk_count, size_t attribute_count) {
  return kFrameHeaderFixedBytes + chunk_count * chunk_desc_bytes(attribute_count) + 8;
}

// Bytes per decoded particle in the buffers decode_chunk fills.
//  Quantized16: uint16 x, y, z, lod (x,y,z relative to the chunk AABB)
//  Float32:     float x, y, z; uint32 lod
inline size_t decoded_particle_bytes(PositionCoding coding) {
  return coding == PositionCoding::Quantized16 ? 8 : 16;
}
// Bytes of the filtered (pre-zstd) payload of a chunk.
inline uint64_t raw_chunk_bytes(PositionCoding coding, uint64_t particles, size_t attribute_count) {
  const uint64_t per = (coding == PositionCoding::Quantized16 ? 8 : 14) + 2 * attribute_count;
  return particles * per;
}

}  // namespace sluice::io
