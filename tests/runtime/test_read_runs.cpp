// Reads by demand in runs (read_runs.h): records close together share one
// read, nothing is read twice, reads are aligned for O_DIRECT, and a
// coarse-to-fine frame's overview is one run per layer.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "read_runs.h"
#include "sluice/io/codec.h"
#include "sluice/io/lod.h"

using namespace sluice;
using runtime::detail::ByteRun;
using runtime::detail::plan_runs;
using runtime::detail::RunLimits;

namespace {

io::RecordPart record(uint64_t offset, uint32_t size) { return {.offset = offset, .size = size}; }

std::vector<io::RecordPart> parts_of(const io::FrameHeader& fh) {
  std::vector<io::RecordPart> parts;
  io::record_parts(fh, parts);
  return parts;
}

void drop_fine_parts(io::FrameHeader& fh) {
  for (io::ChunkDesc& c : fh.chunks) c.fine.dropped = true;
}

// The pieces are in order, never overlap, and cover every record.
// Bytes below `skip` were read before (the table).
void expect_cover(const std::vector<io::RecordPart>& records, uint64_t record_at, const std::vector<ByteRun>& pieces,
                  uint64_t skip = 0) {
  for (size_t p = 1; p < pieces.size(); ++p) EXPECT_GE(pieces[p].at, pieces[p - 1].at + pieces[p - 1].length) << p;
  for (const io::RecordPart& c : records) {
    const uint64_t begin = record_at + c.offset, end = begin + c.size;
    uint64_t covered = std::max(begin, std::min(end, skip));
    for (const ByteRun& r : pieces) {
      if (r.at <= covered && r.at + r.length > covered) covered = std::min(end, r.at + r.length);
    }
    EXPECT_EQ(covered, end) << "record at " << c.offset;
  }
}

}  // namespace

TEST(ReadRuns, RecordsCloseTogetherShareARunAndFarOnesDoNot) {
  const std::vector<io::RecordPart> records{record(100, 1000), record(1100, 500), record(1600 + 1000, 300),
                                           record(1600 + 1000 + 300 + (1 << 20), 50)};
  std::vector<ByteRun> pieces;
  const size_t runs = plan_runs(records, 0, 4 << 20, 4 << 20, 100, {}, pieces);
  EXPECT_EQ(runs, 2u);
  ASSERT_EQ(pieces.size(), 2u);
  EXPECT_EQ(pieces[0].at, 100u);
  EXPECT_EQ(pieces[0].length, 2900u - 100u);  // the 1,000-byte gap is read through
  EXPECT_EQ(pieces[1].length, 50u);
  expect_cover(records, 0, pieces);
}

TEST(ReadRuns, AlignedForDirectReadsAndNeverPastTheBufferOrTheFile) {
  const std::vector<io::RecordPart> records{record(5000, 3000), record(200000, 10)};
  std::vector<ByteRun> pieces;
  // The record lies 300 bytes into a buffer of 256 KiB, whose first 8,192
  // bytes (the table) are read and of which only 200,100 bytes exist in the file.
  const RunLimits limits{.align = 4096, .gap = 1024, .piece = 8 << 20};
  plan_runs(records, 300, 256 << 10, 200100, 8192, limits, pieces);
  ASSERT_EQ(pieces.size(), 2u);
  for (const ByteRun& r : pieces) {
    EXPECT_EQ(r.at % 4096, 0u);
    EXPECT_EQ(r.length % 4096, 0u);
    EXPECT_LE(r.at + r.length, uint64_t(256 << 10));
  }
  EXPECT_EQ(pieces[0].at, 8192u);  // the table's blocks are not read again
  EXPECT_EQ(pieces[0].at + pieces[0].length, 12288u);
  EXPECT_EQ(pieces[1].at, 200704u - 4096u);
  EXPECT_EQ(pieces[1].required, 200100u - pieces[1].at);  // the rest lies past the end of the file
  expect_cover(records, 300, pieces, 8192);
}

TEST(ReadRuns, ALongRunIsReadInPiecesOfAboutEqualLength) {
  std::vector<io::RecordPart> records;
  for (uint64_t at = 0; at < (20 << 20); at += 100000) records.push_back(record(at, 100000));
  std::vector<ByteRun> pieces;
  const size_t runs = plan_runs(records, 0, 32 << 20, 32 << 20, 0, {.align = 1, .gap = 0, .piece = 8 << 20}, pieces);
  EXPECT_EQ(runs, 1u);
  ASSERT_EQ(pieces.size(), 3u);  // 21,000,000 bytes in 3 pieces of 7,000,000
  for (const ByteRun& r : pieces) EXPECT_LE(r.length, uint64_t(8 << 20));
  expect_cover(records, 0, pieces);
}

TEST(ReadRuns, ACoarseToFineOverviewIsOneRunAndACloseUpAFew) {
  // 300,000 scattered particles in a 10 x 10 x 1 slab, format 3.0.
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  std::vector<float> xyz;
  std::vector<uint64_t> ids;
  for (int i = 0; i < 300000; ++i) {
    xyz.insert(xyz.end(), {10 * u(rng), 10 * u(rng), u(rng)});
    ids.push_back(rng());
  }
  const std::vector<uint16_t> lod = io::lod_values(ids, ids.size());
  io::FileHeader h;
  h.particle_spacing = 0.01f;
  io::FrameInput in;
  in.positions = xyz;
  in.lod = lod;
  io::EncodeOptions o;
  o.chunk_particles = 8192;
  const io::EncodedFrame e = io::encode_frame(in, h, o);
  ASSERT_TRUE(e.header.coarse_to_fine);
  ASSERT_TRUE(e.header.split_positions);
  std::vector<ByteRun> pieces;
  // Overview: tiers 0 to t of every record: one run at the coarse
  // precision, and one more (a prefix of the fine parts) at full precision.
  for (uint32_t t = 1; t <= io::kLodTiers; ++t) {
    io::FrameHeader fh = e.header;
    io::keep_tiers(fh, [&](const io::ChunkDesc&) { return t; });
    const std::vector<io::RecordPart> precise = parts_of(fh);
    EXPECT_EQ(plan_runs(precise, 0, e.record.size(), e.record.size(), 0, {.align = 1, .gap = 0}, pieces), t < io::kLodTiers ? 2u : 1u) << t;
    expect_cover(precise, 0, pieces);
    drop_fine_parts(fh);
    const std::vector<io::RecordPart> coarse = parts_of(fh);
    EXPECT_EQ(plan_runs(coarse, 0, e.record.size(), e.record.size(), 0, {.align = 1, .gap = 0}, pieces), 1u) << t;
    expect_cover(coarse, 0, pieces);
  }
  // Close-up of a corner at full detail, the rest at 3 tiers.
  io::FrameHeader fh = e.header;
  io::keep_tiers(fh, [&](const io::ChunkDesc& c) { return c.bounds.min[0] < 2.f && c.bounds.min[1] < 2.f ? io::kLodTiers : 3u; });
  const std::vector<io::RecordPart> parts = parts_of(fh);
  const size_t runs = plan_runs(parts, 0, e.record.size(), e.record.size(), 0, {.align = 1, .gap = 0}, pieces);
  EXPECT_GE(runs, 2u);
  EXPECT_LE(runs, 2u * 4u * io::kLodTiers) << "runs: " << runs << " of " << parts.size() << " parts";
  expect_cover(parts, 0, pieces);
  uint64_t asked = 0, wanted = 0;
  for (const ByteRun& r : pieces) asked += r.length;
  for (const io::RecordPart& c : parts) wanted += c.size;
  EXPECT_EQ(asked, wanted);  // gap 0: nothing but the records and their fine parts
}
