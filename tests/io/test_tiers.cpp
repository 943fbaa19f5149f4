// LOD tiers as format 1.4 writes them (each cell's tiers together; a 2.0
// writer orders frames coarse to fine: test_coarse_to_fine.cpp): each chunk written as records by tier, any prefix
// of tiers one byte range, what cLOD can keep always a prefix, decoding the
// same particles as the untiered file, older layouts read as one tier.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <map>
#include <random>
#include <tuple>

#include "records.h"
#include "sluice/io/reader.h"
#include "sluice/io/codec.h"
#include "sluice/io/lod.h"
#include "sluice/io/writer.h"
#include "test_util.h"

using namespace sluice;

namespace {

// Format 1.5 headers: the layout these tests are about.
io::FileHeader legacy(io::FileHeader h) {
  io::set_format_version(h, 1);
  return h;
}

struct Variant {
  const char* name;
  io::PositionCoding coding;
  io::PlaneCoding planes;
};

io::EncodedFrame encode(const io::ParticleFrame& f, const io::FileHeader& h, const Variant& v, bool tiers) {
  const std::vector<uint16_t> lod = io::lod_values(f.ids, f.count());
  io::FrameInput in;
  in.positions = f.positions;
  in.lod = lod;
  in.attributes.push_back(f.attributes[0]);
  io::EncodeOptions o;
  o.chunk_particles = 8192;
  o.planes = v.planes;
  o.lod_tiers = tiers;
  return io::encode_frame(in, h, o);
}

// Every decoded particle as (lod value, x, y, z bits, attribute value), sorted.
using Particle = std::tuple<uint16_t, uint32_t, uint32_t, uint32_t, float>;
std::vector<Particle> decoded(const io::EncodedFrame& e, const io::FileHeader& h) {
  const io::FrameHeader& fh = e.header;
  std::vector<uint64_t> starts(fh.chunks.size());
  const uint64_t n = io::chunk_starts(fh, starts);
  const size_t stride = io::decoded_particle_bytes(h.position_coding);
  std::vector<std::byte> particles(n * stride);
  std::vector<uint16_t> attr(n);
  std::vector<uint16_t*> attrs{attr.data()};
  io::decode_record(e.record, fh, h, starts, particles, attrs, {});
  std::vector<Particle> out;
  for (size_t c = 0; c < fh.chunks.size(); ++c) {
    const io::ChunkDesc& ch = fh.chunks[c];
    for (uint64_t i = starts[c]; i < starts[c] + ch.particle_count; ++i) {
      float p[3];
      uint16_t lod;
      if (h.position_coding == io::PositionCoding::Quantized16) {
        uint16_t q[4];
        std::memcpy(q, particles.data() + i * stride, 8);
        for (int a = 0; a < 3; ++a) p[a] = io::dequantize(q[a], ch.bounds.min[size_t(a)], ch.bounds.max[size_t(a)]);
        lod = q[3];
      } else {
        uint32_t w[4];
        std::memcpy(w, particles.data() + i * stride, 16);
        std::memcpy(p, w, 12);
        lod = uint16_t(w[3]);
      }
      const auto& r = ch.attribute_ranges[0];
      const float value = io::dequantize(attr[i], r[0], r[1]);
      uint32_t bits[3];
      std::memcpy(bits, p, 12);
      out.emplace_back(lod, bits[0], bits[1], bits[2], value);
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

const Variant kVariants[] = {
    {"packed", io::PositionCoding::Quantized16, io::PlaneCoding::Packed},
    {"zstd only", io::PositionCoding::Quantized16, io::PlaneCoding::Zstd},
    {"gpu-decodable", io::PositionCoding::Quantized16, io::PlaneCoding::GpuDecodable},
    {"stored", io::PositionCoding::Quantized16, io::PlaneCoding::Stored},
    {"float32", io::PositionCoding::Float32, io::PlaneCoding::Packed},
};

}  // namespace

TEST(Tiers, EveryCodecDecodesTheSameParticlesAsUntiered) {
  const io::ParticleFrame f = test::scattered_frame(60000, 5);
  for (const Variant& v : kVariants) {
    SCOPED_TRACE(v.name);
    const io::FileHeader h = legacy(test::test_header(v.coding));
    const io::EncodedFrame tiered = encode(f, h, v, true), flat = encode(f, h, v, false);
    // Stored frames (decoded at once, never read from a file) stay untiered.
    if (v.planes != io::PlaneCoding::Stored) EXPECT_GT(tiered.header.chunks.size(), flat.header.chunks.size());
    else EXPECT_EQ(tiered.header.chunks.size(), flat.header.chunks.size());
    // Positions: each tier is quantized in its cell's box, so they agree bit for bit.
    const std::vector<Particle> a = decoded(tiered, h), b = decoded(flat, h);
    ASSERT_EQ(a.size(), b.size());
    for (size_t i = 0; i < a.size(); ++i) {
      ASSERT_EQ(std::get<0>(a[i]), std::get<0>(b[i])) << i;
      ASSERT_EQ(std::get<1>(a[i]), std::get<1>(b[i])) << i;
      ASSERT_EQ(std::get<2>(a[i]), std::get<2>(b[i])) << i;
      ASSERT_EQ(std::get<3>(a[i]), std::get<3>(b[i])) << i;
      // Attributes are quantized per record (its own range): within a step of the cell's.
      const float step = (h.attributes.empty() ? 1.f : 20.f) / 65535.f;
      ASSERT_NEAR(std::get<4>(a[i]), std::get<4>(b[i]), 2 * step + 1e-3f) << i;
    }
    // The table round-trips through its bytes.
    const io::FrameHeader parsed = io::parse_frame_table(tiered.record, h.attributes.size(), {});
    ASSERT_EQ(parsed.chunks.size(), tiered.header.chunks.size());
    for (size_t c = 0; c < parsed.chunks.size(); ++c) {
      EXPECT_EQ(parsed.chunks[c].tier, tiered.header.chunks[c].tier);
      EXPECT_EQ(parsed.chunks[c].continues_cell, tiered.header.chunks[c].continues_cell);
    }
  }
}

TEST(Tiers, RecordsHoldTheirTiersInOrderAndEveryPrefixIsOneRange) {
  const io::FileHeader h = legacy(test::test_header(io::PositionCoding::Quantized16));
  const io::EncodedFrame e = encode(test::scattered_frame(60000, 9), h, kVariants[0], true);
  const io::FrameHeader& fh = e.header;
  std::vector<uint64_t> starts(fh.chunks.size());
  const uint64_t n = io::chunk_starts(fh, starts);
  std::vector<std::byte> particles(n * 8);
  io::decode_record(e.record, fh, h, starts, particles, {}, {});
  size_t cells = 0;
  for (size_t first = 0; first < fh.chunks.size(); first = io::cell_end(fh.chunks, first)) {
    ++cells;
    const size_t end = io::cell_end(fh.chunks, first);
    EXPECT_FALSE(fh.chunks[first].continues_cell);
    for (size_t c = first; c < end; ++c) {
      const io::ChunkDesc& ch = fh.chunks[c];
      EXPECT_EQ(ch.bounds, fh.chunks[first].bounds);
      if (c > first) {
        EXPECT_GT(ch.tier, fh.chunks[c - 1].tier);
        // Contiguous: the record begins where the one before ends.
        EXPECT_EQ(ch.offset, fh.chunks[c - 1].offset + fh.chunks[c - 1].compressed_size);
      }
      // Its values lie in its tier or, where small tiers were joined, in the
      // tiers after it: what record_value_bounds() tells the renderer's cull.
      const uint32_t next = c + 1 < end ? fh.chunks[c + 1].tier : io::kLodTiers;
      const uint32_t top = ch.tier == 0 ? 65536 : io::kTierFloor[ch.tier - 1];
      const io::ValueBounds bounds = io::record_value_bounds(fh.chunks, c);
      EXPECT_EQ(uint32_t(bounds.hi) + 1, top);
      EXPECT_EQ(bounds.lo, next == io::kLodTiers ? 0u : io::kTierFloor[next - 1]);
      uint16_t lowest = 65535, highest = 0;
      for (uint64_t i = starts[c]; i < starts[c] + ch.particle_count; ++i) {
        uint16_t lod;
        std::memcpy(&lod, particles.data() + i * 8 + 6, 2);
        ASSERT_LT(lod, top);
        ASSERT_GE(lod, io::kTierFloor[next - 1]);
        lowest = std::min(lowest, lod);
        highest = std::max(highest, lod);
      }
      EXPECT_GE(lowest, bounds.lo);
      EXPECT_LE(highest, bounds.hi);
    }
  }
  EXPECT_EQ(cells, 8u);  // 60000 particles in chunks of at most 8192
}

TEST(Tiers, TiersForKeepHoldEveryValueCLodCanKeep) {
  // The renderer keeps value v when u = (v + 0.5) / 65536 >= 1 - p (lod.h).
  for (double p = 0; p <= 1.0; p += 1.0 / 4096) {
    const uint32_t tiers = io::tiers_for_keep(p);
    ASSERT_LE(tiers, io::kLodTiers);
    if (p > 0) ASSERT_GE(tiers, 1u);
    const double lowest_kept = 65536.0 * (1.0 - p) - 0.5;
    for (uint32_t v = 0; v < 65536; v += 7) {
      if (double(v) >= lowest_kept) ASSERT_LT(io::lod_tier(uint16_t(v)), tiers) << "p " << p << " v " << v;
    }
  }
  // At importance 1 the levels 0.1-0.5 fall on boundaries: exactly the tiers that hold them.
  EXPECT_EQ(io::tiers_for_keep(0.1), 4u);
  EXPECT_EQ(io::tiers_for_keep(0.2), 6u);
  EXPECT_EQ(io::tiers_for_keep(0.3), 8u);
  EXPECT_EQ(io::tiers_for_keep(0.5), 10u);
  EXPECT_EQ(io::tiers_for_keep(0.01), 1u);
  EXPECT_EQ(io::tiers_for_keep(1.0), io::kLodTiers);
}

TEST(Tiers, KeepTiersKeepsAPrefixOfEachCell) {
  const io::FileHeader h = legacy(test::test_header(io::PositionCoding::Quantized16));
  const io::EncodedFrame e = encode(test::scattered_frame(60000, 11), h, kVariants[0], true);
  for (uint32_t t = 0; t <= io::kLodTiers; ++t) {
    io::FrameHeader fh = e.header;
    io::keep_tiers(fh, [&](const io::ChunkDesc&) { return t; });
    uint64_t count = 0;
    for (const io::ChunkDesc& c : fh.chunks) {
      EXPECT_LT(c.tier, t);
      count += c.particle_count;
    }
    EXPECT_EQ(count, fh.particle_count);
    // Every particle whose value lies in the first t tiers is kept.
    uint64_t want = 0;
    for (uint64_t id : test::scattered_frame(60000, 11).ids) want += t > 0 && io::lod_tier(io::lod_value_from_id(id)) < t;
    EXPECT_GE(count, want);
    if (t == io::kLodTiers) EXPECT_EQ(count, 60000u);
  }
}

TEST(Tiers, UntieredFilesReadAsOneTierPerChunk) {
  const io::FileHeader h = legacy(test::test_header(io::PositionCoding::Quantized16));
  const io::EncodedFrame e = encode(test::scattered_frame(30000, 3), h, kVariants[0], false);
  const io::FrameHeader parsed = io::parse_frame_table(e.record, h.attributes.size(), {});
  for (const io::ChunkDesc& c : parsed.chunks) {
    EXPECT_EQ(c.tier, 0);
    EXPECT_FALSE(c.continues_cell);
  }
  io::FrameHeader kept = parsed;
  io::keep_tiers(kept, [](const io::ChunkDesc&) { return 1u; });
  EXPECT_EQ(kept.chunks.size(), parsed.chunks.size());
}

TEST(Tiers, TheLayoutDependsOnTheDataNotTheCoding) {
  // Whether a cell stays whole is decided on the default coding's sizes, so
  // --smallest and --gpu-decodable files hold the same records.
  const io::FileHeader h = legacy(test::test_header(io::PositionCoding::Quantized16));
  const io::ParticleFrame f = test::lattice_frame(40000, 0.25);
  const io::EncodedFrame a = encode(f, h, kVariants[0], true), b = encode(f, h, kVariants[1], true),
                         c = encode(f, h, kVariants[2], true);
  ASSERT_EQ(a.header.chunks.size(), b.header.chunks.size());
  ASSERT_EQ(a.header.chunks.size(), c.header.chunks.size());
  for (size_t k = 0; k < a.header.chunks.size(); ++k) {
    EXPECT_EQ(a.header.chunks[k].tier, b.header.chunks[k].tier);
    EXPECT_EQ(a.header.chunks[k].tier, c.header.chunks[k].tier);
    EXPECT_EQ(a.header.chunks[k].particle_count, c.header.chunks[k].particle_count);
  }
}

TEST(Tiers, LatticeCellsThatTiersWouldBloatStayWhole) {
  // A regular lattice: tiers cost far more than 8% there (sparse deltas of
  // a structure zstd codes in a few bits), so cells stay one record each.
  const io::FileHeader h = legacy(test::test_header(io::PositionCoding::Quantized16, false));
  io::ParticleFrame f;
  for (uint32_t i = 0; i < 32768; ++i) {
    f.positions.insert(f.positions.end(), {float(i % 32) * 0.01f, float(i / 32 % 32) * 0.01f, float(i / 1024) * 0.01f});
    f.ids.push_back(i);
  }
  f.attributes.resize(1);
  const std::vector<uint16_t> lod = io::lod_values(f.ids, f.count());
  io::FrameInput in;
  in.positions = f.positions;
  in.lod = lod;
  io::EncodeOptions o;
  o.chunk_particles = 8192;
  const io::EncodedFrame tiered = io::encode_frame(in, h, o);
  o.lod_tiers = false;
  const io::EncodedFrame flat = io::encode_frame(in, h, o);
  EXPECT_LE(double(tiered.record.size()), 1.09 * double(flat.record.size()));
}

TEST(Tiers, TablesThatBreakTheTierRulesAreRejected) {
  const io::FileHeader h = legacy(test::test_header(io::PositionCoding::Quantized16));
  const io::EncodedFrame e = encode(test::scattered_frame(20000, 2), h, kVariants[0], true);
  const size_t desc = io::chunk_desc_bytes(h.attributes.size());
  const size_t table = io::frame_table_bytes(e.header.chunks.size(), h.attributes.size());
  auto reject = [&](size_t chunk, size_t byte, uint8_t value, const char* what) {
    std::vector<std::byte> record = e.record;
    record[io::kFrameHeaderFixedBytes + chunk * desc + byte] = std::byte(value);
    const uint64_t sum = io::chunk_checksum(std::span(record).first(table - 8));
    std::memcpy(record.data() + table - 8, &sum, 8);  // a valid table checksum: the rules themselves must catch it
    try {
      io::parse_frame_table(record, h.attributes.size(), {"f.sluice", 0, {}});
      ADD_FAILURE() << "accepted: " << what;
    } catch (const io::Error& error) {
      EXPECT_NE(std::string(error.what()).find("f.sluice"), std::string::npos) << error.what();
    }
  };
  reject(0, 18, uint8_t(io::kLodTiers), "a tier past the last");
  reject(0, 19, 1, "the first record continuing a cell");
  reject(1, 19, 2, "unknown cell flags");
  ASSERT_TRUE(e.header.chunks[1].continues_cell);
  reject(1, 18, 0, "a continuing record whose tier does not rise");
}
