// Format 3.0: each record's positions in two parts (docs/format.md,
// "Precision parts"). With its fine part a record decodes bit for bit as
// format 2.0 writes it; without, every axis within io::kCoarseSteps
// quantization steps; the fine parts lie after their layer's records, in
// the same order; damaged fine parts and tables that misplace them are
// named errors.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <string>

#include "records.h"
#include "sluice/io/reader.h"
#include "sluice/io/codec.h"
#include "test_util.h"

using namespace sluice;

namespace {

// The records of `f`, chunks of at most 8,192 particles.
io::EncodedFrame encode(const io::ParticleFrame& f, const io::FileHeader& h, bool layers = false) {
  return test::encode(f, h, 8192, layers);
}

io::FileHeader header_of(uint16_t major) {
  io::FileHeader h = test::test_header(io::PositionCoding::Quantized16);
  io::set_format_version(h, major);
  return h;
}

// The frame's 8-byte particles and its attribute, decoded from `record`
// under `fh` (which may leave fine parts out).
struct Decoded {
  std::vector<uint64_t> particles;
  std::vector<uint16_t> attribute;
};
Decoded decode(std::span<const std::byte> record, const io::FrameHeader& fh, const io::FileHeader& h) {
  std::vector<uint64_t> starts(fh.chunks.size());
  const uint64_t n = io::chunk_starts(fh, starts);
  Decoded d;
  d.particles.resize(n);
  d.attribute.resize(n);
  std::vector<uint16_t*> attrs(h.attributes.size(), d.attribute.data());
  io::decode_record(record, fh, h, starts, std::as_writable_bytes(std::span(d.particles)), attrs, {});
  return d;
}

uint64_t record_bytes(const io::FrameHeader& fh) {
  uint64_t bytes = 0;
  for (const io::ChunkDesc& c : fh.chunks) bytes += c.compressed_size;
  return bytes;
}

}  // namespace

TEST(PrecisionParts, WithItsFinePartARecordDecodesAsTheWholeCode) {
  const io::ParticleFrame frame = test::scattered_frame(120000, 3);
  for (const bool layers : {false, true}) {
    SCOPED_TRACE(layers ? "layered" : "one layer");
    const io::FileHeader h3 = header_of(3), h2 = header_of(2);
    const io::EncodedFrame split = encode(frame, h3, layers), whole = encode(frame, h2, layers);
    ASSERT_TRUE(split.header.split_positions);
    ASSERT_FALSE(whole.header.split_positions);
    ASSERT_EQ(split.header.chunks.size(), whole.header.chunks.size()) << "the same records, positions coded apart";
    for (const io::ChunkDesc& c : split.header.chunks) EXPECT_GT(c.fine.size, 0u);
    const Decoded a = decode(split.record, split.header, h3), b = decode(whole.record, whole.header, h2);
    EXPECT_EQ(a.particles, b.particles);
    EXPECT_EQ(a.attribute, b.attribute);
    // The split costs the bytes of a few plane tables, no more.
    EXPECT_LE(double(split.record.size()), 1.01 * double(whole.record.size()));
    // Parsed back from its bytes, the table folds the fine parts into their records.
    const io::FrameHeader parsed = io::parse_frame_table(split.record, h3.attributes.size(), {});
    ASSERT_EQ(parsed.chunks.size(), split.header.chunks.size());
    for (size_t c = 0; c < parsed.chunks.size(); ++c) {
      EXPECT_EQ(parsed.chunks[c].fine.offset, split.header.chunks[c].fine.offset);
      EXPECT_EQ(parsed.chunks[c].fine.checksum, split.header.chunks[c].fine.checksum);
    }
    EXPECT_EQ(parsed.table_records(), 2 * parsed.chunks.size());
  }
}

TEST(PrecisionParts, FinePartsFollowTheirLayersRecordsInTheirOrder) {
  const io::FileHeader h = header_of(3);
  const io::EncodedFrame e = encode(test::scattered_frame(120000, 4), h, true);
  const auto& chunks = e.header.chunks;
  for (size_t c = 0; c < chunks.size(); ++c) {
    // Every fine part lies after the last record of its layer and after
    // the fine part of the record before it in that layer.
    size_t last = c;
    while (last + 1 < chunks.size() && chunks[last + 1].layer == chunks[c].layer) ++last;
    EXPECT_GE(chunks[c].fine.offset, chunks[last].offset + chunks[last].compressed_size) << c;
    if (c > 0 && chunks[c - 1].layer == chunks[c].layer) {
      EXPECT_EQ(chunks[c].fine.offset, chunks[c - 1].fine.offset + chunks[c - 1].fine.size) << c;
    }
  }
}

TEST(PrecisionParts, WithoutItsFinePartEveryAxisIsWithinTheCoarseSteps) {
  const io::FileHeader h = header_of(3);
  const io::EncodedFrame e = encode(test::scattered_frame(120000, 5), h);
  io::FrameHeader coarse = e.header;
  for (io::ChunkDesc& c : coarse.chunks) c.fine.dropped = true;
  // The records alone are all a coarse reader needs: the fine parts' bytes zeroed.
  std::vector<std::byte> record = e.record;
  for (const io::ChunkDesc& c : e.header.chunks) std::memset(record.data() + c.fine.offset, 0, c.fine.size);
  const Decoded full = decode(e.record, e.header, h), rough = decode(record, coarse, h);
  ASSERT_EQ(full.particles.size(), rough.particles.size());
  uint64_t moved = 0;
  for (size_t i = 0; i < full.particles.size(); ++i) {
    for (int a = 0; a < 3; ++a) {
      const int q = int((full.particles[i] >> (16 * a)) & 0xffff), r = int((rough.particles[i] >> (16 * a)) & 0xffff);
      ASSERT_LE(std::abs(q - r), int(io::kCoarseSteps[size_t(a)])) << "particle " << i << " axis " << a;
      moved += q != r;
    }
    ASSERT_EQ(full.particles[i] >> 48, rough.particles[i] >> 48) << "the LOD value is the record's";
  }
  EXPECT_GT(moved, full.particles.size()) << "the fill stands for the low bits: most positions move";
  EXPECT_EQ(full.attribute, rough.attribute);
  // Scattered particles: the low bits are noise, stored, 2 bytes a
  // particle that a coarse reader leaves out.
  uint64_t fine = 0;
  for (const io::ChunkDesc& c : e.header.chunks) fine += c.fine.size;
  EXPECT_EQ(fine, 2 * full.particles.size());
  std::printf("records %llu bytes, fine parts %llu bytes (%.1f%% of both)\n", (unsigned long long)record_bytes(e.header),
              (unsigned long long)fine, 100.0 * double(fine) / double(fine + record_bytes(e.header)));
}

TEST(PrecisionParts, ADamagedFinePartIsNamed) {
  const io::FileHeader h = header_of(3);
  io::EncodedFrame e = encode(test::scattered_frame(30000, 6), h);
  const io::ChunkDesc& target = e.header.chunks[1];
  e.record[target.fine.offset + 7] ^= std::byte{0x20};
  try {
    decode(e.record, e.header, h);
    ADD_FAILURE() << "a damaged fine part was decoded";
  } catch (const io::Error& err) {
    const std::string what = err.what();
    EXPECT_NE(what.find("fine part (table record " + std::to_string(target.fine.index) + ")"), std::string::npos) << what;
    EXPECT_NE(what.find("checksum"), std::string::npos) << what;
    EXPECT_EQ(err.where().chunk, 1u);
  }
  // Left out, it is not read: the frame decodes coarse.
  io::FrameHeader coarse = e.header;
  coarse.chunks[1].fine.dropped = true;
  EXPECT_NO_THROW(decode(e.record, coarse, h));
}

// A table whose fine parts do not follow their records is refused, naming
// what is wrong (the table's checksum made good, so the rules are what
// refuse it).
TEST(PrecisionParts, TablesThatMisplaceFinePartsAreRefused) {
  const io::FileHeader h = header_of(3);
  const io::EncodedFrame e = encode(test::scattered_frame(30000, 7), h);
  const size_t records = e.header.chunks.size();
  ASSERT_GE(records, 2u);
  const size_t desc = io::chunk_desc_bytes(h.attributes.size());
  const uint64_t table = io::frame_table_bytes(e.header.table_records(), h.attributes.size());
  const auto descriptor = [&](std::vector<std::byte>& r, size_t k) { return r.data() + io::kFrameHeaderFixedBytes + k * desc; };
  const auto reseal = [&](std::vector<std::byte>& r) {
    const uint64_t sum = io::chunk_checksum(std::span(r).first(table - 8));
    std::memcpy(r.data() + table - 8, &sum, 8);
  };
  const auto refused = [&](std::vector<std::byte> r, const char* expect) {
    reseal(r);
    try {
      io::parse_frame_table(r, h.attributes.size(), {});
      ADD_FAILURE() << "accepted: " << expect;
    } catch (const io::Error& err) {
      EXPECT_NE(std::string(err.what()).find(expect), std::string::npos) << err.what();
    }
  };
  {  // a fine part whose particle count differs from its record's
    std::vector<std::byte> r = e.record;
    uint32_t n;
    std::memcpy(&n, descriptor(r, records) + 12, 4);
    n -= 1;
    std::memcpy(descriptor(r, records) + 12, &n, 4);
    refused(r, "does not describe its record");
  }
  {  // a record where the first fine part belongs (its fine flag cleared)
    std::vector<std::byte> r = e.record;
    descriptor(r, records)[18] &= std::byte{0x7f};
    refused(r, "lack their fine parts");
  }
  {  // a fine part among the records
    std::vector<std::byte> r = e.record;
    descriptor(r, 0)[18] |= std::byte{0x80};
    refused(r, "precedes its layer's records");
  }
}
