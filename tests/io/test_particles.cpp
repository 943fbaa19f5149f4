// io::read_particles: a frame's particles as world-unit arrays, the same
// values `sluice export` writes, reading only the tiers a LOD level keeps.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "sluice/error.h"
#include "sluice/io/export.h"
#include "sluice/io/particles.h"
#include "sluice/io/reader.h"
#include "test_util.h"

using namespace sluice;

namespace {

struct ParticlesFile : ::testing::Test {
  test::TempDir dir;
  std::filesystem::path path;
  void SetUp() override {
    std::vector<io::ParticleFrame> frames{test::lattice_frame(60000, 0.0), test::lattice_frame(60000, 0.5, 2)};
    path = test::write_file(dir.path / "p.sluice", test::test_header(io::PositionCoding::Quantized16), frames);
  }
};

TEST_F(ParticlesFile, EveryParticleEqualsTheExportersValues) {
  io::ContainerReader reader(path);
  const std::vector<size_t> attrs{0};
  const io::ExportFrame expected = io::to_export_frame(io::decode_frame(reader, 1), reader.header(), attrs);
  io::ParticleQuery q;
  q.attributes = attrs;
  const io::ParticleArrays got = io::read_particles(reader, 1, q);
  ASSERT_EQ(got.count(), expected.count());
  EXPECT_EQ(got.positions, expected.positions);
  EXPECT_EQ(got.lod, expected.lod);
  ASSERT_EQ(got.attributes.size(), 1u);
  EXPECT_EQ(got.attributes[0], expected.attributes[0]);
  EXPECT_EQ(got.time, 0.5);
  for (uint8_t l : got.layer) EXPECT_EQ(l, uint8_t(io::Layer::All));
  EXPECT_EQ(got.bytes_read, reader.index().frames[1].bytes);  // level 1 reads the whole record
}

// A frame whose arrays outgrow the caches (1.2M particles, 18 MB) is
// converted with streaming stores, from odd chunk starts too: the same values.
TEST(ParticlesLargeFrame, StreamingStoresWriteTheExportersValues) {
  test::TempDir dir;
  io::FileHeader file = test::test_header(io::PositionCoding::Quantized16);
  const std::vector<io::ParticleFrame> frames{test::lattice_frame(1'200'003, 0.0)};
  const auto path = test::write_file(dir.path / "large.sluice", file, frames);
  io::ContainerReader reader(path);
  const io::DecodedFrame decoded = io::decode_frame(reader, 0);
  const std::vector<size_t> attrs{0};
  const io::ExportFrame expected = io::to_export_frame(decoded, reader.header(), attrs);
  ASSERT_EQ(expected.count(), 1'200'003u);
  bool odd_start = false;
  for (const uint64_t first : decoded.chunk_first) odd_start |= first % 4 != 0;
  EXPECT_TRUE(odd_start) << "a chunk that starts off a group of four";

  io::ParticleQuery q;
  q.attributes = attrs;
  const io::ParticleArrays read = io::read_particles(reader, 0, q);
  EXPECT_EQ(read.positions, expected.positions);
  EXPECT_EQ(read.lod, expected.lod);
  EXPECT_EQ(read.attributes[0], expected.attributes[0]);
}

TEST_F(ParticlesFile, ALevelKeepsTheExportersParticlesAndReadsLess) {
  io::ContainerReader reader(path);
  const std::vector<size_t> attrs{0};
  io::ExportFrame expected = io::to_export_frame(io::decode_frame(reader, 0), reader.header(), attrs);
  io::thin_by_lod(expected, 0.2f);
  io::ParticleQuery q;
  q.attributes = attrs;
  q.lod_level = 0.2f;
  const io::ParticleArrays got = io::read_particles(reader, 0, q);
  // The same particles; order may differ (tiers reorder within a chunk), so
  // compare as sorted (lod, x, y, z, value) tuples.
  using P = std::tuple<uint16_t, float, float, float, float>;
  auto sorted = [](const std::vector<float>& xyz, const std::vector<uint16_t>& lod, const std::vector<float>& v) {
    std::vector<P> out;
    for (size_t i = 0; i < lod.size(); ++i) out.emplace_back(lod[i], xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2], v[i]);
    std::sort(out.begin(), out.end());
    return out;
  };
  ASSERT_GT(got.count(), 9000u);  // about 0.2 of 60,000
  EXPECT_LT(got.count(), 15000u);
  EXPECT_EQ(sorted(got.positions, got.lod, got.attributes[0]), sorted(expected.positions, expected.lod, expected.attributes[0]));
  // Only the tiers holding the top fifth (plus the tier floor's margin).
  const uint64_t record = reader.index().frames[0].bytes;
  EXPECT_LT(got.bytes_read, record * 35 / 100) << got.bytes_read << " of " << record;
}

TEST_F(ParticlesFile, BadRequestsNameTheFileAndFrame) {
  io::ContainerReader reader(path);
  io::ParticleQuery q;
  q.attributes = {3};
  try {
    io::read_particles(reader, 0, q);
    FAIL() << "no error";
  } catch (const io::Error& e) {
    EXPECT_NE(std::string(e.what()).find("p.sluice"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("attribute 3"), std::string::npos) << e.what();
  }
  q.attributes = {};
  q.lod_level = 0;
  EXPECT_THROW(io::read_particles(reader, 0, q), io::Error);
  q.lod_level = 1;
  EXPECT_THROW(io::read_particles(reader, 2, q), io::Error);
}

TEST_F(ParticlesFile, ADamagedChunkNamesItsChunk) {
  {
    io::ContainerReader reader(path);
    const io::FrameHeader h = reader.read_table(1);
    const uint64_t at = reader.index().frames[1].offset + h.chunks[3].offset + 5;
    std::FILE* f = std::fopen(path.c_str(), "r+b");
    std::fseek(f, long(at), SEEK_SET);
    const int c = std::fgetc(f);
    std::fseek(f, long(at), SEEK_SET);
    std::fputc(c ^ 0x5a, f);
    std::fclose(f);
  }
  io::ContainerReader reader(path);
  EXPECT_NO_THROW(io::read_particles(reader, 0, {}));
  try {
    io::read_particles(reader, 1, {});
    FAIL() << "no error";
  } catch (const io::Error& e) {
    EXPECT_NE(std::string(e.what()).find("frame 1"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("chunk"), std::string::npos) << e.what();
  }
}

}  // namespace
