// The bundled real solver output (PySPH 3D dam break, data/dam_break_3d)
// through the whole io path: import, convert, verify, decode. Sizes are
// deterministic (fixed zstd level), so the compression figure is a
// regression check, not a timing.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>

#include "../io/test_util.h"
#include "sluice/import/frames.h"
#include "sluice/io/maintenance.h"
#include "sluice/io/reader.h"

namespace test = sluice::test;
namespace io = sluice::io;
using namespace sluice::io;
using namespace sluice::import;

namespace {

const std::string kPvd = std::string(SLUICE_SAMPLE_DIR) + "/dam_break_3d.pvd";

std::filesystem::path convert_sample(const std::filesystem::path& out, PositionCoding coding,
                                     PlaneCoding planes = PlaneCoding::Packed) {
  const auto source = open_source(kPvd, {});
  FileHeader h;
  h.position_coding = coding;
  h.particle_spacing = 0.04f;
  h.lod_id_array = source->info().id_array;
  ContainerWriter w(out, h);
  EncodeOptions encode;
  encode.planes = planes;
  convert_frames(*source, std::nullopt, w, FramesSettings{.encode = encode, .max_in_flight = 3});
  w.finish();
  return out;
}

class Sample : public ::testing::Test {
 protected:
  void SetUp() override {
#ifndef SLUICE_WITH_VTK
    GTEST_SKIP() << "built without VTK: the sample is .vtu";
#endif
    // The sample is part of the repository: without it the test fails.
    ASSERT_TRUE(std::filesystem::exists(kPvd)) << kPvd << " is missing (data/ is part of the repository)";
  }
  test::TempDir dir;
};

}  // namespace

TEST_F(Sample, ConvertsWithTimesIdsAndVerifies) {
  const auto path = convert_sample(dir / "q.sluice", PositionCoding::Quantized16);
  const ContainerReader r(path);
  ASSERT_EQ(r.frame_count(), 13u);
  EXPECT_EQ(r.header().lod_id_array, "gid");
  EXPECT_EQ(r.index().frames.front().time, 0.0);
  EXPECT_NEAR(r.index().frames.back().time, 0.25, 1e-9);
  for (const auto& f : r.index().frames) EXPECT_EQ(f.particle_count, 9360u);
  EXPECT_TRUE(verify_container(path).ok());
}

TEST_F(Sample, QuantizedErrorIsWellUnderAThousandthOfTheSpacing) {
  const auto source = open_source(kPvd, {});
  const auto path = convert_sample(dir / "q.sluice", PositionCoding::Quantized16);
  const ContainerReader r(path);
  double worst = 0;
  for (uint64_t f : {uint64_t(0), uint64_t(6), uint64_t(12)}) {
    const ParticleFrame src = source->read(f);
    const std::vector<uint16_t> lod_in = lod_values(src.ids, src.count());
    std::multimap<uint16_t, size_t> by_lod;
    for (size_t i = 0; i < src.count(); ++i) by_lod.emplace(lod_in[i], i);
    const DecodedFrame d = decode_frame(r, f);
    const std::vector<float> xyz = world_positions(d, PositionCoding::Quantized16);
    const std::vector<uint16_t> lod = lod_values_of(d, PositionCoding::Quantized16);
    for (size_t i = 0; i < src.count(); ++i) {
      double best = INFINITY;
      auto [lo, hi] = by_lod.equal_range(lod[i]);
      for (auto it = lo; it != hi; ++it) {
        double e = 0;
        for (int a = 0; a < 3; ++a) e = std::max(e, std::fabs(double(xyz[3 * i + a]) - src.positions[3 * it->second + a]));
        best = std::min(best, e);
      }
      worst = std::max(worst, best);
    }
  }
  RecordProperty("max_error_in_spacings", std::to_string(worst / 0.04));
  EXPECT_LT(worst / 0.04, 1e-3);
}

TEST_F(Sample, LosslessIsExactAndLodValuesAreStableAcrossFrames) {
  const auto source = open_source(kPvd, {});
  const auto path = convert_sample(dir / "f.sluice", PositionCoding::Float32);
  const ContainerReader r(path);
  std::vector<uint16_t> first_lod;
  for (uint64_t f : {uint64_t(0), uint64_t(12)}) {
    const ParticleFrame src = source->read(f);
    const DecodedFrame d = decode_frame(r, f);
    std::vector<float> got = world_positions(d, PositionCoding::Float32), want = src.positions;
    // Same multiset of points (chunks reorder particles).
    auto as_triples = [](const std::vector<float>& v) {
      std::vector<std::array<float, 3>> t(v.size() / 3);
      for (size_t i = 0; i < t.size(); ++i) t[i] = {v[3 * i], v[3 * i + 1], v[3 * i + 2]};
      std::sort(t.begin(), t.end());
      return t;
    };
    EXPECT_EQ(as_triples(got), as_triples(want)) << "frame " << f;
    std::vector<uint16_t> lod = lod_values_of(d, PositionCoding::Float32);
    std::sort(lod.begin(), lod.end());
    if (first_lod.empty()) first_lod = lod;
    else EXPECT_EQ(lod, first_lod) << "the same particles must carry the same LOD values in every frame";
  }
}

TEST_F(Sample, QuantizedFramesAreAtLeastTwiceSmallerThanRawFloat32) {
  const auto path = convert_sample(dir / "q.sluice", PositionCoding::Quantized16);
  const ContainerReader r(path);
  uint64_t bytes = 0, particles = 0;
  for (const auto& f : r.index().frames) bytes += f.bytes, particles += f.particle_count;
  const double per_particle = double(bytes) / double(particles);
  RecordProperty("bytes_per_particle", std::to_string(per_particle));
  EXPECT_LT(per_particle, 6.0) << "12 bytes of float32 xyz should shrink at least 2x, LOD value included";
}

TEST_F(Sample, PackedAndSmallestFilesDecodeToTheSameParticles) {
  // Real SPH frames: the default packs some planes (codec 2), --smallest
  // keeps zstd (codec 0 only, readable by format 1.0); the decoded bytes
  // must not depend on which.
  const ContainerReader packed(convert_sample(dir / "p.sluice", PositionCoding::Quantized16));
  const ContainerReader smallest(convert_sample(dir / "z.sluice", PositionCoding::Quantized16, PlaneCoding::Zstd));
  size_t packed_chunks = 0;
  for (uint64_t f = 0; f < packed.frame_count(); ++f) {
    const DecodedFrame a = decode_frame(packed, f), b = decode_frame(smallest, f);
    EXPECT_EQ(a.particles, b.particles) << "frame " << f;
    EXPECT_EQ(a.attributes, b.attributes) << "frame " << f;
    for (const ChunkDesc& c : a.header.chunks) packed_chunks += c.codec == ChunkCodec::Packed;
    for (const ChunkDesc& c : b.header.chunks) EXPECT_NE(c.codec, ChunkCodec::Packed) << "frame " << f;
  }
  EXPECT_GT(packed_chunks, 0u) << "the dam break's later frames have small-valued planes to pack";
  EXPECT_LE(std::filesystem::file_size(smallest.path()), std::filesystem::file_size(packed.path()));
}
