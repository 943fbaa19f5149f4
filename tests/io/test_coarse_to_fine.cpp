// Format 2.0: a frame ordered coarse to fine (docs/format.md, "Layout of a
// frame"): layer by layer, tier by tier, along the Morton curve within a
// tier; every record its own cell, holding the tiers it says; the same
// particles as the untiered frame; tables that break the rules rejected.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <map>

#include "records.h"
#include "sluice/io/reader.h"
#include "sluice/io/codec.h"
#include "sluice/io/lod.h"
#include "test_util.h"

using namespace sluice;

namespace {

io::EncodedFrame encode(const io::ParticleFrame& f, const io::FileHeader& h, bool tiers, bool layers = false) {
  const std::vector<uint16_t> lod = io::lod_values(f.ids, f.count());
  io::FrameInput in;
  in.positions = f.positions;
  in.lod = lod;
  for (const auto& a : f.attributes) in.attributes.push_back(a);
  io::EncodeOptions o;
  o.chunk_particles = 8192;
  o.lod_tiers = tiers;
  o.layers = layers;
  return io::encode_frame(in, h, o);
}

int rank(io::Layer l) { return l == io::Layer::Blobs ? 1 : l == io::Layer::Interior ? 2 : 0; }

// A frame decoded: each record's first particle and the 8-byte particles.
struct Decoded {
  std::vector<uint64_t> starts;
  std::vector<std::byte> particles;
};
Decoded decode(const io::EncodedFrame& e, const io::FileHeader& h) {
  const io::FrameHeader& fh = e.header;
  Decoded d;
  d.starts.resize(fh.chunks.size());
  const uint64_t n = io::chunk_starts(fh, d.starts);
  d.particles.resize(n * 8);
  std::vector<uint16_t> attr(n);
  std::vector<uint16_t*> attrs(h.attributes.size(), attr.data());
  io::decode_record(e.record, fh, h, d.starts, d.particles, attrs, {});
  return d;
}

// Every particle's LOD value, per record, decoded.
std::vector<std::vector<uint16_t>> values_by_record(const io::EncodedFrame& e, const io::FileHeader& h) {
  const io::FrameHeader& fh = e.header;
  const Decoded d = decode(e, h);
  std::vector<std::vector<uint16_t>> out(fh.chunks.size());
  for (size_t c = 0; c < fh.chunks.size(); ++c) {
    for (uint64_t i = d.starts[c]; i < d.starts[c] + fh.chunks[c].particle_count; ++i) {
      uint16_t v;
      std::memcpy(&v, d.particles.data() + i * 8 + 6, 2);
      out[c].push_back(v);
    }
  }
  return out;
}

}  // namespace

TEST(CoarseToFine, WritersWrite3_0AndOrderEveryFrameLayerTierCurve) {
  const io::FileHeader h = test::test_header(io::PositionCoding::Quantized16);
  EXPECT_EQ(h.version_major, 3);
  const io::EncodedFrame e = encode(test::scattered_frame(200000, 4), h, true);
  const io::FrameHeader& fh = e.header;
  EXPECT_TRUE(fh.coarse_to_fine);
  const std::vector<std::vector<uint16_t>> values = values_by_record(e, h);
  for (size_t c = 0; c < fh.chunks.size(); ++c) {
    const io::ChunkDesc& r = fh.chunks[c];
    EXPECT_FALSE(r.continues_cell);
    ASSERT_GE(r.last_tier, r.tier);
    if (c > 0) {
      const io::ChunkDesc& b = fh.chunks[c - 1];
      EXPECT_LE(rank(b.layer), rank(r.layer));
      if (b.layer == r.layer) EXPECT_TRUE(r.tier == b.tier ? r.last_tier == b.last_tier : r.tier > b.last_tier) << c;
      EXPECT_EQ(r.offset, b.offset + b.compressed_size);  // payloads in table order, back to back
    }
    // Its values lie in its tiers: what record_value_bounds() tells the cull.
    const io::ValueBounds bounds = io::record_value_bounds(fh.chunks, c);
    EXPECT_EQ(bounds.lo, io::kTierFloor[r.last_tier]);
    for (uint16_t v : values[c]) {
      ASSERT_GE(v, bounds.lo) << c;
      ASSERT_LE(v, bounds.hi) << c;
    }
  }
  // Coarse tiers have large cells: tier 0 (1/64 of the particles, 3,125)
  // is one record, not one a cell of the frame as in 1.5.
  const auto tier0 = std::count_if(fh.chunks.begin(), fh.chunks.end(), [](const io::ChunkDesc& r) { return r.tier == 0; });
  EXPECT_EQ(tier0, 1);
  io::FileHeader old = h;
  io::set_format_version(old, 1);
  const io::EncodedFrame cells = encode(test::scattered_frame(200000, 4), old, true);
  EXPECT_FALSE(cells.header.coarse_to_fine);
  EXPECT_LT(fh.chunks.size(), cells.header.chunks.size() / 2) << "records: " << fh.chunks.size() << " against "
                                                               << cells.header.chunks.size();
}

TEST(CoarseToFine, AnyPrefixOfTiersIsOneByteRangePerLayer) {
  const io::FileHeader h = test::test_header(io::PositionCoding::Quantized16);
  const io::EncodedFrame e = encode(test::lattice_frame(120000, 0.37f), h, true, true);
  // Each layer's kept records are its first records in the table: one
  // byte range from where the layer begins.
  std::map<io::Layer, uint32_t> first;
  for (const io::ChunkDesc& c : e.header.chunks) first.emplace(c.layer, c.index);
  ASSERT_EQ(first.size(), 3u);
  for (uint32_t t = 1; t <= io::kLodTiers; ++t) {
    io::FrameHeader fh = e.header;
    io::keep_tiers(fh, [&](const io::ChunkDesc&) { return t; });
    std::map<io::Layer, uint32_t> next = first;
    for (const io::ChunkDesc& c : fh.chunks) {
      EXPECT_EQ(c.index, next[c.layer]) << "tiers " << t;
      next[c.layer] = c.index + 1;
    }
  }
}

TEST(CoarseToFine, DecodesTheParticlesOfTheUntieredFrameWithinTheBound) {
  const io::FileHeader h = test::test_header(io::PositionCoding::Quantized16);
  const io::ParticleFrame f = test::scattered_frame(60000, 7);
  const io::EncodedFrame tiered = encode(f, h, true), flat = encode(f, h, false);
  for (const io::ChunkDesc& c : flat.header.chunks) {
    EXPECT_EQ(c.tier, 0);
    EXPECT_EQ(c.last_tier, io::kLodTiers - 1);
  }
  std::vector<uint16_t> a, b;
  for (const auto& r : values_by_record(tiered, h)) a.insert(a.end(), r.begin(), r.end());
  for (const auto& r : values_by_record(flat, h)) b.insert(b.end(), r.begin(), r.end());
  std::sort(a.begin(), a.end());
  std::sort(b.begin(), b.end());
  EXPECT_EQ(a, b);
  // Every box within the stated bound (131070 x the bound wide at most).
  for (const io::ChunkDesc& c : tiered.header.chunks) EXPECT_EQ(io::axis_over_bound(c.bounds, io::position_bound(h)), -1);
}

TEST(CoarseToFine, ABlobIsReadNoLaterThanTheRendererKeepsIt) {
  // Blob records are tiered by a bound of the blob's random term over the
  // cells its decoded centroid may be found in (lod.h): the record's tier
  // is never after the tier of the value the GPU computes.
  const io::FileHeader h = test::test_header(io::PositionCoding::Quantized16);
  const io::EncodedFrame e = encode(test::lattice_frame(150000, 0.41f), h, true, true);
  const io::FrameHeader& fh = e.header;
  const Decoded d = decode(e, h);
  size_t blobs = 0;
  for (size_t c = 0; c < fh.chunks.size(); ++c) {
    const io::ChunkDesc& r = fh.chunks[c];
    if (r.layer != io::Layer::Blobs) continue;
    for (uint64_t i = d.starts[c]; i < d.starts[c] + r.particle_count; ++i) {
      uint16_t q[4];
      std::memcpy(q, d.particles.data() + i * 8, 8);
      float p[3];
      for (int a = 0; a < 3; ++a) p[a] = io::dequantize(q[a], r.bounds.min[size_t(a)], r.bounds.max[size_t(a)]);
      const uint32_t tier = io::lod_tier_of_uniform(io::blob_lod_uniform_bound(p[0], p[1], p[2], fh.blob_voxel));
      ASSERT_LE(r.tier, tier) << "record " << c;
      ++blobs;
    }
  }
  EXPECT_GT(blobs, 1000u);
}

TEST(CoarseToFine, TablesThatBreakTheOrderAreRejected) {
  const io::FileHeader h = test::test_header(io::PositionCoding::Quantized16);
  const io::EncodedFrame e = encode(test::scattered_frame(200000, 2), h, true);
  const size_t desc = io::chunk_desc_bytes(h.attributes.size());
  const size_t table = io::frame_table_bytes(e.header.chunks.size(), h.attributes.size());
  ASSERT_GE(e.header.chunks.size(), 3u);
  auto reject = [&](size_t at, uint8_t value, const char* what) {
    std::vector<std::byte> record = e.record;
    record[at] = std::byte(value);
    const uint64_t sum = io::chunk_checksum(std::span(record).first(table - 8));
    std::memcpy(record.data() + table - 8, &sum, 8);  // a valid checksum: the rules must catch it
    try {
      io::parse_frame_table(record, h.attributes.size(), {"f.sluice", 3, {}});
      ADD_FAILURE() << "accepted: " << what;
    } catch (const io::Error& error) {
      const std::string text = error.what();
      EXPECT_NE(text.find("f.sluice"), std::string::npos) << text;
      EXPECT_NE(text.find("frame 3"), std::string::npos) << text;
    }
  };
  const size_t first = io::kFrameHeaderFixedBytes;
  const size_t last = first + (e.header.chunks.size() - 1) * desc;
  reject(36, 2, "an unknown frame flag");
  reject(first + 19, 12, "a last tier past 11");
  reject(last + 18, 0, "the last record's tier falling back to 0");
  reject(last + 19, uint8_t(e.header.chunks.back().tier - 1), "a last tier below the record's tier");
  reject(last + 16, uint8_t(io::Layer::Surface), "a surface record after the particles of layer all");
}
