// The view's demand (demand.h): tiers per cell against the renderer's rule
// evaluated particle by particle, the pipeline reading only those tiers on
// the CPU and the kept-encoded paths, a paused player reading the missing
// ones, errors naming the file's record, and demands racing with seeks and
// delivery (run under TSan with the rest of the runtime suite).
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <cstdio>
#include <map>
#include <random>
#include <thread>

#include "demand_test_util.h"
#include "runtime_test_util.h"
#include "sluice/io/lod.h"
#include "sluice/io/reader.h"
#include "sluice/runtime/clock.h"
#include "sluice/runtime/demand.h"
#include "sluice/runtime/pipeline.h"
#include "sluice/runtime/player.h"

namespace sluice::runtime {
namespace {

namespace fs = std::filesystem;
using test::at;
using test::demand_of;
using test::Mat;
using test::write_scattered;

class DemandTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new test::TempDir;
    path_ = write_scattered(*dir_ / "scattered.sluice", 8, 40000);
  }
  static void TearDownTestSuite() { delete dir_; }
  static test::TempDir* dir_;
  static fs::path path_;
};
test::TempDir* DemandTest::dir_ = nullptr;
fs::path DemandTest::path_;

const std::array<float, 3> kFarEye{0.5f, -2.5f, 1.2f}, kNearEye{0.15f, 0.05f, 0.35f}, kCentre{0.5f, 0.3f, 0.15f};

TEST_F(DemandTest, FarViewsNeedFewTiersNearViewsAllAndUnseenCellsNone) {
  const io::ContainerReader reader(path_);
  const io::FrameHeader table = reader.read_table(0);
  ASSERT_GT(table.chunks.size(), 8u) << "the file must hold tiers";
  const ViewDemand far = demand_of(kFarEye, kCentre, 0.3f), near = demand_of(kNearEye, {0.9f, 0.55f, 0.1f}, 0.3f);
  const ViewDemand away = demand_of({0.5f, -2.5f, 1.2f}, {0.5f, -5.0f, 1.2f}, 0.3f);  // looking away from the block
  uint64_t far_tiers = 0, near_tiers = 0, cells = 0;
  for (size_t first = 0; first < table.chunks.size(); first = io::cell_end(table.chunks, first)) {
    const io::ChunkDesc& c = table.chunks[first];
    ++cells;
    far_tiers += tiers_needed(far, c.bounds, c.layer, 0);
    near_tiers += tiers_needed(near, c.bounds, c.layer, 0);
    EXPECT_EQ(tiers_needed(away, c.bounds, c.layer, 0), 0u);
    EXPECT_EQ(tiers_needed({}, c.bounds, c.layer, 0), io::kLodTiers);  // no views: everything
    EXPECT_EQ(tiers_needed(demand_of(kFarEye, kCentre, 0.3f, false), c.bounds, c.layer, 0), io::kLodTiers);  // LOD off
    EXPECT_GE(tiers_needed(far, c.bounds, c.layer, 0), 1u);  // the far view sees the whole block
  }
  EXPECT_LT(far_tiers, near_tiers);
  EXPECT_LE(far_tiers, 8 * cells) << "a far view at level 0.3 keeps at most 30% of any cell";
}

// The renderer's rule (cull_particles.comp; render/lod.h), particle by
// particle in float as the shader computes it: every particle some view
// keeps lies in a tier its cell's demand reads.
TEST_F(DemandTest, EveryParticleTheRuleKeepsIsInADemandedTier) {
  const io::ContainerReader reader(path_);
  const io::DecodedFrame frame = io::decode_frame(reader, 2);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0, 1);
  uint64_t checked = 0, kept = 0;
  for (int trial = 0; trial < 24; ++trial) {
    const std::array<float, 3> eye{-1.0f + 3.0f * u(rng), -1.5f + 3.0f * u(rng), 0.05f + 1.5f * u(rng)};
    const std::array<float, 3> target{u(rng), 0.6f * u(rng), 0.3f * u(rng)};
    const float level = 0.05f + 0.9f * u(rng);
    const ViewDemand d = demand_of(eye, target, level);
    const Mat& v = d.views[0].view;
    const Mat& p = d.views[0].projection;
    const float threshold = -std::log(level);
    for (size_t c = 0; c < frame.header.chunks.size(); ++c) {
      const io::ChunkDesc& chunk = frame.header.chunks[c];
      // This record's cell: the first record at or before it that starts one.
      size_t first = c;
      while (frame.header.chunks[first].continues_cell) --first;
      const uint32_t tiers = tiers_needed(d, frame.header.chunks[first].bounds, chunk.layer, 0);
      for (uint64_t i = frame.chunk_first[c]; i < frame.chunk_first[c] + chunk.particle_count; ++i) {
        uint16_t q[4];
        std::memcpy(q, frame.particles.data() + i * 8, 8);
        float w_pos[3];
        for (int a = 0; a < 3; ++a) w_pos[a] = io::dequantize(q[a], chunk.bounds.min[size_t(a)], chunk.bounds.max[size_t(a)]);
        float e[3];
        Mat vv = v;
        for (int r = 0; r < 3; ++r) e[r] = at(vv, r, 0) * w_pos[0] + at(vv, r, 1) * w_pos[1] + at(vv, r, 2) * w_pos[2] + at(vv, r, 3);
        if (-e[2] <= 0.02f) continue;  // behind or at the near plane: not drawn
        Mat pp = p;
        const float nx = at(pp, 0, 0) * e[0] / -e[2] - at(pp, 0, 2), ny = at(pp, 1, 1) * e[1] / -e[2] - at(pp, 1, 2);
        if (std::abs(nx) > 1 || std::abs(ny) > 1) continue;  // outside the frustum
        const float centre = std::max(1.0f - 0.7f * std::min(std::sqrt(nx * nx + ny * ny) * 0.70710678f, 1.0f), 0.3f);
        const float w = centre / (std::sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]) * (1.0f / d.reference_distance));
        const float uu = (float(q[3]) + 0.5f) * (1.0f / 65536.0f);
        ++checked;
        if (!(w * -std::log(1.0f - uu) >= threshold)) continue;
        ++kept;
        ASSERT_LT(chunk.tier, tiers) << "trial " << trial << ": a kept particle (value " << q[3] << ", w " << w
                                      << ", level " << level << ") in tier " << int(chunk.tier) << " of a cell read to "
                                      << tiers;
      }
    }
  }
  EXPECT_GT(kept, 10000u);
  EXPECT_GT(checked, kept);
}

struct Streamed {
  std::vector<io::FrameHeader> headers;
  PipelineStats stats;
};

Streamed stream(const io::ContainerReader& reader, const ViewDemand& demand, bool encoded) {
  HostFrameAllocator allocator;
  PipelineOptions po;
  po.decode.threads = 2;
  po.read.threads = 2;
  po.demand = demand;
  po.decode.mode = (encoded) ? sluice::runtime::DecodeMode::KeepEncoded : sluice::runtime::DecodeMode::Cpu;
  Pipeline pipeline(reader, allocator, po);
  pipeline.restart({reader.frame_count(), 0, 1, 1, EndMode::Stop});
  Streamed out;
  while (true) {
    const NextEntry next = pipeline.wait_next();
    if (next.end) break;
    FrameHandle h = pipeline.take();
    EXPECT_FALSE(h.failed()) << (h.failed() ? h.error()->text() : "");
    if (h.failed()) break;
    out.headers.push_back(h.header());
    if (!encoded) {
      // The decoded particles are those of the records kept, in their
      // order: bit for bit, or (read without the fine part) each axis within
      // io::kCoarseSteps quantization steps and the LOD value the same.
      const io::DecodedFrame whole = io::decode_frame(reader, h.frame());
      std::map<uint32_t, size_t> position;  // table record -> place in the whole frame's chunks
      for (size_t c = 0; c < whole.header.chunks.size(); ++c) position[whole.header.chunks[c].index] = c;
      for (size_t c = 0; c < h.header().chunks.size(); ++c) {
        const io::ChunkDesc& chunk = h.header().chunks[c];
        const uint64_t from = whole.chunk_first[position.at(chunk.index)];
        const std::byte* got = h.buffers().particles.data() + h.chunk_first()[c] * 8;
        const std::byte* want = whole.particles.data() + from * 8;
        if (!chunk.fine.dropped) {
          EXPECT_EQ(0, std::memcmp(got, want, size_t(chunk.particle_count) * 8));
          continue;
        }
        for (uint32_t i = 0; i < chunk.particle_count; ++i) {
          uint16_t g[4], w[4];
          std::memcpy(g, got + 8 * i, 8);
          std::memcpy(w, want + 8 * i, 8);
          for (int a = 0; a < 3; ++a) EXPECT_LE(std::abs(int(g[a]) - int(w[a])), int(io::kCoarseSteps[size_t(a)]));
          EXPECT_EQ(g[3], w[3]);
        }
      }
    }
  }
  out.stats = pipeline.stats();
  return out;
}

TEST_F(DemandTest, ThePipelineReadsOnlyTheDemandedTiers) {
  const io::ContainerReader reader(path_);
  const ViewDemand far = demand_of(kFarEye, kCentre, 0.2f);
  for (const bool encoded : {false, true}) {
    SCOPED_TRACE(encoded ? "kept encoded" : "decoded on the CPU");
    const Streamed s = stream(reader, far, encoded);
    ASSERT_EQ(s.headers.size(), reader.frame_count());
    for (uint64_t f = 0; f < reader.frame_count(); ++f) {
      io::FrameHeader expected = reader.read_table(f);
      apply_demand(far, expected);
      ASSERT_EQ(s.headers[f].chunks.size(), expected.chunks.size()) << "frame " << f;
      for (size_t c = 0; c < expected.chunks.size(); ++c) EXPECT_EQ(s.headers[f].chunks[c].index, expected.chunks[c].index);
      EXPECT_EQ(s.headers[f].particle_count, expected.particle_count);
    }
    EXPECT_EQ(s.stats.frames_by_demand, reader.frame_count());
    EXPECT_LT(double(s.stats.bytes_read), 0.5 * double(s.stats.record_bytes)) << "a far view at 0.2 reads little";
    // Every tier, no views: the whole records.
    const Streamed all = stream(reader, {}, encoded);
    EXPECT_EQ(all.stats.frames_by_demand, 0u);
    EXPECT_GE(all.stats.bytes_read, all.stats.record_bytes);
  }
}

// The layer spans a frame holds (a run of records of one layer): a demand
// of every cell's first tiers is one prefix of each (format 2.0), and of
// the layer's fine parts (3.0).
size_t layer_spans(const io::FrameHeader& h) {
  size_t spans = 0;
  for (size_t c = 0; c < h.chunks.size(); ++c) spans += c == 0 || h.chunks[c].layer != h.chunks[c - 1].layer;
  return spans;
}

TEST_F(DemandTest, ACoarseToFineOverviewIsARunALayerAndNoByteIsReadTwice) {
  const io::ContainerReader reader(path_);
  ASSERT_EQ(reader.header().version_major, 3);
  uint64_t tables = 0, layers = 0;
  for (uint64_t f = 0; f < reader.frame_count(); ++f) {
    const io::FrameIndexEntry& e = reader.index().frames[f];
    tables += io::frame_table_bytes(e.chunk_count, reader.header().attributes.size());
    layers += layer_spans(reader.read_table(f));
  }
  // An overview (every cell, its first tiers) at full precision and from
  // far enough that every record is read coarse (1 pixel), and a close
  // view at full detail (the cells it sees, every tier).
  const ViewDemand overview = ViewDemand::uniform(0.3f), close = demand_of(kNearEye, kCentre, 1.0f);
  const ViewDemand coarse = demand_of({0.5f, -6.0f, 2.5f}, kCentre, 0.3f, true, 1.0f);
  for (const bool encoded : {false, true}) {
    SCOPED_TRACE(encoded ? "kept encoded" : "decoded on the CPU");
    const PipelineStats o = stream(reader, overview, encoded).stats;
    EXPECT_EQ(o.frames_by_demand, reader.frame_count());
    EXPECT_LE(o.runs_read, 2 * layers) << "at most two runs a layer a frame: its records' prefix and their fine parts'";
    EXPECT_GE(o.runs_read, reader.frame_count());
    EXPECT_EQ(o.bytes_read, tables + o.run_bytes);
    const PipelineStats far = stream(reader, coarse, encoded).stats;
    EXPECT_EQ(far.runs_read, layers) << "one run a layer a frame: no fine part";
    EXPECT_LT(far.run_bytes, o.run_bytes);
    // Every byte read once: the tables, then the runs (which hold the
    // wanted records and the short gaps between them).
    EXPECT_EQ(o.bytes_read, tables + o.run_bytes);
    const PipelineStats c = stream(reader, close, encoded).stats;
    EXPECT_EQ(c.bytes_read, tables + c.run_bytes);
    EXPECT_LE(c.runs_read, reader.frame_count() * 4 * io::kLodTiers) << "a close view's runs are few";
  }
}

// Precision by distance (format 3.0): every particle of a record the rule
// reads without its fine part is drawn within the stated error of where
// its full precision puts it, in every view, from close to far; the rule
// reads coarse from far and whole from close.
TEST_F(DemandTest, ACoarseRecordsParticlesStayWithinTheStatedScreenError) {
  const io::ContainerReader reader(path_);
  const io::FileHeader& file = reader.header();
  const std::vector<std::byte> record = reader.read_record(1);
  const io::FrameHeader whole = reader.parse_record(1, record);
  io::FrameHeader coarse = whole;
  for (io::ChunkDesc& c : coarse.chunks) {
    ASSERT_TRUE(c.fine.split());
    c.fine.dropped = true;
  }
  std::vector<uint64_t> starts(whole.chunks.size());
  const uint64_t n = io::chunk_starts(whole, starts);
  std::vector<uint64_t> exact(n), rough(n);
  io::decode_record(record, whole, file, starts, std::as_writable_bytes(std::span(exact)), {}, {});
  io::decode_record(record, coarse, file, starts, std::as_writable_bytes(std::span(rough)), {}, {});

  uint64_t coarse_records = 0, whole_records = 0, checked = 0;
  double worst = 0;  // the largest error seen, as a share of the stated one
  for (const float error : {0.25f, 1.0f}) {
    for (const float distance : {0.6f, 1.5f, 3.0f, 6.0f, 12.0f}) {
      const std::array<float, 3> eye{0.5f, 0.3f - distance, 0.15f + 0.4f * distance};
      const ViewDemand d = demand_of(eye, kCentre, 0.3f, true, error);
      const DemandView& v = d.views[0];
      // Where a world point lands, in pixels; false when it is not drawn
      // (behind the eye, or more than half a screen outside the viewport).
      const auto pixel = [&](const std::array<double, 3>& p, double& x, double& y) {
        double eye_space[4] = {0, 0, 0, 1}, clip[4] = {0, 0, 0, 0};
        for (int r = 0; r < 3; ++r) {
          eye_space[r] = v.view[size_t(12 + r)];
          for (int c = 0; c < 3; ++c) eye_space[r] += double(v.view[size_t(4 * c + r)]) * p[size_t(c)];
        }
        for (int r = 0; r < 4; ++r) {
          for (int k = 0; k < 4; ++k) clip[r] += double(v.projection[size_t(4 * k + r)]) * eye_space[k];
        }
        if (clip[3] <= 0) return false;
        const double nx = clip[0] / clip[3], ny = clip[1] / clip[3];
        x = (nx + 1) * 0.5 * v.width;
        y = (ny + 1) * 0.5 * v.height;
        return std::abs(nx) <= 1.5 && std::abs(ny) <= 1.5;
      };
      for (size_t c = 0; c < whole.chunks.size(); ++c) {
        const io::ChunkDesc& chunk = whole.chunks[c];
        if (!coarse_enough(d, chunk.bounds, chunk.layer)) {
          ++whole_records;
          continue;
        }
        ++coarse_records;
        for (uint64_t i = starts[c]; i < starts[c] + chunk.particle_count; ++i) {
          std::array<double, 3> p{}, q{};
          for (int a = 0; a < 3; ++a) {
            const float lo = chunk.bounds.min[size_t(a)], hi = chunk.bounds.max[size_t(a)];
            p[size_t(a)] = io::dequantize(uint16_t(exact[i] >> (16 * a)), lo, hi);
            q[size_t(a)] = io::dequantize(uint16_t(rough[i] >> (16 * a)), lo, hi);
          }
          double px = 0, py = 0, qx = 0, qy = 0;
          if (!pixel(p, px, py)) continue;  // not drawn
          pixel(q, qx, qy);
          const double moved = std::hypot(px - qx, py - qy);
          ++checked;
          worst = std::max(worst, moved / error);
          ASSERT_LE(moved, error) << "record " << c << ", particle " << i << ", from " << distance << " m";
        }
      }
    }
  }
  std::printf("coarse records %llu, whole %llu; %llu particles checked, the worst at %.2f of the stated error\n",
              (unsigned long long)coarse_records, (unsigned long long)whole_records, (unsigned long long)checked, worst);
  EXPECT_GT(coarse_records, 0u) << "far views read records coarse";
  EXPECT_GT(whole_records, 0u) << "close views read records whole";
  EXPECT_GT(checked, 10000u);
  EXPECT_GT(worst, 0.02) << "the rule is not vacuous: coarse particles do move";
}

// A frame read coarse for a far view falls short of a close one (its
// records are wanted whole), not of another far one.
TEST_F(DemandTest, AFrameReadCoarseFallsShortOfACloseView) {
  const io::ContainerReader reader(path_);
  io::FrameHeader h = reader.read_table(0);
  const ViewDemand far = demand_of({0.5f, -6.0f, 2.5f}, kCentre, 1.0f, true, 1.0f);
  const ViewDemand close = demand_of(kNearEye, kCentre, 1.0f, true, 1.0f);
  std::vector<CellRead> cells;
  apply_demand(far, h, cells);
  uint64_t dropped = 0;
  for (const io::ChunkDesc& c : h.chunks) dropped += c.fine.dropped;
  EXPECT_EQ(dropped, h.chunks.size()) << "from far every record is read coarse";
  EXPECT_FALSE(short_of(far, cells, h.blob_voxel));
  EXPECT_TRUE(short_of(close, cells, h.blob_voxel));
  ViewDemand exact = far;
  exact.position_error_pixels = 0;  // precision by distance off: every record whole
  EXPECT_TRUE(short_of(exact, cells, h.blob_voxel));
}

TEST_F(DemandTest, APausedPlayerReadsWhatTheLargerDemandLacks) {
  const io::ContainerReader reader(path_);
  HostFrameAllocator allocator;
  VirtualClock clock;
  PlayerOptions po;
  po.start_frame = 3;
  po.pipeline.decode.threads = 2;
  po.pipeline.demand = demand_of(kFarEye, kCentre, 0.1f);
  Player player(reader, allocator, clock, po);
  const auto shown_after = [&](auto done) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while (std::chrono::steady_clock::now() < deadline) {
      player.wait_for_due();
      player.update();
      if (done()) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    return false;
  };
  ASSERT_TRUE(shown_after([&] { return player.shown() != nullptr; }));
  const size_t far_records = player.shown()->header().chunks.size();
  const ViewDemand closer = demand_of(kFarEye, kCentre, 0.9f);
  EXPECT_TRUE(player.pipeline().short_of(*player.shown(), closer));
  player.set_demand(closer);
  ASSERT_TRUE(shown_after([&] { return !player.pipeline().short_of(*player.shown(), closer); }));
  EXPECT_EQ(player.shown()->frame(), 3u);
  EXPECT_EQ(player.stats().refinements, 1u);
  io::FrameHeader expected = reader.read_table(3);
  apply_demand(closer, expected);
  EXPECT_EQ(player.shown()->header().chunks.size(), expected.chunks.size());
  EXPECT_GT(expected.chunks.size(), far_records);
  // Nothing more to read: no second refinement.
  for (int i = 0; i < 20; ++i) player.update();
  EXPECT_EQ(player.stats().refinements, 1u);
}

TEST_F(DemandTest, ABadRecordIsNamedAsTheFileNumbersIt) {
  const fs::path legacy = write_scattered(*dir_ / "legacy.sluice", 2, 40000, 1);
  const io::ContainerReader clean(legacy);
  const ViewDemand far = demand_of(kFarEye, kCentre, 0.05f);
  // The last record the view reads, after records it leaves out (format
  // 1.5, where those are each cell's first tiers: a 2.0 file's far view
  // reads a prefix, its records numbered as read).
  io::FrameHeader table = clean.read_table(1);
  io::FrameHeader kept = table;
  apply_demand(far, kept);
  ASSERT_LT(kept.chunks.size(), table.chunks.size());
  const size_t last = kept.chunks.back().index;
  ASSERT_GE(last, kept.chunks.size());  // some record before it is left out
  const fs::path bad = *dir_ / "bad.sluice";
  fs::copy_file(legacy, bad, fs::copy_options::overwrite_existing);
  {
    std::fstream f(bad, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(std::streamoff(clean.index().frames[1].offset + table.chunks[last].offset + 5));
    const char flip = 0x5a;
    f.write(&flip, 1);
  }
  const io::ContainerReader reader(bad);
  for (const bool encoded : {false, true}) {
    HostFrameAllocator allocator;
    PipelineOptions po;
    po.decode.threads = 2;
    po.demand = far;
    po.decode.mode = (encoded) ? sluice::runtime::DecodeMode::KeepEncoded : sluice::runtime::DecodeMode::Cpu;
    Pipeline pipeline(reader, allocator, po);
    pipeline.restart({reader.frame_count(), 0, 1, 1, EndMode::Stop});
    bool failed = false;
    while (true) {
      if (pipeline.wait_next().end) break;
      FrameHandle h = pipeline.take();
      if (!h.failed()) continue;
      failed = true;
      EXPECT_EQ(h.frame(), 1u);
      EXPECT_EQ(h.error()->where.frame, 1u);
      EXPECT_EQ(h.error()->where.chunk, uint64_t(last)) << h.error()->text();
      EXPECT_NE(h.error()->text().find("bad.sluice"), std::string::npos) << h.error()->text();
    }
    EXPECT_TRUE(failed);
  }
}

// Demands set from another thread while the consumer seeks and takes
// frames: every frame holds, of each cell, a prefix of its tiers, and
// nothing fails (TSan checks the hand-off).
TEST_F(DemandTest, DemandsRaceWithSeeksAndDelivery) {
  const io::ContainerReader reader(path_);
  std::vector<io::FrameHeader> tables;
  for (uint64_t f = 0; f < reader.frame_count(); ++f) tables.push_back(reader.read_table(f));
  const std::vector<ViewDemand> demands{{}, demand_of(kFarEye, kCentre, 0.1f), demand_of(kNearEye, kCentre, 0.5f),
                                        demand_of({0.5f, -2.5f, 1.2f}, {0.5f, -5.0f, 1.2f}, 0.3f)};
  for (const bool encoded : {false, true}) {
    HostFrameAllocator allocator;
    PipelineOptions po;
    po.decode.threads = 2;
    po.read.threads = 2;
    po.decode.mode = (encoded) ? sluice::runtime::DecodeMode::KeepEncoded : sluice::runtime::DecodeMode::Cpu;
    Pipeline pipeline(reader, allocator, po);
    std::atomic<bool> stop{false};
    std::thread setter([&] {
      for (uint32_t i = 0; !stop.load(); ++i) {
        pipeline.set_demand(demands[i % demands.size()]);
        std::this_thread::yield();
      }
    });
    std::mt19937 rng(3);
    uint64_t taken = 0;
    for (int round = 0; round < 30; ++round) {
      pipeline.restart({reader.frame_count(), int64_t(rng() % reader.frame_count()), 1, 1, EndMode::Loop});
      for (int k = 0; k < 3; ++k) {
        const NextEntry next = pipeline.wait_next();
        ASSERT_FALSE(next.end);
        FrameHandle h = pipeline.take();
        ASSERT_FALSE(h.failed()) << h.error()->text();
        ++taken;
        const io::FrameHeader& got = h.header();
        const io::FrameHeader& all = tables[h.frame()];
        uint64_t particles = 0;
        for (size_t c = 0; c < got.chunks.size(); ++c) {
          const io::ChunkDesc& chunk = got.chunks[c];
          particles += chunk.particle_count;
          // The record before it in the file, if of the same cell, was read too.
          if (chunk.continues_cell) {
            ASSERT_GT(c, 0u);
            EXPECT_EQ(got.chunks[c - 1].index + 1, chunk.index) << "a cell's tiers are read as a prefix";
          }
          EXPECT_EQ(all.chunks[chunk.index].checksum, chunk.checksum);
        }
        EXPECT_EQ(particles, got.particle_count);
      }
    }
    stop = true;
    setter.join();
    EXPECT_EQ(taken, 90u);
    EXPECT_EQ(pipeline.stats().frames_failed, 0u);
  }
}

}  // namespace
}  // namespace sluice::runtime
